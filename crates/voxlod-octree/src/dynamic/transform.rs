//! The per-voxel transform ([`transform_voxel`]; rules in the [module docs](super)): the CPU
//! reference of voxlod-gpu's transform kernel, in the same `f32` operations and order.

use rayon::prelude::*;
use voxlod_format::records::quant::decode_dir;
use voxlod_format::records::{AverageRecord, VoxelSkin};

use super::cache::{VoxelCache, unpack_position};
use super::place::{Affine, ObjectFrame};

/// How a moved voxel is put into the world grid (the paper's §3.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Filter {
    /// The world voxel containing the moved voxel's centre: one write, holes where two moved
    /// voxels fall into one world voxel.
    Nearest,
    /// Split over the eight world voxels around the moved centre with trilinear weights (the
    /// volume of each it covers): no holes, eight writes.
    #[default]
    EightNeighbour,
}

impl Filter {
    /// `"nearest"` or `"8-neighbour"`.
    pub fn name(self) -> &'static str {
        match self {
            Filter::Nearest => "nearest",
            Filter::EightNeighbour => "8-neighbour",
        }
    }

    /// World voxels one moved voxel writes: 1 or 8.
    pub fn corners(self) -> u32 {
        match self {
            Filter::Nearest => 1,
            Filter::EightNeighbour => 8,
        }
    }
}

/// A moved voxel: where it lands and its moved normal. 32 bytes (`#[repr(C)]`, the WGSL
/// mirror is a struct of the same fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Placed {
    /// Nearest: the world voxel. 8-neighbour: the lower corner of the eight.
    pub cell: [i32; 3],
    /// 8-neighbour fractions in sixty-fourths, `fx | fy << 8 | fz << 16` (each 0 ..= 64);
    /// 0 for nearest.
    pub frac: u32,
    /// The moved normal, snorm12 (`−2047 ..= 2047`), zero for a record without a normal.
    pub normal: [i32; 3],
    /// [`Placed::INSIDE`] or [`Placed::OUTSIDE`].
    pub status: u32,
}

impl Placed {
    /// Placed: `cell` and `frac` are valid (the cells may still lie outside the grid).
    pub const INSIDE: u32 = 0;
    /// Not placed: a non-finite position, one beyond ±2²³ voxels, or an object outside.
    pub const OUTSIDE: u32 = 1;

    /// The fractions per axis.
    pub fn fractions(&self) -> [u32; 3] {
        [self.frac & 0xff, (self.frac >> 8) & 0xff, (self.frac >> 16) & 0xff]
    }
}

/// Beyond this many voxels from the anchor a position is outside (f32 integers are exact below
/// 2²⁴).
const MAX_OFFSET: f32 = (1u32 << 23) as f32;

/// The map a voxel moves by: its object's single matrix, or the blend of its joints' matrices
/// `Σ (w_k/255)·M_k` in slot order from zero (linear blend skinning).
#[inline]
pub fn voxel_matrix(matrices: &[Affine], skin: Option<&VoxelSkin>) -> Affine {
    match skin {
        None => matrices[0],
        Some(s) => {
            let mut m = [0.0f32; 12];
            for k in 0..4 {
                if s.weights[k] == 0 {
                    continue;
                }
                let w = s.weights[k] as f32 / 255.0;
                let j = &matrices[s.joints[k] as usize].m;
                for e in 0..12 {
                    m[e] += w * j[e];
                }
            }
            Affine { m }
        }
    }
}

/// A direction normalized and quantized to snorm12, `⌊2047·n/|n| + ½⌋` per component (zero
/// stays zero).
#[inline]
pub fn quantize_normal(v: [f32; 3]) -> [i32; 3] {
    let len = ((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2]).sqrt();
    if len > 0.0 {
        v.map(|x| ((x / len * 2047.0 + 0.5).floor() as i32).clamp(-2047, 2047))
    } else {
        [0; 3]
    }
}

/// Moves one cached voxel (module docs): `pos` is its packed position, `matrices` and `anchor`
/// its object's frame.
#[inline]
pub fn transform_voxel(
    pos: u32,
    record: &AverageRecord,
    skin: Option<&VoxelSkin>,
    matrices: &[Affine],
    anchor: [i32; 3],
    filter: Filter,
) -> Placed {
    let m = voxel_matrix(matrices, skin).m;
    let i = unpack_position(pos).as_vec3();
    let mut r = [0.0f32; 3];
    for (c, r) in r.iter_mut().enumerate() {
        *r = ((m[c] * i.x + m[3 + c] * i.y) + m[6 + c] * i.z) + m[9 + c];
    }
    if r.iter().any(|x| x.is_nan() || x.abs() >= MAX_OFFSET) {
        return Placed { status: Placed::OUTSIDE, ..Placed::default() };
    }
    let n = decode_dir(record.normal);
    let mut moved = [0.0f32; 3];
    for (c, o) in moved.iter_mut().enumerate() {
        *o = (m[c] * n.x + m[3 + c] * n.y) + m[6 + c] * n.z;
    }
    let normal = quantize_normal(moved);
    let (cell, frac) = match filter {
        Filter::Nearest => (r.map(|x| x.floor() as i32), 0),
        Filter::EightNeighbour => {
            let mut cell = [0i32; 3];
            let mut frac = 0u32;
            for c in 0..3 {
                let q = r[c] - 0.5;
                let fl = q.floor();
                cell[c] = fl as i32;
                let f = ((q - fl) * 64.0 + 0.5).floor() as u32;
                frac |= f.min(64) << (8 * c);
            }
            (cell, frac)
        }
    };
    Placed {
        cell: [cell[0] + anchor[0], cell[1] + anchor[1], cell[2] + anchor[2]],
        frac,
        normal,
        status: Placed::INSIDE,
    }
}

/// Moves every voxel of `cache` by `frame` (in parallel; the result is in the cache's order).
pub fn transform(cache: &VoxelCache, frame: &ObjectFrame, filter: Filter) -> Vec<Placed> {
    if frame.outside {
        return vec![Placed { status: Placed::OUTSIDE, ..Placed::default() }; cache.len()];
    }
    let skins = cache.skin.as_ref().map(|s| &s.voxels[..]);
    (0..cache.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|v| {
            transform_voxel(
                cache.positions[v],
                &cache.records[v],
                skins.map(|s| &s[v]),
                &frame.matrices,
                frame.anchor,
                filter,
            )
        })
        .collect()
}
