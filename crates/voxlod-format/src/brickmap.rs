//! [`BrickMap<T>`]: a sparse voxel grid of 8³ bricks. Only bricks holding at least one voxel
//! exist, and inside a brick only occupied voxels store a value (a 512-bit occupancy mask plus a
//! packed run of values), so memory follows occupied content, not the bounding box.
//!
//! A voxel's global Morton code is its brick's Morton code shifted left by 9 bits, or'ed with
//! its 9-bit Morton code inside the brick. Bricks are kept sorted by Morton code and values are
//! packed in local Morton order, so [`BrickMap::iter`] visits voxels in global Morton order.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::UVec3;

use crate::{Error, Result, morton};

/// Voxels along a brick edge.
pub const BRICK_EDGE: u32 = 8;
/// Voxels in a brick.
pub const BRICK_VOXELS: usize = 512;
const BRICK_SHIFT: u32 = 3;
const LOCAL_BITS: u32 = 9;

/// One allocated brick: where it is, which of its voxels are occupied, and where its values
/// start in the packed value array.
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct BrickHeader {
    /// Morton code of the brick coordinate (voxel coordinate / 8).
    pub morton: u64,
    /// Occupancy of the brick's 512 voxels, bit `i` is the voxel with local Morton code `i`.
    pub mask: [u64; 8],
    /// Index of this brick's first value in [`BrickMap::values`].
    pub first: u32,
    /// Padding (zero) so the header is 8-byte aligned without implicit padding.
    pub _pad: u32,
}

impl BrickHeader {
    /// Number of occupied voxels in the brick.
    pub fn count(&self) -> u32 {
        self.mask.iter().map(|w| w.count_ones()).sum()
    }

    /// Whether local voxel `local` (a 9-bit Morton code) is occupied.
    #[inline]
    pub fn is_set(&self, local: u32) -> bool {
        self.mask[(local >> 6) as usize] >> (local & 63) & 1 == 1
    }

    /// Rank of `local` among the occupied voxels: the number of occupied voxels before it.
    #[inline]
    pub fn rank(&self, local: u32) -> u32 {
        let word = (local >> 6) as usize;
        let below: u32 = self.mask[..word].iter().map(|w| w.count_ones()).sum();
        let bit = local & 63;
        below + (self.mask[word] & ((1u64 << bit) - 1)).count_ones()
    }
}

/// Hashes a Morton code (already well mixed in its low bits) with one multiply.
#[derive(Default, Clone, Copy)]
pub struct MortonHasher(u64);

