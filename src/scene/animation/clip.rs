//! glTF animation clips: each channel's keyframes read and checked once, and sampled at any
//! time (STEP, LINEAR with shortest-path quaternion slerp, CUBICSPLINE Hermite splines with
//! the tangents scaled by the key interval, glTF 2.0 Appendix C).

use super::super::accessor::{self, BufferData};
use glam::DQuat;
use gltf::json::animation::{Interpolation, Property};
use gltf::json::validation::Checked;

/// The node property a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `translation` (3 values).
    Translation,
    /// `rotation`, a unit quaternion x, y, z, w (4 values).
    Rotation,
    /// `scale` (3 values).
    Scale,
    /// Morph target `weights` (one value per target).
    Weights,
}

/// How values between keys are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interp {
    /// The earlier key's value.
    Step,
    /// Linear, rotations by spherical interpolation along the shorter arc.
    Linear,
    /// Cubic Hermite spline through the keys with the file's in and out tangents.
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug)]
pub struct Channel {
    /// The node animated (index in the file's `nodes`).
    pub node: usize,
    /// Which property.
    pub target: Target,
    /// Interpolation.
    pub interp: Interp,
    /// Key times in seconds, finite and strictly increasing, at least one.
    pub times: Vec<f32>,
    /// Key values, `width` a key (`3 × width` a key for a cubic spline: in tangent, value,
    /// out tangent), all finite.
    pub values: Vec<f32>,
    /// Values per element: 3, 4 or the number of morph targets.
    pub width: usize,
}

/// A named animation: channels over a common timeline from 0 to `duration`.
#[derive(Clone, Debug)]
pub struct Clip {
    /// The file's name, else "animation N".
    pub name: String,
    /// The last key time over its channels (seconds); 0 for a clip of one instant.
    pub duration: f64,
    /// The channels kept (the bad ones were skipped with a warning).
    pub channels: Vec<Channel>,
}

/// The file's clips in order. A bad channel (a sampler, node or accessor that does not exist,
/// times not increasing, a non-finite value, counts that do not match) is skipped with one
/// warning naming it; a clip keeps its place in the list even when all its channels went.
pub fn read_clips(
    root: &gltf::json::Root,
    data: &BufferData,
    warnings: &mut Vec<String>,
) -> Vec<Clip> {
    root.animations
        .iter()
        .enumerate()
        .map(|(a, animation)| {
            let channels: Vec<Channel> = animation
                .channels
                .iter()
                .enumerate()
                .filter_map(|(c, channel)| {
                    read_channel(root, data, animation, channel)
                        .map_err(|why| {
                            warnings.push(format!(
                                "animations[{a}].channels[{c}]{why}; the channel is skipped"
                            ))
                        })
                        .ok()
                })
                .collect();
            let duration = channels
                .iter()
                .filter_map(|c| c.times.last())
                .fold(0.0f64, |d, &t| d.max(f64::from(t)));
            Clip {
                name: animation
                    .name
                    .clone()
                    .unwrap_or_else(|| format!("animation {a}")),
                duration,
                channels,
            }
        })
        .collect()
}

/// One channel read and checked, or why it cannot be used: the rest of a message that starts
/// with the channel's path (": …", or ".target.node: …" for what lies under it).
fn read_channel(
    root: &gltf::json::Root,
    data: &BufferData,
    animation: &gltf::json::Animation,
    channel: &gltf::json::animation::Channel,
) -> Result<Channel, String> {
    let s = channel.sampler.value();
    let sampler = animation
        .samplers
        .get(s)
        .ok_or_else(|| format!(": sampler {s} does not exist"))?;
    let node = channel.target.node.value();
    let json_node = root
        .nodes
        .get(node)
        .ok_or_else(|| format!(".target.node: node {node} does not exist"))?;
    let target = match channel.target.path {
        Checked::Valid(Property::Translation) => Target::Translation,
        Checked::Valid(Property::Rotation) => Target::Rotation,
        Checked::Valid(Property::Scale) => Target::Scale,
        Checked::Valid(Property::MorphTargetWeights) => Target::Weights,
        Checked::Invalid => return Err(".target.path: not a path glTF defines".into()),
    };
    if target != Target::Weights && json_node.matrix.is_some() {
        return Err(format!(
            ": nodes[{node}] is placed by a matrix, which animations may not target"
        ));
    }
    let interp = match sampler.interpolation {
        Checked::Valid(Interpolation::Step) => Interp::Step,
        Checked::Valid(Interpolation::Linear) => Interp::Linear,
        Checked::Valid(Interpolation::CubicSpline) => Interp::CubicSpline,
        Checked::Invalid => return Err(format!(": samplers[{s}].interpolation is unknown")),
    };
    let width = match target {
        Target::Translation | Target::Scale => 3,
        Target::Rotation => 4,
        Target::Weights => {
            let targets = json_node
                .mesh
                .and_then(|m| root.meshes.get(m.value()))
                .and_then(|m| m.primitives.first())
                .and_then(|p| p.targets.as_ref())
                .map_or(0, Vec::len);
            if targets == 0 {
                return Err(format!(
                    ": nodes[{node}] has no mesh with morph targets for its weights"
                ));
            }
            targets
        }
    };
    use gltf::json::accessor::Type;
    // The accessor `index` of `what`, checked to be of the type `wanted`.
    let typed = |index: usize, what: &str, wanted: Type| -> Result<usize, String> {
        let a = root
            .accessors
            .get(index)
            .ok_or_else(|| format!(": samplers[{s}].{what}: accessor {index} does not exist"))?;
        match a.type_ {
            Checked::Valid(t) if t == wanted => Ok(index),
            Checked::Valid(t) if what == "output" => Err(format!(
                ": its sampler's output is {t:?}, the path needs {wanted:?}"
            )),
            _ => Err(format!(
                ": samplers[{s}].{what}: accessor {index} is not {wanted:?}"
            )),
        }
    };
    let wanted = match target {
        Target::Translation | Target::Scale => Type::Vec3,
        Target::Rotation => Type::Vec4,
        Target::Weights => Type::Scalar,
    };
    let output = typed(sampler.output.value(), "output", wanted)?;
    let input = typed(sampler.input.value(), "input", Type::Scalar)?;
    let at = |what: &'static str| move |e: String| format!(": samplers[{s}].{what}: {e}");
    let times = read_flat::<1>(root, data, input).map_err(at("input"))?;
    // Outputs are read flat: a VEC3 or VEC4 accessor as its components in order.
    let values = match wanted {
        Type::Vec3 => read_flat::<3>(root, data, output),
        Type::Vec4 => read_flat::<4>(root, data, output),
        _ => read_flat::<1>(root, data, output),
    }
    .map_err(at("output"))?;
    if times.is_empty() {
        return Err(format!(": samplers[{s}].input has no keys"));
    }
    if let Some(k) = times.iter().position(|t| !t.is_finite()) {
        return Err(format!(": samplers[{s}].input: key {k} is not finite"));
    }
    if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
        return Err(format!(
            ": samplers[{s}].input: key {} ({}) does not come after key {k} ({})",
            k + 1,
            times[k + 1],
            times[k]
        ));
    }
    let per_key = width * if interp == Interp::CubicSpline { 3 } else { 1 };
    if values.len() != times.len() * per_key {
        return Err(format!(
            ": samplers[{s}].output holds {} values for {} keys of {per_key}",
            values.len(),
            times.len()
        ));
    }
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(format!(": samplers[{s}].output: value {k} is not finite"));
    }
    Ok(Channel {
        node,
        target,
        interp,
        times,
        values,
        width,
    })
}

