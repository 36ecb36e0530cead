//! `forest`: a ground plane and N trees with trunks, thin branches and many small leaf quads at
//! random orientations — geometry below a voxel and below a pixel, where filtered voxels matter.
//!
//! With the defaults (10 × 10 ground, 6 trees about 3.5 high) a voxel at 128³ is 7.8 cm and at
//! 256³ 3.9 cm. Branches of level ≥ 3 are thinner than a voxel at 128³ (twigs are under 3 cm
//! across), and every leaf fits in a sphere of 1.12 · `leaf_size` = 1.9 cm, half a voxel at
//! 256³. Leaves grow in tufts of 24 within a ball of 2.9 cm radius around the twigs: a tuft
//! covers a good part of the voxel or two it falls in, at every orientation at once — partial,
//! direction-dependent opacity and a wide normal distribution, the regime where filtered voxel
//! representations differ. (Scattered leaves, `leaf_cluster = 1`, leave every voxel nearly
//! empty unless there are millions of them.) Leaves use a double-sided material, alpha-masked by
//! a small leaf texture by default.
//!
//! Trees stand on a jittered grid; tree `i` draws from its own random stream, so its shape
//! depends on the seed and `i` only. The triangle count is a closed form of the parameters
//! ([`ForestParams::triangle_count`]); [`ForestParams::with_target_triangles`] sizes a forest for
//! a budget (1.2 M triangles: 9 trees of 66 106 leaves on 12.2 × 12.2).

use glam::Vec3;

use super::builder::MeshBuilder;
use super::param::{check_f32, check_triangles, check_u32};
use super::rng::Rng;
use super::tree::{self, TreeShape};
use super::{SKY, framing, sun};
use crate::{AlphaMode, Material, Result, Scene, TextureRef};

/// Parameters of [`forest`]. Cost grows with `trees × (leaves_per_tree + wood)`: see
/// [`ForestParams::triangle_count`].
#[derive(Clone, Debug, PartialEq)]
pub struct ForestParams {
    /// Number of trees, 1..=100 000. Default 6.
    pub trees: u32,
    /// Leaves per tree, 0..=1 000 000, two triangles each. Default 24 000.
    pub leaves_per_tree: u32,
    /// Leaves per tuft, 1..=4 096; a tuft's leaves lie in a ball of radius
    /// `leaf_size · (0.5 + √leaf_cluster / 4)`. Default 24.
    pub leaf_cluster: u32,
    /// Branch levels below the trunk, 0..=6 (0: bare trunks carrying the leaves). Default 4.
    pub branch_depth: u32,
    /// Children per branch including the leader that continues it, 1..=6: a tree has
    /// `Σ branching^level` branches. Default 3 (121 branches, 1 108 bark triangles).
    pub branching: u32,
    /// Random seed: same seed and parameters, same scene, bit for bit. Default 1.
    pub seed: u64,
    /// Side of the square ground, centred at the origin in the xz plane, 0.001..=1e6. Default 10.
    pub extent: f32,
    /// Mean tree height (each varies by ±20 %), in (0, 2 · extent]. Default 3.5.
    pub tree_height: f32,
    /// Largest leaf length, in (0, extent / 10]; leaves are half as wide. Default
    /// `extent / 600` (a leaf fits in half a voxel at 256³).
    pub leaf_size: f32,
    /// Quads per side of the ground grid, 1..=1 024. Default 8.
    pub ground_subdivisions: u32,
    /// Leaves are rectangles cut out by an alpha-masked leaf texture (`AlphaMode::Mask`); when
    /// false, untextured kite-shaped quads. Default true.
    pub alpha_leaves: bool,
}

impl Default for ForestParams {
    fn default() -> Self {
        Self {
            trees: 6,
            leaves_per_tree: 24_000,
            leaf_cluster: 24,
            branch_depth: 4,
            branching: 3,
            seed: 1,
            extent: 10.0,
            tree_height: 3.5,
            leaf_size: 10.0 / 600.0,
            ground_subdivisions: 8,
            alpha_leaves: true,
        }
    }
}

