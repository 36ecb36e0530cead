//! The fixed-point blend of moved voxels into world voxels ([`blend`]) and the resolve of the
//! sums into octree leaves ([`WorldSums::resolve`]); rules in the [module docs](super).
//!
//! The CPU reference sorts the contributions by the Morton code of their world voxel and sums
//! each run: the sums are integers, so neither the sort's order within a run nor the thread
//! count changes them — the GPU kernel adds the same integers with atomics in any order.

use std::sync::OnceLock;

use glam::{IVec3, UVec3, Vec3};
use rayon::prelude::*;
use voxlod_format::records::AverageRecord;
use voxlod_format::records::quant::{decode_dir, srgb_to_linear};
use voxlod_format::{GridSpec, morton};

use super::transform::{Filter, Placed, quantize_normal};
use crate::payload::AveragePayload;
use crate::{Error, Result};

/// A whole voxel's weight: 64³.
pub const FULL_WEIGHT: u64 = 1 << 18;

/// Most contributions (moved voxels × corners, plus static voxels) one frame may sum: every
/// contribution is below 2³⁸ in magnitude, so the 64-bit sums stay exact.
pub const MAX_CONTRIBUTIONS: u64 = 1 << 24;

/// sRGB8 code → linear colour in 12 bits, `⌊4095·srgb_to_linear(code/255) + ½⌋` (the GPU
/// uploads the same table).
pub fn linear12_table() -> &'static [u32; 256] {
    static TABLE: OnceLock<[u32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| (srgb_to_linear(i as f32 / 255.0) * 4095.0 + 0.5).floor() as u32)
    })
}

/// The exact sums of one world voxel (module docs). 64 bytes, `#[repr(C)]`; the GPU keeps each
/// 64-bit sum as two `u32` words (low, high) with carry, two's complement for the normal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct CellSums {
    /// Covered volume `Σ w`, in 2⁻¹⁸ voxel.
    pub weight: u64,
    /// `Σ w·α` (α unorm8).
    pub alpha: u64,
    /// `Σ w·α·c` per channel (c linear, 12 bits).
    pub color: [u64; 3],
    /// `Σ w·α·n` per axis (n snorm12).
    pub normal: [i64; 3],
}

impl CellSums {
    /// One contribution: weight `w` of a voxel with `record` and the (moved, quantized) `normal`.
    #[inline]
    pub fn contribution(w: u64, record: &AverageRecord, normal: [i32; 3]) -> Self {
        let table = linear12_table();
        let wa = w * record.opacity as u64;
        Self {
            weight: w,
            alpha: wa,
            color: record.color.map(|c| wa * table[c as usize] as u64),
            normal: normal.map(|n| wa as i64 * n as i64),
        }
    }

    /// Adds `o`.
    #[inline]
    pub fn add(&mut self, o: &Self) {
        self.weight += o.weight;
        self.alpha += o.alpha;
        for i in 0..3 {
            self.color[i] += o.color[i];
            self.normal[i] += o.normal[i];
        }
    }

    /// Covered volume in voxels.
    pub fn coverage(&self) -> f64 {
        self.weight as f64 / FULL_WEIGHT as f64
    }

    /// The octree leaf of these sums (module docs): opacity `min(1, A/(255·2¹⁸))`, colour
    /// `C/(4095·A)`, normal `N/|N|`; empty for `A = 0`.
    pub fn payload(&self) -> AveragePayload {
        if self.alpha == 0 {
            return AveragePayload::default();
        }
        let a = self.alpha as f64;
        let opacity = (a / (255.0 * FULL_WEIGHT as f64)).min(1.0) as f32;
        let color = Vec3::new(
            (self.color[0] as f64 / (4095.0 * a)) as f32,
            (self.color[1] as f64 / (4095.0 * a)) as f32,
            (self.color[2] as f64 / (4095.0 * a)) as f32,
        );
        let n =
            glam::DVec3::new(self.normal[0] as f64, self.normal[1] as f64, self.normal[2] as f64)
                .normalize_or_zero()
                .as_vec3();
        AveragePayload::new(color, n, opacity)
    }
}

/// What a blend did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BlendStats {
    /// Moved voxels given.
    pub voxels: u64,
    /// Contributions with a non-zero weight inside the grid (summed).
    pub contributions: u64,
    /// Voxels not placed at all ([`Placed::OUTSIDE`]: object outside, non-finite or huge).
    pub outside_voxels: u64,
    /// Contributions with a non-zero weight that fell outside the grid (not written).
    pub clipped_contributions: u64,
    /// Their weight, in 2⁻¹⁸ voxel (outside voxels count a whole voxel each).
    pub clipped_weight: u64,
}

