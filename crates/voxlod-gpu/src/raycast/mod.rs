//! Closest-hit ray casting on the GPU through the CPU-built BVH, the mirror of
//! [`voxlod_cpu::raycast::Bvh::intersect`].
//!
//! # Layout
//! The BVH is voxlod-cpu's: obvhs's compressed wide BVH8 ([`Bvh::cwbvh`]), built on the host
//! (so a geometry the CPU refuses — non-finite vertex, index out of range, a tree deeper than
//! the 32-entry stack — is refused here with the same error). Its nodes are uploaded with the
//! child boxes decompressed to `f32` planes rounded outward, exactly as the CPU traverses them
//! ([`GpuNode`], 224 bytes), and the triangles in BVH order with their original ids
//! ([`GpuTri`], 48 bytes).
//!
//! # Kernel (what a real GPU sees)
//! One invocation per ray, workgroups of 64; a stackful loop (32 entries of `vec2<u32>` in
//! private memory, nearest child first, the CWBVH's octant-ordered hit masks) and the
//! watertight ray/triangle test, with the CPU's tie rule (equal `t`: the lowest triangle id).
//! Coherent primary rays keep neighbouring invocations on the same nodes, so node loads are
//! mostly shared in cache; divergence grows with incoherent rays, as for any wide-BVH
//! traversal, and a real GPU would add a ray-sorting or persistent-thread scheme there.
//!
//! # Agreement with the CPU (the equivalence suite's bound)
//! Identical traversal and tests, but WGSL's `1.0 / det` is only accurate to 2.5 ULP (the
//! CPU's division is exact) and a shader compiler may fuse `a·b − c·d` into an FMA (naga
//! does not mark operations `NoContraction`), so `t`, `u`, `v` may differ by a few ULP, and a
//! ray within a few ULP of an edge, or two triangles whose hits are within a few ULP, may pick
//! a different triangle. The suite bounds the `t` error relatively and allows a different
//! triangle or hit/miss only at such near ties.

use glam::Vec3;
use voxlod_cpu::raycast::{Bvh, Hit};
use voxlod_scene::Geometry;
use voxlod_scene::camera::CameraFrame;

use crate::{Context, Result};

/// The WGSL source of the kernel: the shared traversal (`bvh.wgsl`, also used by the
/// ground-truth kernel) followed by the entry point.
pub const WGSL: &str = concat!(include_str!("../bvh.wgsl"), include_str!("raycast.wgsl"));

/// The WGSL of the BVH traversal alone (structs `Node`, `Tri`, `Hit`, bindings 1 and 2, and
/// `fn trace(origin, dir, t_min, t_max, any_hit) -> Hit`), for kernels that cast rays.
pub const BVH_WGSL: &str = include_str!("../bvh.wgsl");

/// Rays per dispatch (a bound on a dispatch's duration on real GPUs).
pub const RAYS_PER_DISPATCH: u64 = 1 << 22;

/// Triangle id of a miss in [`GpuHit`].
pub const MISS: u32 = u32::MAX;

/// A CWBVH node with `f32` child planes (mirrors WGSL `Node`).
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuNode {
    /// `planes[2·axis + (0 = min, 1 = max)]` for children 0..4, then the same for 4..8.
    pub planes: [[f32; 4]; 12],
    /// obvhs `child_meta` bytes 0..4 (little-endian).
    pub meta_lo: u32,
    /// `child_meta` bytes 4..8.
    pub meta_hi: u32,
    /// Which children are inner nodes.
    pub imask: u32,
    /// Index of the first child node.
    pub child_base: u32,
    /// Index of the first primitive of the leaf children.
    pub primitive_base: u32,
    /// Padding to 16-byte alignment.
    pub pad: [u32; 3],
}

/// A triangle in BVH order (mirrors WGSL `Tri`); `v0[3]` holds the original triangle id's bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuTri {
    /// Vertex 0; `w` = triangle id (as `f32` bits).
    pub v0: [f32; 4],
    /// Vertex 1.
    pub v1: [f32; 4],
    /// Vertex 2.
    pub v2: [f32; 4],
}

