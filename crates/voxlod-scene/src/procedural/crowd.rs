//! `crowd`: skinned characters walking in circles between rotating rigid objects on a static
//! floor — the dynamic scene of voxel transformation (in the spirit of Yalçıner and
//! Sahillioğlu 2020's crowd of 256 characters among rotating tori and cubes).
//!
//! - **Walkers**: a humanoid of 17 joints (hips, spine, chest, neck, head; shoulder, elbow,
//!   wrist per arm; hip, knee, ankle per leg), built from closed tubes around its bones and a
//!   sphere for the head, in three materials (shirt, trousers, skin). Each vertex is weighted
//!   to its bone, blended linearly with the parent bone over the first quarter of the bone and
//!   with the child bone over the last quarter (half and half at the joint), so joints bend
//!   smoothly under linear blend skinning. At the default 12 sides a walker has 3 512
//!   triangles; at the minimum 8 sides 2 288.
//! - **Walk cycle** (an integer number of one-second strides per animation, so it loops):
//!   thighs swing ±30°, knees bend 5°…70°, elbows 15°…60°, shoulders swing ±25°, ankles ±10°,
//!   the pelvis bobs 3 cm and twists ±7° against the spine; every walker has its own phase.
//!   Each walker's root follows a circle of radius `0.3·spacing` once per animation, facing
//!   along it (32 linear keys; its direction alternates).
//! - **Rigid objects**: tori and cubes alternating, each turning about its own tilted axis once
//!   per animation (eight keys a turn, so slerp is the exact rotation), 1.1 to 1.7 above the
//!   floor, between the walkers' circles.
//! - **Floor**: one static quad under everything. A sun, and a camera framing the floor.
//!
//! Bind space is the rest pose in world space: every inverse bind matrix is the inverse of its
//! joint's rest world matrix, so the rest meshes are the bind meshes and every joint matrix at
//! rest is the identity. One animation, `walk`, holds every channel. Deterministic: trigonometry
//! from [`super::rng::sin_cos_turns`], randomness from [`Rng`] streams per walker and object.

use glam::{Mat4, Quat, Vec2, Vec3};

use super::param::{check_f32, check_u32};
use super::rng::{Rng, sin_cos_turns};
use crate::animation::{AnimatedProperty, Channel, Interpolation, Transform};
use crate::mesh::SkinBinding;
use crate::{Animation, Light, Material, Mesh, Node, Result, Scene, Skin};

/// Parameters of [`crowd`].
#[derive(Clone, Debug, PartialEq)]
pub struct CrowdParams {
    /// Walking characters, 1..=256 (default 16), on a square grid of slots.
    pub walkers: u32,
    /// Rotating rigid objects, 0..=1024 (default 16).
    pub rigid: u32,
    /// Sides of every body tube, 8..=64 (default 12): triangles per walker grow linearly.
    pub sides: u32,
    /// Distance between slots, 1.5..=100 (default 2.5).
    pub spacing: f32,
    /// Length of the looping animation in seconds, 1..=60 (default 4).
    pub duration: f32,
    /// Random seed (walk phases, colours, object axes), any u64 (default 1).
    pub seed: u64,
}

impl Default for CrowdParams {
    fn default() -> Self {
        Self { walkers: 16, rigid: 16, sides: 12, spacing: 2.5, duration: 4.0, seed: 1 }
    }
}

/// A joint of the walker: name, parent (index in this table), rest position in the walker's
/// frame (y up, facing +z, feet at y = 0).
const JOINTS: [(&str, Option<usize>, [f32; 3]); 17] = [
    ("hips", None, [0.0, 0.95, 0.0]),
    ("spine", Some(0), [0.0, 1.08, 0.0]),
    ("chest", Some(1), [0.0, 1.28, 0.0]),
    ("neck", Some(2), [0.0, 1.50, 0.0]),
    ("head", Some(3), [0.0, 1.62, 0.0]),
    ("l_shoulder", Some(2), [0.21, 1.45, 0.0]),
    ("l_elbow", Some(5), [0.23, 1.17, 0.0]),
    ("l_wrist", Some(6), [0.24, 0.93, 0.0]),
    ("r_shoulder", Some(2), [-0.21, 1.45, 0.0]),
    ("r_elbow", Some(8), [-0.23, 1.17, 0.0]),
    ("r_wrist", Some(9), [-0.24, 0.93, 0.0]),
    ("l_hip", Some(0), [0.10, 0.92, 0.0]),
    ("l_knee", Some(11), [0.10, 0.50, 0.0]),
    ("l_ankle", Some(12), [0.10, 0.08, 0.0]),
    ("r_hip", Some(0), [-0.10, 0.92, 0.0]),
    ("r_knee", Some(14), [-0.10, 0.50, 0.0]),
    ("r_ankle", Some(15), [-0.10, 0.08, 0.0]),
];

