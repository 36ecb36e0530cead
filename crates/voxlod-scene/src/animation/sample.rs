//! Evaluating channels and animations at a time (the rules are in the [module docs](super)).

use glam::{Mat4, Quat, Vec3};

use super::{AnimatedProperty, Animation, Channel, Interpolation, Node, Transform};
use crate::{Error, Result};

/// Every node's local and world matrix at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Local matrix per node (relative to its parent).
    pub local: Vec<Mat4>,
    /// World matrix per node (the parent's world times the local).
    pub world: Vec<Mat4>,
}

impl Pose {
    /// The rest pose: the nodes' own local and world matrices.
    pub fn rest(nodes: &[Node]) -> Self {
        Self {
            local: nodes.iter().map(|n| n.local).collect(),
            world: nodes.iter().map(|n| n.world).collect(),
        }
    }

    /// The pose with these local matrices: world matrices composed parents first. A parent
    /// index out of range or a cycle in the parents is an [`Error::InvalidParameter`].
    pub fn from_local(nodes: &[Node], local: Vec<Mat4>) -> Result<Self> {
        let n = nodes.len();
        let mut world = vec![Mat4::IDENTITY; n];
        let mut done = vec![false; n];
        let bad = |i: usize, reason: String| Error::InvalidParameter {
            name: format!("nodes[{i}].parent"),
            value: format!("{:?}", nodes[i].parent),
            reason,
        };
        for start in 0..n {
            let mut chain = vec![start];
            let mut i = start;
            while let Some(p) = nodes[i].parent.filter(|_| !done[i]) {
                if p >= n {
                    return Err(bad(i, format!("there are {n} nodes")));
                }
                if done[p] {
                    break;
                }
                if chain.len() > n {
                    return Err(bad(start, "the parents form a cycle".into()));
                }
                chain.push(p);
                i = p;
            }
            for &c in chain.iter().rev() {
                if done[c] {
                    continue;
                }
                let parent = nodes[c].parent.map_or(Mat4::IDENTITY, |p| world[p]);
                world[c] = parent * local[c];
                done[c] = true;
            }
        }
        Ok(Self { local, world })
    }
}

/// What a channel evaluates to.
enum Sampled {
    Vec3(Vec3),
    Rotation(Quat),
}

/// Reads key `k`'s `width` floats starting `offset` values into the key (cubic splines store
/// in-tangent, value, out-tangent).
fn key(values: &[f32], width: usize, k: usize, offset: usize) -> &[f32] {
    let at = k * width + offset * width;
    &values[at..at + width]
}

impl Channel {
    /// Floats per value: 3 (translation, scale), 4 (rotation); `None` for morph weights.
    fn width(&self) -> Option<usize> {
        match self.property {
            AnimatedProperty::Translation | AnimatedProperty::Scale => Some(3),
            AnimatedProperty::Rotation => Some(4),
            AnimatedProperty::MorphWeights => None,
        }
    }

    /// Why this channel cannot be evaluated, if it cannot.
    fn problem(&self) -> Option<String> {
        let Some(width) = self.width() else {
            return Some(
                "drives morph-target weights: voxel transformation moves rigid and skinned \
                 geometry only, and a static pose would be silently wrong"
                    .into(),
            );
        };
        let per_key = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if self.times.is_empty() {
            return Some("has no keys".into());
        }
        if self.values.len() != self.times.len() * per_key * width {
            return Some(format!(
                "{} keys of {per_key}×{width} floats need {} values, has {}",
                self.times.len(),
                self.times.len() * per_key * width,
                self.values.len()
            ));
        }
        if let Some(k) = self.times.iter().position(|t| !t.is_finite()) {
            return Some(format!("key time {k} is {}", self.times[k]));
        }
        if let Some(k) = self.times.windows(2).position(|w| w[1] < w[0]) {
            return Some(format!("key time {} is before key time {k}", k + 1));
        }
        if let Some(i) = self.values.iter().position(|v| !v.is_finite()) {
            return Some(format!("value {i} is {}", self.values[i]));
        }
        None
    }

