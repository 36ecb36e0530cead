//! `island`: a heightfield island in a glossy sea, with rocks along the shore and many thin grass
//! blades. It stresses what `forest` does not:
//!
//! - **Direction-dependent opacity from oriented sub-voxel geometry.** Grass blades are near
//!   vertical and much thinner than a voxel (1.2 cm wide by default, a voxel at 256³ is 7.8 cm):
//!   seen from above, a grass voxel lets most rays through to the ground; at grazing angles it
//!   is nearly opaque. One opacity per voxel (Averages) must be wrong for one of those views;
//!   the normals are anisotropic (mostly horizontal), which an SGGX fit captures and an average
//!   normal does not.
//! - **Several surfaces in one voxel.** Along the shoreline a voxel holds flat water and a sloping
//!   beach or rock, with different colours and normals: a two-lobed normal distribution that a
//!   single mean normal and colour blur, and the virtual mesh's per-face colours keep.
//! - **Specular shading.** The sea is a Blinn-Phong specular material (the sun glints on it), so
//!   a representation that averages normals visibly moves or dulls the highlight.
//! - **Smooth, simple content.** Most of the terrain is a gentle surface whose voxels need only a
//!   simple record: an adaptive representation should spend its bytes on the grass and shore.
//!
//! Geometry: terrain on a `terrain_resolution²` grid (quads wholly under the sea floor's margin
//! are left out), an 8 × 8 water grid at y = 0, `rocks` lumpy icospheres (320 triangles each)
//! and `grass_blades` bent blades of 3 triangles each on the terrain above the beach.

use glam::{Vec2, Vec3};

use super::builder::MeshBuilder;
use super::noise::{fbm2, value3};
use super::param::{check_f32, check_triangles, check_u32};
use super::primitives::icosphere;
use super::rng::{Rng, sin_cos_turns};
use super::{SKY, framing, sun};
use crate::{Material, Mesh, Result, Scene};

/// Parameters of [`island`].
#[derive(Clone, Debug, PartialEq)]
pub struct IslandParams {
    /// Random seed: same seed and parameters, same scene, bit for bit. Default 1.
    pub seed: u64,
    /// Side of the square sea centred at the origin, 0.001..=1e6; the island's radius is
    /// 0.36 · extent and its peak about 0.1 · extent high. Default 20.
    pub extent: f32,
    /// Terrain quads per side over the whole square, 8..=2 048 (cost: 2 triangles per quad on
    /// about 45 % of them). Default 128.
    pub terrain_resolution: u32,
    /// Grass blades, 0..=8 000 000, 3 triangles each. Default 40 000.
    pub grass_blades: u32,
    /// Rocks, 0..=10 000, 320 triangles each. Default 24.
    pub rocks: u32,
    /// Tallest blade height, in (0, extent / 20]. Default 0.25.
    pub blade_height: f32,
    /// Widest blade width at its base, in (0, blade_height]. Default 0.012.
    pub blade_width: f32,
}

impl Default for IslandParams {
    fn default() -> Self {
        Self {
            seed: 1,
            extent: 20.0,
            terrain_resolution: 128,
            grass_blades: 40_000,
            rocks: 24,
            blade_height: 0.25,
            blade_width: 0.012,
        }
    }
}

impl IslandParams {
    /// Checks every field against its documented range, and an upper bound of the size.
    pub fn validate(&self) -> Result<()> {
        check_f32("island", "extent", self.extent, 1e-3, 1e6)?;
        check_u32("island", "terrain", self.terrain_resolution, 8, 2048)?;
        check_u32("island", "grass", self.grass_blades, 0, 8_000_000)?;
        check_u32("island", "rocks", self.rocks, 0, 10_000)?;
        check_f32("island", "blade_height", self.blade_height, 0.0, self.extent / 20.0)?;
        check_f32("island", "blade_width", self.blade_width, 0.0, self.blade_height)?;
        let terrain = 2 * (self.terrain_resolution as u64).pow(2);
        check_triangles(
            "island",
            terrain + 128 + 320 * self.rocks as u64 + 3 * self.grass_blades as u64,
        )
    }
}

