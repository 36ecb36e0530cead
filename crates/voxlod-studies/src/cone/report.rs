//! The cone study's tables, report section (text, images, plots) and float data.

use voxlod_eval::report::{Cell, Column, ImageGrid, NumberFormat, Plot, Report, Series, Table};

use super::{ConeResult, ConeRow};
use crate::Error;

impl ConeResult {
    /// The sweep's table, the leak table and (with the LOD part) its table.
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        let o = self;
        let num = |n: &str, f| Column::number(n, f);
        let mut t = Table::new(
            "cone tracing vs ray-traced references",
            vec![
                num("res", NumberFormat::Integer),
                num("depth", NumberFormat::Integer),
                Column::text("opacity"),
                num("cones", NumberFormat::Integer),
                num("aperture°", NumberFormat::Fixed(0)),
                num("step", NumberFormat::Fixed(2)),
                num("AO MSE", NumberFormat::Significant(3)),
                num("AO SSIM", NumberFormat::Fixed(3)),
                num("indirect MSE", NumberFormat::Significant(3)),
                num("indirect SSIM", NumberFormat::Fixed(3)),
                num("trace ms", NumberFormat::Significant(3)),
                num("samples/px", NumberFormat::Significant(3)),
            ],
        );
        for r in &o.rows {
            let mut cells: Vec<Cell> =
                [r.resolution as f64, r.depth as f64].into_iter().map(Cell::Number).collect();
            cells.push(Cell::Text(r.opacity.clone()));
            cells.extend(
                [
                    r.cones as f64,
                    r.aperture_deg as f64,
                    r.step as f64,
                    r.ao_mse,
                    r.ao_ssim,
                    r.indirect_mse,
                    r.indirect_ssim,
                    r.trace_ms,
                    r.steps_per_pixel,
                ]
                .into_iter()
                .map(Cell::Number),
            );
            t.push_row(cells)?;
        }
        let mut l = Table::new(
            "light leaking through a wall 1/32 of the scene thick (truth 0)",
            vec![
                num("depth", NumberFormat::Integer),
                num("wall voxels", NumberFormat::Integer),
                Column::text("opacity"),
                num("step", NumberFormat::Fixed(2)),
                num("leaked fraction", NumberFormat::Significant(3)),
            ],
        );
        for r in &o.leaks {
            l.push_row(vec![
                Cell::Number(r.depth as f64),
                Cell::Number(r.wall_voxels as f64),
                Cell::Text(r.option.clone()),
                Cell::Number(r.step as f64),
                Cell::Number(r.leak),
            ])?;
        }
        let mut out = vec![t, l];
        if let Some(p) = &o.lod {
            out.push(p.table()?);
        }
        Ok(out)
    }

    /// Appends the cone-tracing section (heading, references, tables, error-vs-time plots).
    pub fn add_to_report(&self, r: &mut Report) -> Result<(), Error> {
        let o = self;
        r.heading(2, format!("Voxel cone tracing: {}", o.scene));
        r.text(format!(
        "References: ray-traced AO and one-bounce path-traced diffuse indirect light on the mesh \
         ({:.0} ms and {:.0} ms, CPU). Their own error against the converged truth, estimated \
         as half the MSE between two independent seeds: AO {:.2e}, indirect {:.2e}; errors \
         below these are not resolved. Octrees (res, voxels, bytes/voxel, \
         build ms, injection ms): {}. Cones traced on {}. Times are wall-clock times on a \
         shared machine (on a CPU adapter such as lavapipe, CPU times of the GPU path).",
        o.reference_ms.ao,
        o.reference_ms.indirect,
        o.reference_error_mse.ao,
        o.reference_error_mse.indirect,
        o.octrees
            .iter()
            .map(|t| format!(
                "{}³: {} voxels, {:.1} B, {:.0} ms, {:.0} ms",
                t.resolution, t.voxels, t.bytes_per_voxel, t.build_ms, t.inject_ms
            ))
            .collect::<Vec<_>>()
            .join("; "),
        o.backend
    ));
        for t in o.tables()? {
            r.table(t);
        }
        if !o.images.is_empty() {
            r.images(
                "cone_references",
                format!(
                    "the ray-traced references, the sweep's best AO row ({}) and best indirect \
                     row ({}), and their per-pixel errors (heat maps: full scale 0.25)",
                    o.best_rows.ao.as_deref().unwrap_or("none"),
                    o.best_rows.indirect.as_deref().unwrap_or("none")
                ),
                ImageGrid::new(3, o.images.clone()),
            );
            r.data(
                "cone_reference_data",
                "the same images in linear float: AO [height, width]; albedo · E/π [height, \
                 width, 3]",
                o.arrays.clone(),
            );
        }
        if let Some(p) = &o.lod {
            r.text(p.summary());
            r.images(
                "cone_lod_images",
                format!("{}: the mesh and the LOD march at each bias", p.scene),
                p.image_grid(),
            );
        }
        let mut keys: Vec<(u32, u32, &str)> = o
            .rows
            .iter()
            .map(|x| (x.resolution, x.aperture_deg as u32, x.opacity.as_str()))
            .collect();
        keys.sort();
        keys.dedup();
        let series = |metric: fn(&ConeRow) -> f64| -> Vec<Series> {
            keys.iter()
                .map(|&(res, ap, opacity)| {
                    let pts = o
                        .rows
                        .iter()
                        .filter(|x| {
                            x.resolution == res
                                && x.aperture_deg as u32 == ap
                                && x.opacity == opacity
                        })
                        .map(|x| (x.trace_ms, metric(x)))
                        .collect();
                    Series::new(format!("{res}³, {ap}°, {opacity}"), pts)
                })
                .collect()
        };
        for (name, title, y_label, metric) in [
            (
                "cone_ao_error_vs_time",
                "AO error vs cone tracing time",
                "AO MSE (8-bit sRGB)",
                (|x: &ConeRow| x.ao_mse) as fn(&ConeRow) -> f64,
            ),
            (
                "cone_indirect_error_vs_time",
                "indirect light error vs cone tracing time",
                "indirect MSE (8-bit sRGB)",
                |x: &ConeRow| x.indirect_mse,
            ),
        ] {
            r.plot(
                name,
                Plot {
                    title: title.into(),
                    x_label: "trace time (ms, CPU)".into(),
                    y_label: y_label.into(),
                    log_x: true,
                    log_y: true,
                    series: series(metric),
                    ..Plot::default()
                },
            );
        }
        Ok(())
    }
}
