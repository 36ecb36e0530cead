//! [`DynamicScene`]: a scene split into its static meshes and its moving objects (rigid nodes
//! and skins an animation drives), each object's geometry in its own space, its placement in a
//! pose, and the posed scene (the ground truth a frame is compared with).

use glam::{DMat4, DVec3, Mat4, Vec3};
use voxlod_octree::dynamic::Placement;
use voxlod_scene::{Animation, Geometry, Mesh, Pose, Scene};

use crate::{Error, Result};

/// How a moving object moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectKind {
    /// With one node's world matrix (meshes placed by that node).
    Rigid {
        /// The node.
        node: usize,
    },
    /// By linear blend skinning of one skin's joints (every mesh bound to it).
    Skinned {
        /// The skin.
        skin: usize,
    },
}

/// One moving object: the meshes that move together.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicObject {
    /// Name (node or skin name), for messages.
    pub name: String,
    /// How it moves.
    pub kind: ObjectKind,
    /// Its meshes (indices into the scene's meshes).
    pub meshes: Vec<usize>,
}

/// A scene with one animation, split into static meshes and moving objects.
///
/// A mesh moves when it is skinned (it belongs to its skin's object) or when the animation
/// drives its node or one of the node's ancestors (it belongs to its node's object); every
/// other mesh is static.
#[derive(Clone, Debug)]
pub struct DynamicScene {
    /// The scene at rest (its meshes in world space at the rest pose).
    pub scene: Scene,
    /// The animation that moves it.
    pub animation: Animation,
    /// Indices of the static meshes.
    pub statics: Vec<usize>,
    /// The moving objects.
    pub objects: Vec<DynamicObject>,
}

/// Relative tolerance of the rest-pose scale checks.
const SCALE_TOLERANCE: f64 = 1e-3;

/// The uniform scale of `m`'s linear part, or `None` if it scales non-uniformly or shears.
pub fn uniform_scale(m: &DMat4) -> Option<f64> {
    let cols = [m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate()];
    let s = cols.map(|c| c.length());
    let mean = (s[0] + s[1] + s[2]) / 3.0;
    let ok = mean > 0.0
        && s.iter().all(|x| (x / mean - 1.0).abs() <= SCALE_TOLERANCE)
        && [(0, 1), (0, 2), (1, 2)]
            .iter()
            .all(|&(i, j)| cols[i].dot(cols[j]).abs() <= SCALE_TOLERANCE * s[i] * s[j]);
    ok.then_some(mean)
}

fn dmat(m: &Mat4) -> DMat4 {
    m.as_dmat4()
}

impl DynamicScene {
    /// Splits `scene` by its animation `animation` (index into `scene.animations`). Errors: no
    /// such animation, an animation [`Animation::check`] refuses, a skinned mesh without
    /// bind-space positions.
    pub fn new(scene: Scene, animation: usize) -> Result<Self> {
        let Some(anim) = scene.animations.get(animation).cloned() else {
            return Err(Error::InvalidParameter {
                name: "animation",
                value: animation.to_string(),
                reason: format!("scene '{}' has {} animations", scene.name, scene.animations.len()),
            });
        };
        scene.validate()?;
        anim.check(&scene.nodes)?;
        let mut driven = vec![false; scene.nodes.len()];
        for c in &anim.channels {
            driven[c.node] = true;
        }
        // A node moves if it or an ancestor is driven.
        let moves = |mut n: usize| {
            for _ in 0..=scene.nodes.len() {
                if driven[n] {
                    return true;
                }
                match scene.nodes[n].parent {
                    Some(p) => n = p,
                    None => return false,
                }
            }
            false
        };
        let mut statics = Vec::new();
        let mut objects: Vec<DynamicObject> = Vec::new();
        for (i, mesh) in scene.meshes.iter().enumerate() {
            let kind = match (&mesh.skin, mesh.node) {
                (Some(s), _) => {
                    let bad = |reason: String| Error::Dynamic { object: mesh.name.clone(), reason };
                    if s.bind_positions.len() != mesh.positions.len()
                        || s.bind_normals.len() != mesh.positions.len()
                    {
                        return Err(bad(
                            "skinned, but without bind-space positions and normals".into()
                        ));
                    }
                    let Some(skin) = scene.skins.get(s.skin) else {
                        return Err(bad(format!("skin {} does not exist", s.skin)));
                    };
                    let n = skin.joints.len().min(skin.inverse_bind_matrices.len());
                    let out_of_range = s
                        .joints
                        .iter()
                        .zip(&s.weights)
                        .any(|(j, w)| (0..4).any(|k| w[k] > 0.0 && j[k] as usize >= n));
                    if out_of_range || skin.joints.iter().any(|&j| j >= scene.nodes.len()) {
                        return Err(bad(format!(
                            "a joint index is outside skin {} or its nodes",
                            s.skin
                        )));
                    }
                    ObjectKind::Skinned { skin: s.skin }
                }
                (None, Some(n)) if n < scene.nodes.len() && moves(n) => {
                    ObjectKind::Rigid { node: n }
                }
                _ => {
                    statics.push(i);
                    continue;
                }
            };
            match objects.iter_mut().find(|o| o.kind == kind) {
                Some(o) => o.meshes.push(i),
                None => {
                    let name = match kind {
                        ObjectKind::Rigid { node } => scene.nodes[node].name.clone(),
                        ObjectKind::Skinned { skin } => scene
                            .skins
                            .get(skin)
                            .map_or_else(|| format!("skins[{skin}]"), |s| s.name.clone()),
                    };
                    objects.push(DynamicObject { name, kind, meshes: vec![i] });
                }
            }
        }
        Ok(Self { scene, animation: anim, statics, objects })
    }

