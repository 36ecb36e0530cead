//! Conservative bounds that end walks early without changing what they meet: where on screen
//! and how far along a camera ray a voxel with a record can lie ([`ScreenTiles`], per brick), and
//! how far a shadow ray toward a directional light can still meet one ([`LightBounds`], per
//! voxel).
//!
//! Both only shorten a walk's `t_max` (or skip a ray that meets no allocated brick at all), so
//! every voxel a walk visits before its end is visited with bit-identical `t` values: the
//! image is the one of unbounded walks.

use glam::{DVec2, DVec3, Vec2, Vec3};
use rayon::prelude::*;
use voxlod_format::{BRICK_EDGE, BrickMap, GridSpec, morton};
use voxlod_scene::camera::CameraFrame;

/// Pixel edge of a screen tile.
pub(super) const TILE: u32 = 8;

/// Extra length, in voxel sizes, added to every bound (float rounding of the walks' `t`).
const MARGIN_VOXELS: f64 = 2.0;

/// The world-space corners of the allocated bricks of `map`, relative to the grid origin.
fn brick_boxes<'a, T>(
    map: &'a BrickMap<T>,
    grid: &'a GridSpec,
) -> impl Iterator<Item = [DVec3; 8]> + 'a {
    let edge = BRICK_EDGE as f64 * grid.voxel_size;
    map.bricks().iter().map(move |h| {
        let lo = morton::decode(h.morton).as_dvec3() * edge;
        std::array::from_fn(|i| {
            lo + DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2 & 1) as f64) * edge
        })
    })
}

/// Per 8×8-pixel tile of one frame: whether a camera ray through it can meet an allocated
/// brick (the tile overlaps, with a pixel of margin, the screen bounding box of a brick's
/// projected corners), and the farthest distance from the eye of such a brick's corners.
/// A brick wholly at or behind the eye plane covers no tile; one with only some corners there
/// covers every tile with an infinite distance.
pub(super) struct ScreenTiles {
    columns: u32,
    /// Per tile: the walk's `t_max`, or a negative value where no brick projects.
    t_max: Vec<f32>,
}

impl ScreenTiles {
    /// The tiles of `frame` over the allocated bricks of `map`.
    pub fn new<T>(frame: &CameraFrame, map: &BrickMap<T>, grid: &GridSpec) -> Self {
        let columns = frame.width.div_ceil(TILE);
        let rows = frame.height.div_ceil(TILE);
        let mut t_max = vec![-1.0f32; (columns * rows) as usize];
        let margin = MARGIN_VOXELS * grid.voxel_size;
        let eye = frame.eye.as_dvec3() - grid.origin;
        for corners in brick_boxes(map, grid) {
            let (mut lo, mut hi, mut far) = (Vec2::INFINITY, Vec2::NEG_INFINITY, 0.0f64);
            let (mut behind, mut unprojected) = (0, 0);
            for c in corners {
                far = far.max((c - eye).length());
                let world = (c + grid.origin).as_vec3();
                match frame.project(world) {
                    Some((p, _)) if p.is_finite() => {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                    Some(_) => unprojected += 1,
                    None => behind += 1,
                }
            }
            // Camera rays only go forward (positive depth): a brick wholly behind the eye plane
            // is never met; one that straddles it may be met anywhere on screen.
            if behind == 8 {
                continue;
            }
            let far = (far * (1.0 + 1e-6) + margin) as f32;
            if behind + unprojected > 0 {
                t_max.iter_mut().for_each(|t| *t = f32::INFINITY);
                break;
            }
            // Pixels [lo − 1, hi + 1], clamped to the image; nothing if the box is off screen.
            let (w, h) = (frame.width as f32 - 1.0, frame.height as f32 - 1.0);
            let (a, b) = ((lo - 1.0).max(Vec2::ZERO), (hi + 1.0).min(Vec2::new(w, h)));
            if a.x > b.x || a.y > b.y {
                continue;
            }
            let (a, b) = (a.as_uvec2() / TILE, b.as_uvec2() / TILE);
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    let t = &mut t_max[(y * columns + x) as usize];
                    *t = t.max(far);
                }
            }
        }
        Self { columns, t_max }
    }

    /// The `t_max` of the camera rays of pixel `(x, y)`, `None` if they meet no brick.
    #[inline]
    pub fn t_max(&self, x: u32, y: u32) -> Option<f32> {
        let t = self.t_max[((y / TILE) * self.columns + x / TILE) as usize];
        (t >= 0.0).then_some(t)
    }
}

