//! The flat NanoVDB buffer of one grid (see the module docs of [`super`] for the layout), its
//! checksum, and the file segment around the grids.

use glam::{DVec3, IVec3};

use super::{
    GridSummary, MAGIC, MAX_GRID_BYTES, MAX_INDEX, MAX_NAME_BYTES, NvdbGrid, NvdbValue, VERSION,
    name_hash, unrepresentable,
};
use crate::Result;

/// Bytes of `GridData`.
pub(super) const GRID_BYTES: usize = 672;
/// Bytes of `TreeData<3>`.
pub(super) const TREE_BYTES: usize = 64;
/// Bytes of one root tile.
pub(super) const TILE_BYTES: usize = 32;
/// Bytes of the file header of a segment.
pub(super) const HEADER_BYTES: usize = 16;
/// Bytes of a metadata record before the grid's name.
pub(super) const META_BYTES: usize = 176;
/// `HasBBox | HasMinMax | HasAverage | HasStdDeviation | IsBreadthFirst`.
pub(super) const GRID_FLAGS: u32 = 2 | 4 | 8 | 16 | 32;
/// Node flag: the node holds active values (its bbox is set).
const NODE_HAS_BBOX: u32 = 2;

/// Log2 of the width, in children, of the upper (5), lower (4) and leaf (3) nodes.
pub(super) const LOG2: [u32; 3] = [5, 4, 3];
/// Log2 of the width in voxels of the upper (12), lower (7) and leaf (3) nodes.
pub(super) const TOTAL: [u32; 3] = [12, 7, 3];

pub(super) const fn align32(n: usize) -> usize {
    (n + 31) & !31
}

/// Byte sizes and field offsets of the nodes for values of `size` bytes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sizes {
    /// `RootData`.
    pub root: usize,
    /// Upper internal node and its table offset.
    pub upper: usize,
    pub upper_table: usize,
    /// Lower internal node and its table offset.
    pub lower: usize,
    pub lower_table: usize,
    /// Bytes of an internal node's table entry (a union of the value and an `i64`).
    pub entry: usize,
    /// Leaf and its value-array offset.
    pub leaf: usize,
    pub leaf_values: usize,
}

impl Sizes {
    pub(super) const fn of(value: usize) -> Self {
        let entry = if value > 8 { (value + 7) & !7 } else { 8 };
        let (upper, upper_table) = internal_size(5, value, entry);
        let (lower, lower_table) = internal_size(4, value, entry);
        let leaf_values = align32(80 + 2 * value + 8);
        Self {
            root: align32(28 + 3 * value + 8),
            upper,
            upper_table,
            lower,
            lower_table,
            entry,
            leaf: align32(leaf_values + 512 * value),
            leaf_values,
        }
    }

    /// Offset of the min/max/average/deviation block of an internal node.
    pub(super) const fn internal_stats(log2: u32) -> usize {
        32 + 2 * ((1usize << (3 * log2)) / 8)
    }
}

/// Bytes of an internal node of `log2` and the offset of its table.
const fn internal_size(log2: u32, value: usize, entry: usize) -> (usize, usize) {
    let n = 1usize << (3 * log2);
    let table = align32(32 + 2 * (n / 8) + 2 * value + 8);
    (align32(table + n * entry), table)
}

/// One grid laid out: its bytes, the metadata record's fields and a summary.
pub(super) struct Built {
    pub bytes: Vec<u8>,
    pub summary: GridSummary,
    name: String,
    class: u32,
    grid_type: u32,
    world_bbox: [DVec3; 2],
    index_bbox: [IVec3; 2],
    voxel_size: DVec3,
    nodes: [u32; 3],
}

/// Running statistics of a node, as NanoVDB's `GridStats` keeps them: count, mean and sum of
/// squared deviations of the stat scalar (Welford, merged with Chan et al.'s formula), the
/// values of least and greatest scalar, and the bbox of the active voxels.
#[derive(Clone, Copy)]
struct Stats<T> {
    n: u64,
    mean: f64,
    m2: f64,
    min: (f32, T),
    max: (f32, T),
    lo: IVec3,
    hi: IVec3,
}