/// A body tube: start, end, radii, owning joint, joint blended in at the start and at the end,
/// part (0 shirt, 1 trousers, 2 skin).
struct Part {
    start: [f32; 3],
    end: [f32; 3],
    r: [f32; 2],
    owner: usize,
    from: Option<usize>,
    to: Option<usize>,
    part: usize,
}

const fn part(
    start: [f32; 3],
    end: [f32; 3],
    r: [f32; 2],
    owner: usize,
    from: Option<usize>,
    to: Option<usize>,
    part: usize,
) -> Part {
    Part { start, end, r, owner, from, to, part }
}

const PARTS: [Part; 16] = [
    part([0.0, 0.84, 0.0], [0.0, 1.08, 0.0], [0.15, 0.15], 0, None, Some(1), 1),
    part([0.0, 1.08, 0.0], [0.0, 1.28, 0.0], [0.15, 0.16], 1, Some(0), Some(2), 0),
    part([0.0, 1.28, 0.0], [0.0, 1.50, 0.0], [0.16, 0.17], 2, Some(1), Some(3), 0),
    part([0.0, 1.48, 0.0], [0.0, 1.64, 0.0], [0.05, 0.05], 3, Some(2), Some(4), 2),
    part([0.21, 1.47, 0.0], [0.23, 1.17, 0.0], [0.055, 0.045], 5, Some(2), Some(6), 0),
    part([0.23, 1.17, 0.0], [0.24, 0.93, 0.0], [0.045, 0.035], 6, Some(5), Some(7), 0),
    part([0.24, 0.93, 0.0], [0.245, 0.79, 0.015], [0.035, 0.03], 7, Some(6), None, 2),
    part([-0.21, 1.47, 0.0], [-0.23, 1.17, 0.0], [0.055, 0.045], 8, Some(2), Some(9), 0),
    part([-0.23, 1.17, 0.0], [-0.24, 0.93, 0.0], [0.045, 0.035], 9, Some(8), Some(10), 0),
    part([-0.24, 0.93, 0.0], [-0.245, 0.79, 0.015], [0.035, 0.03], 10, Some(9), None, 2),
    part([0.10, 0.94, 0.0], [0.10, 0.50, 0.0], [0.08, 0.06], 11, Some(0), Some(12), 1),
    part([0.10, 0.50, 0.0], [0.10, 0.08, 0.0], [0.058, 0.045], 12, Some(11), Some(13), 1),
    part([0.10, 0.07, -0.04], [0.10, 0.04, 0.17], [0.045, 0.035], 13, Some(12), None, 1),
    part([-0.10, 0.94, 0.0], [-0.10, 0.50, 0.0], [0.08, 0.06], 14, Some(0), Some(15), 1),
    part([-0.10, 0.50, 0.0], [-0.10, 0.08, 0.0], [0.058, 0.045], 15, Some(14), Some(16), 1),
    part([-0.10, 0.07, -0.04], [-0.10, 0.04, 0.17], [0.045, 0.035], 16, Some(15), None, 1),
];

/// Rings along every tube.
const SEGMENTS: u32 = 8;
const HEAD_CENTRE: [f32; 3] = [0.0, 1.74, 0.0];
const HEAD_RADIUS: f32 = 0.11;

const SHIRTS: [[f32; 3]; 6] = [
    [0.70, 0.12, 0.10],
    [0.12, 0.35, 0.70],
    [0.15, 0.55, 0.20],
    [0.80, 0.70, 0.15],
    [0.55, 0.20, 0.60],
    [0.85, 0.85, 0.85],
];
const TROUSERS: [[f32; 3]; 3] = [[0.10, 0.10, 0.15], [0.25, 0.20, 0.15], [0.20, 0.28, 0.45]];
const SKIN: [[f32; 3]; 3] = [[0.85, 0.65, 0.50], [0.60, 0.42, 0.30], [0.35, 0.24, 0.17]];

