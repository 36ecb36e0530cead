//! The node hierarchy: local and world transforms, [`Node`]s, the mesh instances of the scene
//! to load, [`Skin`]s with their joint matrices, [`Animation`] channels and the camera.

use std::path::Path;

use ::gltf::json;
use glam::{DMat4, DQuat, DVec3, Mat4, Quat, Vec3};
use json::accessor::Type;
use json::validation::Checked;

use super::accessor::Data;
use super::parse::err;
use crate::animation::{AnimatedProperty, Channel, Interpolation, Transform};
use crate::{Animation, Camera, Node, Result, Skin};

/// `n` numbers of `nodes[i].<key>` read in `f64` from the JSON value, or `None` when absent or
/// not `n` numbers (gltf-json's validation has then refused the file already).
fn raw_numbers<const N: usize>(raw: &json::Value, i: usize, key: &str) -> Option<[f64; N]> {
    let items = raw.pointer(&format!("/nodes/{i}/{key}"))?.as_array()?;
    let mut out = [0.0; N];
    if items.len() != N {
        return None;
    }
    for (o, v) in out.iter_mut().zip(items) {
        *o = v.as_f64()?;
    }
    Some(out)
}

/// A node's local transform in `f64` (the JSON's own digits: gltf-json keeps only `f32`),
/// checked finite, and its TRS form unless given by a matrix.
fn local(
    path: &Path,
    i: usize,
    node: &json::Node,
    raw: &json::Value,
) -> Result<(DMat4, Option<Transform>)> {
    let bad = |what: &str| err(path, format!("nodes[{i}]"), format!("{what} is not finite"));
    if let Some(m) = node.matrix {
        let m = raw_numbers::<16>(raw, i, "matrix")
            .map_or_else(|| Mat4::from_cols_array(&m).as_dmat4(), |m| DMat4::from_cols_array(&m));
        return if m.is_finite() { Ok((m, None)) } else { Err(bad("matrix")) };
    }
    let vec3 = |key: &str, given: Option<[f32; 3]>, default: f64| {
        raw_numbers::<3>(raw, i, key)
            .map(DVec3::from_array)
            .or(given.map(|g| Vec3::from_array(g).as_dvec3()))
            .unwrap_or(DVec3::splat(default))
    };
    let t = vec3("translation", node.translation, 0.0);
    let s = vec3("scale", node.scale, 1.0);
    let r = raw_numbers::<4>(raw, i, "rotation").map(DQuat::from_array).unwrap_or_else(|| {
        Quat::from_array(node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r.0)).as_dquat()
    });
    if !t.is_finite() {
        return Err(bad("translation"));
    }
    if !s.is_finite() {
        return Err(bad("scale"));
    }
    if !r.is_finite() || r.length_squared() == 0.0 {
        return Err(err(path, format!("nodes[{i}]"), format!("rotation {r} is not a rotation")));
    }
    let r = r.normalize();
    let trs = Transform { translation: t.as_vec3(), rotation: r.as_quat(), scale: s.as_vec3() };
    Ok((DMat4::from_scale_rotation_translation(s, r, t), Some(trs)))
}

/// Every node with its local and world (rest pose) transforms, and the world transforms in
/// `f64`. `parents` comes from [`super::parse::node_parents`], so the graph is a forest. The
/// `f32` matrices of the nodes are still in world coordinates: [`recentre`] moves them.
pub(super) fn nodes(
    path: &Path,
    root: &json::Root,
    raw: &json::Value,
    parents: &[Option<usize>],
) -> Result<(Vec<Node>, Vec<DMat4>)> {
    let mut out: Vec<Node> = Vec::with_capacity(root.nodes.len());
    let mut locals = Vec::with_capacity(root.nodes.len());
    for (i, node) in root.nodes.iter().enumerate() {
        let (local, trs) = local(path, i, node, raw)?;
        locals.push(local);
        out.push(Node {
            name: node.name.clone().unwrap_or_else(|| format!("nodes[{i}]")),
            parent: parents[i],
            local: local.as_mat4(),
            world: Mat4::IDENTITY,
            trs,
        });
    }
    let mut world = vec![DMat4::IDENTITY; out.len()];
    let mut done = vec![false; out.len()];
    for start in 0..out.len() {
        let mut chain = vec![start];
        while let Some(p) = out[*chain.last().unwrap_or(&start)].parent.filter(|&p| !done[p]) {
            chain.push(p);
        }
        for &i in chain.iter().rev() {
            let parent_world = out[i].parent.map_or(DMat4::IDENTITY, |p| world[p]);
            world[i] = parent_world * locals[i];
            out[i].world = world[i].as_mat4();
            done[i] = true;
        }
    }
    Ok((out, world))
}