/// For a directional light: in the plane perpendicular to the light, a grid of square cells
/// (one voxel wide, or wider so that there are at most [`MAX_LIGHT_CELLS`] per side), each
/// holding at least the largest height toward the light (`w = p·l`, grid-origin relative) of
/// the voxels with a record whose projected box overlaps it: the largest top of the voxels
/// whose centres project within one cell of it (a superset, built by one write per voxel and
/// a 3×3 max filter). A shadow ray keeps its `(u, v)` and gains height at rate 1, so it leaves
/// the last voxel it can meet at that height: past it (plus half a voxel of margin for float
/// rounding) it meets nothing, and that is its `t_max`.
#[derive(Clone, Debug)]
pub(super) struct LightBounds {
    /// Unit direction toward the light and the plane basis.
    l: DVec3,
    e1: DVec3,
    e2: DVec3,
    lo: DVec2,
    /// 1 / the cell edge.
    inv_cell: f64,
    dims: [u32; 2],
    /// Largest height per cell (`−∞` where no voxel projects).
    top: Vec<f32>,
    margin: f64,
}

/// Largest number of cells per side of a [`LightBounds`] map (4 MiB of heights).
pub(super) const MAX_LIGHT_CELLS: u32 = 1024;

impl LightBounds {
    /// The bounds of `map`'s voxels for the light direction `to_light`.
    pub fn new<T>(to_light: Vec3, map: &BrickMap<T>, grid: &GridSpec) -> Self {
        let s = grid.voxel_size;
        let l = to_light.as_dvec3().normalize();
        let e1 = l.any_orthonormal_vector();
        let e2 = l.cross(e1);
        let size = grid.dims.as_dvec3() * s;
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for i in 0..8 {
            let c = DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2 & 1) as f64) * size;
            let p = DVec2::new(c.dot(e1), c.dot(e2));
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let cell = s.max((hi - lo).max_element() / MAX_LIGHT_CELLS as f64 * (1.0 + 1e-9));
        lo -= cell;
        let dims = ((hi + cell - lo) / cell).ceil().as_uvec2().max(glam::UVec2::ONE);
        let n = (dims.x * dims.y) as usize;
        // A voxel's projected box and top: its centre's, plus half the projected cube. The box
        // of a voxel whose centre lies in cell q reaches at most `k = ⌈r/cell⌉` cells from q
        // per axis (⌊a + b⌋ ≤ ⌊a⌋ + ⌈b⌉), and `r ≤ √3·s/2 < cell`, so k is 1.
        let half = |a: DVec3| 0.5 * s * a.abs().element_sum();
        let (h1, h2, hw) = (half(e1), half(e2), half(l));
        let r = DVec2::new(h1, h2) + cell * 1e-3;
        let reach = (r / cell).ceil().as_uvec2();
        // Each voxel's top into the cell of its centre (the cell `t_max` looks up; the two
        // compute the centre's projection in different orders, which `r`'s 10⁻³-cell slack
        // covers; the truncation of `as u32` is the floor of these non-negative values), then
        // the largest top within `reach` cells: a superset of the cells each projected box
        // overlaps, so the bound stays conservative.
        let mut top = vec![f32::NEG_INFINITY; n];
        let inv_cell = cell.recip();
        // Per brick, its corner's (u, v, w); per local Morton code, the offset of that voxel's
        // centre: one addition per coordinate and voxel instead of a Morton decode and three
        // dot products.
        let project = |p: DVec3| DVec3::new(p.dot(e1), p.dot(e2), p.dot(l));
        let local: Vec<DVec3> =
            (0..512u64).map(|i| project((morton::decode(i).as_dvec3() + 0.5) * s)).collect();
        for h in map.bricks() {
            let corner = project((morton::decode(h.morton) * BRICK_EDGE).as_dvec3() * s);
            for (w, &word) in h.mask.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let p = corner + local[w * 64 + bits.trailing_zeros() as usize];
                    bits &= bits - 1;
                    let q = ((DVec2::new(p.x, p.y) - lo) * inv_cell).as_uvec2().min(dims - 1);
                    let t = &mut top[(q.y * dims.x + q.x) as usize];
                    *t = t.max((p.z + hw) as f32);
                }
            }
        }
        let top = dilate(&top, [dims.x, dims.y], [reach.x, reach.y]);
        let margin = 0.5 * s + 1e-6 * size.length();
        Self { l, e1, e2, lo, inv_cell, dims: [dims.x, dims.y], top, margin }
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.top.capacity() * size_of::<f32>()
    }

    /// The `t_max` of the shadow ray from the centre of voxel `voxel` (negative: it meets
    /// nothing).
    #[inline]
    pub fn t_max(&self, grid: &GridSpec, voxel: glam::UVec3) -> f32 {
        let p = (voxel.as_dvec3() + 0.5) * grid.voxel_size;
        let c = (DVec2::new(p.dot(self.e1), p.dot(self.e2)) - self.lo) * self.inv_cell;
        // Outside the map iff its floor is; inside, truncation is the floor.
        if !(c.x >= 0.0 && c.y >= 0.0 && c.x < self.dims[0] as f64 && c.y < self.dims[1] as f64) {
            return -1.0;
        }
        let top = self.top[(c.y as u32 * self.dims[0] + c.x as u32) as usize];
        (top as f64 - p.dot(self.l) + self.margin) as f32
    }
}