/// Accessor `index`'s elements of `N` components, one after the other.
fn read_flat<const N: usize>(
    root: &gltf::json::Root,
    data: &BufferData,
    index: usize,
) -> Result<Vec<f32>, String> {
    Ok(accessor::read_floats::<N>(root, data, index)?
        .into_iter()
        .flatten()
        .collect())
}

impl Channel {
    /// The channel's value at `t` seconds, written into `out` (`width` values); before the
    /// first key the first value, after the last the last. A rotation comes out unit length.
    pub fn sample(&self, t: f64, out: &mut [f64]) {
        let w = self.width;
        let cubic = self.interp == Interp::CubicSpline;
        let stride = if cubic { 3 * w } else { w };
        // The value (not a tangent) of key `k`, component `c`.
        let value =
            |k: usize, c: usize| f64::from(self.values[k * stride + if cubic { w } else { 0 } + c]);
        let after = self.times.partition_point(|&k| f64::from(k) <= t);
        let last = self.times.len() - 1;
        if after == 0 || after > last || self.interp == Interp::Step {
            let k = after.clamp(1, last + 1) - 1;
            for (c, o) in out.iter_mut().enumerate().take(w) {
                *o = value(k, c);
            }
        } else {
            let (k0, k1) = (after - 1, after);
            let (t0, t1) = (f64::from(self.times[k0]), f64::from(self.times[k1]));
            let dt = t1 - t0;
            let u = (t - t0) / dt;
            match self.interp {
                Interp::Linear if self.target == Target::Rotation => {
                    let q =
                        |k| DQuat::from_xyzw(value(k, 0), value(k, 1), value(k, 2), value(k, 3));
                    let q = slerp(q(k0), q(k1), u);
                    out[..4].copy_from_slice(&q.to_array());
                }
                Interp::Linear => {
                    for (c, o) in out.iter_mut().enumerate().take(w) {
                        *o = value(k0, c) + (value(k1, c) - value(k0, c)) * u;
                    }
                }
                _ => {
                    // Hermite basis; the out tangent of k0 and the in tangent of k1 are
                    // per second, so they are scaled by the interval.
                    let (u2, u3) = (u * u, u * u * u);
                    let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
                    let h10 = u3 - 2.0 * u2 + u;
                    let h01 = -2.0 * u3 + 3.0 * u2;
                    let h11 = u3 - u2;
                    for (c, o) in out.iter_mut().enumerate().take(w) {
                        let out_tangent = f64::from(self.values[k0 * stride + 2 * w + c]);
                        let in_tangent = f64::from(self.values[k1 * stride + c]);
                        *o = h00 * value(k0, c)
                            + h10 * dt * out_tangent
                            + h01 * value(k1, c)
                            + h11 * dt * in_tangent;
                    }
                }
            }
        }
        if self.target == Target::Rotation {
            let q = DQuat::from_slice(&out[..4]);
            let q = if q.length_squared() > 0.0 {
                q.normalize()
            } else {
                DQuat::IDENTITY
            };
            out[..4].copy_from_slice(&q.to_array());
        }
    }
}

/// Spherical interpolation from `a` to `b` along the shorter arc (`b` negated when the two
/// lie in opposite hemispheres), linear where they are nearly equal.
pub fn slerp(a: DQuat, b: DQuat, u: f64) -> DQuat {
    let mut d = a.dot(b);
    let b = if d < 0.0 {
        d = -d;
        -b
    } else {
        b
    };
    if d > 1.0 - 1e-9 {
        return (a + (b - a) * u).normalize();
    }
    let theta = d.acos();
    let s = theta.sin();
    let (wa, wb) = (((1.0 - u) * theta).sin() / s, (u * theta).sin() / s);
    (a * wa + b * wb).normalize()
}
