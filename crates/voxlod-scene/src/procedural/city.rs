//! `city`: a grid of city blocks — buildings of varied heights whose facades carry recessed
//! windows as real geometry, streets with dashed markings, raised sidewalks, lamp posts,
//! benches and parked cars — in the spirit of the City test scene of Brito, Poulin and
//! Teichrieb 2023 (§5, Table 2: 635 k triangles).
//!
//! What it stresses: facades are large occluders whose window recesses (0.3 m deep, about a
//! voxel or less at 128³ over a few blocks) put two parallel surfaces of different colours
//! (wall, dark specular glass) and four jambs in one voxel — direction-dependent colour and
//! opacity on an otherwise flat surface; the props are small closed boxes and thin poles below
//! a voxel; streets are large flat areas with thin bright markings.
//!
//! Layout: `blocks × blocks` square blocks of side `block_size` separated (and surrounded) by
//! streets of width `street_width`; each block is a sidewalk slab 0.15 m high with 2 or 3 × 2 or
//! 3 building lots (jittered) inside a 3 m wide walkway, one building per lot with 2 to
//! `max_floors` floors of 3.2 m (skewed towards low buildings, a few towers), a flat roof and,
//! on half of them, a rooftop box. Every facade is divided into bays of about `window_spacing`
//! per floor; `detail` sets what a bay is:
//! - 0: no windows: a building is a box of plain walls (10 triangles);
//! - 1: each bay is a window recess: wall around it (4 quads), four jambs and the glass
//!   (18 triangles);
//! - 2: as 1, with a protruding sill and a mullion in every window (34 triangles).
//!
//! The random layout depends on the seed, `blocks`, the sizes and `max_floors` only, not on
//! `window_spacing` or `detail`, so [`CityParams::fit_triangles`] sizes a city by its blocks
//! and bay width. The triangle count is exact ([`CityParams::triangle_count`]). Buildings are
//! closed boxes as surfaces but not as meshes: bays meet without gaps, with T-junctions at the
//! roof. Units are metres; the streets lie in y = 0, centred at the origin.

use glam::Vec3;

use super::builder::{MeshBuilder, Tube};
use super::param::{check_f32, check_triangles, check_u32};
use super::rng::Rng;
use super::{SKY, framing, sun};
use crate::{Material, Result, Scene};

/// Parameters of [`city`].
#[derive(Clone, Debug, PartialEq)]
pub struct CityParams {
    /// Blocks per side, 1..=64. Default 3.
    pub blocks: u32,
    /// Random seed: same seed and parameters, same scene, bit for bit. Default 1.
    pub seed: u64,
    /// Facade detail, 0..=2 (see the module docs). Default 1.
    pub detail: u32,
    /// Side of a block including its sidewalk, 16..=1000 m. Default 48.
    pub block_size: f32,
    /// Street width between blocks, 4..=100 m. Default 12.
    pub street_width: f32,
    /// Most floors of a building, 2..=200. Default 16.
    pub max_floors: u32,
    /// Width of a facade bay (one window per floor), 1..=50 m. Default 2.5.
    pub window_spacing: f32,
}

impl Default for CityParams {
    fn default() -> Self {
        Self {
            blocks: 3,
            seed: 1,
            detail: 1,
            block_size: 48.0,
            street_width: 12.0,
            max_floors: 16,
            window_spacing: 2.5,
        }
    }
}

/// Floor height in metres.
const FLOOR: f32 = 3.2;
/// Sidewalk walkway width inside a block, and slab height.
const WALKWAY: f32 = 3.0;
const CURB: f32 = 0.15;
/// Window recess depth.
const RECESS: f32 = 0.3;
/// Spacing of lamp posts along a block's edge, of parking slots, and of street dashes.
const LAMP_SPACING: f32 = 16.0;
const CAR_SLOT: f32 = 6.0;
const DASH_PERIOD: f32 = 6.0;
/// Triangles of the props: lamp (6-sided pole + head box), bench (4 boxes), car (body and cabin
/// without bottoms, 4 wheel boxes), sidewalk slab (no bottom), dash, rooftop box (no bottom).
const LAMP_TRIANGLES: u64 = Tube::triangle_count(6, 1) + 12;
const BENCH_TRIANGLES: u64 = 4 * 12;
const CAR_TRIANGLES: u64 = 2 * 10 + 4 * 12;
const SLAB_TRIANGLES: u64 = 10;
const ROOF_BOX_TRIANGLES: u64 = 10;