    /// Every node's matrices at `time` seconds, looped over the animation's duration.
    pub fn pose(&self, time: f32) -> Result<Pose> {
        let d = self.animation.duration();
        let t = if d > 0.0 && time.is_finite() { time.rem_euclid(d) } else { time };
        Ok(self.animation.pose(&self.scene.nodes, t)?)
    }

    /// The static meshes as one geometry (world space).
    pub fn static_geometry(&self) -> Geometry {
        let mut s = self.scene.clone();
        s.meshes = self.statics.iter().map(|&i| self.scene.meshes[i].clone()).collect();
        s.geometry()
    }

    fn skin_error(&self, o: &DynamicObject, reason: String) -> Error {
        Error::Dynamic { object: o.name.clone(), reason }
    }

    /// Object `o`'s geometry in its own space (a rigid object's node space, a skinned
    /// object's bind space) and its object-to-world scale at rest. Errors: a rest transform
    /// that scales non-uniformly or shears, or joints of different scales.
    pub fn object_geometry(&self, o: &DynamicObject) -> Result<(Geometry, f64)> {
        let mut g = Geometry::default();
        let scale = match o.kind {
            ObjectKind::Rigid { node } => {
                let rest = dmat(&self.scene.nodes[node].world);
                uniform_scale(&rest).ok_or_else(|| {
                    self.skin_error(
                        o,
                        "its node's rest transform scales non-uniformly or shears".into(),
                    )
                })?
            }
            ObjectKind::Skinned { skin } => self.rest_joint_scale(o, skin)?,
        };
        for &i in &o.meshes {
            let m = &self.scene.meshes[i];
            let base = g.positions.len() as u32;
            match o.kind {
                ObjectKind::Rigid { node } => {
                    let rest = dmat(&self.scene.nodes[node].world);
                    let inv = rest.inverse();
                    let lin = glam::DMat3::from_mat4(rest).transpose();
                    g.positions.extend(
                        m.positions.iter().map(|p| inv.transform_point3(p.as_dvec3()).as_vec3()),
                    );
                    g.normals.extend(
                        m.normals
                            .iter()
                            .map(|n| (lin * n.as_dvec3()).normalize_or_zero().as_vec3()),
                    );
                }
                ObjectKind::Skinned { .. } => {
                    let s = m.skin.as_ref().expect("skinned object meshes are skinned");
                    g.positions.extend_from_slice(&s.bind_positions);
                    g.normals.extend_from_slice(&s.bind_normals);
                }
            }
            if m.uvs.is_empty() {
                g.uvs.extend(std::iter::repeat_n(glam::Vec2::ZERO, m.positions.len()));
            } else {
                g.uvs.extend_from_slice(&m.uvs);
            }
            g.indices.extend(m.indices.iter().map(|t| t.map(|v| v + base)));
            g.materials.extend(std::iter::repeat_n(m.material as u32, m.indices.len()));
        }
        Ok((g, scale))
    }

    /// Per vertex of [`DynamicScene::object_geometry`]: joints and weights (skinned objects).
    pub fn object_skin(&self, o: &DynamicObject) -> Vec<([u16; 4], [f32; 4])> {
        o.meshes
            .iter()
            .flat_map(|&i| {
                let m = &self.scene.meshes[i];
                m.skin.iter().flat_map(|s| s.joints.iter().copied().zip(s.weights.iter().copied()))
            })
            .collect()
    }