impl Hasher for MortonHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ b as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (v ^ (v >> 29)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

type MortonMap = HashMap<u64, u32, BuildHasherDefault<MortonHasher>>;

/// A sparse grid of values of type `T` over `dims` voxels, stored in 8³ bricks.
#[derive(Clone, Debug)]
pub struct BrickMap<T> {
    dims: UVec3,
    bricks: Vec<BrickHeader>,
    values: Vec<T>,
    lookup: MortonMap,
}

/// Splits a voxel coordinate into (brick Morton code, local Morton code).
#[inline]
fn split(c: UVec3) -> (u64, u32) {
    let code = morton::encode(c);
    (code >> LOCAL_BITS, (code & ((1 << LOCAL_BITS) - 1)) as u32)
}

impl<T> BrickMap<T> {
    /// An empty map over a grid of `dims` voxels.
    pub fn new(dims: UVec3) -> Self {
        Self { dims, bricks: Vec::new(), values: Vec::new(), lookup: MortonMap::default() }
    }

    /// Builds a map from `(coordinate, value)` pairs in any order. A coordinate outside `dims`
    /// or given twice is an error.
    pub fn from_voxels(dims: UVec3, voxels: impl IntoIterator<Item = (UVec3, T)>) -> Result<Self> {
        let mut keyed: Vec<(u64, T)> = Vec::new();
        for (c, v) in voxels {
            if !c.cmplt(dims).all() {
                return Err(Error::OutOfBounds { coord: c, dims });
            }
            keyed.push((morton::encode(c), v));
        }
        keyed.sort_unstable_by_key(|k| k.0);
        Self::from_morton_sorted(dims, keyed)
    }

    /// Builds a map from `(Morton code, value)` pairs already in strictly increasing code order
    /// (what a voxelizer that sorts by Morton code produces): no sort, no copy of the input.
    /// A code out of order or repeated ([`Error::DuplicateVoxel`]) or a voxel outside `dims`
    /// is an error.
    ///
    /// ```
    /// use glam::UVec3;
    /// use voxlod_format::{BrickMap, morton};
    /// let codes = [UVec3::new(0, 0, 0), UVec3::new(1, 0, 0), UVec3::new(9, 9, 9)].map(morton::encode);
    /// let map = BrickMap::from_morton_sorted(UVec3::splat(16), codes.iter().map(|&c| (c, c))).unwrap();
    /// assert_eq!(map.len(), 3);
    /// assert_eq!(map.bricks().len(), 2);
    /// assert!(BrickMap::from_morton_sorted(UVec3::splat(16), [(5u64, ()), (5, ())]).is_err());
    /// ```
    pub fn from_morton_sorted(
        dims: UVec3,
        voxels: impl IntoIterator<Item = (u64, T)>,
    ) -> Result<Self> {
        let voxels = voxels.into_iter();
        let mut map = Self::new(dims);
        map.values.reserve_exact(voxels.size_hint().0);
        let mut previous: Option<u64> = None;
        for (code, v) in voxels {
            if previous.is_some_and(|p| p >= code) {
                let c = morton::decode(code);
                return Err(if previous == Some(code) {
                    Error::DuplicateVoxel { coord: c }
                } else {
                    Error::InvalidGrid {
                        reason: format!("voxel {c} (Morton code {code}) is out of Morton order"),
                    }
                });
            }
            previous = Some(code);
            let c = morton::decode(code);
            if code >> 63 != 0 || !c.cmplt(dims).all() {
                return Err(Error::OutOfBounds { coord: c, dims });
            }
            let brick = code >> LOCAL_BITS;
            let local = (code & ((1 << LOCAL_BITS) - 1)) as u32;
            if map.bricks.last().is_none_or(|b| b.morton != brick) {
                map.bricks.push(BrickHeader {
                    morton: brick,
                    mask: [0; 8],
                    // Wraps only past u32::MAX values, refused below before the map escapes.
                    first: map.values.len() as u32,
                    _pad: 0,
                });
            }
            let header = map.bricks.last_mut().expect("pushed above");
            header.mask[(local >> 6) as usize] |= 1 << (local & 63);
            map.values.push(v);
        }
        check_value_count(map.values.len())?;
        map.shrink_to_fit();
        map.rebuild_lookup();
        Ok(map)
    }

    /// Builds a map from its parts: brick headers (sorted by Morton code, each with a non-empty
    /// mask and `first` equal to the number of values before it) and the values they address, in
    /// global Morton order. Every invariant is checked — Morton order, bricks and voxels inside
    /// `dims`, `first` offsets, value count — so parts read from a file cannot build a map that
    /// panics later.
    ///
    /// ```
    /// use glam::UVec3;
    /// use voxlod_format::BrickMap;
    /// let map = BrickMap::from_voxels(UVec3::splat(20), [(UVec3::new(9, 1, 17), 5u8)]).unwrap();
    /// let rebuilt =
    ///     BrickMap::from_parts(map.dims(), map.bricks().to_vec(), map.values().to_vec()).unwrap();
    /// assert_eq!(rebuilt.get(UVec3::new(9, 1, 17)), Some(&5));
    /// // Parts that disagree are an error, not a broken map.
    /// assert!(BrickMap::from_parts(map.dims(), map.bricks().to_vec(), vec![1u8, 2]).is_err());
    /// ```
    pub fn from_parts(dims: UVec3, bricks: Vec<BrickHeader>, values: Vec<T>) -> Result<Self> {
        let count = check_bricks(dims, &bricks).map_err(|(_, e)| e)?;
        if count != values.len() {
            return Err(Error::InvalidGrid {
                reason: format!(
                    "the bricks address {count} values but {} were given",
                    values.len()
                ),
            });
        }
        Ok(Self::from_checked_parts(dims, bricks, values))
    }

    /// [`BrickMap::from_parts`] for parts already checked with [`check_bricks`] (whose count
    /// equals `values.len()`).
    pub(crate) fn from_checked_parts(
        dims: UVec3,
        bricks: Vec<BrickHeader>,
        values: Vec<T>,
    ) -> Self {
        let mut map = Self { dims, bricks, values, lookup: MortonMap::default() };
        map.rebuild_lookup();
        map
    }

    fn rebuild_lookup(&mut self) {
        self.lookup = self.bricks.iter().enumerate().map(|(i, b)| (b.morton, i as u32)).collect();
    }

    /// Grid dimensions in voxels.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// Dimensions in bricks (rounded up).
    pub fn brick_dims(&self) -> UVec3 {
        (self.dims + (BRICK_EDGE - 1)) / BRICK_EDGE
    }

    /// Number of occupied voxels.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether no voxel is occupied.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Allocated bricks, sorted by Morton code.
    pub fn bricks(&self) -> &[BrickHeader] {
        &self.bricks
    }

    /// Values of occupied voxels, in global Morton order.
    pub fn values(&self) -> &[T] {
        &self.values
    }

    /// Mutable values of occupied voxels, in global Morton order.
    pub fn values_mut(&mut self) -> &mut [T] {
        &mut self.values
    }

    /// Index of the brick at brick coordinate `b`, if allocated.
    #[inline]
    pub fn brick_index(&self, b: UVec3) -> Option<usize> {
        if !b.cmplt(self.brick_dims()).all() {
            return None;
        }
        self.lookup.get(&morton::encode(b)).map(|&i| i as usize)
    }

    /// Index into [`BrickMap::values`] of voxel `c`, if occupied.
    #[inline]
    pub fn index_of(&self, c: UVec3) -> Option<usize> {
        if !c.cmplt(self.dims).all() {
            return None;
        }
        let (brick, local) = split(c);
        let header = &self.bricks[*self.lookup.get(&brick)? as usize];
        header.is_set(local).then(|| (header.first + header.rank(local)) as usize)
    }

    /// Whether voxel `c` is occupied.
    pub fn contains(&self, c: UVec3) -> bool {
        self.index_of(c).is_some()
    }

    /// Value of voxel `c`, if occupied.
    pub fn get(&self, c: UVec3) -> Option<&T> {
        self.index_of(c).map(|i| &self.values[i])
    }

    /// Mutable value of voxel `c`, if occupied.
    pub fn get_mut(&mut self, c: UVec3) -> Option<&mut T> {
        self.index_of(c).map(|i| &mut self.values[i])
    }

    /// Coordinate of the voxel holding `values()[index]`.
    ///
    /// # Panics
    /// If `index` is not below [`BrickMap::len`].
    pub fn coord_of(&self, index: usize) -> UVec3 {
        let b = self.bricks.partition_point(|h| h.first as usize <= index) - 1;
        let header = &self.bricks[b];
        let mut remaining = (index - header.first as usize) as u32;
        for (w, &word) in header.mask.iter().enumerate() {
            let n = word.count_ones();
            if remaining < n {
                let mut bits = word;
                for _ in 0..remaining {
                    bits &= bits - 1;
                }
                let local = w as u32 * 64 + bits.trailing_zeros();
                return morton::decode((header.morton << LOCAL_BITS) | local as u64);
            }
            remaining -= n;
        }
        unreachable!("brick {b} holds fewer values than its mask says")
    }

    /// Occupied voxels with their values, in global Morton order.
    pub fn iter(&self) -> impl Iterator<Item = (UVec3, &T)> + '_ {
        self.bricks.iter().flat_map(move |h| {
            let base = h.morton << LOCAL_BITS;
            let first = h.first as usize;
            h.mask
                .iter()
                .enumerate()
                .flat_map(|(w, &word)| {
                    let mut bits = word;
                    std::iter::from_fn(move || {
                        (bits != 0).then(|| {
                            let b = bits.trailing_zeros();
                            bits &= bits - 1;
                            w as u64 * 64 + b as u64
                        })
                    })
                })
                .enumerate()
                .map(move |(i, local)| (morton::decode(base | local), &self.values[first + i]))
        })
    }

    /// Coordinates of occupied voxels, in global Morton order.
    pub fn coords(&self) -> impl Iterator<Item = UVec3> + '_ {
        self.iter().map(|(c, _)| c)
    }

    /// A map with the same occupancy and values transformed by `f`.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> BrickMap<U> {
        BrickMap {
            dims: self.dims,
            bricks: self.bricks.clone(),
            values: self.values.iter().map(f).collect(),
            lookup: self.lookup.clone(),
        }
    }

    /// A map with the same occupancy and the given values (in global Morton order). Errors if
    /// the count differs from [`BrickMap::len`].
    pub fn with_values<U>(&self, values: Vec<U>) -> Result<BrickMap<U>> {
        if values.len() != self.values.len() {
            return Err(Error::InvalidGrid {
                reason: format!(
                    "{} values given for a brick map of {} occupied voxels",
                    values.len(),
                    self.values.len()
                ),
            });
        }
        Ok(BrickMap {
            dims: self.dims,
            bricks: self.bricks.clone(),
            values,
            lookup: self.lookup.clone(),
        })
    }

    /// Bytes per brick of the brick look-up as a renderer stores it packed: a (Morton code,
    /// brick index) pair.
    pub const LOOKUP_ENTRY_BYTES: usize = size_of::<u64>() + size_of::<u32>();

    /// Packed bytes of the map, what a renderer needs to hold it: the brick headers, the values
    /// and the brick look-up as [`BrickMap::LOOKUP_ENTRY_BYTES`] per brick. Counted from
    /// lengths, not capacities, so neither `Vec` growth slack nor the hash table's empty slots
    /// inflate it: `bricks().len() · size_of::<BrickHeader>() + len() · size_of::<T>() +
    /// bricks().len() · LOOKUP_ENTRY_BYTES`, exactly.
    pub fn memory_bytes(&self) -> usize {
        self.bricks.len() * (size_of::<BrickHeader>() + Self::LOOKUP_ENTRY_BYTES)
            + self.values.len() * size_of::<T>()
    }

    /// Releases the brick and value arrays' growth slack (their capacity becomes their length).
    pub fn shrink_to_fit(&mut self) {
        self.bricks.shrink_to_fit();
        self.values.shrink_to_fit();
        self.lookup.shrink_to_fit();
    }

    /// Checks every structural invariant: bricks strictly sorted and inside the grid, masks
    /// non-empty with no voxel outside `dims`, `first` offsets consistent with the mask counts,
    /// lookup table agreeing with the brick list.
    pub fn validate(&self) -> Result<()> {
        let fail = |reason: String| Err(Error::InvalidGrid { reason });
        let mut next = 0u32;
        for (i, h) in self.bricks.iter().enumerate() {
            if i > 0 && self.bricks[i - 1].morton >= h.morton {
                return fail(format!("brick {i} is out of Morton order"));
            }
            if h.first != next {
                return fail(format!("brick {i} starts at value {} instead of {next}", h.first));
            }
            let n = h.count();
            if n == 0 {
                return fail(format!("brick {i} is allocated but empty"));
            }
            next += n;
            let origin = morton::decode(h.morton) << BRICK_SHIFT;
            for local in 0..BRICK_VOXELS as u32 {
                if h.is_set(local) {
                    let c = origin + morton::decode(local as u64);
                    if !c.cmplt(self.dims).all() {
                        return Err(Error::OutOfBounds { coord: c, dims: self.dims });
                    }
                }
            }
            if self.lookup.get(&h.morton) != Some(&(i as u32)) {
                return fail(format!("lookup table disagrees on brick {i}"));
            }
        }
        if next as usize != self.values.len() || self.lookup.len() != self.bricks.len() {
            return fail("value count or lookup size disagrees with the bricks".into());
        }
        Ok(())
    }
}