impl ForestParams {
    /// The default forest resized to about `target` triangles: see
    /// [`ForestParams::fit_triangles`].
    pub fn with_target_triangles(target: u64) -> Self {
        Self::default().fit_triangles(target)
    }

    /// Resizes this forest to at least `target` triangles (exceeding it by less than two per
    /// tree), keeping its tree shape: the tree count scales with the fourth root of the growth
    /// and `extent` with the square root of the tree count (same density of trees), and
    /// `leaves_per_tree` fills the rest, so most of a larger budget goes into denser canopies.
    /// Leaves keep their size. Targets below one bare tree give one.
    pub fn fit_triangles(mut self, target: u64) -> Self {
        let ground = self.ground_triangles();
        let wood = tree::wood_triangles(self.branch_depth, self.branching);
        let growth = target as f64 / self.triangle_count().max(1) as f64;
        let scale = growth.sqrt().sqrt();
        let trees = ((self.trees as f64 * scale).round() as u32).clamp(1, 100_000);
        let per_tree = target.saturating_sub(ground).div_ceil(trees as u64);
        let leaves = per_tree.saturating_sub(wood).div_ceil(2).min(1_000_000) as u32;
        self.extent *= (trees as f32 / self.trees as f32).sqrt();
        self.trees = trees;
        self.leaves_per_tree = leaves;
        self
    }

    /// Triangles of the ground grid.
    fn ground_triangles(&self) -> u64 {
        2 * (self.ground_subdivisions as u64).pow(2)
    }

    /// The exact number of triangles [`forest`] generates:
    /// `2·ground² + trees · (bark + 2 · leaves_per_tree)`.
    pub fn triangle_count(&self) -> u64 {
        let per_tree = tree::wood_triangles(self.branch_depth, self.branching)
            + 2 * self.leaves_per_tree as u64;
        self.ground_triangles() + self.trees as u64 * per_tree
    }

    /// Checks every field against its documented range, and the total size.
    pub fn validate(&self) -> Result<()> {
        check_u32("forest", "trees", self.trees, 1, 100_000)?;
        check_u32("forest", "leaves", self.leaves_per_tree, 0, 1_000_000)?;
        check_u32("forest", "cluster", self.leaf_cluster, 1, 4096)?;
        check_u32("forest", "depth", self.branch_depth, 0, 6)?;
        check_u32("forest", "branching", self.branching, 1, 6)?;
        check_f32("forest", "extent", self.extent, 1e-3, 1e6)?;
        check_f32("forest", "height", self.tree_height, 0.0, 2.0 * self.extent)?;
        check_f32("forest", "leaf_size", self.leaf_size, 0.0, 0.1 * self.extent)?;
        check_u32("forest", "ground", self.ground_subdivisions, 1, 1024)?;
        check_triangles("forest", self.triangle_count())
    }

    /// The tree shape all trees share.
    fn shape(&self) -> TreeShape {
        TreeShape {
            height: self.tree_height,
            depth: self.branch_depth,
            branching: self.branching,
            leaves: self.leaves_per_tree,
            leaf_size: self.leaf_size,
            cluster: self.leaf_cluster,
            textured_leaves: self.alpha_leaves,
        }
    }
}

/// Random-stream tags, so each use of the seed is independent.
const STREAM_LAYOUT: u64 = 1;
const STREAM_TREE: u64 = 2;

/// Root positions of the trees: `trees` cells of a `g × g` grid (g = ⌈√trees⌉) chosen by a
/// seeded partial shuffle, each jittered within the middle 60 % of its cell.
fn layout(p: &ForestParams) -> Vec<Vec3> {
    let g = (p.trees as f64).sqrt().ceil() as u32;
    let mut rng = Rng::stream(p.seed, &[STREAM_LAYOUT]);
    let mut cells: Vec<u32> = (0..g * g).collect();
    for i in 0..p.trees as usize {
        let j = i + rng.below((cells.len() - i) as u32) as usize;
        cells.swap(i, j);
    }
    let cell = p.extent / g as f32;
    cells[..p.trees as usize]
        .iter()
        .map(|&c| {
            let x = ((c % g) as f32 + rng.range(0.2, 0.8)) * cell - 0.5 * p.extent;
            let z = ((c / g) as f32 + rng.range(0.2, 0.8)) * cell - 0.5 * p.extent;
            Vec3::new(x, 0.0, z)
        })
        .collect()
}

