//! The 255-colour palette of a `.vox` export: median cut refined by k-means, in sRGB8 space,
//! weighted by how many voxels have each colour.
//!
//! 1. Every distinct sRGB8 colour is counted. If there are at most 255, they are the palette
//!    and quantization is exact.
//! 2. Otherwise, median cut (Heckbert 1982, "Color image quantization for frame buffer
//!    display", SIGGRAPH): starting from one box holding every colour, the box with the largest
//!    weighted sum of squared distances to its mean is split across its axis of largest
//!    variance at the weighted median, until there are 255 boxes (or no box holds two colours);
//!    each box's weighted mean is an entry.
//! 3. Lloyd iterations (k-means) refine the entries: each colour goes to its nearest entry,
//!    each entry moves to the weighted mean of its colours, at most [`LLOYD_ITERATIONS`] times
//!    or until no colour changes entry. An iteration never increases the total squared error
//!    (up to the rounding of the means to bytes).
//!
//! Distances are Euclidean in sRGB8 units, the space the metrics and the records use. Time is
//! `O(distinct colours × 255 × iterations)`, memory `O(distinct colours)`.

use std::collections::HashMap;

/// Most entries of a `.vox` palette (index 0 is the empty voxel).
pub const MAX_COLORS: usize = 255;
/// Most Lloyd iterations after the median cut.
pub const LLOYD_ITERATIONS: usize = 8;

/// A palette and how well it represents the colours it was built from.
#[derive(Clone, Debug, PartialEq)]
pub struct Palette {
    /// The entries, sRGB8; at most [`MAX_COLORS`]. Entry `e` is `.vox` colour index `e + 1`.
    pub colors: Vec<[u8; 3]>,
    /// Entry of each distinct input colour.
    lookup: HashMap<[u8; 3], u8>,
    /// The quantization error.
    pub error: PaletteError,
}

/// Error of a palette over the voxels it was built from, in sRGB8 units (0–255 per channel).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PaletteError {
    /// Distinct colours among the voxels.
    pub distinct_colors: usize,
    /// Root mean square over voxels and channels of (entry − colour).
    pub rms: f64,
    /// Largest absolute channel difference of any voxel.
    pub max: u8,
    /// The root mean square error of the median cut alone, before the Lloyd iterations.
    pub rms_median_cut: f64,
}

impl Palette {
    /// The palette of `colors` (one per voxel; see the [module docs](self)).
    pub fn quantize(colors: impl IntoIterator<Item = [u8; 3]>) -> Self {
        let mut counts: HashMap<[u8; 3], u64> = HashMap::new();
        for c in colors {
            *counts.entry(c).or_default() += 1;
        }
        let mut distinct: Vec<([u8; 3], u64)> = counts.into_iter().collect();
        distinct.sort_unstable();
        let entries: Vec<[f64; 3]> = if distinct.len() <= MAX_COLORS {
            distinct.iter().map(|(c, _)| c.map(f64::from)).collect()
        } else {
            median_cut(&distinct)
        };
        let mut palette: Vec<[u8; 3]> = entries.iter().map(|e| e.map(round_byte)).collect();
        let rms_median_cut = error(&distinct, &palette, &assign(&distinct, &palette)).0;
        if distinct.len() > MAX_COLORS {
            let mut assigned = assign(&distinct, &palette);
            for _ in 0..LLOYD_ITERATIONS {
                let means = weighted_means(&distinct, &assigned, palette.len());
                for (p, m) in palette.iter_mut().zip(means) {
                    if let Some(m) = m {
                        *p = m.map(round_byte);
                    }
                }
                let next = assign(&distinct, &palette);
                if next == assigned {
                    break;
                }
                assigned = next;
            }
        }
        let assigned = assign(&distinct, &palette);
        let (rms, max) = error(&distinct, &palette, &assigned);
        let lookup = distinct.iter().zip(&assigned).map(|((c, _), &e)| (*c, e as u8)).collect();
        let error = PaletteError { distinct_colors: distinct.len(), rms, max, rms_median_cut };
        Self { colors: palette, lookup, error }
    }

    /// The `.vox` colour index (1–255) of a colour the palette was built from, or of its nearest
    /// entry for any other colour.
    pub fn index_of(&self, c: [u8; 3]) -> u8 {
        let entry = match self.lookup.get(&c) {
            Some(&e) => e as usize,
            None => nearest(&self.colors, c.map(f64::from)),
        };
        entry as u8 + 1
    }
}