impl BlendStats {
    fn add(&mut self, o: &Self) {
        self.voxels += o.voxels;
        self.contributions += o.contributions;
        self.outside_voxels += o.outside_voxels;
        self.clipped_contributions += o.clipped_contributions;
        self.clipped_weight += o.clipped_weight;
    }
}

/// World voxels with their sums, in strictly increasing Morton order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WorldSums {
    /// Morton codes of the world voxels.
    pub codes: Vec<u64>,
    /// Their sums.
    pub sums: Vec<CellSums>,
}

/// One object's moved voxels and their records (same length and order).
#[derive(Clone, Copy, Debug)]
pub struct BlendInput<'a> {
    /// Output of the transform.
    pub placed: &'a [Placed],
    /// The cache's records.
    pub records: &'a [AverageRecord],
}

/// The world voxel of corner `k` of a placed voxel and its weight (0: no contribution).
#[inline]
pub fn corner(p: &Placed, k: u32, filter: Filter) -> (IVec3, u64) {
    let base = IVec3::from_array(p.cell);
    match filter {
        Filter::Nearest => (base, FULL_WEIGHT),
        Filter::EightNeighbour => {
            let f = p.fractions();
            let mut w = 1u64;
            let mut off = IVec3::ZERO;
            for a in 0..3 {
                let up = (k >> a) & 1 == 1;
                w *= if up { f[a] as u64 } else { 64 - f[a] as u64 };
                off[a] = up as i32;
            }
            (base + off, w)
        }
    }
}

/// The Morton code of `c` if it lies in a grid of `dims`.
#[inline]
fn code_in(c: IVec3, dims: UVec3) -> Option<u64> {
    (c.cmpge(IVec3::ZERO).all() && c.as_uvec3().cmplt(dims).all())
        .then(|| morton::encode(c.as_uvec3()))
}

/// Blends every input's moved voxels into the world voxels of `grid` (module docs). Errors:
/// an input whose placed and record arrays differ in length, or more than
/// [`MAX_CONTRIBUTIONS`] contributions (`extra` counts contributions that will be merged in
/// later, such as static voxels).
pub fn blend(
    grid: &GridSpec,
    inputs: &[BlendInput],
    filter: Filter,
    extra: u64,
) -> Result<(WorldSums, BlendStats)> {
    grid.validate()?;
    let corners = filter.corners() as u64;
    let mut offsets = vec![0u64];
    for (i, input) in inputs.iter().enumerate() {
        if input.placed.len() != input.records.len() {
            return Err(Error::InvalidParameter {
                name: "blend input",
                value: format!(
                    "input {i}: {} placed voxels, {} records",
                    input.placed.len(),
                    input.records.len()
                ),
                reason: "one record per placed voxel",
            });
        }
        offsets.push(offsets[i] + input.placed.len() as u64);
    }
    let voxels = *offsets.last().unwrap_or(&0);
    let contributions = voxels * corners + extra;
    if contributions > MAX_CONTRIBUTIONS {
        return Err(Error::FrameTooLarge { contributions, max: MAX_CONTRIBUTIONS });
    }
    let dims = grid.dims;
    // (world voxel code, global voxel index, weight) per contribution inside the grid.
    let mut keyed: Vec<(u64, u32, u32)> = Vec::new();
    let mut stats = BlendStats { voxels, ..Default::default() };
    for (i, input) in inputs.iter().enumerate() {
        let first = offsets[i] as u32;
        let (mut part, s): (Vec<(u64, u32, u32)>, BlendStats) = input
            .placed
            .par_iter()
            .enumerate()
            .with_min_len(2048)
            .fold(
                || (Vec::new(), BlendStats::default()),
                |(mut out, mut s), (v, p)| {
                    if p.status != Placed::INSIDE {
                        s.outside_voxels += 1;
                        s.clipped_weight += FULL_WEIGHT;
                        return (out, s);
                    }
                    for k in 0..filter.corners() {
                        let (c, w) = corner(p, k, filter);
                        if w == 0 {
                            continue;
                        }
                        match code_in(c, dims) {
                            Some(code) => out.push((code, first + v as u32, w as u32)),
                            None => {
                                s.clipped_contributions += 1;
                                s.clipped_weight += w;
                            }
                        }
                    }
                    (out, s)
                },
            )
            .reduce(
                || (Vec::new(), BlendStats::default()),
                |(mut a, mut sa), (b, sb)| {
                    a.extend_from_slice(&b);
                    sa.add(&sb);
                    (a, sa)
                },
            );
        keyed.append(&mut part);
        stats.add(&s);
    }
    stats.voxels = voxels;
    stats.contributions = keyed.len() as u64;
    keyed.par_sort_unstable_by_key(|k| k.0);
    // Runs of equal codes.
    let starts: Vec<usize> = (0..keyed.len())
        .into_par_iter()
        .with_min_len(8192)
        .filter(|&i| i == 0 || keyed[i].0 != keyed[i - 1].0)
        .collect();
    let lookup = |g: u32| {
        let i = offsets.partition_point(|&o| o <= g as u64) - 1;
        let local = g as usize - offsets[i] as usize;
        (&inputs[i].placed[local], &inputs[i].records[local])
    };
    let (codes, sums): (Vec<u64>, Vec<CellSums>) = starts
        .par_iter()
        .enumerate()
        .with_min_len(1024)
        .map(|(r, &s)| {
            let end = starts.get(r + 1).copied().unwrap_or(keyed.len());
            let mut sum = CellSums::default();
            for &(_, g, w) in &keyed[s..end] {
                let (p, record) = lookup(g);
                sum.add(&CellSums::contribution(w as u64, record, p.normal));
            }
            (keyed[s].0, sum)
        })
        .unzip();
    Ok((WorldSums { codes, sums }, stats))
}