/// The forest's materials: ground, bark and three leaf greens.
fn materials(alpha_leaves: bool) -> Vec<Material> {
    let greens = [(0.12, 0.36, 0.06), (0.20, 0.45, 0.08), (0.09, 0.27, 0.05)];
    let mut m = vec![
        Material::diffuse("forest/ground", Vec3::new(0.20, 0.16, 0.09)),
        Material::diffuse("forest/bark", Vec3::new(0.22, 0.14, 0.08)),
    ];
    m.extend(greens.iter().enumerate().map(|(i, &(r, g, b))| Material {
        double_sided: true,
        base_color_texture: alpha_leaves.then_some(TextureRef { texture: 0 }),
        alpha_mode: if alpha_leaves { AlphaMode::Mask { cutoff: 0.5 } } else { AlphaMode::Opaque },
        ..Material::diffuse(&format!("forest/leaves{i}"), Vec3::new(r, g, b))
    }));
    m
}

/// Generates the forest: meshes `forest/ground`, `forest/bark` and `forest/leaves0..2` (empty
/// ones left out), a sun, a sky background and a camera looking down at it from a corner.
pub fn forest(p: &ForestParams) -> Result<Scene> {
    p.validate()?;
    let shape = p.shape();
    let trees = p.trees as usize;
    let wood_tris = tree::wood_triangles(p.branch_depth, p.branching) as usize * trees;
    let wood_verts = tree::wood_vertices(p.branch_depth, p.branching) as usize * trees;
    let mut ground = MeshBuilder::with_capacity(0, 0, true);
    let (half, n) = (0.5 * p.extent, p.ground_subdivisions);
    ground.grid(Vec3::new(-half, 0.0, half), Vec3::X * p.extent, Vec3::NEG_Z * p.extent, n);
    let mut bark = MeshBuilder::with_capacity(wood_verts, wood_tris, false);
    // Leaves go to three builders at random: room for a third of them each, plus a margin far
    // above the binomial spread, so that no builder reallocates.
    let leaves = p.leaves_per_tree as usize * trees;
    let share = leaves / 3 + leaves / 64 + 64;
    let mut foliage: Vec<MeshBuilder> =
        (0..3).map(|_| MeshBuilder::with_capacity(4 * share, 2 * share, true)).collect();
    for (i, &root) in layout(p).iter().enumerate() {
        let mut rng = Rng::stream(p.seed, &[STREAM_TREE, i as u64]);
        let branches = tree::skeleton(&mut rng, root, &shape);
        tree::emit_wood(&branches, &mut bark);
        tree::emit_leaves(&mut rng, &branches, &shape, &mut foliage);
    }
    let mut meshes = vec![ground.finish("forest/ground", 0), bark.finish("forest/bark", 1)];
    let leaf_meshes = foliage.into_iter().enumerate();
    meshes.extend(leaf_meshes.map(|(i, b)| b.finish(&format!("forest/leaves{i}"), 2 + i)));
    meshes.retain(|m| !m.indices.is_empty());
    let mut scene = Scene {
        name: "forest".into(),
        meshes,
        materials: materials(p.alpha_leaves),
        textures: if p.alpha_leaves { vec![tree::leaf_texture()] } else { Vec::new() },
        lights: vec![sun(Vec3::new(0.35, 0.8, 0.45))],
        background: SKY,
        ..Default::default()
    };
    let (lo, hi) = scene.bounds()?;
    let radius = 0.5 * (hi - lo).length();
    scene.camera = Some(framing(Vec3::new(0.9, 0.6, 1.0), (lo + hi) * 0.5, radius, 40.0));
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{heavy_tests, scene_hash};
    use super::*;

    fn small() -> ForestParams {
        ForestParams { trees: 3, leaves_per_tree: 300, ..Default::default() }
    }

    #[test]
    fn same_parameters_same_bits_and_seeds_differ() {
        let a = forest(&small()).unwrap();
        let b = forest(&small()).unwrap();
        assert_eq!(scene_hash(&a), scene_hash(&b));
        let c = forest(&ForestParams { seed: 2, ..small() }).unwrap();
        assert_ne!(scene_hash(&a), scene_hash(&c));
        assert_eq!(a.triangle_count(), c.triangle_count());
        // Every position differs, not just a few: the seed reaches every tree.
        let (pa, pc) = (&a.meshes[1].positions, &c.meshes[1].positions);
        assert!(pa.iter().zip(pc).filter(|(x, y)| x == y).count() < pa.len() / 100);
    }

    #[test]
    fn triangle_count_is_exact_for_many_shapes() {
        for (trees, leaves, depth, branching, ground, alpha) in [
            (1, 0, 0, 1, 1, false),
            (2, 7, 0, 3, 2, true),
            (5, 50, 2, 2, 3, true),
            (3, 100, 3, 4, 8, false),
            (1, 10, 6, 2, 1, true),
        ] {
            let p = ForestParams {
                trees,
                leaves_per_tree: leaves,
                branch_depth: depth,
                branching,
                ground_subdivisions: ground,
                alpha_leaves: alpha,
                ..Default::default()
            };
            let s = forest(&p).unwrap();
            s.validate().unwrap();
            assert_eq!(s.triangle_count() as u64, p.triangle_count(), "{p:?}");
            let bark = &s.meshes[1];
            let wood = tree::wood_vertices(depth, branching) * trees as u64;
            assert_eq!(
                (bark.positions.len() as u64, bark.positions.capacity() as u64),
                (wood, wood)
            );
            let leaf_tris: usize = s
                .meshes
                .iter()
                .filter(|m| m.name.contains("leaves"))
                .map(|m| m.indices.len())
                .sum();
            assert_eq!(leaf_tris as u32, 2 * trees * leaves);
        }
        assert_eq!(ForestParams::default().triangle_count(), 294_776);
    }

    #[test]
    fn target_triangles_are_reached_closely() {
        for target in [5_000u64, 50_000, 1_200_000, 5_000_000] {
            let p = ForestParams::with_target_triangles(target);
            p.validate().unwrap();
            let n = p.triangle_count();
            assert!(n >= target && n < target + 2 * p.trees as u64 + 2, "{target}: {n} {p:?}");
        }
        let p = ForestParams::with_target_triangles(1_200_000);
        assert_eq!((p.trees, p.leaves_per_tree), (9, 66_106));
        if heavy_tests() {
            let s = forest(&p).unwrap();
            s.validate().unwrap();
            assert_eq!(s.triangle_count() as u64, p.triangle_count());
        }
        // Tiny targets still give a valid forest of one tree.
        let p = ForestParams::with_target_triangles(10);
        assert_eq!((p.trees, p.leaves_per_tree), (1, 0));
    }

    #[test]
    fn leaves_and_twigs_are_below_a_voxel() {
        let p = ForestParams { trees: 2, leaves_per_tree: 2_000, ..Default::default() };
        let s = forest(&p).unwrap();
        let (lo, hi) = s.bounds().unwrap();
        let extent = (hi - lo).max_element();
        assert!(extent >= p.extent && extent < 1.1 * p.extent, "{lo} {hi}");
        // Every leaf fits in half a voxel at 256³.
        let bound = 1.12 * p.leaf_size;
        assert!(bound < 0.5 * extent / 256.0, "{bound} vs {}", extent / 256.0);
        for m in s.meshes.iter().filter(|m| m.name.contains("leaves")) {
            for t in 0..m.triangle_count() {
                let [a, b, c] = m.triangle(t);
                let longest = (a - b).length().max((b - c).length()).max((c - a).length());
                assert!(longest <= bound, "{}: {longest} > {bound}", m.name);
            }
        }
        // Branches from level 3 on are thinner than a voxel at 128³.
        let branches = tree::skeleton(&mut Rng::new(0), Vec3::ZERO, &p.shape());
        assert_eq!(branches.len(), 121);
        let widest = |level| {
            branches.iter().filter(|b| b.level >= level).fold(0.0, |m, b| b.tube.r0.max(m)) * 2.0
        };
        assert!(widest(3) < extent / 128.0, "{} vs {}", widest(3), extent / 128.0);
        assert!(widest(4) < 0.03, "twigs up to {} across", widest(4));
    }

    #[test]
    fn leaves_grow_in_tufts() {
        // One tree of 10 tufts: each leaf mesh holds whole tufts of 24 consecutive leaves.
        let spread = |cluster: u32| {
            let p =
                ForestParams { trees: 1, leaves_per_tree: 240, leaf_cluster: cluster, ..small() };
            let s = forest(&p).unwrap();
            let mut worst = 0.0f32;
            for m in s.meshes.iter().filter(|m| m.name.contains("leaves")) {
                if cluster == 24 {
                    assert_eq!(m.positions.len() % (4 * 24), 0);
                }
                for tuft in m.positions.chunks_exact(4 * 24) {
                    let centres: Vec<Vec3> =
                        tuft.chunks(4).map(|q| q.iter().sum::<Vec3>() * 0.25).collect();
                    let mean = centres.iter().sum::<Vec3>() / centres.len() as f32;
                    worst = centres.iter().map(|c| (*c - mean).length()).fold(worst, f32::max);
                }
            }
            worst
        };
        let radius = tree::cluster_radius(24, ForestParams::default().leaf_size);
        let tufted = spread(24);
        assert!(tufted <= 2.0 * radius, "{tufted} vs radius {radius}");
        // Scattered leaves (clusters of one): 24 consecutive ones spread over the crown.
        assert!(spread(1) > 5.0 * radius);
    }

    #[test]
    fn invalid_parameters_name_themselves() {
        for (p, key) in [
            (ForestParams { trees: 0, ..small() }, "forest.trees"),
            (ForestParams { extent: f32::NAN, ..small() }, "forest.extent"),
            (ForestParams { leaf_size: 5.0, ..small() }, "forest.leaf_size"),
            (ForestParams { branching: 7, ..small() }, "forest.branching"),
            (ForestParams { leaf_cluster: 0, ..small() }, "forest.cluster"),
            (
                ForestParams { trees: 100_000, leaves_per_tree: 1_000, ..small() },
                "forest.triangles",
            ),
        ] {
            let e = forest(&p).unwrap_err().to_string();
            assert!(e.contains(key), "{e}");
        }
    }

    #[test]
    fn alpha_leaves_use_the_mask_texture() {
        let s = forest(&small()).unwrap();
        assert_eq!(s.textures.len(), 1);
        let leaf = &s.materials[2];
        assert!(leaf.double_sided && matches!(leaf.alpha_mode, AlphaMode::Mask { .. }));
        // The texture is opaque at the leaf's centre and transparent at its corners.
        let m = leaf.sample(&s.textures, glam::Vec2::new(0.5, 0.5));
        assert_eq!(m.alpha, 1.0);
        assert_eq!(leaf.sample(&s.textures, glam::Vec2::new(0.02, 0.02)).alpha, 0.0);
        let covered = s.textures[0].texels.iter().filter(|t| t[3] == 255).count() as f32
            / s.textures[0].texels.len() as f32;
        assert!((0.55..0.7).contains(&covered), "{covered}");
        let plain = forest(&ForestParams { alpha_leaves: false, ..small() }).unwrap();
        assert!(plain.textures.is_empty() && plain.materials[2].alpha_mode == AlphaMode::Opaque);
        plain.validate().unwrap();
    }
}