    /// The common scale of the joint matrices at rest of the joints `o`'s vertices use.
    fn rest_joint_scale(&self, o: &DynamicObject, skin: usize) -> Result<f64> {
        let s = self.scene.skins.get(skin).ok_or_else(|| {
            self.skin_error(
                o,
                format!("skin {skin} does not exist ({} skins)", self.scene.skins.len()),
            )
        })?;
        let joints = s.joint_matrices(&Pose::rest(&self.scene.nodes))?;
        let mut used = vec![false; joints.len()];
        for (j, w) in self.object_skin(o) {
            for k in 0..4 {
                if w[k] > 0.0 {
                    match used.get_mut(j[k] as usize) {
                        Some(u) => *u = true,
                        None => {
                            return Err(self.skin_error(
                                o,
                                format!(
                                    "a vertex uses joint {} of a skin with {} joints",
                                    j[k],
                                    joints.len()
                                ),
                            ));
                        }
                    }
                }
            }
        }
        let mut scale: Option<f64> = None;
        for (k, m) in joints.iter().enumerate().filter(|(k, _)| used[*k]) {
            let s = uniform_scale(&dmat(m)).ok_or_else(|| {
                self.skin_error(
                    o,
                    format!("joint {k}'s rest matrix scales non-uniformly or shears"),
                )
            })?;
            match scale {
                None => scale = Some(s),
                Some(t) if (s / t - 1.0).abs() <= SCALE_TOLERANCE => {}
                Some(t) => {
                    return Err(self.skin_error(
                        o,
                        format!("joint matrices at rest have different scales ({t} and {s} at joint {k})"),
                    ));
                }
            }
        }
        scale.ok_or_else(|| self.skin_error(o, "no vertex has a joint weight".into()))
    }

    /// Every object's placement in `pose` (same order as [`DynamicScene::objects`]): a rigid
    /// object's node world matrix, a skinned object's joint matrices.
    pub fn placements(&self, pose: &Pose) -> Result<Vec<Placement>> {
        self.objects
            .iter()
            .map(|o| {
                Ok(match o.kind {
                    ObjectKind::Rigid { node } => Placement::Rigid(dmat(&pose.world[node])),
                    ObjectKind::Skinned { skin } => Placement::Skinned(
                        self.scene.skins[skin].joint_matrices(pose)?.iter().map(dmat).collect(),
                    ),
                })
            })
            .collect()
    }

    /// The scene in `pose`: every moving mesh moved (rigid: by its node's motion from the rest
    /// pose; skinned: linear blend skinning of its bind positions and normals), static meshes
    /// as they are.
    pub fn posed_scene(&self, pose: &Pose) -> Result<Scene> {
        let mut scene = self.scene.clone();
        for o in &self.objects {
            for &i in &o.meshes {
                let mesh = &mut scene.meshes[i];
                match o.kind {
                    ObjectKind::Rigid { node } => {
                        let m =
                            dmat(&pose.world[node]) * dmat(&self.scene.nodes[node].world).inverse();
                        let n = glam::DMat3::from_mat4(m).inverse().transpose();
                        for p in &mut mesh.positions {
                            *p = m.transform_point3(p.as_dvec3()).as_vec3();
                        }
                        for v in &mut mesh.normals {
                            *v = (n * v.as_dvec3()).normalize_or_zero().as_vec3();
                        }
                    }
                    ObjectKind::Skinned { skin } => {
                        let joints = self.scene.skins[skin].joint_matrices(pose)?;
                        skin_mesh(mesh, &joints);
                    }
                }
            }
        }
        scene.validate()?;
        Ok(scene)
    }
}

/// Linear blend skinning of `mesh`'s bind positions and normals by `joints`.
fn skin_mesh(mesh: &mut Mesh, joints: &[Mat4]) {
    let Some(s) = &mesh.skin else { return };
    for v in 0..mesh.positions.len() {
        let mut m = Mat4::ZERO;
        for k in 0..4 {
            if s.weights[v][k] > 0.0 {
                m += joints[s.joints[v][k] as usize] * s.weights[v][k];
            }
        }
        mesh.positions[v] = m.transform_point3(s.bind_positions[v]);
        mesh.normals[v] = m.transform_vector3(s.bind_normals[v]).try_normalize().unwrap_or(Vec3::Y);
    }
}

/// The bounds of a geometry's vertices in `f64`.
pub(crate) fn bounds(g: &Geometry) -> Option<(DVec3, DVec3)> {
    g.bounds().map(|(lo, hi)| (lo.as_dvec3(), hi.as_dvec3()))
}