impl<T: NvdbValue> Stats<T> {
    fn new() -> Self {
        Self {
            n: 0,
            mean: 0.0,
            m2: 0.0,
            min: (f32::MAX, T::ZERO),
            max: (f32::MIN, T::ZERO),
            lo: IVec3::MAX,
            hi: IVec3::MIN,
        }
    }

    fn add(&mut self, c: IVec3, v: T) {
        let s = v.stat();
        self.n += 1;
        let delta = s as f64 - self.mean;
        self.mean += delta / self.n as f64;
        self.m2 += delta * (s as f64 - self.mean);
        if s < self.min.0 {
            self.min = (s, v);
        }
        if self.max.0 < s {
            self.max = (s, v);
        }
        self.lo = self.lo.min(c);
        self.hi = self.hi.max(c);
    }

    fn merge(&mut self, o: &Self) {
        if o.n == 0 {
            return;
        }
        let denom = 1.0 / (self.n + o.n) as f64;
        let delta = o.mean - self.mean;
        self.mean += denom * delta * o.n as f64;
        self.m2 += o.m2 + denom * delta * delta * self.n as f64 * o.n as f64;
        if o.min.0 < self.min.0 {
            self.min = o.min;
        }
        if self.max.0 < o.max.0 {
            self.max = o.max;
        }
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
        self.n += o.n;
    }

    fn std(&self) -> f64 {
        if self.n < 2 { 0.0 } else { (self.m2 / self.n as f64).sqrt() }
    }

    /// Writes min, max (values), average and standard deviation (`f32`) at `at`.
    fn put(&self, out: &mut [u8], at: usize) {
        let s = T::SIZE;
        self.min.1.put(&mut out[at..]);
        self.max.1.put(&mut out[at + s..]);
        put_f32(out, at + 2 * s, self.mean as f32);
        put_f32(out, at + 2 * s + 4, self.std() as f32);
    }

    fn put_bbox(&self, out: &mut [u8], at: usize) {
        put_ivec3(out, at, self.lo);
        put_ivec3(out, at + 12, self.hi);
    }
}

struct Leaf<T> {
    origin: IVec3,
    mask: [u64; 8],
    values: Vec<(u32, T)>,
    stats: Stats<T>,
}

struct Internal<T> {
    origin: IVec3,
    /// (entry index in this node, child index in the next level's list).
    children: Vec<(u32, usize)>,
    stats: Stats<T>,
}

/// Origin of the node of level `level` (0 upper, 1 lower, 2 leaf) holding `c`.
fn origin(c: IVec3, level: usize) -> IVec3 {
    c & IVec3::splat(!((1i32 << TOTAL[level]) - 1))
}

/// Entry index of `c` in the node of level `level`.
fn entry(c: IVec3, level: usize) -> u32 {
    let child = if level == 2 { 0 } else { TOTAL[level + 1] };
    let mask = (1i32 << TOTAL[level]) - 1;
    let l = ((c & IVec3::splat(mask)) >> child as i32).as_uvec3();
    (l.x << (2 * LOG2[level])) | (l.y << LOG2[level]) | l.z
}