/// One building: footprint `[lo.x, hi.x] × [lo.z, hi.z]` on the sidewalk, `floors` floors.
#[derive(Clone, Debug, PartialEq)]
struct Building {
    lo: Vec3,
    hi: Vec3,
    floors: u32,
    facade: usize,
    roof_box: Option<(Vec3, Vec3)>,
}

/// A parked car: centre on the street, along x (`along_x`) or z, paint index.
#[derive(Clone, Debug, PartialEq)]
struct Car {
    center: Vec3,
    along_x: bool,
    paint: usize,
}

/// Everything random about a city; window spacing and detail are applied when building.
#[derive(Clone, Debug, Default, PartialEq)]
struct Layout {
    extent: f32,
    blocks: Vec<(f32, f32)>,
    buildings: Vec<Building>,
    lamps: Vec<(Vec3, Vec3)>,
    benches: Vec<(Vec3, bool)>,
    cars: Vec<Car>,
    dashes: Vec<(Vec3, bool)>,
}

/// Random-stream tags.
const STREAM_BLOCK: u64 = 1;
const STREAM_CARS: u64 = 2;

impl CityParams {
    /// Checks every field against its documented range, and the total size.
    pub fn validate(&self) -> Result<()> {
        check_u32("city", "blocks", self.blocks, 1, 64)?;
        check_u32("city", "detail", self.detail, 0, 2)?;
        check_f32("city", "block_size", self.block_size, 16.0, 1000.0)?;
        check_f32("city", "street_width", self.street_width, 4.0, 100.0)?;
        check_u32("city", "max_floors", self.max_floors, 2, 200)?;
        check_f32("city", "window_spacing", self.window_spacing, 1.0, 50.0)?;
        check_triangles("city", self.triangle_count())
    }

    /// Side of the whole city, streets around it included.
    pub fn extent(&self) -> f32 {
        self.blocks as f32 * self.block_size + (self.blocks + 1) as f32 * self.street_width
    }

    /// The exact number of triangles [`city`] generates.
    pub fn triangle_count(&self) -> u64 {
        self.count(&self.layout())
    }

    fn count(&self, l: &Layout) -> u64 {
        let ground = 2 * self.ground_cells() as u64 * self.ground_cells() as u64;
        let buildings: u64 = l.buildings.iter().map(|b| self.building_triangles(b)).sum();
        ground
            + SLAB_TRIANGLES * l.blocks.len() as u64
            + buildings
            + LAMP_TRIANGLES * l.lamps.len() as u64
            + BENCH_TRIANGLES * l.benches.len() as u64
            + CAR_TRIANGLES * l.cars.len() as u64
            + 2 * l.dashes.len() as u64
    }

    fn ground_cells(&self) -> u32 {
        4 * self.blocks
    }

    /// Bays of a facade `width` wide.
    fn bays(&self, width: f32) -> u32 {
        ((width / self.window_spacing) as u32).max(1)
    }

    fn building_triangles(&self, b: &Building) -> u64 {
        let roof = 2 + if b.roof_box.is_some() { ROOF_BOX_TRIANGLES } else { 0 };
        let size = b.hi - b.lo;
        let bays = 2 * (self.bays(size.x) + self.bays(size.z)) as u64;
        let per_window = match self.detail {
            0 => return 8 + roof,
            1 => 18,
            _ => 34,
        };
        roof + per_window * bays * b.floors as u64
    }