impl WorldSums {
    /// Static voxels: each record a whole voxel's weight at its own world voxel, its normal
    /// quantized as a moved one would be. Voxels outside `grid` are an error naming them; a
    /// voxel given twice adds up.
    pub fn from_static(
        grid: &GridSpec,
        voxels: impl IntoIterator<Item = (UVec3, AverageRecord)>,
    ) -> Result<Self> {
        let mut keyed: Vec<(u64, CellSums)> = Vec::new();
        for (c, r) in voxels {
            if !c.cmplt(grid.dims).all() {
                return Err(Error::OutOfBounds { coord: c, dims: grid.dims });
            }
            let n = decode_dir(r.normal).to_array();
            keyed.push((
                morton::encode(c),
                CellSums::contribution(FULL_WEIGHT, &r, quantize_normal(n)),
            ));
        }
        keyed.par_sort_unstable_by_key(|k| k.0);
        let mut out = Self::default();
        for (code, s) in keyed {
            match out.codes.last() {
                Some(&last) if last == code => out.sums.last_mut().expect("same length").add(&s),
                _ => {
                    out.codes.push(code);
                    out.sums.push(s);
                }
            }
        }
        Ok(out)
    }

    /// World voxels held.
    pub fn len(&self) -> usize {
        self.codes.len()
    }

    /// Whether no world voxel is held.
    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    /// Heap bytes.
    pub fn memory_bytes(&self) -> usize {
        self.codes.capacity() * 8 + self.sums.capacity() * size_of::<CellSums>()
    }

    /// The sums of both, voxel by voxel (a linear merge of the two Morton orders).
    pub fn merge(&self, other: &Self) -> Self {
        let (a, b) = (self, other);
        let mut out = Self {
            codes: Vec::with_capacity(a.len() + b.len()),
            sums: Vec::with_capacity(a.len() + b.len()),
        };
        let (mut i, mut j) = (0, 0);
        while i < a.len() || j < b.len() {
            let take_a = j == b.len() || (i < a.len() && a.codes[i] <= b.codes[j]);
            let take_b = i == a.len() || (j < b.len() && b.codes[j] <= a.codes[i]);
            let mut s = CellSums::default();
            let code = if take_a { a.codes[i] } else { b.codes[j] };
            if take_a {
                s.add(&a.sums[i]);
                i += 1;
            }
            if take_b {
                s.add(&b.sums[j]);
                j += 1;
            }
            out.codes.push(code);
            out.sums.push(s);
        }
        out
    }

    /// The occupied world voxels (module docs: covered volume ≥ `threshold` voxels and not
    /// transparent) with their leaf payloads, in Morton order — the input of
    /// [`crate::Octree::from_morton_sorted`] — and how many voxels the threshold dropped.
    pub fn resolve(&self, threshold: f32) -> Result<(Vec<(u64, AveragePayload)>, u64)> {
        if !(threshold.is_finite() && (0.0..=8.0).contains(&threshold)) {
            return Err(Error::InvalidParameter {
                name: "occupancy_threshold",
                value: threshold.to_string(),
                reason: "a covered volume in [0, 8] voxels",
            });
        }
        let min = (threshold as f64 * FULL_WEIGHT as f64).ceil() as u64;
        let leaves: Vec<(u64, AveragePayload)> = self
            .codes
            .par_iter()
            .zip(&self.sums)
            .with_min_len(4096)
            .filter(|(_, s)| s.weight >= min.max(1) && s.alpha > 0)
            .map(|(&c, s)| (c, s.payload()))
            .collect();
        let dropped = self.len() as u64 - leaves.len() as u64;
        Ok((leaves, dropped))
    }
}
