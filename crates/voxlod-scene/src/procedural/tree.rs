//! One tree of the forest: a recursive branch skeleton (trunk, then `branching` children per
//! branch for `depth` levels: a leader continuing the parent and side branches spiralling by the
//! golden angle), its bark tubes, tufts of small leaf quads around the twigs, and the leaf's
//! alpha-mask texture. Everything is drawn from the tree's own [`Rng`] stream.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::builder::{MeshBuilder, Tube};
use super::rng::{Rng, sin_cos_deg, sin_cos_turns};
use crate::{Sampler, Texture, WrapMode};

/// The shape parameters of one tree (from [`super::ForestParams`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct TreeShape {
    /// Mean height (each tree varies by ±20 %).
    pub height: f32,
    /// Branch levels below the trunk.
    pub depth: u32,
    /// Children per branch (the leader included).
    pub branching: u32,
    /// Leaves on the tree.
    pub leaves: u32,
    /// Largest leaf length.
    pub leaf_size: f32,
    /// Leaves per cluster (tuft).
    pub cluster: u32,
    /// Rectangular leaves for the alpha-mask texture (else untextured kites).
    pub textured_leaves: bool,
}

/// A branch of the skeleton.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Branch {
    /// Its tube.
    pub tube: Tube,
    /// 0 for the trunk, 1 for its children…
    pub level: u32,
}

/// Ratio of a branch's end radius to its start radius.
const TAPER: f32 = 0.62;
/// The golden angle in turns: side branches spiral by it.
const GOLDEN_TURN: f32 = 0.381_966;

/// Sides and rings of the tube of a branch at `level`: finer branches get fewer of both.
pub(crate) const fn tube_shape(level: u32) -> (u32, u32) {
    match level {
        0 => (8, 4),
        1 => (6, 2),
        2 => (5, 1),
        3 => (4, 1),
        _ => (3, 1),
    }
}

/// Branches at `level`: `branching^level`.
pub(crate) fn branches_at(level: u32, branching: u32) -> u64 {
    (branching as u64).pow(level)
}

/// Bark triangles of one tree.
pub(crate) fn wood_triangles(depth: u32, branching: u32) -> u64 {
    (0..=depth)
        .map(|l| {
            let (sides, rings) = tube_shape(l);
            branches_at(l, branching) * Tube::triangle_count(sides, rings)
        })
        .sum()
}

/// Bark vertices of one tree.
pub(crate) fn wood_vertices(depth: u32, branching: u32) -> u64 {
    (0..=depth)
        .map(|l| {
            let (sides, rings) = tube_shape(l);
            branches_at(l, branching) * Tube::vertex_count(sides, rings)
        })
        .sum()
}

/// A small random vector perpendicular to `dir`, of length up to `scale`.
fn sideways(rng: &mut Rng, dir: Vec3, scale: f32) -> Vec3 {
    let v = rng.in_unit_ball() * scale;
    v - dir * v.dot(dir)
}

/// The skeleton of a tree rooted at `root` (on the ground), level by level: the trunk first, and
/// each level's branches in the order of their parents.
pub(crate) fn skeleton(rng: &mut Rng, root: Vec3, shape: &TreeShape) -> Vec<Branch> {
    let height = shape.height * rng.range(0.8, 1.2);
    let lean = rng.in_unit_ball() * 0.06;
    let dir = Vec3::new(lean.x, 1.0, lean.z).normalize();
    let (length, r0) = (0.38 * height, 0.025 * height);
    let start = root - dir * (0.5 * r0);
    let trunk = Tube {
        start,
        end: start + dir * length,
        r0,
        r1: r0 * TAPER,
        bend: sideways(rng, dir, 0.03 * length),
    };
    let mut all = vec![Branch { tube: trunk, level: 0 }];
    let mut first = 0;
    for level in 1..=shape.depth {
        let last = all.len();
        for p in first..last {
            let parent = all[p].tube;
            let (pdir, plen) = (parent.direction(), parent.length());
            let (e1, e2) = pdir.any_orthonormal_pair();
            let azimuth0 = rng.next_f32();
            for j in 0..shape.branching {
                let (t, tilt, len, r0) = if j == 0 {
                    // The leader continues the parent from its tip.
                    (1.0, rng.range(8.0, 20.0), plen * rng.range(0.7, 0.8), parent.r1)
                } else {
                    let t =
                        (0.35 + 0.6 * j as f32 / shape.branching as f32 + rng.range(-0.05, 0.05))
                            .min(0.97);
                    let len = plen * rng.range(0.55, 0.75) * (1.1 - 0.4 * t);
                    (t, rng.range(35.0, 60.0), len, parent.radius(t) * 0.7)
                };
                let (st, ct) = sin_cos_deg(tilt);
                let (sa, ca) = sin_cos_turns(azimuth0 + j as f32 * GOLDEN_TURN);
                // Tilted away from the parent, then nudged upward (phototropism).
                let d = pdir * ct + (e1 * ca + e2 * sa) * st;
                let d = (d + Vec3::Y * 0.12).normalize();
                let start = parent.point(t);
                let bend = sideways(rng, d, 0.05 * len);
                let tube = Tube { start, end: start + d * len, r0, r1: r0 * TAPER, bend };
                all.push(Branch { tube, level });
            }
        }
        first = last;
    }
    all
}

