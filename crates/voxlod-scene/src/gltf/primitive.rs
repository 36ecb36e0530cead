//! One mesh primitive instanced by one node, to a [`Mesh`]: triangle lists, strips and fans;
//! morph targets at the node's (or mesh's) default weights; skinning at the rest pose; positions
//! by the world matrix in `f64` (re-centred by the caller), normals by its inverse transpose,
//! winding flipped where the transform mirrors.

use ::gltf::json;
use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};
use json::accessor::{ComponentType as C, Type};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

use super::LoadReport;
use super::accessor::Data;
use super::material::UvMapping;
use super::parse::err;
use crate::mesh::SkinBinding;
use crate::{Mesh, Result};

/// Where a primitive is instanced.
pub(super) struct Instance<'a> {
    /// The node.
    pub node: usize,
    /// The node's world matrix (ignored for a skinned mesh, as the specification says).
    pub world: DMat4,
    /// The node's skin and its joint matrices (joint world × inverse bind matrix).
    pub skin: Option<(usize, &'a [DMat4])>,
}

/// The triangles of an index list drawn with `mode`.
fn assemble(mode: Mode, idx: &[u32]) -> std::result::Result<Vec<[u32; 3]>, String> {
    let n = idx.len();
    Ok(match mode {
        Mode::Triangles if !n.is_multiple_of(3) => {
            return Err(format!("TRIANGLES needs a multiple of 3 vertices or indices, has {n}"));
        }
        Mode::Triangles => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        // Triangles repeating an index only stitch strips together: dropped.
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i], idx[i + 2], idx[i + 1]]
                }
            })
            .filter(|[a, b, c]| a != b && b != c && a != c)
            .collect(),
        Mode::TriangleFan => {
            (1..n.saturating_sub(1)).map(|i| [idx[i], idx[i + 1], idx[0]]).collect()
        }
        _ => Vec::new(),
    })
}

/// The inverse transpose of `m`'s linear part, or `None` when it is singular.
fn normal_matrix(m: &DMat4) -> Option<DMat3> {
    let m3 = DMat3::from_mat4(*m);
    let inv = m3.inverse();
    (m3.determinant() != 0.0 && inv.is_finite()).then(|| inv.transpose())
}

/// A primitive built by [`mesh`]: its positions in `f32` relative to its own re-centring origin
/// (so that its normals are computed at full precision) and in world coordinates in `f64`, for
/// the caller to re-centre on the scene's origin.
pub(super) struct Built {
    /// The mesh, positions relative to the primitive's own re-centring origin.
    pub mesh: Mesh,
    /// World positions in `f64`.
    pub world: Vec<DVec3>,
}

/// Unit bind-space normals: the file's where they have a length, else area-weighted ones of the
/// bind-space triangles (wound as the world ones).
fn bind_normals(positions: &[Vec3], triangles: &[[u32; 3]], file: Option<&[Vec3]>) -> Vec<Vec3> {
    let mut m =
        Mesh { positions: positions.to_vec(), indices: triangles.to_vec(), ..Default::default() };
    m.compute_normals();
    if let Some(file) = file {
        for (out, n) in m.normals.iter_mut().zip(file) {
            if let Some(unit) = n.try_normalize() {
                *out = unit;
            }
        }
    }
    m.normals
}