/// A ray (mirrors WGSL `Ray`): `origin[3]` = `t_min`, `dir[3]` = `t_max`.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuRay {
    /// Origin; `w` = `t_min`.
    pub origin: [f32; 4],
    /// Direction; `w` = `t_max`.
    pub dir: [f32; 4],
}

impl GpuRay {
    /// A ray with the CPU's rules ([`Bvh::intersect`]): `t_min` below 0 counts as 0; a
    /// non-finite or zero origin/direction, a NaN bound or `t_min > t_max` gives a ray that
    /// misses (decided here, on the host: shader compilers may assume no NaN).
    pub fn new(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        let valid = origin.is_finite()
            && dir.is_finite()
            && dir != Vec3::ZERO
            && !t_min.is_nan()
            && !t_max.is_nan();
        let t_min = t_min.max(0.0);
        let (t_min, t_max) = if valid && t_min <= t_max { (t_min, t_max) } else { (1.0, -1.0) };
        let o = if valid { origin } else { Vec3::ZERO };
        let d = if valid { dir } else { Vec3::Z };
        Self { origin: [o.x, o.y, o.z, t_min], dir: [d.x, d.y, d.z, t_max] }
    }
}

/// A hit as the kernel writes it (mirrors WGSL `Hit`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuHit {
    /// Ray parameter.
    pub t: f32,
    /// Original triangle id, or [`MISS`].
    pub triangle: u32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
}

impl GpuHit {
    /// As the CPU's [`Hit`].
    pub fn hit(&self) -> Option<Hit> {
        (self.triangle != MISS).then_some(Hit {
            t: self.t,
            triangle: self.triangle,
            u: self.u,
            v: self.v,
        })
    }
}

/// The kernel's parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuRaycastParams {
    /// `x` = rays, `y` = nodes.
    pub counts: [u32; 4],
}

/// `x` rounded to an `f32` no greater (`up = false`) or no less (`up = true`) than it.
fn round_outward(x: f64, up: bool) -> f32 {
    let f = x as f32;
    match (up, (f as f64).partial_cmp(&x)) {
        (false, Some(std::cmp::Ordering::Greater)) => f.next_down(),
        (true, Some(std::cmp::Ordering::Less)) => f.next_up(),
        _ => f,
    }
}

/// The nodes of `bvh` in the GPU layout: child boxes decompressed to `f32` exactly as
/// voxlod-cpu's traversal decompresses them (empty slots get inverted boxes).
pub fn gpu_nodes(bvh: &Bvh) -> Vec<GpuNode> {
    bvh.cwbvh()
        .nodes
        .iter()
        .map(|n| {
            let q = [
                &n.child_min_x,
                &n.child_max_x,
                &n.child_min_y,
                &n.child_max_y,
                &n.child_min_z,
                &n.child_max_z,
            ];
            let mut planes = [[0f32; 4]; 12];
            for (k, q) in q.iter().enumerate() {
                let axis = k / 2;
                let scale = f32::from_bits((n.e[axis] as u32) << 23) as f64;
                for child in 0..8 {
                    planes[2 * k + child / 4][child % 4] = if n.child_meta[child] == 0 {
                        if k % 2 == 0 { f32::INFINITY } else { f32::NEG_INFINITY }
                    } else {
                        let exact = n.p[axis] as f64 + q[child] as f64 * scale;
                        round_outward(exact, k % 2 == 1)
                    };
                }
            }
            let meta = n.child_meta;
            GpuNode {
                planes,
                meta_lo: u32::from_le_bytes([meta[0], meta[1], meta[2], meta[3]]),
                meta_hi: u32::from_le_bytes([meta[4], meta[5], meta[6], meta[7]]),
                imask: n.imask as u32,
                child_base: n.child_base_idx,
                primitive_base: n.primitive_base_idx,
                pad: [0; 3],
            }
        })
        .collect()
}

/// The triangles of `geometry` in the BVH's primitive order, with their ids.
pub fn gpu_tris(bvh: &Bvh, geometry: &Geometry) -> Vec<GpuTri> {
    bvh.cwbvh()
        .primitive_indices
        .iter()
        .map(|&id| {
            let [a, b, c] = geometry.triangle(id as usize);
            GpuTri {
                v0: [a.x, a.y, a.z, f32::from_bits(id)],
                v1: [b.x, b.y, b.z, 0.0],
                v2: [c.x, c.y, c.z, 0.0],
            }
        })
        .collect()
}

