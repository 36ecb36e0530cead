//! Animation sampling: hand-made channels of every interpolation, the glTF `simple_skin` file,
//! and the errors.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};

use super::*;

fn node(name: &str, parent: Option<usize>, t: Transform) -> Node {
    Node { name: name.into(), parent, local: t.matrix(), world: Mat4::IDENTITY, trs: Some(t) }
}

fn channel(
    node: usize,
    property: AnimatedProperty,
    interpolation: Interpolation,
    times: &[f32],
    values: &[f32],
) -> Channel {
    Channel { node, property, interpolation, times: times.to_vec(), values: values.to_vec() }
}

fn anim(channels: Vec<Channel>) -> Animation {
    Animation { name: "test".into(), channels }
}

fn translation_at(a: &Animation, nodes: &[Node], t: f32) -> Vec3 {
    a.pose(nodes, t).unwrap().local[0].w_axis.truncate()
}

fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
    (a - b).abs().max_element() <= eps
}

#[test]
fn step_linear_and_clamping_of_a_translation() {
    let nodes = [node("n", None, Transform::default())];
    let keys = [1.0, 2.0, 4.0];
    let values = [0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 10.0, 20.0, 0.0];
    let lin = anim(vec![channel(
        0,
        AnimatedProperty::Translation,
        Interpolation::Linear,
        &keys,
        &values,
    )]);
    assert_eq!(translation_at(&lin, &nodes, 0.0), Vec3::ZERO, "before the first key");
    assert_eq!(translation_at(&lin, &nodes, 1.5), Vec3::new(5.0, 0.0, 0.0));
    assert_eq!(translation_at(&lin, &nodes, 3.0), Vec3::new(10.0, 10.0, 0.0));
    assert_eq!(translation_at(&lin, &nodes, 9.0), Vec3::new(10.0, 20.0, 0.0), "after the last");
    assert_eq!(lin.duration(), 4.0);
    let step =
        anim(vec![channel(0, AnimatedProperty::Translation, Interpolation::Step, &keys, &values)]);
    assert_eq!(translation_at(&step, &nodes, 1.99), Vec3::ZERO);
    assert_eq!(translation_at(&step, &nodes, 2.0), Vec3::new(10.0, 0.0, 0.0), "at a key");
    assert_eq!(translation_at(&step, &nodes, 3.99), Vec3::new(10.0, 0.0, 0.0));
    // Equal key times: the later key holds from that time on (a jump).
    let jump = anim(vec![channel(
        0,
        AnimatedProperty::Translation,
        Interpolation::Linear,
        &[0.0, 1.0, 1.0, 2.0],
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 5.0, 0.0, 0.0, 6.0, 0.0, 0.0],
    )]);
    assert_eq!(translation_at(&jump, &nodes, 0.5).x, 0.5);
    assert_eq!(translation_at(&jump, &nodes, 1.0).x, 5.0);
    assert_eq!(translation_at(&jump, &nodes, 1.5).x, 5.5);
}

#[test]
fn cubic_spline_is_the_hermite_spline_with_scaled_tangents() {
    let nodes = [node("n", None, Transform::default())];
    // Keys at t = 1 and 3 (interval 2): value 0 → 1 on x, out-tangent of key 0 = 2, in-tangent
    // of key 1 = −1 (per second). Layout per key: in-tangent, value, out-tangent.
    let values = [
        9.0, 9.0, 9.0, /* in 0 (unused) */ 0.0, 0.0, 0.0, 2.0, 0.0, 0.0,
        /* key 1 */ -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 9.0, 9.0, 9.0, /* out 1 (unused) */
    ];
    let a = anim(vec![channel(
        0,
        AnimatedProperty::Translation,
        Interpolation::CubicSpline,
        &[1.0, 3.0],
        &values,
    )]);
    for s in [0.0f32, 0.25, 0.5, 0.9] {
        let (s2, s3) = (s * s, s * s * s);
        let expected = (s3 - 2.0 * s2 + s) * 2.0 * 2.0 + (-2.0 * s3 + 3.0 * s2) - (s3 - s2) * 2.0;
        let got = translation_at(&a, &nodes, 1.0 + 2.0 * s).x;
        assert!((got - expected).abs() < 1e-6, "s = {s}: {got} vs {expected}");
    }
    assert_eq!(translation_at(&a, &nodes, 0.0), Vec3::ZERO, "the value, not a tangent");
    assert_eq!(translation_at(&a, &nodes, 5.0), Vec3::X);
    // A cubic rotation comes out normalized.
    let q0 = Quat::IDENTITY.to_array();
    let q1 = Quat::from_rotation_y(1.0).to_array();
    let zero = [0.0; 4];
    let rot = anim(vec![channel(
        0,
        AnimatedProperty::Rotation,
        Interpolation::CubicSpline,
        &[0.0, 1.0],
        &[zero, q0, zero, zero, q1, zero].concat(),
    )]);
    let m = rot.pose(&nodes, 0.5).unwrap().local[0];
    let (_, r, _) = m.to_scale_rotation_translation();
    assert!((r.length() - 1.0).abs() < 1e-5);
    assert!((Mat4::from_quat(r).x_axis.length() - 1.0).abs() < 1e-5);
}