/// Moves the node hierarchy into the scene's local coordinates: every world matrix becomes
/// `translate(−origin) · world` (from the `f64` ones), and so does every root's local transform,
/// its TRS translation and the values of the translation channels that animate a root, so that
/// posed and rest-pose meshes stay in the same local frame.
pub(super) fn recentre(
    nodes: &mut [Node],
    world: &[DMat4],
    animations: &mut [Animation],
    origin: DVec3,
) {
    if origin == DVec3::ZERO {
        return;
    }
    let shift = DMat4::from_translation(-origin);
    for (node, w) in nodes.iter_mut().zip(world) {
        node.world = (shift * *w).as_mat4();
        if node.parent.is_none() {
            node.local = node.world;
            if let Some(t) = &mut node.trs {
                t.translation = (t.translation.as_dvec3() - origin).as_vec3();
            }
        }
    }
    for ch in animations.iter_mut().flat_map(|a| &mut a.channels) {
        let root = nodes.get(ch.node).is_some_and(|n| n.parent.is_none());
        if ch.property != AnimatedProperty::Translation || !root {
            continue;
        }
        // Cubic splines store (in-tangent, value, out-tangent) per key: only values move.
        let (per_key, at) =
            if ch.interpolation == Interpolation::CubicSpline { (9, 3) } else { (3, 0) };
        for key in ch.values.chunks_exact_mut(per_key) {
            let v = &mut key[at..at + 3];
            let moved = Vec3::from_slice(v).as_dvec3() - origin;
            v.copy_from_slice(&moved.as_vec3().to_array());
        }
    }
}

/// The nodes of the scene to load, parents before children: the default scene, else the first
/// scene, else (no scenes at all) every root node.
pub(super) fn scene_nodes(root: &json::Root, parents: &[Option<usize>]) -> Vec<usize> {
    let roots: Vec<usize> =
        match root.scene.map(|s| s.value()).or((!root.scenes.is_empty()).then_some(0)) {
            Some(s) => root.scenes[s].nodes.iter().map(|n| n.value()).collect(),
            None => (0..root.nodes.len()).filter(|&i| parents[i].is_none()).collect(),
        };
    let mut order = Vec::new();
    let mut stack: Vec<usize> = roots.into_iter().rev().collect();
    while let Some(i) = stack.pop() {
        order.push(i);
        stack.extend(root.nodes[i].children.iter().flatten().rev().map(|c| c.value()));
    }
    order
}

/// Skins, with their inverse bind matrices (identity when absent).
pub(super) fn skins(data: &Data) -> Result<Vec<Skin>> {
    let mut out = Vec::new();
    for (s, skin) in data.root.skins.iter().enumerate() {
        let joints: Vec<usize> = skin.joints.iter().map(|j| j.value()).collect();
        let ibms = match skin.inverse_bind_matrices {
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(a) => {
                let usage = format!("inverseBindMatrices of skins[{s}]");
                let (_, m) = data.floats(a.value(), &[Type::Mat4], false, &usage)?;
                let m: Vec<Mat4> = m.chunks_exact(16).map(Mat4::from_cols_slice).collect();
                if m.len() < joints.len() {
                    return Err(err(
                        data.path,
                        format!("skins[{s}]"),
                        format!(
                            "{} joints but accessors[{}] has {} inverse bind matrices",
                            joints.len(),
                            a.value(),
                            m.len()
                        ),
                    ));
                }
                m
            }
        };
        out.push(Skin {
            name: skin.name.clone().unwrap_or_else(|| format!("skins[{s}]")),
            joints,
            inverse_bind_matrices: ibms,
        });
    }
    Ok(out)
}

