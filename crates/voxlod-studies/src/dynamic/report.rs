//! The dynamic study's tables and report section (text, images, plots).

use voxlod_eval::report::{
    Cell, Column, ImageGrid, LabeledImage, NumberFormat, Plot, Report, Series, Table,
};

use super::{DynamicResult, ScalingRow};
use crate::Error;

fn num(name: &str, f: NumberFormat) -> Column {
    Column::number(name, f)
}

fn spread_cell(s: &crate::Spread) -> Cell {
    Cell::Text(s.display(if s.mean < 10.0 { 2 } else { 0 }))
}

impl DynamicResult {
    /// The study's tables: caches, agreement, images, rotations, stability, scaling, frames.
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        let mut out = Vec::new();
        let mut t = Table::new(
            "voxel caches (built once per object)",
            vec![
                Column::text("object"),
                Column::text("kind"),
                Column::text("voxelizer"),
                num("voxels", NumberFormat::Integer),
                Column::text("grid"),
                num("bytes/voxel", NumberFormat::Integer),
                num("build ms", NumberFormat::Significant(3)),
            ],
        );
        for r in &self.caches {
            t.push_row(vec![
                Cell::Text(r.object.clone()),
                Cell::Text(r.kind.clone()),
                Cell::Text(r.voxelizer.clone()),
                Cell::Number(r.voxels as f64),
                Cell::Text(format!("{}×{}×{}", r.grid[0], r.grid[1], r.grid[2])),
                Cell::Number(r.bytes_per_voxel as f64),
                Cell::Number(r.build_ms),
            ])?;
        }
        out.push(t);
        let mut t = Table::new(
            "occupancy and colour against re-voxelizing the posed meshes",
            vec![
                num("t (s)", NumberFormat::Fixed(2)),
                Column::text("objects"),
                Column::text("voxelizer"),
                Column::text("filter"),
                num("threshold", NumberFormat::Fixed(2)),
                num("ref voxels", NumberFormat::Integer),
                num("IoU", NumberFormat::Fixed(3)),
                num("missing", NumberFormat::Fixed(3)),
                num("extra", NumberFormat::Fixed(3)),
                num("colour err", NumberFormat::Significant(3)),
            ],
        );
        for r in &self.agreement {
            t.push_row(vec![
                Cell::Number(r.time_s as f64),
                Cell::Text(r.objects.clone()),
                Cell::Text(r.voxelizer.clone()),
                Cell::Text(r.filter.clone()),
                Cell::Number(r.threshold as f64),
                Cell::Number(r.reference_voxels as f64),
                Cell::Number(r.iou),
                Cell::Number(r.missing_fraction),
                Cell::Number(r.extra_fraction),
                Cell::Number(r.colour_error),
            ])?;
        }
        out.push(t);
        let mut t = Table::new(
            "cone-traced AO and indirect light against the ray-traced posed mesh and the re-voxelized octree",
            vec![
                num("t (s)", NumberFormat::Fixed(2)),
                Column::text("voxelizer"),
                Column::text("method"),
                num("AO MSE", NumberFormat::Significant(3)),
                num("AO SSIM", NumberFormat::Fixed(3)),
                num("indirect MSE", NumberFormat::Significant(3)),
                num("indirect SSIM", NumberFormat::Fixed(3)),
                num("AO MSE vs re-vox.", NumberFormat::Significant(3)),
                num("AO SSIM vs re-vox.", NumberFormat::Fixed(3)),
                num("indirect MSE vs re-vox.", NumberFormat::Significant(3)),
                num("indirect SSIM vs re-vox.", NumberFormat::Fixed(3)),
            ],
        );
        for r in &self.images {
            t.push_row(vec![
                Cell::Number(r.time_s as f64),
                Cell::Text(r.voxelizer.clone()),
                Cell::Text(r.method.clone()),
                Cell::Number(r.ao_mse),
                Cell::Number(r.ao_ssim),
                Cell::Number(r.indirect_mse),
                Cell::Number(r.indirect_ssim),
                Cell::Number(r.ao_mse_revoxelized),
                Cell::Number(r.ao_ssim_revoxelized),
                Cell::Number(r.indirect_mse_revoxelized),
                Cell::Number(r.indirect_ssim_revoxelized),
            ])?;
        }
        out.push(t);
        if !self.rotations.is_empty() {
            let mut t = Table::new(
                "a rigid object turned in place: occupancy against its re-voxelization",
                vec![
                    Column::text("rotation"),
                    Column::text("voxelizer"),
                    Column::text("filter"),
                    num("ref voxels", NumberFormat::Integer),
                    num("IoU", NumberFormat::Fixed(3)),
                    num("missing", NumberFormat::Fixed(3)),
                    num("extra", NumberFormat::Fixed(3)),
                ],
            );
            for r in &self.rotations {
                t.push_row(vec![
                    Cell::Text(r.rotation.clone()),
                    Cell::Text(r.voxelizer.clone()),
                    Cell::Text(r.filter.clone()),
                    Cell::Number(r.reference_voxels as f64),
                    Cell::Number(r.iou),
                    Cell::Number(r.missing_fraction),
                    Cell::Number(r.extra_fraction),
                ])?;
            }
            out.push(t);
        }
        if !self.stability.is_empty() {
            let mut t = Table::new(
                "temporal stability: AO change between consecutive frames of a slowly moving object",
                vec![
                    Column::text("voxelizer"),
                    Column::text("method"),
                    num("frames", NumberFormat::Integer),
                    num("mean change", NumberFormat::Significant(3)),
                    num("max change", NumberFormat::Significant(3)),
                ],
            );
            for r in &self.stability {
                t.push_row(vec![
                    Cell::Text(r.voxelizer.clone()),
                    Cell::Text(r.method.clone()),
                    Cell::Number(r.frames as f64),
                    Cell::Number(r.mean_change),
                    Cell::Number(r.max_change),
                ])?;
            }
            out.push(t);
        }
        if !self.scaling.is_empty() {
            let gpu = self.scaling.iter().any(|r| r.frame_gpu_ms.is_some());
            let mut cols = vec![
                num("walkers", NumberFormat::Integer),
                num("objects", NumberFormat::Integer),
                num("triangles", NumberFormat::Integer),
                num("cached voxels", NumberFormat::Integer),
                Column::text("transform ms"),
                Column::text("blend ms"),
                Column::text("pose ms"),
                Column::text("voxelize cons. ms"),
                Column::text("voxelize thin ms"),
                Column::text("frame (transform) ms"),
                Column::text("frame (voxelize) ms"),
            ];
            if gpu {
                cols.push(Column::text("frame on GPU ms"));
            }
            cols.extend([
                num("peak MB (transform)", NumberFormat::Fixed(1)),
                num("peak MB (voxelize)", NumberFormat::Fixed(1)),
                num("transient MB", NumberFormat::Fixed(1)),
                num("cache MB", NumberFormat::Fixed(2)),
            ]);
            let mut t = Table::new(
                "time per frame against object count (mean and range of the runs)",
                cols,
            );
            let mb =
                |b: Option<u64>| b.map_or(Cell::Text("-".into()), |b| Cell::Number(b as f64 / 1e6));
            for r in &self.scaling {
                let mut cells = vec![
                    Cell::Number(r.walkers as f64),
                    Cell::Number(r.objects as f64),
                    Cell::Number(r.moving_triangles as f64),
                    Cell::Number(r.cached_voxels as f64),
                    spread_cell(&r.transform_ms),
                    spread_cell(&r.blend_ms),
                    spread_cell(&r.pose_ms),
                    spread_cell(&r.voxelize_conservative_ms),
                    spread_cell(&r.voxelize_thin_ms),
                    spread_cell(&r.frame_transform_ms),
                    spread_cell(&r.frame_voxelize_ms),
                ];
                if gpu {
                    cells.push(r.frame_gpu_ms.as_ref().map_or(Cell::Text("-".into()), spread_cell));
                }
                cells.extend([
                    mb(r.frame_transform_peak_bytes),
                    mb(r.frame_voxelize_peak_bytes),
                    Cell::Number(r.transient_bytes as f64 / 1e6),
                    Cell::Number(r.cache_bytes as f64 / 1e6),
                ]);
                t.push_row(cells)?;
            }
            out.push(t);
        }
        if !self.frames.is_empty() {
            let mut t = Table::new(
                format!("frames through the pipeline ({})", self.backend),
                vec![
                    num("frame", NumberFormat::Integer),
                    num("t (s)", NumberFormat::Fixed(2)),
                    num("leaves", NumberFormat::Integer),
                    num("transform ms", NumberFormat::Significant(3)),
                    num("blend ms", NumberFormat::Significant(3)),
                    num("octree ms", NumberFormat::Significant(3)),
                    num("inject ms", NumberFormat::Significant(3)),
                    num("trace ms", NumberFormat::Significant(3)),
                    num("frame ms", NumberFormat::Significant(3)),
                ],
            );
            for r in &self.frames {
                t.push_row(
                    [
                        r.frame as f64,
                        r.time_s as f64,
                        r.leaves as f64,
                        r.transform_ms,
                        r.blend_ms,
                        r.build_ms,
                        r.inject_ms,
                        r.trace_ms,
                        r.frame_ms,
                    ]
                    .into_iter()
                    .map(Cell::Number)
                    .collect(),
                )?;
            }
            out.push(t);
        }
        Ok(out)
    }

    /// Appends the dynamic-scene section: what was measured, the tables, the time-per-frame
    /// plot and the images.
    pub fn add_to_report(&self, r: &mut Report) -> Result<(), Error> {
        r.heading(2, format!("Dynamic scenes by voxel transformation: {}", self.scene));
        r.text(format!(
            "Measured on {}. World grid {}×{}×{} of {} world units; records: {}. Moving objects are voxelized \
             once into object-space caches and moved every frame (nearest: the world voxel of the \
             moved centre; 8-neighbour: split over the eight around it by the volume each \
             covers, a world voxel occupied when half of it is covered), against re-voxelizing the \
             posed meshes with the same voxelizer. Frames ran on {}. Times are wall-clock \
             on a machine shared with other work (on a CPU adapter such as lavapipe, CPU times \
             of the GPU path).",
            self.machine,
            self.grid[0],
            self.grid[1],
            self.grid[2],
            self.voxel_size as f32,
            self.records,
            self.backend
        ));
        for t in self.tables()? {
            r.table(t);
        }
        if !self.scaling.is_empty() {
            let series = |name: &str, f: &dyn Fn(&ScalingRow) -> Option<f64>| {
                Series::new(
                    name,
                    self.scaling
                        .iter()
                        .filter_map(|x| f(x).map(|y| (x.objects as f64, y)))
                        .collect(),
                )
            };
            let mut all = vec![
                series("transform", &|x| Some(x.transform_ms.mean)),
                series("voxelize (conservative)", &|x| Some(x.voxelize_conservative_ms.mean)),
                series("voxelize (thin)", &|x| Some(x.voxelize_thin_ms.mean)),
                series("frame by transform", &|x| Some(x.frame_transform_ms.mean)),
                series("frame by re-voxelization", &|x| Some(x.frame_voxelize_ms.mean)),
            ];
            if self.scaling.iter().any(|x| x.frame_gpu_ms.is_some()) {
                all.push(series("frame on the GPU backend", &|x| {
                    x.frame_gpu_ms.as_ref().map(|s| s.mean)
                }));
            }
            r.plot(
                "dynamic_time_per_frame",
                Plot {
                    title: "time per frame against moving objects".into(),
                    x_label: "moving objects".into(),
                    y_label: "ms".into(),
                    log_x: true,
                    log_y: true,
                    series: all,
                    ..Plot::default()
                },
            );
        }
        for (i, set) in self.image_sets.iter().enumerate() {
            let images =
                set.images.iter().map(|(l, im)| LabeledImage::new(l.clone(), im.clone())).collect();
            r.images(
                format!("dynamic_ao_{i}"),
                "AO: the ray-traced mesh, then each method's cone-traced octree",
                ImageGrid::new(4, images),
            );
        }
        if !self.frame_images.is_empty() {
            let images = self
                .frame_images
                .iter()
                .flat_map(|(l, ao, e)| {
                    [
                        LabeledImage::new(format!("{l} AO"), ao.clone()),
                        LabeledImage::new(format!("{l} indirect"), e.clone()),
                    ]
                })
                .collect();
            r.images(
                "dynamic_frames",
                format!("frames through the pipeline ({})", self.backend),
                ImageGrid::new(4, images),
            );
        }
        Ok(())
    }
}
