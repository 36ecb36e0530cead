//! Tests of the report writer: what lands on disk, in which form, and what is refused.

use std::fs;

use voxlod_scene::Srgb8Image;

use super::*;
use crate::patterns;

struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("voxlod-eval-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        Self(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

fn sample_table() -> Table {
    let mut t = Table::new(
        "errors",
        vec![
            Column::text("method"),
            Column::number("MSE", NumberFormat::Scientific(2)),
            Column::number("PSNR", NumberFormat::Fixed(2)),
        ],
    );
    t.push_row(vec!["averages".into(), 0.00123.into(), 29.1.into()]).unwrap();
    t.push_row(vec!["ground truth".into(), 0.0.into(), f64::INFINITY.into()]).unwrap();
    t
}

fn sample_plot() -> Plot {
    Plot {
        title: "error <against> cost & more".into(),
        x_label: "time (ms)".into(),
        y_label: "MSE".into(),
        log_x: true,
        series: vec![
            Series::new("averages", vec![(10.0, 0.01), (f64::NAN, 0.5), (100.0, 0.002)]),
            Series::new("subgrid", vec![(20.0, 0.005), (0.0, 0.1), (200.0, f64::INFINITY)])
                .with_style(SeriesStyle::Points),
        ],
        ..Plot::default()
    }
}

#[test]
fn writes_markdown_json_svg_and_pngs() {
    let tmp = TempDir::new("report");
    let a = patterns::gradient(24, 16);
    let b = patterns::box_blur(&patterns::noise(24, 16, 2));
    let grid = ImageGrid::new(
        3,
        vec![
            LabeledImage::new("reference", a.clone()),
            LabeledImage::new("voxels", b.clone()),
            LabeledImage::new("error", crate::error_heatmap(&b, &a, 0.5).unwrap()),
        ],
    );
    let mut report = Report::new("Test report");
    report
        .text("Intro paragraph.")
        .heading(2, "Scene A")
        .table(sample_table())
        .images("scene-a", "reference, voxels, error", grid)
        .plot("scene_a_plot", sample_plot());
    let written = report.write(&tmp.0).unwrap();

    let md = fs::read_to_string(&written.markdown).unwrap();
    assert!(md.starts_with("# Test report\n\nIntro paragraph.\n\n## Scene A\n"), "{md}");
    let table = "\
| method       |     MSE |  PSNR |
| :----------- | ------: | ----: |
| averages     | 1.23e-3 | 29.10 |
| ground truth |  0.00e0 |   inf |
";
    assert!(md.contains(table), "{md}");
    assert!(md.contains("![reference, voxels, error](assets/scene-a.png)"), "{md}");
    assert!(md.contains("[voxels](assets/scene-a/1.png)"), "{md}");
    assert!(md.contains("![error <against> cost & more](assets/scene_a_plot.svg)"), "{md}");
    assert!(md.contains("3 point(s) not drawn"), "{md}");
    assert!(md.contains("'averages' #1 (NaN, 0.5): not finite"), "{md}");
    assert!(md.contains("'subgrid' #1 (0, 0.1): not positive on a log axis"), "{md}");
    assert_eq!(written.skipped_points.len(), 3);

    let svg = fs::read_to_string(tmp.0.join("assets/scene_a_plot.svg")).unwrap();
    let svg = svg.trim();
    assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"), "{svg}");
    assert!(svg.contains("time (ms)") && svg.contains("averages") && svg.contains("subgrid"));
    assert!(svg.contains("&lt;against&gt; cost &amp; more"), "title must be escaped");
    assert!(!svg.contains("NaN") && !svg.contains("inf"), "non-finite values leaked into SVG");

    let grid_png = Srgb8Image::load(&tmp.0.join("assets/scene-a.png")).unwrap();
    assert!(grid_png.width > 3 * 24 && grid_png.height > 16);
    assert_eq!(Srgb8Image::load(&tmp.0.join("assets/scene-a/0.png")).unwrap(), a);
    assert_eq!(written.assets.len(), 5);
    assert!(written.assets.iter().all(|p| p.exists()));

    let summary: Summary = serde_json::from_slice(&fs::read(&written.summary).unwrap()).unwrap();
    assert_eq!(summary.title, "Test report");
    let t = &summary.tables[0];
    assert_eq!((t.name.as_str(), t.section.as_str()), ("errors", "Scene A"));
    assert_eq!(t.columns, ["method", "MSE", "PSNR"]);
    assert_eq!(
        serde_json::to_string(&t.rows).unwrap(),
        r#"[["averages",0.00123,29.1],["ground truth",0.0,"inf"]]"#
    );
    assert_eq!(summary.plots[0].skipped.len(), 3);
    assert_eq!(summary.plots[0].series[0].points[1][0], "nan");
    assert_eq!(summary.images[0].file, "assets/scene-a.png");
    // No temporary files are left behind.
    let names: Vec<_> = fs::read_dir(&tmp.0).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 3, "{names:?}");
}