#[test]
fn rotations_slerp_along_the_shorter_arc_and_keep_the_other_components() {
    let rest = Transform {
        translation: Vec3::new(1.0, 2.0, 3.0),
        rotation: Quat::IDENTITY,
        scale: Vec3::splat(2.0),
    };
    let nodes = [node("n", None, rest)];
    // 0° and 270° about y, the latter stored as −q (the same rotation as −90°): the shorter arc
    // passes through −45°, not +135°.
    let a = Quat::IDENTITY;
    let b = -Quat::from_rotation_y(-std::f32::consts::FRAC_PI_2);
    let anim = anim(vec![channel(
        0,
        AnimatedProperty::Rotation,
        Interpolation::Linear,
        &[0.0, 1.0],
        &[a.to_array(), b.to_array()].concat(),
    )]);
    let m = anim.pose(&nodes, 0.5).unwrap().local[0];
    let expected =
        Transform { rotation: Quat::from_rotation_y(-std::f32::consts::FRAC_PI_4), ..rest };
    assert!(m.abs_diff_eq(expected.matrix(), 1e-5), "{m} vs {}", expected.matrix());
}

#[test]
fn poses_compose_parents_first_whatever_the_node_order() {
    // Node 0 is the child of node 1, which rotates 90° about z at t = 1.
    let nodes = [
        node("child", Some(1), Transform { translation: Vec3::X, ..Default::default() }),
        node("parent", None, Transform { translation: Vec3::Y, ..Default::default() }),
    ];
    let q = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let a = anim(vec![channel(
        1,
        AnimatedProperty::Rotation,
        Interpolation::Linear,
        &[0.0, 1.0],
        &[Quat::IDENTITY.to_array(), q.to_array()].concat(),
    )]);
    let pose = a.pose(&nodes, 1.0).unwrap();
    let child = pose.world[0].transform_point3(Vec3::ZERO);
    assert!(close(child, Vec3::new(0.0, 2.0, 0.0), 1e-6), "{child}");
    let cyclic =
        [node("a", Some(1), Transform::default()), node("b", Some(0), Transform::default())];
    let e = Pose::from_local(&cyclic, vec![Mat4::IDENTITY; 2]).unwrap_err().to_string();
    assert!(e.contains("cycle"), "{e}");
}