impl CrowdParams {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<()> {
        check_u32("crowd", "walkers", self.walkers, 1, 256)?;
        check_u32("crowd", "rigid", self.rigid, 0, 1024)?;
        check_u32("crowd", "sides", self.sides, 8, 64)?;
        check_f32("crowd", "spacing", self.spacing, 1.5, 100.0)?;
        check_f32("crowd", "duration", self.duration, 1.0, 60.0)?;
        Ok(())
    }

    /// Triangles of one walker: 16 closed tubes and the head sphere.
    pub fn walker_triangles(&self) -> u64 {
        let s = self.sides as u64;
        16 * (2 * s * SEGMENTS as u64 + 2 * (s - 2)) + head_triangles(self.sides)
    }

    /// Triangles of the whole scene.
    pub fn triangle_count(&self) -> u64 {
        let s = self.sides as u64;
        let torus = 2 * s * 2 * s;
        let tori = self.rigid.div_ceil(2) as u64;
        self.walkers as u64 * self.walker_triangles()
            + tori * torus
            + (self.rigid as u64 / 2) * 12
            + 2
    }
}

fn head_triangles(sides: u32) -> u64 {
    let (seg, rings) = (sides as u64, (sides / 2).max(3) as u64);
    2 * seg * (rings - 1)
}

/// A quaternion turning `turns` (1 = 360°) about unit `axis`, from the deterministic sine.
fn quat(axis: Vec3, turns: f32) -> Quat {
    let (s, c) = sin_cos_turns(0.5 * turns);
    Quat::from_xyzw(axis.x * s, axis.y * s, axis.z * s, c)
}

fn deg(d: f32) -> f32 {
    d / 360.0
}

/// One skinned mesh under construction: positions, normals, joints, weights, triangles.
#[derive(Default)]
struct SkinnedBuilder {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
    indices: Vec<[u32; 3]>,
}

impl SkinnedBuilder {
    fn vertex(&mut self, p: Vec3, n: Vec3, influences: &[(usize, f32)]) -> u32 {
        let mut j = [0u16; 4];
        let mut w = [0.0f32; 4];
        for (k, &(joint, weight)) in influences.iter().take(4).enumerate() {
            j[k] = joint as u16;
            w[k] = weight;
        }
        self.positions.push(p);
        self.normals.push(n);
        self.joints.push(j);
        self.weights.push(w);
        self.positions.len() as u32 - 1
    }

    /// A tube closed at both ends, weighted as the module docs say.
    fn tube(&mut self, part: &Part, sides: u32) {
        let (a, b) = (Vec3::from(part.start), Vec3::from(part.end));
        let dir = (b - a).normalize();
        let (e1, e2) = dir.any_orthonormal_pair();
        let weights = |t: f32| -> Vec<(usize, f32)> {
            let mut w = vec![(part.owner, 1.0)];
            if let Some(p) = part.from.filter(|_| t < 0.25) {
                let x = 0.5 * (1.0 - t / 0.25);
                w[0].1 -= x;
                w.push((p, x));
            }
            if let Some(c) = part.to.filter(|_| t > 0.75) {
                let x = 0.5 * (t - 0.75) / 0.25;
                w[0].1 -= x;
                w.push((c, x));
            }
            w
        };
        let ring: Vec<Vec3> = (0..sides)
            .map(|k| {
                let (s, c) = sin_cos_turns(k as f32 / sides as f32);
                e1 * c + e2 * s
            })
            .collect();
        let base = self.positions.len() as u32;
        for j in 0..=SEGMENTS {
            let t = j as f32 / SEGMENTS as f32;
            let (centre, r) = (a + (b - a) * t, part.r[0] + (part.r[1] - part.r[0]) * t);
            let w = weights(t);
            for &radial in &ring {
                self.vertex(centre + radial * r, radial, &w);
            }
        }
        let at = |k: u32, j: u32| base + j * sides + k % sides;
        for j in 0..SEGMENTS {
            for k in 0..sides {
                self.indices.push([at(k, j), at(k + 1, j), at(k + 1, j + 1)]);
                self.indices.push([at(k, j), at(k + 1, j + 1), at(k, j + 1)]);
            }
        }
        for (t, normal, centre, r) in [(0.0, -dir, a, part.r[0]), (1.0, dir, b, part.r[1])] {
            let w = weights(t);
            let cap = self.positions.len() as u32;
            for &radial in &ring {
                self.vertex(centre + radial * r, normal, &w);
            }
            for k in 1..sides - 1 {
                if t == 0.0 {
                    self.indices.push([cap, cap + k + 1, cap + k]);
                } else {
                    self.indices.push([cap, cap + k, cap + k + 1]);
                }
            }
        }
    }