/// Random-stream tags, so each use of the seed is independent.
const STREAM_ROCKS: u64 = 1;
const STREAM_GRASS: u64 = 2;

/// The terrain: heights on a `(n + 1)²` grid over `[−extent/2, extent/2]²`, vertex `(i, j)` at
/// `x = −extent/2 + i·cell`, `z = −extent/2 + j·cell`, triangulated along the `(i, j)–(i+1, j+1)`
/// diagonals, which [`Terrain::height_at`] follows exactly.
struct Terrain {
    n: u32,
    half: f32,
    cell: f32,
    heights: Vec<f32>,
}

impl Terrain {
    fn new(p: &IslandParams) -> Self {
        let (n, half) = (p.terrain_resolution, 0.5 * p.extent);
        let cell = p.extent / n as f32;
        let (radius, peak) = (0.36 * p.extent, 0.1 * p.extent);
        let heights = (0..(n + 1) * (n + 1))
            .map(|k| {
                let x = -half + (k % (n + 1)) as f32 * cell;
                let z = -half + (k / (n + 1)) as f32 * cell;
                // A dome with a definite shore slope, roughened by fractal noise, floored below.
                let s = (1.0 - (x * x + z * z) / (radius * radius)).max(-1.0);
                let dome = peak * s * (0.6 + 0.4 * s);
                let rough = 0.25 * peak * fbm2(p.seed, Vec2::new(x, z) * (5.0 / p.extent), 4);
                (dome + rough).max(-0.25 * peak)
            })
            .collect();
        Self { n, half, cell, heights }
    }

    fn h(&self, i: u32, j: u32) -> f32 {
        self.heights[(j * (self.n + 1) + i) as usize]
    }

    fn position(&self, i: u32, j: u32) -> Vec3 {
        Vec3::new(
            -self.half + i as f32 * self.cell,
            self.h(i, j),
            -self.half + j as f32 * self.cell,
        )
    }

    /// Height of the triangulated surface at `(x, z)` (clamped to the grid).
    fn height_at(&self, x: f32, z: f32) -> f32 {
        let gx = ((x + self.half) / self.cell).clamp(0.0, self.n as f32);
        let gz = ((z + self.half) / self.cell).clamp(0.0, self.n as f32);
        let (i, j) = ((gx as u32).min(self.n - 1), (gz as u32).min(self.n - 1));
        let (fx, fz) = (gx - i as f32, gz - j as f32);
        let (a, b) = (self.h(i, j), self.h(i + 1, j));
        let (c, d) = (self.h(i + 1, j + 1), self.h(i, j + 1));
        if fz >= fx { a + (c - d) * fx + (d - a) * fz } else { a + (b - a) * fx + (c - b) * fz }
    }

    /// Central-difference vertex normal.
    fn normal(&self, i: u32, j: u32) -> Vec3 {
        let (il, ir) = (i.saturating_sub(1), (i + 1).min(self.n));
        let (jl, jr) = (j.saturating_sub(1), (j + 1).min(self.n));
        let dx = (self.h(ir, j) - self.h(il, j)) / ((ir - il) as f32 * self.cell);
        let dz = (self.h(i, jr) - self.h(i, jl)) / ((jr - jl) as f32 * self.cell);
        Vec3::new(-dx, 1.0, -dz).normalize()
    }