/// Lays out `grid` (validated here).
pub(super) fn build<T: NvdbValue>(grid: &NvdbGrid<T>) -> Result<Built> {
    validate(grid)?;
    let sz = Sizes::of(T::SIZE);
    // Sort the voxels by (upper origin, lower origin, leaf origin, entry): each level's nodes
    // then come in depth-first order and each node's children by entry.
    let key = |c: IVec3| {
        let (u, l, f) = (origin(c, 0), origin(c, 1), origin(c, 2));
        ([u.x, u.y, u.z], [l.x, l.y, l.z], [f.x, f.y, f.z], entry(c, 2))
    };
    let mut order: Vec<(_, usize)> =
        grid.voxels.iter().enumerate().map(|(i, v)| (key(v.0), i)).collect();
    order.sort_unstable_by_key(|a| a.0);
    if let Some(w) = order.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(unrepresentable(
            format!("voxel {} of grid {:?}, given twice", grid.voxels[w[0].1].0, grid.name),
            "a VDB voxel holds one value".into(),
        ));
    }

    let mut leaves: Vec<Leaf<T>> = Vec::new();
    let mut lowers: Vec<Internal<T>> = Vec::new();
    let mut uppers: Vec<Internal<T>> = Vec::new();
    for &(_, i) in &order {
        let (c, v) = grid.voxels[i];
        let f = origin(c, 2);
        if leaves.last().is_none_or(|l| l.origin != f) {
            let l = origin(c, 1);
            if lowers.last().is_none_or(|n| n.origin != l) {
                let u = origin(c, 0);
                if uppers.last().is_none_or(|n| n.origin != u) {
                    uppers.push(Internal { origin: u, children: Vec::new(), stats: Stats::new() });
                }
                let up = uppers.last_mut().expect("pushed");
                up.children.push((entry(c, 0), lowers.len()));
                lowers.push(Internal { origin: l, children: Vec::new(), stats: Stats::new() });
            }
            let low = lowers.last_mut().expect("pushed");
            low.children.push((entry(c, 1), leaves.len()));
            leaves.push(Leaf { origin: f, mask: [0; 8], values: Vec::new(), stats: Stats::new() });
        }
        let leaf = leaves.last_mut().expect("pushed");
        let n = entry(c, 2);
        leaf.mask[n as usize / 64] |= 1 << (n % 64);
        leaf.values.push((n, v));
        leaf.stats.add(c, v);
    }
    for low in &mut lowers {
        for &(_, c) in &low.children {
            low.stats.merge(&leaves[c].stats);
        }
    }
    for up in &mut uppers {
        for &(_, c) in &up.children {
            up.stats.merge(&lowers[c].stats);
        }
    }
    let mut root = Stats::new();
    for up in &uppers {
        root.merge(&up.stats);
    }

    // Offsets from the start of the grid.
    let root_at = GRID_BYTES + TREE_BYTES;
    let root_end = root_at + sz.root + TILE_BYTES * uppers.len();
    let upper_at = align32(root_end);
    let lower_at = upper_at as u64 + (uppers.len() * sz.upper) as u64;
    let leaf_at = lower_at + (lowers.len() * sz.lower) as u64;
    let total = leaf_at + (leaves.len() * sz.leaf) as u64;
    if total > MAX_GRID_BYTES {
        return Err(unrepresentable(
            format!(
                "grid {:?} of {} voxels in {} leaves, {} lower and {} upper nodes ({total} bytes)",
                grid.name,
                grid.voxels.len(),
                leaves.len(),
                lowers.len(),
                uppers.len()
            ),
            format!("this library writes grids of at most {MAX_GRID_BYTES} bytes"),
        ));
    }
    let (lower_at, leaf_at, total) = (lower_at as usize, leaf_at as usize, total as usize);
    let mut b = vec![0u8; total];

    // Grid.
    put_u64(&mut b, 0, MAGIC);
    put_u32(&mut b, 16, VERSION);
    put_u32(&mut b, 20, GRID_FLAGS);
    put_u32(&mut b, 24, 0); // grid index
    put_u32(&mut b, 28, 1); // grid count
    put_u64(&mut b, 32, total as u64);
    b[40..40 + grid.name.len()].copy_from_slice(grid.name.as_bytes());
    let m = grid.map.matrix;
    let inv = m.inverse();
    let t = grid.map.translation;
    for r in 0..3 {
        for c in 0..3 {
            let (x, y) = (m.col(c)[r], inv.col(c)[r]);
            put_f32(&mut b, 296 + 4 * (3 * r + c), x as f32);
            put_f32(&mut b, 332 + 4 * (3 * r + c), y as f32);
            put_f64(&mut b, 384 + 8 * (3 * r + c), x);
            put_f64(&mut b, 456 + 8 * (3 * r + c), y);
        }
        put_f32(&mut b, 368 + 4 * r, t[r] as f32);
        put_f64(&mut b, 528 + 8 * r, t[r]);
    }
    put_f32(&mut b, 380, 1.0); // taper
    put_f64(&mut b, 552, 1.0);
    let (lo, hi) = (root.lo, root.hi);
    let mut world = [DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)];
    for corner in 0..8 {
        let pick =
            |bit: i32, a: i32, z: i32| if corner & bit == 0 { a as f64 } else { z as f64 + 1.0 };
        let p = apply_fma(
            &grid.map,
            DVec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z)),
        );
        world = [world[0].min(p), world[1].max(p)];
    }
    for (i, x) in world[0].to_array().into_iter().chain(world[1].to_array()).enumerate() {
        put_f64(&mut b, 560 + 8 * i, x);
    }
    let voxel_size = grid.map.voxel_size();
    for (i, x) in voxel_size.to_array().into_iter().enumerate() {
        put_f64(&mut b, 608 + 8 * i, x);
    }
    put_u32(&mut b, 632, grid.class.code());
    put_u32(&mut b, 636, T::GRID_TYPE.code());
    // Blind metadata offset and count, and the three spare words, stay 0.

    // Tree: offsets from the tree to the first leaf, lower, upper node and the root.
    let tree = GRID_BYTES;
    put_u64(&mut b, tree, (leaf_at - tree) as u64);
    put_u64(&mut b, tree + 8, (lower_at - tree) as u64);
    put_u64(&mut b, tree + 16, (upper_at - tree) as u64);
    put_u64(&mut b, tree + 24, (root_at - tree) as u64);
    let nodes = [leaves.len() as u32, lowers.len() as u32, uppers.len() as u32];
    for (i, n) in nodes.iter().enumerate() {
        put_u32(&mut b, tree + 32 + 4 * i, *n);
    }
    // Active tile counts (tree + 44..56) stay 0.
    put_u64(&mut b, tree + 56, root.n);

    // Root and its tiles.
    root.put_bbox(&mut b, root_at);
    put_u32(&mut b, root_at + 24, uppers.len() as u32);
    grid.background.put(&mut b[root_at + 28..]);
    root.put(&mut b, root_at + 28 + T::SIZE);
    for (i, up) in uppers.iter().enumerate() {
        let at = root_at + sz.root + TILE_BYTES * i;
        put_u64(&mut b, at, root_key(up.origin));
        put_i64(&mut b, at + 8, (upper_at + i * sz.upper - root_at) as i64);
    }

    // Internal nodes.
    let write_internal = |b: &mut [u8],
                          at: usize,
                          node: &Internal<T>,
                          level: usize,
                          child_at: usize,
                          child_size: usize| {
        let (log2, table) = if level == 0 { (5, sz.upper_table) } else { (4, sz.lower_table) };
        let n = 1usize << (3 * log2);
        node.stats.put_bbox(b, at);
        put_u64(b, at + 24, NODE_HAS_BBOX as u64);
        let child_mask = at + 32 + n / 8;
        let stats = at + Sizes::internal_stats(log2);
        node.stats.put(b, stats);
        if grid.background != T::ZERO {
            for e in 0..n {
                grid.background.put(&mut b[at + table + e * sz.entry..]);
            }
        }
        for &(e, c) in &node.children {
            let e = e as usize;
            b[child_mask + 8 * (e / 64) + (e % 64) / 8] |= 1 << (e % 8);
            let entry = at + table + e * sz.entry;
            b[entry..entry + sz.entry].fill(0);
            put_i64(b, entry, (child_at + c * child_size - at) as i64);
        }
    };
    for (i, up) in uppers.iter().enumerate() {
        write_internal(&mut b, upper_at + i * sz.upper, up, 0, lower_at, sz.lower);
    }
    for (i, low) in lowers.iter().enumerate() {
        write_internal(&mut b, lower_at + i * sz.lower, low, 1, leaf_at, sz.leaf);
    }

    // Leaves.
    for (i, leaf) in leaves.iter().enumerate() {
        let at = leaf_at + i * sz.leaf;
        let (lo, hi) = (leaf.stats.lo, leaf.stats.hi);
        debug_assert_eq!(lo & IVec3::splat(!7), leaf.origin);
        put_ivec3(&mut b, at, lo);
        let dif = hi - lo;
        b[at + 12..at + 15].copy_from_slice(&[dif.x as u8, dif.y as u8, dif.z as u8]);
        b[at + 15] = NODE_HAS_BBOX as u8;
        for (w, word) in leaf.mask.iter().enumerate() {
            put_u64(&mut b, at + 16 + 8 * w, *word);
        }
        leaf.stats.put(&mut b, at + 80);
        let values = at + sz.leaf_values;
        if grid.background != T::ZERO {
            for e in 0..512 {
                grid.background.put(&mut b[values + e * T::SIZE..]);
            }
        }
        for &(e, v) in &leaf.values {
            v.put(&mut b[values + e as usize * T::SIZE..]);
        }
    }

    let checksum = checksum(
        &b,
        root_end,
        &[
            (upper_at, sz.upper, uppers.len()),
            (lower_at, sz.lower, lowers.len()),
            (leaf_at, sz.leaf, leaves.len()),
        ],
    );
    put_u64(&mut b, 8, checksum);
    Ok(Built {
        summary: GridSummary {
            name: grid.name.clone(),
            grid_type: T::GRID_TYPE,
            voxels: root.n,
            nodes: [nodes[0], nodes[1], nodes[2], uppers.len() as u32],
            bytes: total as u64,
            checksum,
        },
        bytes: b,
        name: grid.name.clone(),
        class: grid.class.code(),
        grid_type: T::GRID_TYPE.code(),
        world_bbox: world,
        index_bbox: [lo, hi],
        voxel_size,
        nodes,
    })
}