    /// This city resized to at least `target` triangles: the fewest blocks whose count at the
    /// current bay width reaches it, then the widest bays (at least the current width, at most
    /// 50 m) that still reach it. The layout keeps its seed; only blocks and bay width change.
    /// Targets beyond 64 blocks give 64 blocks.
    pub fn fit_triangles(mut self, target: u64) -> Self {
        let mut layout = self.layout();
        while self.count(&layout) < target && self.blocks < 64 {
            self.blocks += 1;
            layout = self.layout();
        }
        let (mut lo, mut hi) = (self.window_spacing, 50.0f32);
        let at = |s: f32| Self { window_spacing: s, ..self.clone() }.count(&layout);
        if at(lo) < target {
            return self;
        }
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if at(mid) >= target { lo = mid } else { hi = mid }
        }
        self.window_spacing = lo;
        self
    }

    /// The random layout (independent of window spacing and detail).
    fn layout(&self) -> Layout {
        let (bs, sw) = (self.block_size, self.street_width);
        let extent = self.extent();
        let half = 0.5 * extent;
        let mut l = Layout { extent, ..Default::default() };
        let pitch = bs + sw;
        for j in 0..self.blocks {
            for i in 0..self.blocks {
                let x0 = -half + sw + i as f32 * pitch;
                let z0 = -half + sw + j as f32 * pitch;
                l.blocks.push((x0, z0));
                let mut rng = Rng::stream(self.seed, &[STREAM_BLOCK, (j * self.blocks + i) as u64]);
                self.block(&mut rng, x0, z0, &mut l);
            }
        }
        // Dashes along every street's centre line, both directions.
        let dashes = (extent / DASH_PERIOD) as u32;
        for k in 0..=self.blocks {
            let c = -half + k as f32 * pitch + 0.5 * sw;
            for d in 0..dashes {
                let s = -half + (d as f32 + 0.5) * DASH_PERIOD;
                l.dashes.push((Vec3::new(c, 0.0, s), false));
                l.dashes.push((Vec3::new(s, 0.0, c), true));
            }
        }
        // Parked cars: a slot every 6 m along both kerbs of every street segment, a third full.
        let mut rng = Rng::stream(self.seed, &[STREAM_CARS]);
        let slots = ((bs - 4.0) / CAR_SLOT) as u32;
        for k in 0..=self.blocks {
            let c = -half + k as f32 * pitch + 0.5 * sw;
            for seg in 0..self.blocks {
                let s0 = -half + sw + seg as f32 * pitch + 2.0;
                for side in [-1.0f32, 1.0] {
                    let lane = c + side * (0.5 * sw - 1.4);
                    for along_x in [false, true] {
                        for slot in 0..slots {
                            if rng.next_f32() > 0.35 {
                                continue;
                            }
                            let s = s0 + (slot as f32 + 0.5) * CAR_SLOT;
                            let center = if along_x {
                                Vec3::new(s, 0.0, lane)
                            } else {
                                Vec3::new(lane, 0.0, s)
                            };
                            l.cars.push(Car { center, along_x, paint: rng.below(5) as usize });
                        }
                    }
                }
            }
        }
        l
    }

    /// One block's buildings, lamps and benches.
    fn block(&self, rng: &mut Rng, x0: f32, z0: f32, l: &mut Layout) {
        let bs = self.block_size;
        let inner = bs - 2.0 * WALKWAY;
        let splits = |rng: &mut Rng| -> Vec<f32> {
            let n = 2 + rng.below(2);
            let mut cuts = vec![0.0];
            for k in 1..n {
                let jitter = rng.range(-0.15, 0.15) / n as f32;
                cuts.push((k as f32 / n as f32 + jitter) * inner);
            }
            cuts.push(inner);
            cuts
        };
        let (xs, zs) = (splits(rng), splits(rng));
        for w in zs.windows(2) {
            for v in xs.windows(2) {
                let gap = rng.range(0.6, 2.0);
                let lo = Vec3::new(x0 + WALKWAY + v[0] + gap, CURB, z0 + WALKWAY + w[0] + gap);
                let hi = Vec3::new(x0 + WALKWAY + v[1] - gap, CURB, z0 + WALKWAY + w[1] - gap);
                let u = rng.next_f32();
                let floors = 2 + ((self.max_floors - 2) as f32 * u * u * u).round() as u32;
                let facade = rng.below(4) as usize;
                let roof_box = (rng.next_f32() < 0.5).then(|| {
                    let size = hi - lo;
                    let half = Vec3::new(0.15 * size.x, 1.0, 0.15 * size.z);
                    let top = CURB + floors as f32 * FLOOR;
                    let c = Vec3::new(
                        lo.x + size.x * rng.range(0.3, 0.7),
                        top + half.y,
                        lo.z + size.z * rng.range(0.3, 0.7),
                    );
                    (c, half)
                });
                l.buildings.push(Building { lo, hi, floors, facade, roof_box });
            }
        }
        // Lamp posts along the four edges of the block, 0.6 m in from the kerb, heads out.
        let n = (bs / LAMP_SPACING) as u32;
        for k in 0..n {
            let s = (k as f32 + 0.5) * bs / n as f32;
            for (p, out) in [
                (Vec3::new(x0 + s, CURB, z0 + 0.6), Vec3::NEG_Z),
                (Vec3::new(x0 + s, CURB, z0 + bs - 0.6), Vec3::Z),
                (Vec3::new(x0 + 0.6, CURB, z0 + s), Vec3::NEG_X),
                (Vec3::new(x0 + bs - 0.6, CURB, z0 + s), Vec3::X),
            ] {
                l.lamps.push((p, out));
            }
        }
        // Two benches on the walkway, between lamps.
        l.benches.push((Vec3::new(x0 + rng.range(0.2, 0.8) * bs, CURB, z0 + 1.6), true));
        l.benches.push((Vec3::new(x0 + 1.6, CURB, z0 + rng.range(0.2, 0.8) * bs), false));
    }
}