/// Primary rays through the pixel centres of `frame`, row by row from the top-left (the
/// direction is [`CameraFrame::ray_dir`], as on the CPU), `t` in `[0, ∞)`.
pub fn primary_rays(frame: &CameraFrame) -> Vec<GpuRay> {
    let mut rays = Vec::with_capacity(frame.width as usize * frame.height as usize);
    for y in 0..frame.height {
        for x in 0..frame.width {
            let d = frame.ray_dir(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            rays.push(GpuRay::new(frame.eye, d, 0.0, f32::INFINITY));
        }
    }
    rays
}

/// A BVH uploaded to one device.
pub struct GpuBvh {
    pub(crate) nodes: wgpu::Buffer,
    pub(crate) tris: wgpu::Buffer,
    node_count: u32,
}

/// Uploads `bvh`, built from `geometry`, to `ctx`'s device (checked against the buffer
/// limits); an error if `bvh` was built from another geometry.
pub fn upload_bvh(ctx: &Context, bvh: &Bvh, geometry: &Geometry) -> Result<GpuBvh> {
    if bvh.triangle_count() != geometry.triangle_count() {
        return Err(voxlod_cpu::Error::InvalidParameter {
            name: "bvh",
            value: format!("{} triangles", bvh.triangle_count()),
            reason: format!(
                "built from another geometry (this one has {} triangles)",
                geometry.triangle_count()
            ),
        }
        .into());
    }
    let nodes = gpu_nodes(bvh);
    let tris = gpu_tris(bvh, geometry);
    Ok(GpuBvh {
        nodes: ctx.storage_init("BVH nodes", bytemuck::cast_slice(&nodes))?,
        tris: ctx.storage_init("BVH triangles", bytemuck::cast_slice(&tris))?,
        node_count: nodes.len() as u32,
    })
}

/// The ray casting kernel, compiled for one [`Context`].
pub struct RayCaster<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
}