/// Checks a brick table against a grid of `dims` voxels: Morton codes canonical, strictly
/// increasing and inside the grid, masks non-empty with no voxel outside `dims`, `first` equal to
/// the running value count. Returns the number of values the table addresses, or the index of the
/// first offending brick with the error. Cost: O(bricks), plus 512 steps per brick on the grid's
/// far boundary.
pub(crate) fn check_bricks(
    dims: UVec3,
    bricks: &[BrickHeader],
) -> std::result::Result<usize, (usize, Error)> {
    if dims.max_element() > morton::MAX_COORD {
        let requested = dims.as_u64vec3().to_array();
        return Err((0, Error::GridTooLarge { requested, max: morton::MAX_COORD as u64 }));
    }
    let invalid = |i: usize, reason: String| (i, Error::InvalidGrid { reason });
    let brick_dims = (dims + (BRICK_EDGE - 1)) / BRICK_EDGE;
    let mut next = 0u32;
    for (i, h) in bricks.iter().enumerate() {
        let b = morton::decode(h.morton);
        if morton::encode(b) != h.morton {
            return Err(invalid(
                i,
                format!("brick {i} has a non-canonical Morton code {:#x}", h.morton),
            ));
        }
        if !b.cmplt(brick_dims).all() {
            return Err((i, Error::OutOfBounds { coord: b << BRICK_SHIFT, dims }));
        }
        if i > 0 && bricks[i - 1].morton >= h.morton {
            return Err(invalid(i, format!("brick {i} is out of Morton order")));
        }
        if h.first != next {
            return Err(invalid(
                i,
                format!("brick {i} starts at value {} instead of {next}", h.first),
            ));
        }
        let n = h.count();
        if n == 0 {
            return Err(invalid(i, format!("brick {i} is allocated but empty")));
        }
        let origin = b << BRICK_SHIFT;
        if (origin + BRICK_EDGE).cmpgt(dims).any() {
            let inside = inside_mask(origin, dims);
            if let Some(w) = (0..8).find(|&w| h.mask[w] & !inside[w] != 0) {
                let local = w as u64 * 64 + (h.mask[w] & !inside[w]).trailing_zeros() as u64;
                return Err((
                    i,
                    Error::OutOfBounds { coord: origin + morton::decode(local), dims },
                ));
            }
        }
        next = next.checked_add(n).ok_or_else(|| {
            invalid(i, format!("brick {i} takes the value count past {}", u32::MAX))
        })?;
    }
    Ok(next as usize)
}