/// `map` applied as NanoVDB's `Map::applyMap` does it (fused multiply-adds, row by row), so the
/// world bbox rounds as NanoVDB's own `GridStats` rounds it.
fn apply_fma(map: &super::IndexToWorld, ijk: DVec3) -> DVec3 {
    let (m, t) = (map.matrix, map.translation);
    DVec3::from_array(std::array::from_fn(|r| {
        let row = m.row(r);
        ijk.x.mul_add(row.x, ijk.y.mul_add(row.y, ijk.z.mul_add(row.z, t[r])))
    }))
}

/// The root key of the upper node at `origin`: 21 bits per axis of `coordinate >> 12`, x
/// highest.
pub(super) fn root_key(origin: IVec3) -> u64 {
    let k = |x: i32| ((x as u32) >> TOTAL[0]) as u64;
    (k(origin.z)) | (k(origin.y) << 21) | (k(origin.x) << 42)
}

/// NanoVDB's full checksum of grid bytes `b` (see the module docs): the CRC-32 of `b[16..
/// root_end]` low, the CRC-32 of the nodes' CRC-32s (as 64-bit words) high. `levels`: first
/// offset, node size and count of the upper, lower and leaf nodes.
pub(super) fn checksum(b: &[u8], root_end: usize, levels: &[(usize, usize, usize); 3]) -> u64 {
    let head = crc32fast::hash(&b[16..root_end]);
    let count: usize = levels.iter().map(|l| l.2).sum();
    if count == 0 {
        return head as u64 | (0xffff_ffffu64 << 32);
    }
    let mut tail = crc32fast::Hasher::new();
    for &(at, size, n) in levels {
        for i in 0..n {
            let node = at + i * size;
            tail.update(&(crc32fast::hash(&b[node..node + size]) as u64).to_le_bytes());
        }
    }
    head as u64 | ((tail.finalize() as u64) << 32)
}