    /// The terrain split into beach (below `sand`) and meadow meshes, leaving out quads wholly
    /// under `floor`.
    fn meshes(&self, sand: f32, floor: f32) -> [Mesh; 2] {
        let mut out = [(); 2].map(|_| MeshBuilder::with_capacity(0, 0, false));
        let mut remap = vec![[u32::MAX; 2]; self.heights.len()];
        for j in 0..self.n {
            for i in 0..self.n {
                let corners = [(i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j)];
                let hs = corners.map(|(a, b)| self.h(a, b));
                if hs.iter().all(|&h| h < floor) {
                    continue;
                }
                let m = usize::from(hs.iter().sum::<f32>() * 0.25 >= sand);
                let ids = corners.map(|(a, b)| {
                    let slot = &mut remap[(b * (self.n + 1) + a) as usize][m];
                    if *slot == u32::MAX {
                        *slot = out[m].vertex(self.position(a, b), self.normal(a, b), Vec2::ZERO);
                    }
                    *slot
                });
                // (i,j), (i,j+1), (i+1,j+1), (i+1,j) winds counter-clockwise seen from +y.
                out[m].quad(ids[0], ids[1], ids[2], ids[3]);
            }
        }
        let [beach, meadow] = out;
        [beach.finish("island/beach", 1), meadow.finish("island/meadow", 2)]
    }
}

/// A lumpy, flattened rock sunk into the terrain at `(x, z)`.
fn rock(rng: &mut Rng, seed: u64, terrain: &Terrain, x: f32, z: f32, size: f32) -> Mesh {
    let mut m = icosphere(Vec3::ZERO, 1.0, 2);
    let scale = Vec3::new(rng.range(0.8, 1.2), rng.range(0.5, 0.8), rng.range(0.8, 1.2)) * size;
    let offset = rng.in_unit_ball() * 8.0;
    let center = Vec3::new(x, terrain.height_at(x, z) - 0.25 * scale.y, z);
    for p in &mut m.positions {
        let lump = 1.0 + 0.3 * value3(seed, *p * 1.7 + offset);
        *p = center + *p * lump * scale;
    }
    m.compute_normals();
    m
}

/// One grass blade rooted at `root`: two quads' worth of bent ribbon and a tip, 3 triangles.
fn blade(rng: &mut Rng, p: &IslandParams, root: Vec3, b: &mut MeshBuilder) {
    let height = p.blade_height * rng.range(0.6, 1.0);
    let width = p.blade_width * rng.range(0.7, 1.0);
    let (s, c) = sin_cos_turns(rng.next_f32());
    let side = Vec3::new(c, 0.0, s);
    let lean = Vec3::new(-s, 0.0, c) * (height * rng.range(-0.45, 0.45));
    let root = root - Vec3::Y * (0.1 * height);
    let at = |t: f32| root + Vec3::Y * (height * t) + lean * (t * t);
    let normal = |t: f32| side.cross(Vec3::Y * height + lean * (2.0 * t)).normalize();
    let mut pair = |t: f32, half: f32| {
        let (q, n) = (at(t), normal(t));
        [b.vertex(q - side * half, n, Vec2::ZERO), b.vertex(q + side * half, n, Vec2::ZERO)]
    };
    let [bl, br] = pair(0.0, 0.5 * width);
    let [ml, mr] = pair(0.55, 0.35 * width);
    let tip = b.vertex(at(1.0), normal(1.0), Vec2::ZERO);
    b.quad(bl, br, mr, ml);
    b.triangle(ml, mr, tip);
}