    /// The head: a UV sphere on the head joint.
    fn head(&mut self, sides: u32) {
        let (seg, rings) = (sides, (sides / 2).max(3));
        let c = Vec3::from(HEAD_CENTRE);
        let base = self.positions.len() as u32;
        for j in 0..=rings {
            let (sp, cp) = sin_cos_turns(0.5 * j as f32 / rings as f32);
            for k in 0..seg {
                let (st, ct) = sin_cos_turns(k as f32 / seg as f32);
                let n = Vec3::new(sp * ct, cp, sp * st);
                self.vertex(c + n * HEAD_RADIUS, n, &[(4, 1.0)]);
            }
        }
        let at = |k: u32, j: u32| base + j * seg + k % seg;
        for j in 0..rings {
            for k in 0..seg {
                let (a, b, cc, d) = (at(k, j), at(k + 1, j), at(k + 1, j + 1), at(k, j + 1));
                if j > 0 {
                    self.indices.push([a, b, d]);
                }
                if j + 1 < rings {
                    self.indices.push([b, cc, d]);
                }
            }
        }
    }

    /// The finished mesh, moved to world space by `root` (a rigid transform), bound to `skin`.
    fn finish(self, name: String, material: usize, skin: usize, root: &Mat4, node: usize) -> Mesh {
        let positions: Vec<Vec3> =
            self.positions.iter().map(|p| root.transform_point3(*p)).collect();
        let normals: Vec<Vec3> =
            self.normals.iter().map(|n| root.transform_vector3(*n).normalize()).collect();
        Mesh {
            name,
            uvs: vec![Vec2::ZERO; positions.len()],
            indices: self.indices,
            material,
            skin: Some(SkinBinding {
                skin,
                joints: self.joints,
                weights: self.weights,
                bind_positions: positions.clone(),
                bind_normals: normals.clone(),
            }),
            node: Some(node),
            positions,
            normals,
        }
    }
}

/// Keys of one channel sampled at `times` by `f` (rotations as xyzw, vectors as xyz).
fn keyed(node: usize, property: AnimatedProperty, times: &[f32], values: Vec<f32>) -> Channel {
    Channel { node, property, interpolation: Interpolation::Linear, times: times.to_vec(), values }
}

/// The walker's root placement at phase `a` (turns) of its circle.
fn on_circle(centre: Vec3, radius: f32, a: f32, clockwise: bool) -> Transform {
    let (s, c) = sin_cos_turns(a);
    let (pos, facing) = if clockwise {
        (centre + Vec3::new(c, 0.0, -s) * radius, quat(Vec3::Y, a + 0.5))
    } else {
        (centre + Vec3::new(c, 0.0, s) * radius, quat(Vec3::Y, -a))
    };
    Transform { translation: pos, rotation: facing, scale: Vec3::ONE }
}

