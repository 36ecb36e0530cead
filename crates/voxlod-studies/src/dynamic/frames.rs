//! A frame sequence through the pipeline on the chosen backend: at evenly spaced times of the
//! animation, the objects placed, the frame built (transform, blend, octree, injection — on the
//! CPU reference or all on the device) and AO and indirect light cone traced at the posed
//! mesh's G-buffer points; per frame its counts, step times and images.

use std::time::Instant;

use serde::Serialize;
use voxlod_cone::{FramePipeline, RadiancePayload, Shadows, TraceOptions};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_gpu::cone::{ConeQuery, ShadingPoint};
use voxlod_gpu::dynamic::DynamicKernels;
use voxlod_octree::dynamic::FrameOptions;
use voxlod_scene::Srgb8Image;

use super::setup::{Prepared, colour, cone_light, gray, ms, trace_gbuffer};
use crate::Error;
use crate::backend::Backend;

/// One frame of the sequence.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRow {
    /// Frame index.
    pub frame: u32,
    /// Animation time, seconds.
    pub time_s: f32,
    /// Occupied world voxels (octree leaves).
    pub leaves: u64,
    /// Transform (CPU; on the GPU the whole device frame), ms.
    pub transform_ms: f64,
    /// Blend and resolve (CPU), ms.
    pub blend_ms: f64,
    /// Octree build (CPU), ms.
    pub build_ms: f64,
    /// Light injection (CPU), ms.
    pub inject_ms: f64,
    /// Cone tracing AO and `E/π` at the G-buffer's points, ms.
    pub trace_ms: f64,
    /// The whole frame (everything above), ms.
    pub frame_ms: f64,
}

/// The sequence's rows and its images (AO, indirect) per frame.
pub struct Sequence {
    /// Where it ran: `cpu (rayon)` or `gpu: <adapter>`.
    pub backend: String,
    /// One row per frame.
    pub rows: Vec<FrameRow>,
    /// `(label, AO image, indirect image)` per frame.
    pub images: Vec<(String, Srgb8Image, Srgb8Image)>,
}

/// Renders `frames` frames of `p`'s animation at `width` pixels (height ¾ of it) on `backend`.
pub fn run(
    p: &Prepared,
    frames: u32,
    width: u32,
    ao_radius: f32,
    backend: Backend<'_>,
    say: &dyn Fn(&str),
) -> Result<Sequence, Error> {
    let light = cone_light(p.ds.scene.light());
    let options = FrameOptions::default();
    let trace = TraceOptions { ao_radius, ..Default::default() };
    let query = ConeQuery { ambient_occlusion: true, diffuse: true, specular: false };
    let (w, h) = (width, (width * 3 / 4).max(1));
    let d = p.ds.animation.duration();
    let kernels = match backend {
        Backend::Gpu(ctx) => Some(DynamicKernels::new(ctx)?),
        Backend::Cpu => None,
    };
    let uploaded = match &kernels {
        Some(k) => Some(k.upload(&p.world, &p.caches)?),
        None => None,
    };
    let mut pipeline: FramePipeline<RadiancePayload> =
        FramePipeline::new(&p.world, &p.caches, options, light, Shadows::MARCH);
    let (mut rows, mut images) = (Vec::new(), Vec::new());
    for f in 0..frames {
        let time = d * f as f32 / frames.max(1) as f32;
        say(&format!("frame {f} of {frames} (t = {time:.2} s) on {}", backend.describe()));
        let pose = p.ds.pose(time)?;
        let placements = p.ds.placements(&pose)?;
        let posed = p.ds.posed_scene(&pose)?;
        let g = posed.geometry();
        let bvh = Bvh::new(&g)?;
        let camera = posed.default_camera()?;
        let gb = ground_truth::gbuffer(&posed, &g, &bvh, &camera, w, h)?;
        let (row, ao, e) = match (&kernels, &uploaded) {
            (Some(k), Some(up)) => {
                let points = ShadingPoint::from_gbuffer(&gb, camera.eye, 0.5);
                let t = Instant::now();
                let frame =
                    k.frame(up, &p.caches, &placements, &options, &light, &Shadows::MARCH)?;
                let built = ms(t);
                let t = Instant::now();
                let shades = k.trace(&frame, &trace, query, &points, w)?;
                let traced = ms(t);
                let row = FrameRow {
                    frame: f,
                    time_s: time,
                    leaves: frame.leaves.count,
                    transform_ms: built,
                    blend_ms: 0.0,
                    build_ms: 0.0,
                    inject_ms: 0.0,
                    trace_ms: traced,
                    frame_ms: built + traced,
                };
                let ao: Vec<f32> = shades.iter().map(|s| s.ao).collect();
                let e: Vec<_> = shades.iter().map(|s| s.diffuse).collect();
                (row, ao, e)
            }
            _ => {
                let t = Instant::now();
                let (geometry, radiance, report) = pipeline.frame(&placements)?;
                let leaves = geometry.voxel_count();
                let built = ms(t);
                let t = Instant::now();
                let (ao, e) = trace_gbuffer(radiance, &gb, trace)?;
                let traced = ms(t);
                let row = FrameRow {
                    frame: f,
                    time_s: time,
                    leaves,
                    transform_ms: report.transform_ms,
                    blend_ms: report.blend_ms,
                    build_ms: report.build_ms,
                    inject_ms: report.inject_ms,
                    trace_ms: traced,
                    frame_ms: built + traced,
                };
                (row, ao, e)
            }
        };
        images.push((format!("frame {f}"), gray(&gb, &ao), colour(&gb, &e)));
        rows.push(row);
    }
    Ok(Sequence { backend: backend.describe(), rows, images })
}