    /// The value at `time` (module rules); the channel has passed [`Channel::problem`].
    fn sample(&self, time: f32) -> std::result::Result<Sampled, String> {
        let width = self.width().unwrap_or(3);
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let stride = if cubic { 3 } else { 1 };
        let value = |k: usize| key(&self.values, width, k * stride, usize::from(cubic));
        let n = self.times.len();
        // The last key at or before `time` (the later of equal keys), or none.
        let after = self.times.partition_point(|&t| t <= time);
        let rotation = self.property == AnimatedProperty::Rotation;
        let out = |v: Vec<f32>| -> std::result::Result<Sampled, String> {
            if rotation {
                let q = Quat::from_slice(&v);
                let len = q.length();
                if len.is_nan() || len <= 1e-6 || !len.is_finite() {
                    return Err(format!("the rotation at time {time} is {q}, not a rotation"));
                }
                Ok(Sampled::Rotation(q / len))
            } else {
                Ok(Sampled::Vec3(Vec3::from_slice(&v)))
            }
        };
        if after == 0 {
            return out(value(0).to_vec());
        }
        let k = after - 1;
        if k + 1 >= n || self.interpolation == Interpolation::Step {
            return out(value(k).to_vec());
        }
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let td = t1 - t0; // > 0: t0 ≤ time < t1
        let s = ((time - t0) / td).clamp(0.0, 1.0);
        match self.interpolation {
            Interpolation::Linear if rotation => {
                let a = Quat::from_slice(value(k));
                let b = Quat::from_slice(value(k + 1));
                let (la, lb) = (a.length(), b.length());
                if !(la > 1e-6 && lb > 1e-6) {
                    return Err(format!("key {k} or {} is a zero quaternion", k + 1));
                }
                let (a, mut b) = (a / la, b / lb);
                if a.dot(b) < 0.0 {
                    b = -b;
                }
                out(a.slerp(b, s).to_array().to_vec())
            }
            Interpolation::Linear => {
                let (a, b) = (value(k), value(k + 1));
                out(a.iter().zip(b).map(|(a, b)| a + (b - a) * s).collect())
            }
            Interpolation::CubicSpline => {
                let v0 = value(k);
                let b0 = key(&self.values, width, 3 * k, 2); // out-tangent of key k
                let v1 = value(k + 1);
                let a1 = key(&self.values, width, 3 * (k + 1), 0); // in-tangent of key k+1
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                out((0..width)
                    .map(|i| h00 * v0[i] + h10 * td * b0[i] + h01 * v1[i] + h11 * td * a1[i])
                    .collect())
            }
            Interpolation::Step => unreachable!("handled above"),
        }
    }
}

impl Animation {
    fn error(&self, channel: usize, reason: String) -> Error {
        Error::Animation {
            animation: self.name.clone(),
            channel,
            node: self.channels[channel].node,
            reason,
        }
    }

    /// Checks that every channel can be evaluated on `nodes` (module rules): no morph weights,
    /// existing TRS nodes, keys matching values, finite and ordered times and values.
    pub fn check(&self, nodes: &[Node]) -> Result<()> {
        for (c, ch) in self.channels.iter().enumerate() {
            if let Some(reason) = ch.problem() {
                return Err(self.error(c, reason));
            }
            match nodes.get(ch.node) {
                None => {
                    return Err(
                        self.error(c, format!("the node does not exist ({} nodes)", nodes.len()))
                    );
                }
                Some(node) if node.trs.is_none() => {
                    return Err(self.error(
                        c,
                        format!(
                            "node '{}' is given by a matrix, which cannot be animated",
                            node.name
                        ),
                    ));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }

    /// Every node's local and world matrix at `time` seconds (module rules; clamped to the
    /// keys, not looped). Errors as [`Animation::check`], and for a non-finite time or a
    /// rotation that interpolates to zero.
    pub fn pose(&self, nodes: &[Node], time: f32) -> Result<Pose> {
        self.check(nodes)?;
        if !time.is_finite() {
            let reason = format!("time {time} is not finite");
            return Err(match self.channels.is_empty() {
                true => Error::InvalidParameter {
                    name: format!("time of animation '{}'", self.name),
                    value: time.to_string(),
                    reason,
                },
                false => self.error(0, reason),
            });
        }
        let mut trs: Vec<Option<Transform>> = vec![None; nodes.len()];
        for (c, ch) in self.channels.iter().enumerate() {
            let t = trs[ch.node].get_or_insert_with(|| nodes[ch.node].trs.unwrap_or_default());
            match ch.sample(time).map_err(|reason| self.error(c, reason))? {
                Sampled::Rotation(q) => t.rotation = q,
                Sampled::Vec3(v) if ch.property == AnimatedProperty::Scale => t.scale = v,
                Sampled::Vec3(v) => t.translation = v,
            }
        }
        let local =
            nodes.iter().zip(&trs).map(|(n, t)| t.map_or(n.local, |t| t.matrix())).collect();
        Pose::from_local(nodes, local)
    }
}