fn validate<T: NvdbValue>(grid: &NvdbGrid<T>) -> Result<()> {
    let name = &grid.name;
    if name.len() > MAX_NAME_BYTES || name.contains('\0') {
        return Err(unrepresentable(
            format!("the grid name {name:?} ({} bytes)", name.len()),
            format!("NanoVDB grid names have at most {MAX_NAME_BYTES} bytes and no NUL"),
        ));
    }
    if grid.voxels.is_empty() {
        return Err(unrepresentable(
            format!("grid {name:?} with no active voxel"),
            "an empty grid has no bounding box; NanoVDB's tools refuse it".into(),
        ));
    }
    grid.map.validate()?;
    if !grid.background.is_finite() {
        return Err(unrepresentable(
            format!("the background {:?} of grid {name:?}", grid.background),
            "VDB values written here are finite".into(),
        ));
    }
    for &(c, v) in &grid.voxels {
        if c.cmpgt(IVec3::splat(MAX_INDEX)).any() || c.cmplt(IVec3::splat(-MAX_INDEX)).any() {
            return Err(unrepresentable(
                format!("voxel {c} of grid {name:?}"),
                format!("index coordinates are limited to ±{MAX_INDEX} (i32 node arithmetic)"),
            ));
        }
        if !v.is_finite() {
            return Err(unrepresentable(
                format!("value {v:?} at voxel {c} of grid {name:?}"),
                "VDB values written here are finite".into(),
            ));
        }
    }
    Ok(())
}