/// The largest value within `reach[0]` columns and `reach[1]` rows of each cell of the
/// row-major `dims` map `top` (a separable max filter: rows, then columns, in parallel).
fn dilate(top: &[f32], dims: [u32; 2], reach: [u32; 2]) -> Vec<f32> {
    let (w, h) = (dims[0] as usize, dims[1] as usize);
    let (kx, ky) = (reach[0] as usize, reach[1] as usize);
    let mut rows = vec![f32::NEG_INFINITY; top.len()];
    rows.par_chunks_mut(w).zip(top.par_chunks(w)).for_each(|(out, row)| {
        for (x, o) in out.iter_mut().enumerate() {
            *o = row[x.saturating_sub(kx)..(x + kx + 1).min(w)].iter().fold(*o, |a, &b| a.max(b));
        }
    });
    let mut out = vec![f32::NEG_INFINITY; top.len()];
    out.par_chunks_mut(w).enumerate().for_each(|(y, out)| {
        for row in rows[y.saturating_sub(ky) * w..(y + ky + 1).min(h) * w].chunks(w) {
            out.iter_mut().zip(row).for_each(|(o, &v)| *o = o.max(v));
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec3};

    use super::*;

    /// A floor at y = 1 over a 32 × 16 × 32 grid, and a plate at y = 10 over x, z < 8.
    fn floor_and_plate() -> (GridSpec, BrickMap<()>) {
        let grid = GridSpec::new(DVec3::new(5.0, -3.0, 2.0), 0.5, UVec3::new(32, 16, 32)).unwrap();
        let mut v = Vec::new();
        for x in 0..32 {
            for z in 0..32 {
                v.push((UVec3::new(x, 1, z), ()));
                if x < 8 && z < 8 {
                    v.push((UVec3::new(x, 10, z), ()));
                }
            }
        }
        (grid, BrickMap::from_voxels(grid.dims, v).unwrap())
    }

    #[test]
    fn shadow_rays_end_just_past_the_highest_voxel_above_them() {
        let (grid, map) = floor_and_plate();
        let up = LightBounds::new(Vec3::Y, &map, &grid);
        // In voxels: the floor's own top is 0.5 above its centre, plus the 0.5 margin.
        let open = up.t_max(&grid, UVec3::new(20, 1, 20)) / 0.5;
        assert!((open - 1.0).abs() < 1e-3, "{open}");
        let covered = up.t_max(&grid, UVec3::new(3, 1, 4)) / 0.5;
        assert!((covered - 10.0).abs() < 1e-3, "{covered}");
        // Slanted light: the ray from (12, 1, 6) meets the plate 9 voxels up, at t = 9/l_y
        // voxels; the one from (20, 1, 20) meets nothing but its neighbours in the floor.
        let l = Vec3::new(-1.0, 1.0, -0.3).normalize();
        let slanted = LightBounds::new(l, &map, &grid);
        let t = slanted.t_max(&grid, UVec3::new(12, 1, 6)) / 0.5;
        // Conservative by up to a cell, a projected voxel and the margin.
        assert!(t > 9.0 / l.y && t < 9.0 / l.y + 4.0, "{t}");
        let t = slanted.t_max(&grid, UVec3::new(20, 1, 20)) / 0.5;
        assert!(t < 3.0, "{t}");
    }

    #[test]
    fn shadow_rays_meet_no_voxel_past_their_bound() {
        // Uneven columns with holes, at a scale and origin far from 1 and 0.
        let dims = UVec3::new(30, 24, 27);
        let voxels = (0..dims.x).flat_map(|x| {
            (0..dims.z).flat_map(move |z| {
                let h = (x * 7 + z * 13) % 23;
                (0..dims.y)
                    .filter(move |&y| y <= h && (x + y + z) % 3 != 0)
                    .map(move |y| (UVec3::new(x, y, z), ()))
            })
        });
        let map = BrickMap::from_voxels(dims, voxels).unwrap();
        let grid = GridSpec::new(DVec3::new(-1.0, 2.0, 0.5), 0.25, dims).unwrap();
        let mut met = 0;
        for l in [Vec3::new(0.3, 0.9, -0.4), Vec3::Y, Vec3::new(-1.0, 0.2, 1.0), Vec3::NEG_X] {
            let l = l.normalize();
            let bounds = LightBounds::new(l, &map, &grid);
            for c in map.coords().step_by(5) {
                let t_max = bounds.t_max(&grid, c);
                let centre = c.as_vec3() + 0.5;
                let d = l / grid.voxel_size as f32;
                let walk = crate::render::dda::Dda::in_grid_space(dims, centre, d, 0.0, f32::MAX);
                for v in walk.filter(|v| map.get(v.voxel).is_some() && v.voxel != c) {
                    assert!(v.t_enter < t_max, "{c} meets {} at {} > {t_max}", v.voxel, v.t_enter);
                    met += 1;
                }
            }
        }
        assert!(met > 1000, "too few voxels met to mean anything: {met}");
    }

    #[test]
    fn dilation_takes_the_largest_value_within_reach() {
        let (w, h) = (7usize, 5usize);
        let top: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32 - 5.0).collect();
        for reach in [[0, 0], [1, 1], [2, 1], [0, 3]] {
            let got = dilate(&top, [w as u32, h as u32], reach);
            for y in 0..h {
                for x in 0..w {
                    let mut want = f32::NEG_INFINITY;
                    for yy in
                        y.saturating_sub(reach[1] as usize)..(y + reach[1] as usize + 1).min(h)
                    {
                        for xx in
                            x.saturating_sub(reach[0] as usize)..(x + reach[0] as usize + 1).min(w)
                        {
                            want = want.max(top[yy * w + xx]);
                        }
                    }
                    assert_eq!(got[y * w + x], want, "{x} {y} {reach:?}");
                }
            }
        }
    }

    #[test]
    fn screen_tiles_cover_the_projected_bricks_only() {
        let (grid, map) = floor_and_plate();
        let centre = Vec3::new(13.0, -2.0, 10.0);
        let cam = voxlod_scene::Camera::look_at(Vec3::new(13.0, 30.0, 10.0), centre, Vec3::Z, 30.0);
        let frame = cam.frame(64, 64);
        let tiles = ScreenTiles::new(&frame, &map, &grid);
        // Straight down onto the floor: the central tiles are covered, to a finite depth
        // beyond the floor's distance; a camera looking away covers nothing.
        let t = tiles.t_max(32, 32).expect("covered");
        assert!(t > 30.0 && t < 40.0, "{t}");
        let away = voxlod_scene::Camera::look_at(cam.eye, cam.eye + Vec3::Y, Vec3::Z, 30.0);
        let none = ScreenTiles::new(&away.frame(64, 64), &map, &grid);
        assert!((0..64).all(|y| (0..64).all(|x| none.t_max(x, y).is_none())));
    }
}