/// Material indices.
const ASPHALT: usize = 0;
const SIDEWALK: usize = 1;
const MARKING: usize = 2;
const FACADES: usize = 3; // four: 3..=6
const GLASS: usize = 7;
const FRAME: usize = 8;
const ROOF: usize = 9;
const METAL: usize = 10;
const LAMP: usize = 11;
const WOOD: usize = 12;
const PAINTS: usize = 13; // five: 13..=17
const TYRE: usize = 18;

fn materials() -> Vec<Material> {
    let d = |name: &str, r: f32, g: f32, b: f32| Material::diffuse(name, Vec3::new(r, g, b));
    vec![
        d("city/asphalt", 0.08, 0.08, 0.09),
        d("city/sidewalk", 0.55, 0.54, 0.50),
        d("city/marking", 0.90, 0.88, 0.80),
        d("city/brick", 0.45, 0.18, 0.12),
        d("city/sandstone", 0.72, 0.62, 0.45),
        d("city/concrete", 0.50, 0.50, 0.48),
        d("city/slate", 0.30, 0.38, 0.48),
        Material {
            specular: Vec3::splat(0.4),
            shininess: 120.0,
            ..d("city/glass", 0.04, 0.08, 0.12)
        },
        d("city/frame", 0.85, 0.85, 0.80),
        d("city/roof", 0.20, 0.20, 0.21),
        d("city/metal", 0.10, 0.12, 0.10),
        d("city/lamp", 1.00, 0.90, 0.60),
        d("city/wood", 0.40, 0.25, 0.12),
        d("city/paint-red", 0.60, 0.05, 0.04),
        d("city/paint-blue", 0.05, 0.15, 0.55),
        d("city/paint-yellow", 0.80, 0.65, 0.05),
        d("city/paint-white", 0.85, 0.85, 0.85),
        d("city/paint-black", 0.03, 0.03, 0.03),
        d("city/tyre", 0.03, 0.03, 0.03),
    ]
}

/// All six faces / all but the bottom (−axes[1]) / all but the back (−axes[2]) of a box.
const ALL: u8 = 0b11_1111;
const NO_BOTTOM: u8 = 0b11_0111;
const NO_BACK: u8 = 0b01_1111;
const MULLION: u8 = 0b01_0011;

/// One facade: points `origin + u·s + y·t − n·depth`, `s` in `[0, width]`, `u × y = n`.
struct Facade {
    origin: Vec3,
    u: Vec3,
    n: Vec3,
    width: f32,
}

