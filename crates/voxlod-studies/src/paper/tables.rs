//! The paper setup's tables: each method's scores beside the paper's Table 1, and the paired
//! differences between methods.

use voxlod_eval::report::{Cell, Column, NumberFormat, Table};

use super::{CaseResult, MethodScores, PairedDiff};
use crate::Error;

/// Brito, Poulin and Teichrieb (2023), Table 1: `(scene, resolution, method, MSE, SSIM)`, the
/// method being `Averages`, `[VJK21]` or `Ours` (the virtual mesh with its opacity subgrid).
pub const PAPER_TABLE_1: &[(&str, u32, &str, f64, f64)] = &[
    ("Bunny", 128, "Averages", 0.0201, 0.8581),
    ("Bunny", 128, "[VJK21]", 0.0053, 0.8383),
    ("Bunny", 128, "Ours", 0.0043, 0.9133),
    ("Trees", 128, "Averages", 0.0180, 0.7888),
    ("Trees", 128, "[VJK21]", 0.0079, 0.8786),
    ("Trees", 128, "Ours", 0.0104, 0.8221),
    ("Island", 128, "Averages", 0.0051, 0.9071),
    ("Island", 128, "[VJK21]", 0.0038, 0.9162),
    ("Island", 128, "Ours", 0.0035, 0.9294),
    ("City", 128, "Averages", 0.0113, 0.7613),
    ("City", 128, "[VJK21]", 0.0059, 0.8180),
    ("City", 128, "Ours", 0.0045, 0.8548),
    ("Bistro", 128, "Averages", 0.0107, 0.8044),
    ("Bistro", 128, "[VJK21]", 0.0096, 0.7977),
    ("Bistro", 128, "Ours", 0.0049, 0.8731),
    ("Bunny", 256, "Averages", 0.0205, 0.8690),
    ("Bunny", 256, "[VJK21]", 0.0050, 0.8342),
    ("Bunny", 256, "Ours", 0.0029, 0.9236),
    ("Trees", 256, "Averages", 0.0205, 0.7675),
    ("Trees", 256, "[VJK21]", 0.0100, 0.8439),
    ("Trees", 256, "Ours", 0.0093, 0.8250),
    ("Island", 256, "Averages", 0.0065, 0.8825),
    ("Island", 256, "[VJK21]", 0.0039, 0.8937),
    ("Island", 256, "Ours", 0.0040, 0.9113),
    ("City", 256, "Averages", 0.0087, 0.8298),
    ("City", 256, "[VJK21]", 0.0050, 0.8573),
    ("City", 256, "Ours", 0.0036, 0.8851),
    ("Bistro", 256, "Averages", 0.0115, 0.7999),
    ("Bistro", 256, "[VJK21]", 0.0067, 0.8243),
    ("Bistro", 256, "Ours", 0.0039, 0.8702),
];

/// The paper's `(MSE, SSIM)` for `method` on `scene` at `res`, where it has one.
pub fn paper_value(scene: Option<&str>, res: u32, method: &str) -> Option<(f64, f64)> {
    let name = match method {
        "Averages" => "Averages",
        "[VJK21]" => "[VJK21]",
        "virtual mesh" => "Ours",
        _ => return None,
    };
    PAPER_TABLE_1
        .iter()
        .find(|(s, r, m, _, _)| Some(*s) == scene && *r == res && *m == name)
        .map(|&(_, _, _, mse, ssim)| (mse, ssim))
}

fn range(v: &[f64], digits: usize, sci: bool) -> String {
    let (lo, hi) =
        v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    if sci {
        format!("{mean:.d$e} ({lo:.d$e}–{hi:.d$e})", d = digits)
    } else {
        format!("{mean:.d$} ({lo:.d$}–{hi:.d$})", d = digits)
    }
}

impl CaseResult {
    /// The case's scores: one row per method, with the paper's Table 1 values beside where
    /// the scene corresponds to one of its scenes.
    pub fn scores_table(&self) -> Result<Table, Error> {
        let mut table = Table::new(
            format!(
                "{} {}³ ({}): {} triangles, {} voxels, {} samples",
                self.scene,
                self.resolution,
                self.variant.name,
                self.triangles,
                self.voxels,
                self.samples
            ),
            vec![
                Column::text("method"),
                Column::number("B/voxel", NumberFormat::Fixed(1)),
                Column::number("precompute (ms)", NumberFormat::Fixed(0)),
                Column::number("render (ms/frame)", NumberFormat::Fixed(1)),
                Column::text("MSE mean (min–max)"),
                Column::text("SSIM mean (min–max)"),
                Column::text("paper MSE"),
                Column::text("paper SSIM"),
            ],
        );
        for m in &self.methods {
            let paper = paper_value(self.paper.as_deref(), self.resolution, &m.method);
            table.push_row(vec![
                m.method.clone().into(),
                Cell::Number(m.bytes_per_voxel),
                Cell::Number(m.precompute_ms),
                Cell::Number(m.render_ms),
                Cell::Text(range(&m.mse, 2, true)),
                Cell::Text(range(&m.ssim, 4, false)),
                paper.map_or(Cell::Empty, |(mse, _)| Cell::Text(format!("{mse:.4}"))),
                paper.map_or(Cell::Empty, |(_, ssim)| Cell::Text(format!("{ssim:.4}"))),
            ])?;
        }
        Ok(table)
    }