/// Appends the bark tubes of `branches`.
pub(crate) fn emit_wood(branches: &[Branch], bark: &mut MeshBuilder) {
    for b in branches {
        let (sides, rings) = tube_shape(b.level);
        bark.tube(&b.tube, sides, rings);
    }
}

/// Radius of a cluster of `cluster` leaves of largest length `leaf_size`: 0.75 · leaf_size for
/// one leaf, growing with the square root of the count (1.7 · leaf_size for 24).
pub(crate) fn cluster_radius(cluster: u32, leaf_size: f32) -> f32 {
    leaf_size * (0.5 + 0.25 * (cluster.max(1) as f32).sqrt())
}

/// Appends `shape.leaves` leaves in clusters of `shape.cluster` around the finest branches of
/// `branches` (the clusters go round the twigs in turn, each at a random point of the outer 70 %
/// of its twig, up to a fifth of its length away), each cluster to one of the `leaves` builders
/// (one per leaf material) chosen at random. Within a cluster the leaf centres are uniform in a
/// ball of [`cluster_radius`]. A leaf is a quad of two triangles, uniformly random in
/// orientation, of length in [0.7, 1] · `leaf_size` and half as wide: it fits in a sphere of
/// diameter 1.12 · `leaf_size`.
pub(crate) fn emit_leaves(
    rng: &mut Rng,
    branches: &[Branch],
    shape: &TreeShape,
    leaves: &mut [MeshBuilder],
) {
    let finest = branches.iter().map(|b| b.level).max().unwrap_or(0);
    let twigs: Vec<&Tube> =
        branches.iter().filter(|b| b.level == finest).map(|b| &b.tube).collect();
    let cluster = shape.cluster.max(1) as usize;
    let radius = cluster_radius(shape.cluster, shape.leaf_size);
    let (mut hub, mut slot) = (Vec3::ZERO, 0);
    for i in 0..shape.leaves as usize {
        if i % cluster == 0 {
            let twig = twigs[(i / cluster) % twigs.len()];
            hub = twig.point(rng.range(0.3, 1.0)) + rng.in_unit_ball() * (0.2 * twig.length());
            slot = rng.below(leaves.len() as u32) as usize;
        }
        let center = hub + rng.in_unit_ball() * radius;
        let n = rng.unit_vector();
        let (e1, e2) = n.any_orthonormal_pair();
        let (s, c) = sin_cos_turns(rng.next_f32());
        let along = e1 * c + e2 * s;
        let across = along.cross(n); // across × along = n: counter-clockwise seen from n
        let len = shape.leaf_size * rng.range(0.7, 1.0);
        let (l2, w2) = (along * (0.5 * len), across * (0.25 * len));
        let b = &mut leaves[slot];
        let ids = if shape.textured_leaves {
            // The rectangle the alpha mask cuts the leaf from; texture v runs tip (0) to base (1).
            [
                b.vertex(center - l2 - w2, n, Vec2::new(0.0, 1.0)),
                b.vertex(center - l2 + w2, n, Vec2::new(1.0, 1.0)),
                b.vertex(center + l2 + w2, n, Vec2::new(1.0, 0.0)),
                b.vertex(center + l2 - w2, n, Vec2::new(0.0, 0.0)),
            ]
        } else {
            // A kite: base, right, tip, left, widest at 40 % of the length.
            let waist = center - along * (0.1 * len);
            [
                b.vertex(center - l2, n, Vec2::new(0.5, 1.0)),
                b.vertex(waist + w2, n, Vec2::new(1.0, 0.6)),
                b.vertex(center + l2, n, Vec2::new(0.5, 0.0)),
                b.vertex(waist - w2, n, Vec2::new(0.0, 0.6)),
            ]
        };
        b.quad(ids[0], ids[1], ids[2], ids[3]);
    }
}

/// Side of the leaf texture in texels.
pub(crate) const LEAF_TEXTURE_SIZE: u32 = 32;

/// The leaf texture: a pale grey leaf (the material's colour tints it) with a brighter midrib and
/// darker veins, alpha 255 inside the leaf outline and 0 outside, on [0, 1]² with u across the
/// leaf and v from tip (0) to base (1). The outline is the parabola |u − ½| < 0.48 · 4v(1 − v):
/// it covers about 64 % of the square.
pub(crate) fn leaf_texture() -> Texture {
    let n = LEAF_TEXTURE_SIZE;
    let texels: Vec<[u8; 4]> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
            let (u, v) = (x / n as f32, y / n as f32);
            let off = (u - 0.5).abs();
            if off >= 0.48 * 4.0 * v * (1.0 - v) {
                return [0, 0, 0, 0];
            }
            let vein = ((v + 1.2 * off) * 6.0).fract() < 0.15;
            let g = if off < 0.04 {
                255
            } else if vein {
                212
            } else {
                232
            };
            [g, g, g, 255]
        })
        .collect();
    Texture {
        name: "leaf".into(),
        width: n,
        height: n,
        texels: Arc::from(texels),
        srgb: true,
        sampler: Sampler { wrap_u: WrapMode::ClampToEdge, wrap_v: WrapMode::ClampToEdge },
    }
}