/// Animation channels with their key times and values.
pub(super) fn animations(data: &Data) -> Result<Vec<Animation>> {
    let mut out = Vec::new();
    for (a, anim) in data.root.animations.iter().enumerate() {
        let mut channels = Vec::new();
        for (c, ch) in anim.channels.iter().enumerate() {
            let element = format!("animations[{a}].channels[{c}]");
            let bad = |reason: String| err(data.path, &element, reason);
            let sampler = anim
                .samplers
                .get(ch.sampler.value())
                .ok_or_else(|| bad("sampler does not exist".into()))?;
            let (Checked::Valid(prop), Checked::Valid(interp)) =
                (&ch.target.path, &sampler.interpolation)
            else {
                return Err(bad("invalid target path or interpolation".into()));
            };
            use json::animation::{Interpolation as I, Property as P};
            let (property, types) = match prop {
                P::Translation => (AnimatedProperty::Translation, &[Type::Vec3][..]),
                P::Rotation => (AnimatedProperty::Rotation, &[Type::Vec4][..]),
                P::Scale => (AnimatedProperty::Scale, &[Type::Vec3][..]),
                P::MorphTargetWeights => (AnimatedProperty::MorphWeights, &[Type::Scalar][..]),
            };
            let interpolation = match interp {
                I::Linear => Interpolation::Linear,
                I::Step => Interpolation::Step,
                I::CubicSpline => Interpolation::CubicSpline,
            };
            let (_, times) = data.floats(
                sampler.input.value(),
                &[Type::Scalar],
                false,
                &format!("input of {element}"),
            )?;
            if let Some(k) = times.windows(2).position(|w| w[1] < w[0]) {
                return Err(bad(format!("key time {} is before key time {k}", k + 1)));
            }
            let usage = format!("output of {element}");
            let (_, values) = data.floats(sampler.output.value(), types, true, &usage)?;
            let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
            let width = types[0].multiplicity();
            if times.is_empty() || values.len() % (times.len() * per_key * width) != 0 {
                return Err(bad(format!(
                    "{} output values do not fit {} keys of {per_key}×{width}",
                    values.len() / width,
                    times.len()
                )));
            }
            channels.push(Channel {
                node: ch.target.node.value(),
                property,
                interpolation,
                times,
                values,
            });
        }
        out.push(Animation {
            name: anim.name.clone().unwrap_or_else(|| format!("animations[{a}]")),
            channels,
        });
    }
    Ok(out)
}

/// The first perspective camera met in `order`, placed by its node's world transform, and the
/// number of orthographic cameras skipped.
pub(super) fn camera(
    path: &Path,
    root: &json::Root,
    order: &[usize],
    world: &[DMat4],
    origin: DVec3,
) -> Result<(Option<Camera>, usize)> {
    let mut orthographic = 0;
    for &n in order {
        let Some(c) = root.nodes[n].camera.map(|c| c.value()) else { continue };
        let Some(p) = &root.cameras[c].perspective else {
            orthographic += 1;
            continue;
        };
        let w = world[n];
        let eye = (w.transform_point3(DVec3::ZERO) - origin).as_vec3();
        let forward = w.transform_vector3(DVec3::NEG_Z).normalize_or_zero().as_vec3();
        let cam = Camera {
            eye,
            target: eye + forward,
            up: w.transform_vector3(DVec3::Y).as_vec3(),
            fov_y_deg: p.yfov.to_degrees(),
        };
        cam.validate().map_err(|e| err(path, format!("cameras[{c}] (on nodes[{n}])"), e))?;
        return Ok((Some(cam), orthographic));
    }
    Ok((None, orthographic))
}