    /// Every pair of methods: the paired differences of MSE and SSIM (row minus column method)
    /// with their 95 % bootstrap interval, and which is better where the interval excludes zero.
    pub fn pairs_table(&self) -> Result<Table, Error> {
        let mut table = Table::new(
            format!(
                "{} {}³ ({}): paired differences between methods",
                self.scene, self.resolution, self.variant.name
            ),
            vec![
                Column::text("A − B"),
                Column::text("ΔMSE mean [95 % interval]"),
                Column::text("lower MSE"),
                Column::text("ΔSSIM mean [95 % interval]"),
                Column::text("higher SSIM"),
            ],
        );
        for (i, a) in self.methods.iter().enumerate() {
            for b in &self.methods[i + 1..] {
                let (mse, ssim) = pair(a, b);
                table.push_row(vec![
                    Cell::Text(format!("{} − {}", a.method, b.method)),
                    Cell::Text(mse.display_sci(2)),
                    Cell::Text(verdict(&mse, &a.method, &b.method, false)),
                    Cell::Text(ssim.display_fixed(4)),
                    Cell::Text(verdict(&ssim, &a.method, &b.method, true)),
                ])?;
            }
        }
        Ok(table)
    }

    /// Each Adaptive method against the target: SSIM at least the best single representation's
    /// minus the interval (the paired difference's interval reaches zero or above) at no more
    /// than 25 % of the virtual mesh's bytes per voxel. None when the case has no Adaptive
    /// method.
    pub fn adaptive_table(&self) -> Result<Option<Table>, Error> {
        let singles = ["Averages", "[VJK21]", "virtual mesh"];
        let best = self
            .methods
            .iter()
            .filter(|m| singles.contains(&m.method.as_str()))
            .max_by(|a, b| a.ssim_mean().total_cmp(&b.ssim_mean()));
        let (Some(best), Some(vm)) = (best, self.method("virtual mesh")) else { return Ok(None) };
        let adaptive: Vec<&MethodScores> =
            self.methods.iter().filter(|m| m.method.starts_with("Adaptive")).collect();
        if adaptive.is_empty() {
            return Ok(None);
        }
        let mut table = Table::new(
            format!(
                "{} {}³ ({}): Adaptive against its target (SSIM ≥ the best single representation's, {}, within the interval, at ≤ 25 % of the virtual mesh's {:.1} B/voxel)",
                self.scene, self.resolution, self.variant.name, best.method, vm.bytes_per_voxel
            ),
            vec![
                Column::text("method"),
                Column::number("B/voxel", NumberFormat::Fixed(1)),
                Column::text("of virtual mesh"),
                Column::text(format!("ΔSSIM vs {} [95 %]", best.method)),
                Column::text("target"),
            ],
        );
        for a in adaptive {
            let d = PairedDiff::of(&a.ssim, &best.ssim);
            let ratio = a.bytes_per_voxel / vm.bytes_per_voxel;
            let quality = d.hi >= 0.0;
            let verdict = match (quality, ratio <= 0.25) {
                (true, true) => "met".to_string(),
                (false, true) => format!("missed: SSIM {:.4} below", -d.hi),
                (true, false) => "missed: bytes".to_string(),
                (false, false) => "missed: SSIM and bytes".to_string(),
            };
            table.push_row(vec![
                a.method.clone().into(),
                Cell::Number(a.bytes_per_voxel),
                Cell::Text(format!("{:.1} %", ratio * 100.0)),
                Cell::Text(d.display_fixed(4)),
                Cell::Text(verdict),
            ])?;
        }
        Ok(Some(table))
    }

    /// The best method by mean SSIM, and whether its lead over the runner-up is resolved.
    pub fn best_by_ssim(&self) -> Option<(&MethodScores, bool)> {
        let mut sorted: Vec<&MethodScores> = self.methods.iter().collect();
        sorted.sort_by(|a, b| b.ssim_mean().total_cmp(&a.ssim_mean()));
        let best = *sorted.first()?;
        let resolved = sorted.get(1).is_none_or(|second| {
            let d = PairedDiff::of(&best.ssim, &second.ssim);
            d.resolved()
        });
        Some((best, resolved))
    }
}

/// The paired differences `a − b` of MSE and SSIM.
pub fn pair(a: &MethodScores, b: &MethodScores) -> (PairedDiff, PairedDiff) {
    (PairedDiff::of(&a.mse, &b.mse), PairedDiff::of(&a.ssim, &b.ssim))
}

/// Which of `a`, `b` is better by a difference `d = a − b` (higher is better when
/// `higher_better`), or "not resolved".
pub fn verdict(d: &PairedDiff, a: &str, b: &str, higher_better: bool) -> String {
    if !d.resolved() {
        return "not resolved".into();
    }
    let a_better = (d.mean > 0.0) == higher_better;
    if a_better { a.into() } else { b.into() }
}