/// Mask of the local voxels of the brick at voxel `origin` that lie inside `dims`.
fn inside_mask(origin: UVec3, dims: UVec3) -> [u64; 8] {
    let mut mask = [0u64; 8];
    for local in 0..BRICK_VOXELS as u32 {
        if (origin + morton::decode(local as u64)).cmplt(dims).all() {
            mask[(local >> 6) as usize] |= 1 << (local & 63);
        }
    }
    mask
}

/// Brick offsets are `u32`: a map holds at most `u32::MAX` values (reachable with a zero-sized
/// record such as `Occupancy` on a 2048³ solid grid), refused rather than wrapped.
fn check_value_count(len: usize) -> Result<()> {
    if len as u64 > u32::MAX as u64 {
        return Err(Error::TooManyVoxels { voxels: len as u64, max: u32::MAX as u64 });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::BTreeMap;

    fn dense_strategy() -> impl Strategy<Value = (UVec3, BTreeMap<u64, (UVec3, u32)>)> {
        (1u32..40, 1u32..40, 1u32..40).prop_flat_map(|(x, y, z)| {
            let dims = UVec3::new(x, y, z);
            let voxel = (0..x, 0..y, 0..z, any::<u32>());
            proptest::collection::vec(voxel, 0..300).prop_map(move |v| {
                let map = v
                    .into_iter()
                    .map(|(a, b, c, val)| {
                        let c = UVec3::new(a, b, c);
                        (morton::encode(c), (c, val))
                    })
                    .collect();
                (dims, map)
            })
        })
    }

    proptest! {
        #[test]
        fn matches_a_dense_grid((dims, voxels) in dense_strategy()) {
            let map = BrickMap::from_voxels(dims, voxels.values().copied()).unwrap();
            map.validate().unwrap();
            prop_assert_eq!(map.len(), voxels.len());
            // Every voxel of the dense grid agrees.
            for x in 0..dims.x { for y in 0..dims.y { for z in 0..dims.z {
                let c = UVec3::new(x, y, z);
                let expected = voxels.get(&morton::encode(c)).map(|v| &v.1);
                prop_assert_eq!(map.get(c), expected);
            }}}
            // Iteration is in global Morton order and round-trips through coord_of.
            let iterated: Vec<_> = map.iter().map(|(c, &v)| (c, v)).collect();
            let expected: Vec<_> = voxels.values().copied().collect();
            prop_assert_eq!(&iterated, &expected);
            for (i, (c, _)) in iterated.iter().enumerate() {
                prop_assert_eq!(map.coord_of(i), *c);
            }
            // Only occupied bricks exist.
            let bricks: std::collections::BTreeSet<_> =
                voxels.values().map(|(c, _)| morton::encode(*c >> 3)).collect();
            prop_assert_eq!(map.bricks().len(), bricks.len());
        }
    }

    #[test]
    fn rejects_duplicates_and_out_of_bounds() {
        let dims = UVec3::splat(4);
        assert!(matches!(
            BrickMap::from_voxels(dims, [(UVec3::ONE, 1), (UVec3::ONE, 2)]),
            Err(Error::DuplicateVoxel { .. })
        ));
        assert!(matches!(
            BrickMap::from_voxels(dims, [(UVec3::new(4, 0, 0), 1)]),
            Err(Error::OutOfBounds { .. })
        ));
        assert_eq!(BrickMap::<u8>::new(dims).get(UVec3::new(9, 9, 9)), None);
    }

    #[test]
    fn from_parts_rebuilds_and_rejects_inconsistent_parts() {
        let dims = UVec3::new(12, 9, 17);
        let voxels =
            [(UVec3::new(0, 0, 0), 1u32), (UVec3::new(11, 8, 16), 2), (UVec3::new(3, 8, 9), 3)];
        let map = BrickMap::from_voxels(dims, voxels).unwrap();
        let rebuilt =
            BrickMap::from_parts(dims, map.bricks().to_vec(), map.values().to_vec()).unwrap();
        rebuilt.validate().unwrap();
        for (c, v) in voxels {
            assert_eq!(rebuilt.get(c), Some(&v));
        }
        let parts = |f: &dyn Fn(&mut Vec<BrickHeader>)| {
            let mut bricks = map.bricks().to_vec();
            f(&mut bricks);
            BrickMap::from_parts(dims, bricks, map.values().to_vec())
        };
        let reason = |r: Result<BrickMap<u32>>| r.unwrap_err().to_string();
        // Unsorted: each brick holds one voxel, so swapping codes and masks leaves only the
        // order wrong.
        let swapped = parts(&|b| {
            let zero = (b[0].morton, b[0].mask);
            (b[0].morton, b[0].mask) = (b[1].morton, b[1].mask);
            (b[1].morton, b[1].mask) = zero;
        });
        assert!(reason(swapped).contains("Morton order"));
        assert!(reason(parts(&|b| b[1].mask = [0; 8])).contains("empty"));
        assert!(reason(parts(&|b| b[1].first += 1)).contains("starts at value"));
        // A voxel beyond the grid's far face, a non-canonical code, too few values.
        assert!(matches!(
            parts(&|b| b.last_mut().unwrap().mask[7] |= 1 << 63),
            Err(Error::OutOfBounds { .. })
        ));
        assert!(parts(&|b| b[0].morton |= 1 << 63).is_err());
        assert!(
            BrickMap::from_parts(UVec3::new(8, 8, 8), map.bricks().to_vec(), map.values().to_vec())
                .is_err()
        );
        assert!(BrickMap::from_parts(dims, map.bricks().to_vec(), vec![0u32; 2]).is_err());
    }

    #[test]
    fn memory_follows_occupancy_not_bounds() {
        // One voxel in a 2^20-voxel-wide grid: one brick, one value.
        let dims = UVec3::splat(1 << 20);
        let map = BrickMap::from_voxels(dims, [(UVec3::splat(123_456), 7u8)]).unwrap();
        assert_eq!(map.bricks().len(), 1);
        assert!(map.memory_bytes() < 1024, "{} bytes", map.memory_bytes());
        assert_eq!(map.get(UVec3::splat(123_456)), Some(&7));
    }

    #[test]
    fn memory_is_the_packed_size_without_growth_slack() {
        // 11 voxels in 3 bricks, pushed through an iterator without a size hint so that the
        // value array grows by doubling while it is built.
        let dims = UVec3::splat(32);
        let coords: Vec<UVec3> = (0..9)
            .map(|i| UVec3::new(i % 4, i / 4, 0))
            .chain([UVec3::new(9, 0, 0), UVec3::new(31, 31, 31)])
            .collect();
        let mut codes: Vec<u64> = coords.iter().map(|&c| morton::encode(c)).collect();
        codes.sort_unstable();
        let unsized_iter = codes.iter().filter(|_| true).map(|&c| (c, [0u8; 12]));
        let map = BrickMap::from_morton_sorted(dims, unsized_iter).unwrap();
        assert_eq!((map.len(), map.bricks().len()), (11, 3));
        assert_eq!(map.values.capacity(), map.len());
        assert_eq!(map.bricks.capacity(), map.bricks().len());
        let header = size_of::<BrickHeader>() + BrickMap::<[u8; 12]>::LOOKUP_ENTRY_BYTES;
        assert_eq!(header, 92);
        assert_eq!(map.memory_bytes(), 3 * 92 + 11 * 12);
    }

    #[test]
    fn more_values_than_u32_offsets_address_are_refused() {
        assert!(check_value_count(u32::MAX as usize).is_ok());
        let err = check_value_count(u32::MAX as usize + 1).unwrap_err();
        assert!(matches!(err, Error::TooManyVoxels { voxels: 4_294_967_296, .. }), "{err}");
    }
}
