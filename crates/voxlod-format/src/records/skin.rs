//! Skinning influences of a cached voxel ([`VoxelSkin`]) and the record of a skinned object's
//! voxel cache ([`SkinnedRecord`]).
//!
//! Weights are **unorm8 summing to exactly 255**, so a blend of joint matrices weighted by them
//! is an affine combination on both backends without renormalizing, and fixed-point sums stay
//! exact. [`VoxelSkin::from_influences`] keeps the four largest influences and quantizes them by
//! the largest-remainder rule.

use crate::vxl::VxlRecord;

use super::AverageRecord;

/// Up to four joints (indices into the skin's joint list, so at most 256 joints per skin) and
/// their weights, unorm8 summing to 255; unused slots have joint 0 and weight 0. 8 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct VoxelSkin {
    /// Joint indices.
    pub joints: [u8; 4],
    /// Weights in 1/255, summing to 255.
    pub weights: [u8; 4],
}

impl VoxelSkin {
    /// The most joints a skin may have for its indices to fit a byte.
    pub const MAX_JOINTS: u32 = 256;

    /// One joint with all the weight.
    pub fn rigid(joint: u8) -> Self {
        Self { joints: [joint, 0, 0, 0], weights: [255, 0, 0, 0] }
    }

    /// The four largest of `influences` (joint, weight ≥ 0; a joint may repeat: its weights
    /// add), ties broken toward the lower joint, renormalized and quantized to unorm8 summing
    /// to 255 (floors, then the remaining units to the largest remainders, ties toward the
    /// earlier slot). Slots are ordered by decreasing weight. `None` when the weights do not
    /// have a positive finite sum, a weight is negative or not finite, or a joint is ≥
    /// [`VoxelSkin::MAX_JOINTS`].
    pub fn from_influences(influences: &[(u32, f32)]) -> Option<Self> {
        let mut merged: Vec<(u32, f64)> = Vec::with_capacity(influences.len());
        for &(j, w) in influences {
            if !w.is_finite() || w < 0.0 || j >= Self::MAX_JOINTS {
                return None;
            }
            match merged.iter_mut().find(|(k, _)| *k == j) {
                Some(m) => m.1 += w as f64,
                None => merged.push((j, w as f64)),
            }
        }
        merged.retain(|&(_, w)| w > 0.0);
        merged.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        merged.truncate(4);
        let sum: f64 = merged.iter().map(|m| m.1).sum();
        if !(sum > 0.0 && sum.is_finite()) {
            return None;
        }
        let scaled: Vec<f64> = merged.iter().map(|m| m.1 / sum * 255.0).collect();
        let mut q: Vec<u32> = scaled.iter().map(|s| s.floor() as u32).collect();
        let mut left = 255 - q.iter().sum::<u32>();
        let mut order: Vec<usize> = (0..q.len()).collect();
        order.sort_by(|&a, &b| {
            let (ra, rb) = (scaled[a] - scaled[a].floor(), scaled[b] - scaled[b].floor());
            rb.total_cmp(&ra).then(a.cmp(&b))
        });
        for &i in order.iter().cycle() {
            if left == 0 {
                break;
            }
            q[i] += 1;
            left -= 1;
        }
        let mut out = Self::default();
        for (slot, (&(j, _), &w)) in merged.iter().zip(&q).enumerate() {
            out.joints[slot] = j as u8;
            out.weights[slot] = w as u8;
        }
        Some(out)
    }

    /// Weight of slot `k` in \[0, 1\].
    pub fn weight(&self, k: usize) -> f32 {
        self.weights[k] as f32 / 255.0
    }

    /// Whether the weights sum to 255 (every value [`VoxelSkin::from_influences`] makes does).
    pub fn is_normalized(&self) -> bool {
        self.weights.iter().map(|&w| w as u32).sum::<u32>() == 255
    }
}

/// A voxel of a skinned object's cache: its Averages record and its skin. 16 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct SkinnedRecord {
    /// Appearance (object space: the normal is the object's).
    pub average: AverageRecord,
    /// Skinning influences.
    pub skin: VoxelSkin,
}

impl VxlRecord for VoxelSkin {
    const TAG: [u8; 4] = *b"SKN1";
    const FIELD_WIDTHS: &'static [u8] = &[1];
}

impl VxlRecord for SkinnedRecord {
    const TAG: [u8; 4] = *b"SKV1";
    const FIELD_WIDTHS: &'static [u8] = &[1];
}

const _: () = assert!(size_of::<VoxelSkin>() == 8 && size_of::<SkinnedRecord>() == 16);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn influences_keep_the_four_largest_and_sum_to_255() {
        let s = VoxelSkin::from_influences(&[(3, 0.1), (1, 0.4), (7, 0.05), (2, 0.3), (9, 0.15)])
            .unwrap();
        assert_eq!(s.joints, [1, 2, 9, 3]);
        assert!(s.is_normalized(), "{s:?}");
        // Renormalized over 0.95: 0.4/0.95·255 = 107.4 …
        assert_eq!(s.weights, [107, 81, 40, 27]);
        // A repeated joint adds up; zero weights are dropped.
        let s = VoxelSkin::from_influences(&[(4, 0.25), (4, 0.25), (5, 0.5), (6, 0.0)]).unwrap();
        assert_eq!((s.joints, s.weights), ([4, 5, 0, 0], [128, 127, 0, 0]));
        assert_eq!(VoxelSkin::from_influences(&[(0, 1.0)]), Some(VoxelSkin::rigid(0)));
        // Thirds: 85 each, no remainder.
        let s = VoxelSkin::from_influences(&[(0, 1.0), (1, 1.0), (2, 1.0)]).unwrap();
        assert_eq!(s.weights, [85, 85, 85, 0]);
    }

    #[test]
    fn zero_negative_and_out_of_range_influences_are_refused() {
        assert_eq!(VoxelSkin::from_influences(&[]), None);
        assert_eq!(VoxelSkin::from_influences(&[(0, 0.0), (1, 0.0)]), None);
        assert_eq!(VoxelSkin::from_influences(&[(0, -0.5), (1, 1.0)]), None);
        assert_eq!(VoxelSkin::from_influences(&[(0, f32::NAN)]), None);
        assert_eq!(VoxelSkin::from_influences(&[(256, 1.0)]), None);
        assert!(VoxelSkin::from_influences(&[(255, 1.0)]).is_some());
    }

    #[test]
    fn every_split_of_two_sums_exactly() {
        for i in 0..=1000 {
            let a = i as f32 / 1000.0;
            let s = VoxelSkin::from_influences(&[(0, a), (1, 1.0 - a)]).unwrap();
            assert!(s.is_normalized());
            let w0 = if s.joints[0] == 0 { s.weight(0) } else { s.weight(1) };
            assert!((w0 - a).abs() <= 0.5 / 255.0 + 1e-6, "{a}: {s:?}");
        }
    }
}