impl<'a> RayCaster<'a> {
    /// Compiles the kernel.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self { ctx, pipeline: ctx.pipeline("raycast", WGSL)? })
    }

    /// Uploads `bvh`, built from `geometry` (see [`upload_bvh`]).
    pub fn upload(&self, bvh: &Bvh, geometry: &Geometry) -> Result<GpuBvh> {
        upload_bvh(self.ctx, bvh, geometry)
    }

    /// Closest hits of `rays` (in order), in dispatches of at most [`RAYS_PER_DISPATCH`].
    pub fn intersect(&self, bvh: &GpuBvh, rays: &[GpuRay]) -> Result<Vec<GpuHit>> {
        let ctx = self.ctx;
        let binding = ctx.limits().max_storage_buffer_binding_size;
        let per = (binding / size_of::<GpuRay>() as u64).clamp(1, RAYS_PER_DISPATCH) as usize;
        let mut out = Vec::with_capacity(rays.len());
        for chunk in rays.chunks(per) {
            let n = chunk.len() as u64;
            let params = GpuRaycastParams { counts: [chunk.len() as u32, bvh.node_count, 0, 0] };
            let uniform = ctx.uniform("raycast params", bytemuck::bytes_of(&params))?;
            let ray_buf = ctx.storage_init("rays", bytemuck::cast_slice(chunk))?;
            let hit_bytes = n * size_of::<GpuHit>() as u64;
            let hits = ctx.storage_zeroed("hits", hit_bytes)?;
            let (x, y) = ctx.dispatch_size("raycast workgroups", n.div_ceil(64))?;
            let buffers = [&uniform, &bvh.nodes, &bvh.tris, &ray_buf, &hits];
            ctx.dispatch("casting rays", &self.pipeline, &buffers, (x, y))?;
            out.extend_from_slice(bytemuck::cast_slice(&ctx.read(&hits, hit_bytes)?));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn raycast_types_mirror_their_wgsl() {
        assert_mirrors(
            WGSL,
            "Node",
            size_of::<GpuNode>(),
            &[
                ("planes", offset_of!(GpuNode, planes)),
                ("meta_lo", offset_of!(GpuNode, meta_lo)),
                ("meta_hi", offset_of!(GpuNode, meta_hi)),
                ("imask", offset_of!(GpuNode, imask)),
                ("child_base", offset_of!(GpuNode, child_base)),
                ("primitive_base", offset_of!(GpuNode, primitive_base)),
                ("pad0", offset_of!(GpuNode, pad)),
                ("pad1", offset_of!(GpuNode, pad) + 4),
                ("pad2", offset_of!(GpuNode, pad) + 8),
            ],
        );
        assert_mirrors(
            WGSL,
            "Tri",
            size_of::<GpuTri>(),
            &[
                ("v0", offset_of!(GpuTri, v0)),
                ("v1", offset_of!(GpuTri, v1)),
                ("v2", offset_of!(GpuTri, v2)),
            ],
        );
        assert_mirrors(
            WGSL,
            "Ray",
            size_of::<GpuRay>(),
            &[("origin", offset_of!(GpuRay, origin)), ("dir", offset_of!(GpuRay, dir))],
        );
        assert_mirrors(
            WGSL,
            "Hit",
            size_of::<GpuHit>(),
            &[
                ("t", offset_of!(GpuHit, t)),
                ("triangle", offset_of!(GpuHit, triangle)),
                ("u", offset_of!(GpuHit, u)),
                ("v", offset_of!(GpuHit, v)),
            ],
        );
        assert_mirrors(
            WGSL,
            "Params",
            size_of::<GpuRaycastParams>(),
            &[("counts", offset_of!(GpuRaycastParams, counts))],
        );
    }

    #[test]
    fn invalid_rays_are_encoded_as_misses_on_the_host() {
        let ok = GpuRay::new(Vec3::ZERO, Vec3::X, -3.0, 5.0);
        assert_eq!((ok.origin[3], ok.dir[3]), (0.0, 5.0));
        for bad in [
            GpuRay::new(Vec3::splat(f32::NAN), Vec3::X, 0.0, 1.0),
            GpuRay::new(Vec3::ZERO, Vec3::ZERO, 0.0, 1.0),
            GpuRay::new(Vec3::ZERO, Vec3::X, f32::NAN, 1.0),
            GpuRay::new(Vec3::ZERO, Vec3::X, 2.0, 1.0),
        ] {
            assert!(bad.origin[3] > bad.dir[3], "{bad:?}");
        }
    }

    #[test]
    fn nodes_decompress_conservatively() {
        let geometry = Geometry {
            positions: vec![
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(1.7, 0.2, 0.3),
                Vec3::new(0.1, 2.9, -0.4),
                Vec3::new(-1.0, 5.0, 2.0),
            ],
            indices: vec![[0, 1, 2], [1, 2, 3]],
            ..Default::default()
        };
        let bvh = Bvh::new(&geometry).unwrap();
        let nodes = gpu_nodes(&bvh);
        assert!(!nodes.is_empty());
        let tris = gpu_tris(&bvh, &geometry);
        let mut ids: Vec<u32> = tris.iter().map(|t| t.v0[3].to_bits()).collect();
        ids.sort();
        ids.dedup();
        assert_eq!(ids, vec![0, 1]);
        // The root's occupied children contain every vertex of the scene.
        let root = &nodes[0];
        let (lo, hi) = geometry.bounds().unwrap();
        let mut min = Vec3::INFINITY;
        let mut max = Vec3::NEG_INFINITY;
        for c in 0..8 {
            if (if c < 4 { root.meta_lo } else { root.meta_hi }) >> (8 * (c % 4)) & 0xff == 0 {
                continue;
            }
            let p = |k: usize| root.planes[2 * k + c / 4][c % 4];
            min = min.min(Vec3::new(p(0), p(2), p(4)));
            max = max.max(Vec3::new(p(1), p(3), p(5)));
        }
        assert!(min.cmple(lo).all() && max.cmpge(hi).all(), "{min} {max} vs {lo} {hi}");
    }
}