/// Adds walker `w` (its nodes, skin, meshes and channels) to the scene under construction.
fn walker(
    p: &CrowdParams,
    w: u32,
    centre: Vec3,
    scene: &mut Scene,
    channels: &mut Vec<Channel>,
    materials: [usize; 3],
) {
    let mut rng = Rng::stream(p.seed, &[1, w as u64]);
    let phase = rng.next_f32();
    let clockwise = w % 2 == 1;
    let start = rng.next_f32();
    let radius = 0.3 * p.spacing;
    let root_rest = on_circle(centre, radius, start, clockwise);
    let root = scene.nodes.len();
    scene.nodes.push(Node {
        name: format!("walker{w}"),
        parent: None,
        local: root_rest.matrix(),
        world: root_rest.matrix(),
        trs: Some(root_rest),
    });
    let first = scene.nodes.len();
    let mut joint_world = Vec::with_capacity(JOINTS.len());
    for (name, parent, pos) in JOINTS {
        let parent_pos = parent.map_or(Vec3::ZERO, |q| Vec3::from(JOINTS[q].2));
        let t = Transform { translation: Vec3::from(pos) - parent_pos, ..Default::default() };
        let parent_world = parent.map_or(root_rest.matrix(), |q| joint_world[q]);
        let world = parent_world * t.matrix();
        joint_world.push(world);
        scene.nodes.push(Node {
            name: format!("walker{w}/{name}"),
            parent: Some(parent.map_or(root, |q| first + q)),
            local: t.matrix(),
            world,
            trs: Some(t),
        });
    }
    let skin = scene.skins.len();
    scene.skins.push(Skin {
        name: format!("walker{w}"),
        joints: (first..first + JOINTS.len()).collect(),
        inverse_bind_matrices: joint_world.iter().map(|m| m.inverse()).collect(),
    });
    let mut parts: [SkinnedBuilder; 3] = Default::default();
    for part in &PARTS {
        parts[part.part].tube(part, p.sides);
    }
    parts[2].head(p.sides);
    let root_m = root_rest.matrix();
    for (k, b) in parts.into_iter().enumerate() {
        let name = format!("walker{w}/{}", ["shirt", "trousers", "skin"][k]);
        scene.meshes.push(b.finish(name, materials[k], skin, &root_m, root));
    }
    // The root's circle: 32 keys over the animation.
    let keys = 32;
    let times: Vec<f32> = (0..=keys).map(|k| p.duration * k as f32 / keys as f32).collect();
    let path: Vec<Transform> = (0..=keys)
        .map(|k| on_circle(centre, radius, start + k as f32 / keys as f32, clockwise))
        .collect();
    channels.push(keyed(
        root,
        AnimatedProperty::Translation,
        &times,
        path.iter().flat_map(|t| t.translation.to_array()).collect(),
    ));
    channels.push(keyed(
        root,
        AnimatedProperty::Rotation,
        &times,
        path.iter().flat_map(|t| t.rotation.to_array()).collect(),
    ));
    // The walk cycle: whole strides of about a second, 16 keys a stride.
    let strides = p.duration.round().max(1.0) as u32;
    let keys = 16 * strides;
    let times: Vec<f32> = (0..=keys).map(|k| p.duration * k as f32 / keys as f32).collect();
    let phi: Vec<f32> =
        (0..=keys).map(|k| phase + strides as f32 * k as f32 / keys as f32).collect();
    let sin = |t: f32| sin_cos_turns(t).0;
    let cos = |t: f32| sin_cos_turns(t).1;
    let rot = |joint: usize, f: &dyn Fn(f32) -> Quat| {
        keyed(
            first + joint,
            AnimatedProperty::Rotation,
            &times,
            phi.iter().flat_map(|&x| f(x).to_array()).collect(),
        )
    };
    let hips_rest = Vec3::from(JOINTS[0].2);
    channels.push(keyed(
        first,
        AnimatedProperty::Translation,
        &times,
        phi.iter()
            .flat_map(|&x| (hips_rest + Vec3::Y * (0.03 * cos(2.0 * x))).to_array())
            .collect(),
    ));
    channels.push(rot(0, &|x| quat(Vec3::Y, deg(7.0) * sin(x))));
    channels.push(rot(1, &|x| quat(Vec3::Y, -deg(7.0) * sin(x))));
    for (hip, knee, ankle, shoulder, elbow, side) in
        [(11, 12, 13, 5, 6, 0.0), (14, 15, 16, 8, 9, 0.5)]
    {
        channels.push(rot(hip, &move |x| quat(Vec3::X, -deg(30.0) * sin(x + side))));
        channels.push(rot(knee, &move |x| {
            quat(Vec3::X, deg(5.0 + 65.0 * (0.5 - 0.5 * cos(x + side + 0.07))))
        }));
        channels.push(rot(ankle, &move |x| quat(Vec3::X, deg(10.0) * sin(x + side))));
        channels.push(rot(shoulder, &move |x| quat(Vec3::X, deg(25.0) * sin(x + side))));
        channels.push(rot(elbow, &move |x| {
            quat(Vec3::X, -deg(15.0 + 45.0 * (0.5 - 0.5 * cos(x + side))))
        }));
    }
}

