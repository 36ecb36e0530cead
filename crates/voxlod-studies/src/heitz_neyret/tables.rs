//! The study's tables, plots and report sections.

use voxlod_eval::report::{
    Cell, Column, ImageGrid, LabeledImage, NumberFormat, Plot, Report, Series, Table,
};

use super::{HeitzNeyretResult, Method};
use crate::Error;

/// `(R, G)/(R + G + B)` (zero for black).
pub(super) fn chromaticity(c: [f32; 3]) -> [f32; 2] {
    let s = c[0] + c[1] + c[2];
    if s > 0.0 { [c[0] / s, c[1] / s] } else { [0.0; 2] }
}

/// The paper's bytes per voxel (8- and 16-bit channels, isotropic NDF, RGB colour).
const PAPER_BYTES: &str = "15–20";

impl HeitzNeyretResult {
    /// The trade table: per scene, zoom and method, error, silhouette, work, time.
    pub fn trade_table(&self) -> Result<Table, Error> {
        let num = |n: &str, f| Column::number(n, f);
        let gpu = self.scenes.iter().any(|s| {
            s.zooms.iter().any(|z| z.rows.iter().any(|r| r.gpu_us_per_covered_pixel.is_some()))
        });
        let mut columns = vec![
            Column::text("scene"),
            num("zoom", NumberFormat::Fixed(0)),
            num("voxels/px", NumberFormat::Significant(2)),
            num("truth error MSE", NumberFormat::Significant(2)),
            Column::text("method"),
            num("MSE", NumberFormat::Significant(3)),
            num("SSIM", NumberFormat::Fixed(3)),
            num("silhouette px", NumberFormat::Fixed(2)),
            num("coverage excess %", NumberFormat::Fixed(1)),
            num("elements/px", NumberFormat::Significant(3)),
            num("shadow el./px", NumberFormat::Significant(3)),
            Column::text("CPU ms (min–max)"),
            num("CPU µs/covered px", NumberFormat::Significant(3)),
        ];
        if gpu {
            columns.push(num("GPU µs/covered px", NumberFormat::Significant(3)));
            columns.push(num("GPU vs CPU steps", NumberFormat::Integer));
        }
        let mut t = Table::new(
            format!(
                "coverage masks against alpha blending over distance, {}² px, truth {} spp",
                self.image_size, self.spp
            ),
            columns,
        );
        for s in &self.scenes {
            let label = if s.case.in_domain {
                s.case.label.clone()
            } else {
                format!("{} (out of domain)", s.case.label)
            };
            for z in &s.zooms {
                for r in &z.rows {
                    let mut cells = vec![
                        Cell::Text(label.clone()),
                        Cell::Number(z.zoom as f64),
                        Cell::Number(z.footprint_voxels as f64),
                        Cell::Number(z.truth_error_mse),
                        Cell::Text(r.method.label().into()),
                        Cell::Number(r.mse),
                        Cell::Number(r.ssim),
                        Cell::Number(r.silhouette_thickness_px),
                        Cell::Number(100.0 * r.coverage_excess),
                        Cell::Number(r.elements_per_pixel),
                        Cell::Number(r.shadow_elements_per_pixel),
                        Cell::Text(format!("{:.1}–{:.1}", r.cpu.min_ms, r.cpu.max_ms)),
                        Cell::Number(r.cpu_us_per_covered_pixel),
                    ];
                    if gpu {
                        cells.push(r.gpu_us_per_covered_pixel.map_or(Cell::Empty, Cell::Number));
                        let step = r.gpu_worst_step.map_or(Cell::Empty, |s| Cell::Number(s as f64));
                        cells.push(step);
                    }
                    t.push_row(cells)?;
                }
            }
        }
        Ok(t)
    }

    /// The grazing-colour table: per radial scene, zoom and `μ` bin, the truth's mean colour
    /// and each method's chromaticity distance to it.
    pub fn grazing_table(&self) -> Result<Table, Error> {
        let num = |n: &str, f| Column::number(n, f);
        let mut columns = vec![
            Column::text("scene"),
            num("zoom", NumberFormat::Fixed(0)),
            Column::text("μ = |v·n|"),
            num("pixels", NumberFormat::Integer),
            Column::text("truth RGB"),
            Column::text("truth (r, g)"),
        ];
        for m in Method::ALL {
            columns.push(num(format!("|Δ(r,g)| {}", m.label()).as_str(), NumberFormat::Fixed(4)));
        }
        let mut t = Table::new(
            "mean colour by view angle (radial macro-normal): chromaticity distance to the truth",
            columns,
        );
        for s in self.scenes.iter().filter(|s| s.case.radial) {
            for z in &s.zooms {
                for b in z.grazing.iter().filter(|b| b.pixels > 0) {
                    let truth = chromaticity(b.truth_rgb);
                    let mut cells = vec![
                        Cell::Text(s.case.label.clone()),
                        Cell::Number(z.zoom as f64),
                        Cell::Text(format!("{:.2}–{:.2}", b.mu_min, b.mu_max)),
                        Cell::Number(b.pixels as f64),
                        Cell::Text(format!(
                            "{:.3} {:.3} {:.3}",
                            b.truth_rgb[0], b.truth_rgb[1], b.truth_rgb[2]
                        )),
                        Cell::Text(format!("{:.3}, {:.3}", truth[0], truth[1])),
                    ];
                    for c in &b.method_rgb {
                        let m = chromaticity(*c);
                        let d = (m[0] - truth[0]).hypot(m[1] - truth[1]);
                        cells.push(Cell::Number(d as f64));
                    }
                    t.push_row(cells)?;
                }
            }
        }
        Ok(t)
    }