#[test]
fn bad_or_repeated_asset_names_fail_before_writing() {
    let tmp = TempDir::new("report-names");
    for bad in ["", "a b", "../up", "x.svg"] {
        let mut r = Report::new("r");
        r.plot(bad, Plot::default());
        assert!(matches!(r.write(&tmp.0), Err(Error::InvalidAssetName { .. })), "{bad:?}");
    }
    let mut r = Report::new("r");
    r.plot("p", Plot::default()).plot("P", Plot::default());
    let err = r.write(&tmp.0).unwrap_err();
    assert!(matches!(err, Error::DuplicateAsset { .. }), "{err}");
    // A grid that cannot be composed fails the whole write, before any file exists.
    let mut r = Report::new("r");
    r.plot("ok", Plot::default()).images("g", "", ImageGrid::new(1, vec![]));
    assert!(matches!(r.write(&tmp.0), Err(Error::InvalidGrid { .. })));
    assert!(!tmp.0.exists());
}

#[test]
fn plots_with_nothing_drawable_or_extreme_values_render_without_hanging() {
    let plot = |points: Vec<(f64, f64)>, log_x: bool, log_y: bool| Plot {
        series: vec![Series::new("s", points)],
        log_x,
        log_y,
        ..Plot::default()
    };
    // (plot, number of points that must be skipped)
    let cases = [
        (Plot::default(), 0),
        (Plot { log_x: true, log_y: true, ..Plot::default() }, 0),
        (plot(vec![(f64::NAN, f64::NAN)], false, true), 1),
        (plot(vec![(3.0, 3.0)], false, false), 0),
        (plot(vec![(3.0, 3.0)], true, true), 0),
        (plot(vec![(1e10, 0.0), (1e10 + 1e-5, 0.0)], false, false), 0),
        (plot(vec![(-1e100, 1e-100), (1e100, 1e100)], false, false), 0),
        (plot(vec![(1e-100, 1.0), (2e-100, 2.0)], true, false), 0),
        (plot(vec![(1e-100, 1e-100), (2e-100, 1e100)], true, true), 0),
        // 600 decades made plotters' log-axis tick loop run (practically) forever.
        (plot(vec![(1e-300, 1e-300), (2e-300, 1e300), (1.0, 2.0)], true, true), 2),
        (plot(vec![(1.0, f64::MAX), (2.0, 1e-310), (3.0, -1e101), (4.0, 5.0)], false, true), 3),
        (plot(vec![(-f64::MAX, f64::MAX), (0.0, 0.0)], false, false), 1),
    ];
    for (i, (plot, skipped)) in cases.into_iter().enumerate() {
        let r = plot.render_svg().unwrap();
        let svg = r.svg.trim();
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"), "case {i}");
        assert_eq!(r.skipped.len(), skipped, "case {i}: {:?}", r.skipped);
    }
}

#[test]
fn data_sections_write_npy_arrays_and_link_them() {
    use crate::npy::{FloatArray, decode_f32};
    let tmp = TempDir::new("data");
    let ao = FloatArray { name: "ao".into(), shape: vec![2, 3], data: vec![0.5; 6] };
    let rgb = FloatArray {
        name: "rgb".into(),
        shape: vec![1, 2, 3],
        data: (0..6).map(|i| i as f32).collect(),
    };
    let mut r = Report::new("data");
    r.data("refs", "the references", vec![ao.clone(), rgb.clone()]);
    let written = r.write(&tmp.0).unwrap();
    let md = fs::read_to_string(&written.markdown).unwrap();
    assert!(
        md.contains("[ao](assets/refs/ao.npy)") && md.contains("[rgb](assets/refs/rgb.npy)"),
        "{md}"
    );
    for a in [ao, rgb] {
        let bytes = fs::read(tmp.0.join(format!("assets/refs/{}.npy", a.name))).unwrap();
        assert_eq!(decode_f32(&bytes).unwrap(), (a.shape, a.data));
    }
    // A bad or repeated array name is refused before anything is written.
    let bad = FloatArray { name: "a b".into(), shape: vec![1], data: vec![0.0] };
    let mut r = Report::new("bad");
    r.data("refs", "x", vec![bad]);
    assert!(matches!(r.write(&tmp.0.join("bad")), Err(Error::InvalidAssetName { .. })));
    assert!(!tmp.0.join("bad").exists());
    let one = FloatArray { name: "x".into(), shape: vec![1], data: vec![0.0] };
    let mut r = Report::new("dup");
    r.data("refs", "x", vec![one.clone(), one]);
    assert!(matches!(r.write(&tmp.0.join("dup")), Err(Error::DuplicateAsset { .. })));
}