/// A torus of major radius `big` and tube radius `small` around the y axis at the origin.
fn torus(big: f32, small: f32, sides: u32) -> Mesh {
    let (seg, ring) = (2 * sides, sides);
    let mut m = Mesh { name: "torus".into(), ..Default::default() };
    for j in 0..seg {
        let (sa, ca) = sin_cos_turns(j as f32 / seg as f32);
        let centre = Vec3::new(ca, 0.0, sa) * big;
        for k in 0..ring {
            let (sb, cb) = sin_cos_turns(k as f32 / ring as f32);
            let n = Vec3::new(ca * cb, sb, sa * cb);
            m.positions.push(centre + n * small);
            m.normals.push(n);
        }
    }
    let at = |j: u32, k: u32| (j % seg) * ring + k % ring;
    for j in 0..seg {
        for k in 0..ring {
            let (a, b, c, d) = (at(j, k), at(j + 1, k), at(j + 1, k + 1), at(j, k + 1));
            m.indices.push([a, d, c]);
            m.indices.push([a, c, b]);
        }
    }
    m
}

/// Builds the crowd (module docs).
pub fn crowd(p: &CrowdParams) -> Result<Scene> {
    p.validate()?;
    // Walkers on a grid of slots, rigid objects on the corners between them.
    let cols = (p.walkers as f32).sqrt().ceil() as u32;
    let rows = p.walkers.div_ceil(cols);
    let rigid_rows = p.rigid.div_ceil(cols + 1);
    let width = (cols + 1) as f32 * p.spacing;
    let depth = (rows + 1).max(rigid_rows) as f32 * p.spacing;
    let at =
        |x: f32, z: f32| Vec3::new(x * p.spacing - 0.5 * width, 0.0, z * p.spacing - 0.5 * depth);
    let walker_slot = |w: u32| at((w % cols) as f32 + 1.0, (w / cols) as f32 + 1.0);
    let object_slot = |o: u32| at((o % (cols + 1)) as f32 + 0.5, (o / (cols + 1)) as f32 + 0.5);
    let mut scene = Scene { name: "crowd".into(), ..Default::default() };
    scene.materials.push(Material::diffuse("floor", Vec3::splat(0.55)));
    let mut palette = |name: &str, colours: &[[f32; 3]]| -> Vec<usize> {
        colours
            .iter()
            .enumerate()
            .map(|(i, c)| {
                scene.materials.push(Material::diffuse(&format!("{name}{i}"), Vec3::from(*c)));
                scene.materials.len() - 1
            })
            .collect()
    };
    let shirts = palette("shirt", &SHIRTS);
    let trousers = palette("trousers", &TROUSERS);
    let skins = palette("skin", &SKIN);
    let objects = palette("object", &[[0.75, 0.55, 0.2], [0.3, 0.6, 0.65]]);
    let mut channels = Vec::new();
    for w in 0..p.walkers {
        let mut rng = Rng::stream(p.seed, &[2, w as u64]);
        let materials = [
            shirts[rng.below(SHIRTS.len() as u32) as usize],
            trousers[rng.below(TROUSERS.len() as u32) as usize],
            skins[rng.below(SKIN.len() as u32) as usize],
        ];
        let centre = walker_slot(w);
        walker(p, w, centre, &mut scene, &mut channels, materials);
    }
    let keys = 8;
    let times: Vec<f32> = (0..=keys).map(|k| p.duration * k as f32 / keys as f32).collect();
    for o in 0..p.rigid {
        let mut rng = Rng::stream(p.seed, &[3, o as u64]);
        let axis = (rng.unit_vector() + Vec3::Y * 1.5).normalize();
        let height = rng.range(1.1, 1.7);
        let pos = object_slot(o) + Vec3::Y * height;
        let t = Transform { translation: pos, ..Default::default() };
        let node = scene.nodes.len();
        scene.nodes.push(Node {
            name: format!("object{o}"),
            parent: None,
            local: t.matrix(),
            world: t.matrix(),
            trs: Some(t),
        });
        let mut mesh = if o % 2 == 0 {
            let mut m = torus(0.3, 0.1, p.sides);
            m.name = format!("object{o}/torus");
            m
        } else {
            let mut m = super::primitives::cube(Vec3::splat(-0.25), Vec3::splat(0.25));
            m.name = format!("object{o}/cube");
            m
        };
        for v in &mut mesh.positions {
            *v += pos;
        }
        mesh.material = objects[(o % 2) as usize];
        mesh.node = Some(node);
        scene.meshes.push(mesh);
        let turns = if rng.next_f32() < 0.5 { 1.0 } else { -1.0 };
        channels.push(keyed(
            node,
            AnimatedProperty::Rotation,
            &times,
            (0..=keys)
                .flat_map(|k| quat(axis, turns * k as f32 / keys as f32).to_array())
                .collect(),
        ));
    }
    let (hw, hd) = (0.5 * width, 0.5 * depth);
    let mut floor = super::primitives::quad(
        Vec3::new(-hw, 0.0, hd),
        Vec3::new(width, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -depth),
        false,
    );
    floor.name = "floor".into();
    floor.material = 0;
    scene.meshes.push(floor);
    scene.animations.push(Animation { name: "walk".into(), channels });
    scene.lights.push(Light::Directional {
        to_light: Vec3::new(0.35, 1.0, 0.45).normalize(),
        irradiance: Vec3::new(3.0, 2.9, 2.7),
    });
    scene.background = super::SKY;
    let radius = 0.5 * (width * width + depth * depth).sqrt();
    scene.camera =
        Some(super::framing(Vec3::new(0.25, 0.55, 1.0), Vec3::new(0.0, 0.8, 0.0), radius, 40.0));
    scene.validate()?;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Pose;

    #[test]
    fn walkers_have_17_joints_over_2k_triangles_and_the_counts_are_exact() {
        for sides in [8, 12] {
            let p = CrowdParams { walkers: 3, rigid: 4, sides, ..Default::default() };
            let s = crowd(&p).unwrap();
            assert_eq!(s.skins.len(), 3);
            assert!(s.skins.iter().all(|k| k.joints.len() == 17));
            let walker: usize = s
                .meshes
                .iter()
                .filter(|m| m.name.starts_with("walker0/"))
                .map(|m| m.triangle_count())
                .sum();
            assert_eq!(walker as u64, p.walker_triangles());
            assert!(walker >= 2000, "{walker}");
            assert_eq!(s.triangle_count() as u64, p.triangle_count());
        }
        assert_eq!(CrowdParams::default().walker_triangles(), 3512);
        assert_eq!(CrowdParams { sides: 8, ..Default::default() }.walker_triangles(), 2288);
    }

    #[test]
    fn rest_joint_matrices_are_the_identity_and_the_walk_bends_the_knees() {
        let p = CrowdParams { walkers: 2, rigid: 2, ..Default::default() };
        let s = crowd(&p).unwrap();
        let rest = Pose::rest(&s.nodes);
        for skin in &s.skins {
            for m in skin.joint_matrices(&rest).unwrap() {
                assert!(m.abs_diff_eq(Mat4::IDENTITY, 1e-5), "{m}");
            }
        }
        let anim = &s.animations[0];
        anim.check(&s.nodes).unwrap();
        assert!((anim.duration() - 4.0).abs() < 1e-6);
        // Over a stride the left knee's angle spans 5° … 70° (sampled).
        let knee = s.skins[0].joints[12];
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        for k in 0..64 {
            let pose = anim.pose(&s.nodes, k as f32 / 64.0).unwrap();
            let (_, r, _) = pose.local[knee].to_scale_rotation_translation();
            let a = r.to_axis_angle().1.to_degrees();
            lo = lo.min(a);
            hi = hi.max(a);
        }
        assert!(lo < 6.0 && hi > 69.0, "{lo} … {hi}");
        // The loop closes: t = 0 and t = duration give the same pose.
        let a = anim.pose(&s.nodes, 0.0).unwrap();
        let b = anim.pose(&s.nodes, anim.duration()).unwrap();
        for (x, y) in a.world.iter().zip(&b.world) {
            assert!(x.abs_diff_eq(*y, 1e-4), "{x} vs {y}");
        }
    }

    #[test]
    fn the_crowd_is_deterministic_and_checks_its_parameters() {
        let p = CrowdParams { walkers: 4, rigid: 3, ..Default::default() };
        assert_eq!(crowd(&p).unwrap(), crowd(&p).unwrap());
        let e = crowd(&CrowdParams { walkers: 257, ..Default::default() }).unwrap_err().to_string();
        assert!(e.contains("crowd.walkers"), "{e}");
        let e = crowd(&CrowdParams { sides: 4, ..Default::default() }).unwrap_err().to_string();
        assert!(e.contains("crowd.sides"), "{e}");
    }
}