    /// Memory and precompute of both representations per scene.
    pub fn memory_table(&self) -> Result<Table, Error> {
        let num = |n: &str, f| Column::number(n, f);
        let mut t = Table::new(
            format!("memory and precompute (the paper: {PAPER_BYTES} B per voxel)"),
            vec![
                Column::text("scene"),
                num("res", NumberFormat::Integer),
                num("voxels", NumberFormat::Integer),
                Column::text("records"),
                num("B/node", NumberFormat::Integer),
                num("sparse payload B/voxel", NumberFormat::Fixed(1)),
                num("octree B/voxel", NumberFormat::Fixed(1)),
                num("fit ms", NumberFormat::Significant(3)),
                num("build ms", NumberFormat::Significant(3)),
            ],
        );
        for s in &self.scenes {
            for r in &s.representations {
                t.push_row(vec![
                    Cell::Text(s.case.label.clone()),
                    Cell::Number(s.resolution as f64),
                    Cell::Number(s.voxels as f64),
                    Cell::Text(r.name.clone()),
                    Cell::Number(r.payload_bytes_per_node as f64),
                    Cell::Number(r.payload_bytes_per_voxel),
                    Cell::Number(r.total_bytes_per_voxel),
                    Cell::Number(r.fit_ms),
                    Cell::Number(r.build_ms),
                ])?;
            }
        }
        Ok(t)
    }

    /// Every table.
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        Ok(vec![self.trade_table()?, self.grazing_table()?, self.memory_table()?])
    }

    /// SSIM against the zoom, one series per in-domain scene and method.
    pub fn ssim_plot(&self) -> Plot {
        let mut series = Vec::new();
        for s in self.scenes.iter().filter(|s| s.case.in_domain) {
            for m in [Method::Masks, Method::Blending, Method::AveragesDirectional] {
                let pts = s
                    .zooms
                    .iter()
                    .filter_map(|z| {
                        z.rows.iter().find(|r| r.method == m).map(|r| (z.zoom as f64, r.ssim))
                    })
                    .collect();
                series.push(Series::new(format!("{}, {}", s.case.label, m.label()), pts));
            }
        }
        Plot {
            title: "SSIM against the mesh over distance".into(),
            x_label: "camera distance (× default)".into(),
            y_label: "SSIM".into(),
            log_x: true,
            series,
            ..Plot::default()
        }
    }

    /// Appends the study's sections to `r`.
    pub fn add_to_report(&self, r: &mut Report) -> Result<(), Error> {
        r.heading(2, "Heitz–Neyret: surface statistics and coverage masks");
        r.text(format!(
            "Each scene voxelized, its Heitz–Neyret and Averages records fitted to {} sampling \
             lines per voxel, rendered from its default camera moved away by each zoom factor \
             ({}² pixels, so the pixel footprint covers more voxels) and compared with the mesh \
             at {} rays per pixel. Renders on {}; machine: {}. Times are wall-clock times of \
             the CPU renderers (rayon) on a shared machine, per pixel the truth covers; a GPU \
             column, where present, is the wgpu kernel's time, which on a CPU adapter \
             (lavapipe) is a CPU time of the GPU path. Silhouette px: by how many pixels the \
             silhouette is thicker (> 0) than the truth's; coverage excess: the total coverage \
             over the truth's. Truth error MSE: the ground truth's own error, half the MSE \
             between two of its seeds; MSE differences below it are not resolved.",
            self.rays, self.image_size, self.spp, self.backend, self.machine
        ));
        for t in self.tables()? {
            r.table(t);
        }
        if let Some(d) = &self.depth_of_field {
            r.text(format!(
                "Depth of field on {} (lens radius {:.3}, focused at {:.3}, the scene out of \
                 focus): total coverage with the lens over the pinhole's, coverage masks {:.3}, \
                 alpha blending {:.3} (a blur moves coverage and should not add any).",
                d.scene,
                d.lens_radius,
                d.focus_distance,
                d.masks_coverage_ratio,
                d.blending_coverage_ratio
            ));
        }
        r.plot("heitz_neyret_ssim_vs_zoom", self.ssim_plot());
        for s in &self.scenes {
            let per_zoom = 1 + Method::ALL.len();
            let images: Vec<LabeledImage> = s
                .images
                .iter()
                .map(|(label, img)| LabeledImage::new(label.clone(), img.clone()))
                .collect();
            if images.is_empty() {
                continue;
            }
            let name = format!(
                "heitz_neyret_{}",
                s.case.label.replace(|c: char| !c.is_ascii_alphanumeric(), "_")
            );
            r.images(
                name,
                format!(
                    "{}: the mesh and each method ({}), one row per zoom",
                    s.case.label,
                    Method::ALL.map(|m| m.label()).join(", ")
                ),
                ImageGrid::new(per_zoom as u32, images),
            );
        }
        Ok(())
    }
}