/// Generates the island: meshes `island/water`, `island/beach`, `island/meadow`, `island/rocks`
/// and `island/grass0..1` (empty ones left out), a sun, a sky background and a camera placed to
/// see the sun's glint on the water in front of the island.
pub fn island(p: &IslandParams) -> Result<Scene> {
    p.validate()?;
    let (terrain, peak) = (Terrain::new(p), 0.1 * p.extent);
    let (radius, half) = (0.36 * p.extent, 0.5 * p.extent);
    let mut water = MeshBuilder::with_capacity(81, 128, false);
    water.grid(Vec3::new(-half, 0.0, half), Vec3::X * p.extent, Vec3::NEG_Z * p.extent, 8);
    let [beach, meadow] = terrain.meshes(0.06 * peak, -0.05 * peak);

    let mut rng = Rng::stream(p.seed, &[STREAM_ROCKS]);
    let mut rocks = Mesh { name: "island/rocks".into(), material: 3, ..Default::default() };
    for k in 0..p.rocks {
        // Two thirds along the shore, the rest anywhere on the island.
        let r = if k % 3 < 2 { rng.range(0.85, 1.1) } else { rng.next_f32().sqrt() } * radius;
        let (s, c) = sin_cos_turns(rng.next_f32());
        let size = rng.range(0.0075, 0.03) * p.extent;
        let m = rock(&mut rng, p.seed ^ k as u64, &terrain, r * c, r * s, size);
        let base = rocks.positions.len() as u32;
        rocks.positions.extend(m.positions);
        rocks.normals.extend(m.normals);
        rocks.indices.extend(m.indices.iter().map(|t| t.map(|i| i + base)));
    }

    // Blades go to two builders at random: room for half of them each, plus a margin.
    let share = p.grass_blades as usize / 2 + p.grass_blades as usize / 64 + 64;
    let mut grass: Vec<MeshBuilder> =
        (0..2).map(|_| MeshBuilder::with_capacity(5 * share, 3 * share, false)).collect();
    let grass_line = 0.12 * peak;
    for k in 0..p.grass_blades as u64 {
        let mut rng = Rng::stream(p.seed, &[STREAM_GRASS, k]);
        // Uniform on the island's disc until above the grass line; after 16 misses, pull the
        // last try toward the centre (which is above it) until it is.
        let mut q = Vec2::ZERO;
        for _ in 0..16 {
            let (s, c) = sin_cos_turns(rng.next_f32());
            q = Vec2::new(c, s) * (radius * rng.next_f32().sqrt());
            if terrain.height_at(q.x, q.y) > grass_line {
                break;
            }
        }
        for _ in 0..64 {
            if terrain.height_at(q.x, q.y) > grass_line {
                break;
            }
            q *= 0.5;
        }
        let root = Vec3::new(q.x, terrain.height_at(q.x, q.y), q.y);
        let b = &mut grass[rng.below(2) as usize];
        blade(&mut rng, p, root, b);
    }

    let mut meshes = vec![water.finish("island/water", 0), beach, meadow, rocks];
    let grass_meshes = grass.into_iter().enumerate();
    meshes.extend(grass_meshes.map(|(i, b)| b.finish(&format!("island/grass{i}"), 4 + i)));
    meshes.retain(|m| !m.indices.is_empty());
    let grass_material = |i: usize, c: Vec3| Material {
        double_sided: true,
        ..Material::diffuse(&format!("island/grass{i}"), c)
    };
    let materials = vec![
        Material {
            // About water's reflectance at normal incidence: a small, bright glint.
            specular: Vec3::splat(0.05),
            shininess: 300.0,
            ..Material::diffuse("island/water", Vec3::new(0.02, 0.07, 0.10))
        },
        Material::diffuse("island/sand", Vec3::new(0.62, 0.55, 0.38)),
        Material::diffuse("island/meadow", Vec3::new(0.17, 0.23, 0.07)),
        Material::diffuse("island/rock", Vec3::new(0.33, 0.31, 0.29)),
        grass_material(0, Vec3::new(0.16, 0.34, 0.06)),
        grass_material(1, Vec3::new(0.26, 0.40, 0.09)),
    ];
    let to_light = Vec3::new(0.5, 0.6, -0.62);
    // Facing the sun's azimuth from lower than its elevation (28° against 40°): the sun's
    // mirror image on the sea lies between the camera and the island.
    let camera = framing(
        Vec3::new(-to_light.x, 0.42, -to_light.z),
        Vec3::new(0.0, 0.25 * peak, 0.0),
        0.5 * p.extent,
        40.0,
    );
    Ok(Scene {
        name: "island".into(),
        meshes,
        materials,
        camera: Some(camera),
        lights: vec![sun(to_light)],
        background: SKY,
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{check_closed, scene_hash, signed_volume};
    use super::*;

    fn small() -> IslandParams {
        IslandParams { terrain_resolution: 32, grass_blades: 2_000, rocks: 4, ..Default::default() }
    }

    fn mesh<'a>(s: &'a Scene, name: &str) -> &'a Mesh {
        s.meshes.iter().find(|m| m.name == name).unwrap()
    }

    #[test]
    fn deterministic_valid_and_counted() {
        let a = island(&small()).unwrap();
        a.validate().unwrap();
        assert_eq!(scene_hash(&a), scene_hash(&island(&small()).unwrap()));
        let b = island(&IslandParams { seed: 2, ..small() }).unwrap();
        assert_ne!(scene_hash(&a), scene_hash(&b));
        let grass: usize =
            a.meshes.iter().filter(|m| m.name.contains("grass")).map(|m| m.indices.len()).sum();
        assert_eq!(grass, 3 * 2_000);
        assert_eq!(mesh(&a, "island/rocks").triangle_count(), 4 * 320);
        assert_eq!(mesh(&a, "island/water").triangle_count(), 128);
        let terrain =
            mesh(&a, "island/beach").triangle_count() + mesh(&a, "island/meadow").triangle_count();
        // The seabed far from the island is left out, the island itself kept.
        assert!(terrain > 2 * 32 * 32 / 4 && terrain < 2 * 32 * 32, "{terrain}");
        assert!(a.materials[0].is_specular());
        let none = island(&IslandParams { grass_blades: 0, rocks: 0, ..small() }).unwrap();
        none.validate().unwrap();
        assert_eq!(none.meshes.len(), 3);
    }

    #[test]
    fn heights_follow_the_triangulation() {
        let t = Terrain::new(&small());
        let p = |i, j| t.position(i, j);
        for (i, j) in [(0, 0), (5, 9), (16, 16), (31, 2)] {
            let (a, c) = (p(i, j), p(i + 1, j + 1));
            assert!((t.height_at(a.x, a.z) - a.y).abs() < 1e-4);
            // On the diagonal both triangles agree with the edge's midpoint.
            let m = (a + c) * 0.5;
            assert!((t.height_at(m.x, m.z) - m.y).abs() < 1e-4, "{i},{j}");
            // Inside triangle (a, b, c) a point is the barycentric mix of its corners.
            let b = p(i + 1, j);
            let q = a * 0.2 + b * 0.5 + c * 0.3;
            assert!((t.height_at(q.x, q.z) - q.y).abs() < 1e-4, "{i},{j}");
        }
    }

    #[test]
    fn shore_rocks_and_grass_have_the_promised_shape() {
        let p = small();
        let s = island(&p).unwrap();
        let peak = 0.1 * p.extent;
        // The beach crosses the water line: a shoreline exists.
        let beach = mesh(&s, "island/beach");
        assert!(
            beach.positions.iter().any(|v| v.y > 0.0) && beach.positions.iter().any(|v| v.y < 0.0)
        );
        let rocks = mesh(&s, "island/rocks");
        check_closed(rocks).unwrap();
        assert!(signed_volume(rocks) > 0.0);
        // Blades: 5 vertices each, base no wider than blade_width, rooted above the grass
        // line (sunk by a tenth of their height), no taller than blade_height — and much
        // thinner than a voxel at 256³.
        assert!(p.blade_width < 0.2 * p.extent / 256.0);
        for m in s.meshes.iter().filter(|m| m.name.contains("grass")) {
            for v in m.positions.chunks(5) {
                assert!((v[1] - v[0]).length() <= p.blade_width * 1.0001);
                let root = (v[0] + v[1]) * 0.5;
                assert!(root.y > 0.12 * peak - 0.1 * p.blade_height - 1e-4, "{root}");
                assert!(v[4].y - root.y <= p.blade_height * 1.0001);
                assert!(v[4].y > root.y);
            }
        }
    }

    #[test]
    fn invalid_parameters_name_themselves() {
        for (p, key) in [
            (IslandParams { terrain_resolution: 4, ..small() }, "island.terrain"),
            (IslandParams { blade_width: 1.0, ..small() }, "island.blade_width"),
            (IslandParams { extent: -1.0, ..small() }, "island.extent"),
            (IslandParams { grass_blades: 8_000_001, ..small() }, "island.grass"),
        ] {
            let e = island(&p).unwrap_err().to_string();
            assert!(e.contains(key), "{e}");
        }
    }
}