/// Builds primitive `p` of mesh `m` as instanced by `inst`; `None` for points, lines and
/// primitives without triangles (counted in `report`).
pub(super) fn mesh(
    data: &Data,
    (m, p): (usize, usize),
    inst: &Instance,
    material: usize,
    uv_map: &UvMapping,
    report: &mut LoadReport,
) -> Result<Option<Built>> {
    let gmesh = &data.root.meshes[m];
    let prim = &gmesh.primitives[p];
    let element = format!("meshes[{m}].primitives[{p}]");
    let usage = |what: &str| format!("{what} of {element}");
    let Checked::Valid(mode) = prim.mode else {
        return Err(err(data.path, &element, "invalid mode"));
    };
    match mode {
        Mode::Points => report.points_skipped += 1,
        Mode::Lines | Mode::LineLoop | Mode::LineStrip => report.lines_skipped += 1,
        Mode::TriangleStrip | Mode::TriangleFan => report.strips_and_fans_converted += 1,
        Mode::Triangles => {}
    }
    if matches!(mode, Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
        return Ok(None);
    }
    let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
    let pos_a =
        attr(Semantic::Positions).ok_or_else(|| err(data.path, &element, "has no POSITION"))?;
    let (_, pos) = data.floats(pos_a, &[Type::Vec3], false, &usage("POSITION"))?;
    let mut positions: Vec<Vec3> = pos.chunks_exact(3).map(Vec3::from_slice).collect();
    let n = positions.len();
    let same_count = |a: usize, len: usize, what: &str| {
        if len == n {
            Ok(())
        } else {
            Err(err(
                data.path,
                format!("accessors[{a}]"),
                format!("{} has {len} elements, POSITION has {n}", usage(what)),
            ))
        }
    };
    let indices = match prim.indices.map(|a| a.value()) {
        Some(a) => {
            let idx =
                data.uints(a, &[Type::Scalar], &[C::U8, C::U16, C::U32], &usage("indices"))?;
            if let Some(k) = idx.iter().position(|&i| i as usize >= n) {
                return Err(err(
                    data.path,
                    format!("accessors[{a}]"),
                    format!(
                        "index {k} = {} is out of range: POSITION (accessors[{pos_a}]) has {n} vertices ({})",
                        idx[k],
                        usage("indices")
                    ),
                ));
            }
            idx
        }
        None => (0..n as u32).collect(),
    };
    let mut triangles = assemble(mode, &indices).map_err(|e| err(data.path, &element, e))?;
    if triangles.is_empty() {
        return Ok(None);
    }

    let mut normals: Option<Vec<Vec3>> = match attr(Semantic::Normals) {
        Some(a) => {
            let (_, v) = data.floats(a, &[Type::Vec3], false, &usage("NORMAL"))?;
            same_count(a, v.len() / 3, "NORMAL")?;
            Some(v.chunks_exact(3).map(Vec3::from_slice).collect())
        }
        None => None,
    };
    let weights = data.root.nodes[inst.node].weights.as_ref().or(gmesh.weights.as_ref());
    for (t, target) in prim.targets.iter().flatten().enumerate() {
        let w = weights.and_then(|w| w.get(t)).copied().unwrap_or(0.0);
        if w == 0.0 {
            continue;
        }
        if !w.is_finite() {
            return Err(err(
                data.path,
                format!("nodes[{}]", inst.node),
                format!("morph weight {t} is {w}"),
            ));
        }
        report.morph_targets_applied += 1;
        if let Some(a) = target.positions.map(|a| a.value()) {
            let (_, d) =
                data.floats(a, &[Type::Vec3], true, &usage(&format!("targets[{t}].POSITION")))?;
            same_count(a, d.len() / 3, "a morph target")?;
            positions
                .iter_mut()
                .zip(d.chunks_exact(3))
                .for_each(|(p, d)| *p += w * Vec3::from_slice(d));
        }
        if let (Some(a), Some(normals)) = (target.normals.map(|a| a.value()), normals.as_mut()) {
            let (_, d) =
                data.floats(a, &[Type::Vec3], true, &usage(&format!("targets[{t}].NORMAL")))?;
            same_count(a, d.len() / 3, "a morph target")?;
            normals
                .iter_mut()
                .zip(d.chunks_exact(3))
                .for_each(|(n, d)| *n += w * Vec3::from_slice(d));
        }
    }

    let uv_set = uv_map.set.unwrap_or(0);
    let uvs = match attr(Semantic::TexCoords(uv_set)) {
        Some(a) => {
            let what = format!("TEXCOORD_{uv_set}");
            let (_, v) = data.floats(a, &[Type::Vec2], true, &usage(&what))?;
            same_count(a, v.len() / 2, &what)?;
            v.chunks_exact(2).map(|c| uv_map.apply(Vec2::from_slice(c))).collect()
        }
        None if uv_map.set.is_some() => {
            return Err(err(
                data.path,
                &element,
                format!(
                    "its material's baseColorTexture reads TEXCOORD_{uv_set}, which the primitive does not have"
                ),
            ));
        }
        None => Vec::new(),
    };

    // Per-vertex transforms: the node's, or the skin's blend of joint matrices.
    let mut skin = None;
    let per_vertex: Option<Vec<DMat4>> = match inst.skin {
        None => None,
        Some((s, joint_mats)) => {
            let (Some(ja), Some(wa)) = (attr(Semantic::Joints(0)), attr(Semantic::Weights(0)))
            else {
                return Err(err(
                    data.path,
                    &element,
                    format!("is skinned by nodes[{}] but has no JOINTS_0/WEIGHTS_0", inst.node),
                ));
            };
            let joints = data.uints(ja, &[Type::Vec4], &[C::U8, C::U16], &usage("JOINTS_0"))?;
            let (_, w) = data.floats(wa, &[Type::Vec4], true, &usage("WEIGHTS_0"))?;
            same_count(ja, joints.len() / 4, "JOINTS_0")?;
            same_count(wa, w.len() / 4, "WEIGHTS_0")?;
            let mut mats = Vec::with_capacity(n);
            let mut binding = SkinBinding {
                skin: s,
                joints: Vec::with_capacity(n),
                weights: Vec::with_capacity(n),
                bind_positions: positions.clone(),
                bind_normals: Vec::new(),
            };
            for (v, (j, w)) in joints.chunks_exact(4).zip(w.chunks_exact(4)).enumerate() {
                let sum: f32 = w.iter().sum();
                if let Some(&bad) = j
                    .iter()
                    .zip(w)
                    .find(|(j, w)| **j as usize >= joint_mats.len() && **w != 0.0)
                    .map(|(j, _)| j)
                {
                    return Err(err(
                        data.path,
                        format!("accessors[{ja}]"),
                        format!(
                            "element {v}: joint {bad} does not exist in skins[{s}] ({} joints)",
                            joint_mats.len()
                        ),
                    ));
                }
                if sum.is_nan() || sum <= 0.0 || w.iter().any(|&x| x < 0.0) {
                    return Err(err(
                        data.path,
                        format!("accessors[{wa}]"),
                        format!(
                            "element {v} of {}: weights {w:?} are negative or sum to 0",
                            usage("WEIGHTS_0")
                        ),
                    ));
                }
                let wn = [w[0] / sum, w[1] / sum, w[2] / sum, w[3] / sum];
                let blend = (0..4)
                    .filter(|&k| wn[k] != 0.0)
                    .fold(DMat4::ZERO, |acc, k| acc + joint_mats[j[k] as usize] * wn[k] as f64);
                mats.push(blend);
                binding.joints.push([j[0], j[1], j[2], j[3]].map(|x| x as u16));
                binding.weights.push(wn);
            }
            // Before the winding is flipped for mirroring transforms: bind-space winding.
            binding.bind_normals = bind_normals(&positions, &triangles, normals.as_deref());
            skin = Some(binding);
            Some(mats)
        }
    };
    let transform = |v: usize| per_vertex.as_ref().map_or(&inst.world, |m| &m[v]);
    let world: Vec<DVec3> = positions
        .iter()
        .enumerate()
        .map(|(v, p)| transform(v).transform_point3(p.as_dvec3()))
        .collect();
    // Positions relative to the primitive's own re-centring origin: finite in f32 unless the
    // transform made a vertex non-finite or the primitive wider than f32 holds.
    let bounds = world.iter().try_fold(None::<(DVec3, DVec3)>, |b, &p| {
        p.is_finite().then(|| Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p)))))
    });
    let anchor = bounds
        .flatten()
        .and_then(|(lo, hi)| voxlod_format::origin::recentring_origin(lo, hi))
        .unwrap_or(DVec3::ZERO);
    for (p, w) in positions.iter_mut().zip(&world) {
        *p = (*w - anchor).as_vec3();
    }
    if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
        return Err(err(
            data.path,
            format!("nodes[{}]", inst.node),
            format!("its transform makes vertex {v} of {element} non-finite"),
        ));
    }
    for t in &mut triangles {
        if DMat3::from_mat4(*transform(t[0] as usize)).determinant() < 0.0 {
            t.swap(1, 2);
        }
    }
    let name = gmesh.name.clone().unwrap_or_else(|| format!("meshes[{m}]"));
    let mut mesh = Mesh {
        name: format!("{name} ({element}, nodes[{}])", inst.node),
        positions,
        uvs,
        indices: triangles,
        material,
        skin,
        node: Some(inst.node),
        ..Default::default()
    };
    mesh.compute_normals();
    let mut computed = n;
    if let Some(file) = normals {
        let world_nm = normal_matrix(&inst.world);
        for (v, (out, nf)) in mesh.normals.iter_mut().zip(file).enumerate() {
            let nm = match &per_vertex {
                Some(mats) => normal_matrix(&mats[v]),
                None => world_nm,
            };
            if let Some(unit) = nm.and_then(|nm| (nm * nf.as_dvec3()).as_vec3().try_normalize()) {
                *out = unit;
                computed -= 1;
            }
        }
    }
    report.normals_computed += computed;
    Ok(Some(Built { mesh, world }))
}
