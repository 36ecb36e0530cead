//! The node hierarchy: local and world transforms, [`Node`]s, the mesh instances of the scene
//! to load, [`Skin`]s with their joint matrices, [`Animation`] channels and the camera.

use std::path::Path;

use ::gltf::json;
use glam::{Mat4, Quat, Vec3};
use json::accessor::Type;
use json::validation::Checked;

use super::accessor::Data;
use super::parse::err;
use crate::animation::{AnimatedProperty, Channel, Interpolation, Transform};
use crate::{Animation, Camera, Node, Result, Skin};

/// A node's local transform, checked finite, and its TRS form unless given by a matrix.
fn local(path: &Path, i: usize, node: &json::Node) -> Result<(Mat4, Option<Transform>)> {
    let bad = |what: &str| err(path, format!("nodes[{i}]"), format!("{what} is not finite"));
    if let Some(m) = node.matrix {
        let m = Mat4::from_cols_array(&m);
        return if m.is_finite() { Ok((m, None)) } else { Err(bad("matrix")) };
    }
    let t = Vec3::from_array(node.translation.unwrap_or([0.0; 3]));
    let s = Vec3::from_array(node.scale.unwrap_or([1.0; 3]));
    let r = Quat::from_array(node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r.0));
    if !t.is_finite() {
        return Err(bad("translation"));
    }
    if !s.is_finite() {
        return Err(bad("scale"));
    }
    if !r.is_finite() || r.length_squared() == 0.0 {
        return Err(err(path, format!("nodes[{i}]"), format!("rotation {r} is not a rotation")));
    }
    let trs = Transform { translation: t, rotation: r.normalize(), scale: s };
    Ok((trs.matrix(), Some(trs)))
}

/// Every node with its local and world (rest pose) transforms. `parents` comes from
/// [`super::parse::node_parents`], so the graph is a forest.
pub(super) fn nodes(
    path: &Path,
    root: &json::Root,
    parents: &[Option<usize>],
) -> Result<Vec<Node>> {
    let mut out: Vec<Node> = Vec::with_capacity(root.nodes.len());
    for (i, node) in root.nodes.iter().enumerate() {
        let (local, trs) = local(path, i, node)?;
        out.push(Node {
            name: node.name.clone().unwrap_or_else(|| format!("nodes[{i}]")),
            parent: parents[i],
            local,
            world: Mat4::IDENTITY,
            trs,
        });
    }
    let mut done = vec![false; out.len()];
    for start in 0..out.len() {
        let mut chain = vec![start];
        while let Some(p) = out[*chain.last().unwrap_or(&start)].parent.filter(|&p| !done[p]) {
            chain.push(p);
        }
        for &i in chain.iter().rev() {
            let parent_world = out[i].parent.map_or(Mat4::IDENTITY, |p| out[p].world);
            out[i].world = parent_world * out[i].local;
            done[i] = true;
        }
    }
    Ok(out)
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
    nodes: &[Node],
) -> Result<(Option<Camera>, usize)> {
    let mut orthographic = 0;
    for &n in order {
        let Some(c) = root.nodes[n].camera.map(|c| c.value()) else { continue };
        let Some(p) = &root.cameras[c].perspective else {
            orthographic += 1;
            continue;
        };
        let w = nodes[n].world;
        let eye = w.transform_point3(Vec3::ZERO);
        let forward = w.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let cam = Camera {
            eye,
            target: eye + forward,
            up: w.transform_vector3(Vec3::Y),
            fov_y_deg: p.yfov.to_degrees(),
        };
        cam.validate().map_err(|e| err(path, format!("cameras[{c}] (on nodes[{n}])"), e))?;
        return Ok((Some(cam), orthographic));
    }
    Ok((None, orthographic))
}