fn round_byte(x: f64) -> u8 {
    x.round().clamp(0.0, 255.0) as u8
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum()
}

fn nearest(palette: &[[u8; 3]], c: [f64; 3]) -> usize {
    let mut best = (f64::INFINITY, 0);
    for (i, p) in palette.iter().enumerate() {
        let d = dist2(p.map(f64::from), c);
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1
}

fn assign(distinct: &[([u8; 3], u64)], palette: &[[u8; 3]]) -> Vec<usize> {
    distinct.iter().map(|(c, _)| nearest(palette, c.map(f64::from))).collect()
}

fn weighted_means(
    distinct: &[([u8; 3], u64)],
    assigned: &[usize],
    k: usize,
) -> Vec<Option<[f64; 3]>> {
    let mut sums = vec![([0.0f64; 3], 0u64); k];
    for ((c, n), &e) in distinct.iter().zip(assigned) {
        for (sum, &x) in sums[e].0.iter_mut().zip(c) {
            *sum += x as f64 * *n as f64;
        }
        sums[e].1 += n;
    }
    sums.into_iter().map(|(s, n)| (n > 0).then(|| s.map(|x| x / n as f64))).collect()
}

/// RMS over voxels and channels, and the largest channel difference.
fn error(distinct: &[([u8; 3], u64)], palette: &[[u8; 3]], assigned: &[usize]) -> (f64, u8) {
    let (mut sum, mut voxels, mut max) = (0.0f64, 0u64, 0u8);
    for ((c, n), &e) in distinct.iter().zip(assigned) {
        let p = palette[e];
        for i in 0..3 {
            let d = c[i].abs_diff(p[i]);
            sum += (d as f64).powi(2) * *n as f64;
            max = max.max(d);
        }
        voxels += n;
    }
    ((sum / (3 * voxels.max(1)) as f64).sqrt(), max)
}

/// A box of the median cut: a range of `colors` (sorted along the last split axis).
struct Cut {
    start: usize,
    end: usize,
    sse: f64,
    axis: usize,
}

fn measure(colors: &[([u8; 3], u64)], start: usize, end: usize) -> Cut {
    let slice = &colors[start..end];
    let n: f64 = slice.iter().map(|(_, w)| *w as f64).sum();
    let mut mean = [0.0; 3];
    for (c, w) in slice {
        for i in 0..3 {
            mean[i] += c[i] as f64 * *w as f64 / n;
        }
    }
    let mut var = [0.0; 3];
    for (c, w) in slice {
        for i in 0..3 {
            var[i] += (c[i] as f64 - mean[i]).powi(2) * *w as f64;
        }
    }
    let axis = (0..3).max_by(|&a, &b| var[a].total_cmp(&var[b])).unwrap_or(0);
    let sse = if end - start < 2 { -1.0 } else { var.iter().sum() };
    Cut { start, end, sse, axis }
}

fn median_cut(distinct: &[([u8; 3], u64)]) -> Vec<[f64; 3]> {
    let mut colors = distinct.to_vec();
    let mut cuts = vec![measure(&colors, 0, colors.len())];
    while cuts.len() < MAX_COLORS {
        let Some((i, _)) = cuts
            .iter()
            .enumerate()
            .filter(|(_, c)| c.sse > 0.0)
            .max_by(|a, b| a.1.sse.total_cmp(&b.1.sse))
        else {
            break;
        };
        let Cut { start, end, axis, .. } = cuts.swap_remove(i);
        let slice = &mut colors[start..end];
        slice.sort_unstable_by_key(|(c, _)| (c[axis], *c));
        let total: u64 = slice.iter().map(|(_, w)| w).sum();
        let mut acc = 0;
        let mut split = slice.len() - 1;
        for (j, (_, w)) in slice.iter().enumerate() {
            acc += w;
            if 2 * acc >= total {
                split = j + 1;
                break;
            }
        }
        let split = start + split.clamp(1, slice.len() - 1);
        cuts.push(measure(&colors, start, split));
        cuts.push(measure(&colors, split, end));
    }
    cuts.iter()
        .map(|c| {
            let slice = &colors[c.start..c.end];
            let n: f64 = slice.iter().map(|(_, w)| *w as f64).sum();
            let mut mean = [0.0; 3];
            for (col, w) in slice {
                for i in 0..3 {
                    mean[i] += col[i] as f64 * *w as f64 / n;
                }
            }
            mean
        })
        .collect()
}