impl Facade {
    fn at(&self, s: f32, t: f32, depth: f32) -> Vec3 {
        self.origin + self.u * s + Vec3::Y * t - self.n * depth
    }
}

impl CityParams {
    /// The four facades of `b`, counter-clockwise seen from above, starting with +z.
    fn facades(b: &Building) -> [Facade; 4] {
        let (lo, hi) = (b.lo, b.hi);
        [
            Facade {
                origin: Vec3::new(lo.x, lo.y, hi.z),
                u: Vec3::X,
                n: Vec3::Z,
                width: hi.x - lo.x,
            },
            Facade {
                origin: Vec3::new(hi.x, lo.y, hi.z),
                u: Vec3::NEG_Z,
                n: Vec3::X,
                width: hi.z - lo.z,
            },
            Facade {
                origin: Vec3::new(hi.x, lo.y, lo.z),
                u: Vec3::NEG_X,
                n: Vec3::NEG_Z,
                width: hi.x - lo.x,
            },
            Facade {
                origin: Vec3::new(lo.x, lo.y, lo.z),
                u: Vec3::Z,
                n: Vec3::NEG_X,
                width: hi.z - lo.z,
            },
        ]
    }

    fn building(&self, b: &Building, out: &mut [MeshBuilder]) {
        let height = b.floors as f32 * FLOOR;
        for f in Self::facades(b) {
            let wall = &mut out[FACADES + b.facade];
            if self.detail == 0 {
                wall.flat_quad(f.at(0.0, 0.0, 0.0), f.u * f.width, Vec3::Y * height);
                continue;
            }
            let bays = self.bays(f.width);
            let bay = f.width / bays as f32;
            let edge = |i: u32| if i == bays { f.width } else { i as f32 * bay };
            let (w, h) = (0.55 * bay, 0.55 * FLOOR);
            for floor in 0..b.floors {
                let (t0, t1) = (floor as f32 * FLOOR, (floor + 1) as f32 * FLOOR);
                let (wy0, wy1) = (t0 + 0.3 * FLOOR, t0 + 0.3 * FLOOR + h);
                for i in 0..bays {
                    let (s0, s1) = (edge(i), edge(i + 1));
                    let c = 0.5 * (s0 + s1);
                    let (wx0, wx1) = (c - 0.5 * w, c + 0.5 * w);
                    let wall = &mut out[FACADES + b.facade];
                    let y = Vec3::Y;
                    wall.flat_quad(f.at(s0, t0, 0.0), f.u * (s1 - s0), y * (wy0 - t0));
                    wall.flat_quad(f.at(s0, wy1, 0.0), f.u * (s1 - s0), y * (t1 - wy1));
                    wall.flat_quad(f.at(s0, wy0, 0.0), f.u * (wx0 - s0), y * h);
                    wall.flat_quad(f.at(wx1, wy0, 0.0), f.u * (s1 - wx1), y * h);
                    // Jambs, sill and head face into the opening; the glass faces out.
                    let inward = -f.n * RECESS;
                    wall.flat_quad(f.at(wx0, wy0, 0.0), inward, y * h);
                    wall.flat_quad(f.at(wx1, wy0, 0.0), y * h, inward);
                    wall.flat_quad(f.at(wx0, wy0, 0.0), f.u * w, inward);
                    wall.flat_quad(f.at(wx0, wy1, 0.0), inward, f.u * w);
                    out[GLASS].flat_quad(f.at(wx0, wy0, RECESS), f.u * w, y * h);
                    if self.detail >= 2 {
                        let axes = [f.u, Vec3::Y, f.n];
                        let sill = f.at(c, wy0 - 0.05, 0.0) + f.n * 0.06;
                        out[FRAME].oriented_box(
                            sill,
                            axes,
                            Vec3::new(0.5 * w + 0.08, 0.05, 0.06),
                            NO_BACK,
                        );
                        let mullion = f.at(c, 0.5 * (wy0 + wy1), 0.5 * RECESS);
                        out[FRAME].oriented_box(
                            mullion,
                            axes,
                            Vec3::new(0.03, 0.5 * h, 0.03),
                            MULLION,
                        );
                    }
                }
            }
        }
        let roof = &mut out[ROOF];
        let size = b.hi - b.lo;
        roof.flat_quad(
            Vec3::new(b.lo.x, b.lo.y + height, b.hi.z),
            Vec3::X * size.x,
            Vec3::NEG_Z * size.z,
        );
        if let Some((c, half)) = b.roof_box {
            roof.oriented_box(c, [Vec3::X, Vec3::Y, Vec3::Z], half, NO_BOTTOM);
        }
    }
}