/// Writes one segment: header, metadata records, grids.
pub(super) fn write_file(out: &mut Vec<u8>, grids: &[Built]) {
    let mut h = [0u8; HEADER_BYTES];
    put_u64(&mut h, 0, MAGIC);
    put_u32(&mut h, 8, VERSION);
    h[12..14].copy_from_slice(&(grids.len() as u16).to_le_bytes());
    // codec (14..16) = 0: none.
    out.extend_from_slice(&h);
    for g in grids {
        let mut m = [0u8; META_BYTES];
        let size = g.bytes.len() as u64;
        put_u64(&mut m, 0, size); // in memory
        put_u64(&mut m, 8, size); // on disk, uncompressed
        put_u64(&mut m, 16, name_hash(&g.name));
        put_u64(&mut m, 24, g.summary.voxels);
        put_u32(&mut m, 32, g.grid_type);
        put_u32(&mut m, 36, g.class);
        for (i, x) in
            g.world_bbox[0].to_array().into_iter().chain(g.world_bbox[1].to_array()).enumerate()
        {
            put_f64(&mut m, 40 + 8 * i, x);
        }
        put_ivec3(&mut m, 88, g.index_bbox[0]);
        put_ivec3(&mut m, 100, g.index_bbox[1]);
        for (i, x) in g.voxel_size.to_array().into_iter().enumerate() {
            put_f64(&mut m, 112 + 8 * i, x);
        }
        put_u32(&mut m, 136, g.name.len() as u32 + 1);
        for (i, n) in g.nodes.iter().chain(&[1]).enumerate() {
            put_u32(&mut m, 140 + 4 * i, *n);
        }
        // tile counts (156..168) = 0, codec (168) = 0, padding (170) = 0.
        put_u32(&mut m, 172, VERSION);
        out.extend_from_slice(&m);
        out.extend_from_slice(g.name.as_bytes());
        out.push(0);
    }
    for g in grids {
        out.extend_from_slice(&g.bytes);
    }
}

pub(super) fn put_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}
pub(super) fn put_u64(b: &mut [u8], at: usize, v: u64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}
fn put_i64(b: &mut [u8], at: usize, v: i64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}
fn put_f32(b: &mut [u8], at: usize, v: f32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}
fn put_f64(b: &mut [u8], at: usize, v: f64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}
fn put_ivec3(b: &mut [u8], at: usize, v: IVec3) {
    for (i, x) in v.to_array().into_iter().enumerate() {
        b[at + 4 * i..at + 4 * i + 4].copy_from_slice(&x.to_le_bytes());
    }
}