#[test]
fn morph_weights_matrix_nodes_and_bad_keys_are_errors() {
    let nodes = [
        node("n", None, Transform::default()),
        Node { name: "m".into(), trs: None, ..Default::default() },
    ];
    let err = |a: Animation, t: f32| a.pose(&nodes, t).unwrap_err().to_string();
    let morph = anim(vec![channel(
        0,
        AnimatedProperty::MorphWeights,
        Interpolation::Linear,
        &[0.0, 1.0],
        &[0.0, 1.0],
    )]);
    let e = err(morph, 0.5);
    assert!(e.contains("animation 'test', channel 0 (node 0)") && e.contains("morph"), "{e}");
    let lin = |node, times: &[f32], values: &[f32]| {
        anim(vec![channel(
            node,
            AnimatedProperty::Translation,
            Interpolation::Linear,
            times,
            values,
        )])
    };
    let e = err(lin(1, &[0.0], &[0.0; 3]), 0.0);
    assert!(e.contains("given by a matrix"), "{e}");
    let e = err(lin(7, &[0.0], &[0.0; 3]), 0.0);
    assert!(e.contains("does not exist"), "{e}");
    let e = err(lin(0, &[0.0, 1.0], &[0.0; 3]), 0.0);
    assert!(e.contains("need 6 values, has 3"), "{e}");
    let e = err(lin(0, &[1.0, 0.0], &[0.0; 6]), 0.0);
    assert!(e.contains("before key time"), "{e}");
    let e = err(lin(0, &[0.0], &[f32::NAN, 0.0, 0.0]), 0.0);
    assert!(e.contains("NaN"), "{e}");
    let e = err(lin(0, &[0.0], &[0.0; 3]), f32::INFINITY);
    assert!(e.contains("not finite"), "{e}");
    let zero_rot =
        anim(vec![channel(0, AnimatedProperty::Rotation, Interpolation::Step, &[0.0], &[0.0; 4])]);
    let e = err(zero_rot, 0.0);
    assert!(e.contains("not a rotation"), "{e}");
}

/// The glTF sample `simple_skin`: joint 1 (node 2, at (0, 1, 0)) rotates about z, 0° → 45° →
/// 90° over t = 0 … 1 (linear keys every 0.5 s); both inverse bind matrices translate by
/// (−0.5, −1, 0). Linear blend skinning of the bind positions reproduces the loaded rest pose
/// and the analytic pose at t = 1.
#[test]
fn simple_skin_moves_by_linear_blend_skinning() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/gltf/good/simple_skin/simple_skin.gltf");
    let scene = crate::Scene::load(&path).unwrap();
    let mesh = &scene.meshes[0];
    let skin = mesh.skin.as_ref().unwrap();
    assert_eq!(mesh.node, Some(0));
    assert_eq!(skin.bind_positions.len(), mesh.positions.len());
    assert_eq!(skin.bind_normals.len(), mesh.positions.len());
    let anim = &scene.animations[0];
    assert_eq!(anim.duration(), 5.5);
    let blend = |pose: &Pose, v: usize| {
        let j = scene.skins[skin.skin].joint_matrices(pose).unwrap();
        let m = (0..4)
            .fold(Mat4::ZERO, |acc, k| acc + j[skin.joints[v][k] as usize] * skin.weights[v][k]);
        m.transform_point3(skin.bind_positions[v])
    };
    let rest = Pose::rest(&scene.nodes);
    for v in 0..mesh.positions.len() {
        assert!(close(blend(&rest, v), mesh.positions[v], 1e-6), "vertex {v}");
    }
    // t = 0 is the rest pose too.
    let p0 = anim.pose(&scene.nodes, 0.0).unwrap();
    assert!(close(blend(&p0, 8), mesh.positions[8], 1e-6));
    // t = 1: joint 1 at (0, 1, 0) turned 90°. Vertex 8, bind (0, 2, 0), all on joint 1:
    // T(0,1,0)·Rz(90°)·(−0.5, 1, 0) = (−1, 0.5, 0). Vertex 4, bind (0, 1, 0), half on each
    // joint: joint 0 gives (−0.5, 1, 0), joint 1 T(0,1,0)·Rz(90°)·(−0.5, 0, 0) = (0, 0.5, 0).
    let p1 = anim.pose(&scene.nodes, 1.0).unwrap();
    assert_eq!(skin.bind_positions[8], Vec3::new(0.0, 2.0, 0.0));
    assert!(close(blend(&p1, 8), Vec3::new(-1.0, 0.5, 0.0), 1e-5), "{}", blend(&p1, 8));
    assert_eq!(skin.weights[4], [0.5, 0.5, 0.0, 0.0]);
    assert!(close(blend(&p1, 4), Vec3::new(-0.25, 0.75, 0.0), 1e-5), "{}", blend(&p1, 4));
    // t = 0.25: halfway to 45°, i.e. 22.5°.
    let q = anim.pose(&scene.nodes, 0.25).unwrap().local[2];
    let (_, r, _) = q.to_scale_rotation_translation();
    assert!((r.angle_between(Quat::from_rotation_z(22.5f32.to_radians()))).abs() < 1e-3);
}