/// Generates the city: one mesh per material (`city/asphalt`, `city/brick`, `city/glass`, …,
/// empty ones left out), a sun, a sky background and a camera looking down at it from a
/// corner.
pub fn city(p: &CityParams) -> Result<Scene> {
    p.validate()?;
    let l = p.layout();
    let mut out: Vec<MeshBuilder> =
        (0..=TYRE).map(|_| MeshBuilder::with_capacity(0, 0, false)).collect();
    let half = 0.5 * l.extent;
    let n = p.ground_cells();
    out[ASPHALT].grid(Vec3::new(-half, 0.0, half), Vec3::X * l.extent, Vec3::NEG_Z * l.extent, n);
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    for &(x0, z0) in &l.blocks {
        let h = 0.5 * p.block_size;
        let c = Vec3::new(x0 + h, 0.5 * CURB, z0 + h);
        out[SIDEWALK].oriented_box(c, axes, Vec3::new(h, 0.5 * CURB, h), NO_BOTTOM);
    }
    for &(c, along_x) in &l.dashes {
        let (len, wid) = (0.5 * DASH_PERIOD, 0.15);
        let y = Vec3::new(0.0, 0.01, 0.0);
        if along_x {
            let corner = c + y + Vec3::new(-0.5 * len, 0.0, 0.5 * wid);
            out[MARKING].flat_quad(corner, Vec3::X * len, Vec3::NEG_Z * wid);
        } else {
            let corner = c + y + Vec3::new(-0.5 * wid, 0.0, 0.5 * len);
            out[MARKING].flat_quad(corner, Vec3::X * wid, Vec3::NEG_Z * len);
        }
    }
    for b in &l.buildings {
        p.building(b, &mut out);
    }
    for &(base, outward) in &l.lamps {
        let top = base + Vec3::Y * 6.0;
        let pole = Tube { start: base, end: top, r0: 0.09, r1: 0.06, bend: Vec3::ZERO };
        out[METAL].tube(&pole, 6, 1);
        let head = top + outward * 0.6 + Vec3::Y * 0.1;
        let half = Vec3::new(0.35, 0.1, 0.35);
        out[LAMP].oriented_box(head, axes, half, ALL);
    }
    for &(at, along_x) in &l.benches {
        // Seat, back and two legs, 1.8 m long, along x or z.
        let ax = if along_x { axes } else { [Vec3::Z, Vec3::Y, Vec3::NEG_X] };
        let place = |s: f32, y: f32, d: f32| at + ax[0] * s + Vec3::Y * y + ax[2] * d;
        let wood = &mut out[WOOD];
        wood.oriented_box(place(0.0, 0.45, 0.0), ax, Vec3::new(0.9, 0.04, 0.22), ALL);
        wood.oriented_box(place(0.0, 0.75, -0.2), ax, Vec3::new(0.9, 0.25, 0.03), ALL);
        for s in [-0.75, 0.75] {
            wood.oriented_box(place(s, 0.2, 0.0), ax, Vec3::new(0.05, 0.2, 0.2), ALL);
        }
    }
    for car in &l.cars {
        let ax = if car.along_x { axes } else { [Vec3::Z, Vec3::Y, Vec3::NEG_X] };
        let place = |s: f32, y: f32, d: f32| car.center + ax[0] * s + Vec3::Y * y + ax[2] * d;
        let paint = &mut out[PAINTS + car.paint];
        paint.oriented_box(place(0.0, 0.75, 0.0), ax, Vec3::new(2.1, 0.4, 0.85), NO_BOTTOM);
        paint.oriented_box(place(-0.2, 1.4, 0.0), ax, Vec3::new(1.1, 0.25, 0.8), NO_BOTTOM);
        for (s, d) in [(-1.35, -0.8), (-1.35, 0.8), (1.35, -0.8), (1.35, 0.8)] {
            let wheel = place(s, 0.33, d);
            out[TYRE].oriented_box(wheel, ax, Vec3::new(0.33, 0.33, 0.12), ALL);
        }
    }
    let names = materials();
    let mut meshes: Vec<_> =
        out.into_iter().enumerate().map(|(i, b)| b.finish(&names[i].name, i)).collect();
    meshes.retain(|m| !m.indices.is_empty());
    let to_light = Vec3::new(0.45, 0.8, 0.35);
    let tallest = l.buildings.iter().map(|b| b.floors).max().unwrap_or(2) as f32 * FLOOR;
    let camera = framing(
        Vec3::new(-0.75, 0.85, 1.0),
        Vec3::new(0.0, 0.2 * tallest, 0.0),
        0.5 * l.extent * std::f32::consts::SQRT_2,
        40.0,
    );
    Ok(Scene {
        name: "city".into(),
        meshes,
        materials: names,
        camera: Some(camera),
        lights: vec![sun(to_light)],
        background: SKY,
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::scene_hash;
    use super::*;

    fn small(detail: u32) -> CityParams {
        CityParams { blocks: 1, detail, max_floors: 4, ..Default::default() }
    }

    #[test]
    fn counts_are_exact_at_every_detail() {
        for detail in 0..=2 {
            let p = small(detail);
            let s = city(&p).unwrap();
            s.validate().unwrap();
            assert_eq!(s.triangle_count() as u64, p.triangle_count(), "detail {detail}");
        }
        let p = CityParams { blocks: 2, window_spacing: 3.7, ..small(1) };
        assert_eq!(city(&p).unwrap().triangle_count() as u64, p.triangle_count());
        // More detail, more triangles; the layout does not move.
        let [a, b, c] = [0, 1, 2].map(|d| small(d).triangle_count());
        assert!(a < b && b < c, "{a} {b} {c}");
    }

    #[test]
    fn windows_are_recessed_with_distinct_materials() {
        let s = city(&small(1)).unwrap();
        let glass = s.meshes.iter().find(|m| m.name == "city/glass").unwrap();
        assert!(s.materials[glass.material].is_specular());
        // Each pane sits RECESS behind the wall plane of its facade: on a +z facade its z is
        // the building's hi.z − 0.3, so panes never lie on a wall.
        let l = small(1).layout();
        let b = &l.buildings[0];
        let front: Vec<f32> = glass
            .positions
            .iter()
            .filter(|p| p.x > b.lo.x && p.x < b.hi.x && (p.z - b.hi.z).abs() < 0.5)
            .map(|p| p.z)
            .collect();
        assert!(!front.is_empty());
        assert!(front.iter().all(|z| (z - (b.hi.z - RECESS)).abs() < 1e-4), "{front:?}");
        // Colours differ across materials used by meshes.
        let colours: std::collections::BTreeSet<_> = s
            .meshes
            .iter()
            .map(|m| s.materials[m.material].base_color.to_array().map(f32::to_bits))
            .collect();
        assert!(colours.len() >= 8, "{}", colours.len());
    }

    #[test]
    fn deterministic_and_seeded() {
        let p = small(1);
        assert_eq!(scene_hash(&city(&p).unwrap()), scene_hash(&city(&p).unwrap()));
        let q = CityParams { seed: 2, ..p.clone() };
        assert_ne!(scene_hash(&city(&p).unwrap()), scene_hash(&city(&q).unwrap()));
        let e = city(&CityParams { detail: 3, ..p }).unwrap_err().to_string();
        assert!(e.contains("city.detail") && e.contains("0..=2"), "{e}");
    }

    #[test]
    fn fit_reaches_the_target_closely() {
        for target in [50_000u64, 200_000] {
            let p = CityParams::default().fit_triangles(target);
            let n = p.triangle_count();
            assert!(n >= target && n < target + target / 100, "{target}: {n} ({p:?})");
        }
    }
}