/// What every paper-setup report says first: the conditions, the samples and the interval.
pub fn intro(config: &super::PaperConfig, result: &super::PaperResult) -> String {
    format!(
        "Conditions of Brito, Poulin and Teichrieb (2023, §5): images at a side equal to the voxel \
         resolution, the ground truth at {spp} rays per pixel box-filtered (its own error, half \
         the MSE of a second seed against the first, is reported with each case), \
         {rays} sampling rays per voxel, the scene's sun and a point light on the camera's side \
         (an image under both is the sum of one render per light), white background unless a \
         variant says otherwise. Each method is scored on {views} views × {seeds} seeds of its \
         sampling lines; a difference between two methods, or between a variant and the setup, \
         is paired over these samples and shown with the 95 % percentile-bootstrap interval of \
         its mean ({resamples} resamples); a method is called better only where that interval \
         excludes zero. Ground truths: {cached} loaded from the cache, {rendered} rendered. \
         Times are wall-clock on this machine and vary from run to run; every other figure is \
         reproduced exactly by the same command.",
        spp = config.gt_spp,
        rays = config.rays,
        views = config.views,
        seeds = config.seeds,
        resamples = super::stats::BOOTSTRAP_RESAMPLES,
        cached = result.truths_cached,
        rendered = result.truths_rendered,
    )
}

/// One sentence per case: the best method by SSIM and whether the paper's ranking (its method
/// ahead of \[VJK21\] and Averages) holds with resolved intervals.
pub fn findings(case: &CaseResult) -> String {
    let best = case.best_by_ssim().map_or("no method".to_string(), |(m, resolved)| {
        format!(
            "{} has the highest SSIM ({:.4}){}",
            m.method,
            m.ssim_mean(),
            if resolved {
                ", ahead of the runner-up beyond the interval"
            } else {
                ", but its lead over the runner-up is within the interval"
            }
        )
    });
    let vs = |other: &str| -> String {
        match (case.method("virtual mesh"), case.method(other)) {
            (Some(a), Some(b)) => {
                let (mse, ssim) = pair(a, b);
                format!(
                    "virtual mesh − {other}: ΔSSIM {} ({}), ΔMSE {} ({})",
                    ssim.display_fixed(4),
                    verdict(&ssim, "virtual mesh better", &format!("{other} better"), true),
                    mse.display_sci(2),
                    verdict(&mse, "virtual mesh better", &format!("{other} better"), false),
                )
            }
            _ => String::new(),
        }
    };
    format!(
        "**{} {}³, {}:** {best}. {}; {}.",
        case.scene,
        case.resolution,
        case.variant.name,
        vs("[VJK21]"),
        vs("Averages")
    )
}

impl super::PaperResult {
    /// The scores and pairs tables of every case.
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        let mut tables = Vec::new();
        for c in &self.cases {
            tables.push(c.scores_table()?);
            tables.push(c.pairs_table()?);
            tables.extend(c.adaptive_table()?);
        }
        Ok(tables)
    }

    /// The report: conditions, per case its findings, scores beside the paper's Table 1, the
    /// paired differences and the view-0 images.
    pub fn add_to_report(
        &self,
        report: &mut voxlod_eval::report::Report,
        config: &super::PaperConfig,
    ) -> Result<(), Error> {
        report.heading(2, "Filtered appearance under the paper's conditions");
        report.text(intro(config, self));
        for c in &self.cases {
            report.heading(3, format!("{} at {}³ ({})", c.scene, c.resolution, c.variant.name));
            report.text(format!(
                "`{}`: {} triangles, {} voxels; ground truth error {:.2e} (MSE); wall time {:.1} s.\n\n{}",
                c.spec,
                c.triangles,
                c.voxels,
                c.truth_error_mse,
                c.wall_ms / 1e3,
                findings(c)
            ));
            report.table(c.scores_table()?);
            report.table(c.pairs_table()?);
            if let Some(t) = c.adaptive_table()? {
                report.table(t);
            }
            if !c.figure.is_empty() {
                let name = format!("paper-{}-{}-{}", c.scene, c.resolution, slug(&c.variant.name));
                let caption = format!(
                    "{} {}³, view 0, seed 0: ground truth and each method",
                    c.scene, c.resolution
                );
                let grid = voxlod_eval::report::ImageGrid::new(
                    c.figure.len().min(6) as u32,
                    c.figure.clone(),
                );
                report.images(name, caption, grid);
            }
        }
        Ok(())
    }
}

/// A file-name-safe form of `s`.
pub(super) fn slug(s: &str) -> String {
    let mut out = String::new();
    for ch in s.chars() {
        if ch.is_ascii_alphanumeric() {
            out.push(ch.to_ascii_lowercase());
        } else if !out.ends_with('-') {
            out.push('-');
        }
    }
    out.trim_matches('-').to_string()
}
