//! MagicaVoxel's rotations: signed permutation matrices packed in one byte (the `_r` frame
//! attribute of a transform node), and where a rotated, translated model puts its voxels.

use glam::{IVec3, UVec3};

/// A rotation (or reflection) of a `.vox` transform node: a signed permutation matrix, row-major.
///
/// The byte layout (ephtracy's scene-graph extension of the format, "ROTATION type"): bits 0–1
/// hold the column of the first row's non-zero entry, bits 2–3 the second row's, the third row
/// takes the remaining column; bits 4, 5, 6 are the signs of the first, second and third rows
/// (set = −1). Reflections (determinant −1) are valid rotations of the format.
///
/// ```
/// use glam::IVec3;
/// use voxlod_format::vox::VoxRotation;
/// // The specification's example: rows (0 1 0), (0 0 −1), (−1 0 0).
/// let r = VoxRotation::from_byte((1 << 0) | (2 << 2) | (1 << 5) | (1 << 6)).unwrap();
/// assert_eq!(r.rows(), [[0, 1, 0], [0, 0, -1], [-1, 0, 0]]);
/// assert_eq!(r.apply(IVec3::new(1, 2, 3)), IVec3::new(2, -3, -1));
/// assert_eq!(VoxRotation::from_byte(0b0000_0100), Some(VoxRotation::IDENTITY));
/// assert_eq!(VoxRotation::from_byte(0b0000_0000), None); // two rows on column 0
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VoxRotation {
    /// Per row: the column of its non-zero entry.
    columns: [u8; 3],
    /// Per row: the sign of that entry (±1).
    signs: [i8; 3],
}

impl VoxRotation {
    /// The identity (byte 4: rows pick x, y, z, all signs positive).
    pub const IDENTITY: Self = Self { columns: [0, 1, 2], signs: [1, 1, 1] };

    /// Decodes a rotation byte; `None` when the first two rows name the same column or a column
    /// index is 3, or when bit 7 is set (none of these is a permutation the format defines).
    pub fn from_byte(b: u8) -> Option<Self> {
        let (c0, c1) = (b & 3, (b >> 2) & 3);
        if c0 == 3 || c1 == 3 || c0 == c1 || b & 0x80 != 0 {
            return None;
        }
        let c2 = 3 - c0 - c1;
        let sign = |bit: u8| if b & (1 << bit) != 0 { -1 } else { 1 };
        Some(Self { columns: [c0, c1, c2], signs: [sign(4), sign(5), sign(6)] })
    }

    /// The byte that encodes this rotation (the inverse of [`VoxRotation::from_byte`]).
    pub fn to_byte(self) -> u8 {
        let bit = |row: usize| u8::from(self.signs[row] < 0) << (4 + row);
        self.columns[0] | (self.columns[1] << 2) | bit(0) | bit(1) | bit(2)
    }

    /// The matrix, row-major.
    pub fn rows(self) -> [[i32; 3]; 3] {
        let mut m = [[0; 3]; 3];
        for (row, r) in m.iter_mut().enumerate() {
            r[self.columns[row] as usize] = self.signs[row] as i32;
        }
        m
    }

    /// `R · v`.
    pub fn apply(self, v: IVec3) -> IVec3 {
        let v = v.to_array();
        IVec3::from_array(std::array::from_fn(|row| {
            self.signs[row] as i32 * v[self.columns[row] as usize]
        }))
    }

    /// The composition `self · inner` (apply `inner` first), as a parent transform node
    /// composes with its child's.
    pub fn then_inner(self, inner: Self) -> Self {
        // Row `r` of self·inner: self picks inner's row `self.columns[r]`, scaled by its sign.
        let mut columns = [0; 3];
        let mut signs = [1; 3];
        for r in 0..3 {
            let k = self.columns[r] as usize;
            columns[r] = inner.columns[k];
            signs[r] = self.signs[r] * inner.signs[k];
        }
        Self { columns, signs }
    }

    /// The determinant: +1 for a rotation, −1 for a reflection.
    pub fn determinant(self) -> i32 {
        let m = self.rows();
        let m = |r: usize, c: usize| m[r][c];
        m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
            - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
            + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0))
    }
}

impl Default for VoxRotation {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// The world voxel (its minimum corner, in whole voxels) that voxel `p` of a model of `size`
/// occupies under rotation `r` and translation `t`.
///
/// MagicaVoxel anchors a model at its pivot `⌊size/2⌋` (in voxels from the model's minimum
/// corner): the voxel's centre `p + ½ − ⌊size/2⌋` is rotated, translated by `t`, and the voxel
/// is the unit cell around the result. For an even size the pivot is the box's centre; for an
/// odd size it is the minimum corner of the middle voxel, so a half turn about an axis of odd
/// size moves the model by one voxel along it (MagicaVoxel's editor compensates in `t` when it
/// rotates such a model). This is the placement the reference readers (ogt_vox, vengi) apply.
/// In whole numbers: twice the centre is `c = 2p + 1 − 2⌊size/2⌋` (odd), and the corner is
/// `t + (R·c − 1) / 2`, exact.
pub fn place(p: UVec3, size: UVec3, r: VoxRotation, t: IVec3) -> IVec3 {
    let c = 2 * p.as_ivec3() + IVec3::ONE - 2 * (size / 2).as_ivec3();
    t + (r.apply(c) - IVec3::ONE) / 2
}
