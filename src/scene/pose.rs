//! Skins and morph targets at the rest pose, applied on the host: morph targets at the node's
//! (else the mesh's) weights, then joint matrices (joint world transform at its TRS × inverse
//! bind matrix) blended per vertex.

use super::accessor::{self, Attributes, BufferData};
use super::limits;
use super::validate::PreciseNode;
use glam::{DMat4, DQuat, DVec3, Vec3, Vec4};

/// The pose a mesh is drawn in: morph target weights and skin joint matrices.
#[derive(Default)]
pub struct Pose {
    /// Morph target weights (the node's, else the mesh's; missing ones are 0).
    pub weights: Vec<f32>,
    /// `world_from_joint × inverse bind matrix` of each joint of the node's skin; empty
    /// when the node has no skin.
    pub joints: Vec<DMat4>,
}

/// World transforms of every node at its rest transform, as the scene graph nests them
/// (a node no scene reaches is placed by its own transform). Used for skin joints.
pub fn rest_worlds(document: &gltf::Document, precise: &[PreciseNode]) -> Vec<DMat4> {
    let count = document.nodes().len();
    let parent = parents(document);
    let local: Vec<DMat4> = document
        .nodes()
        .map(|n| node_matrix(&n, precise.get(n.index())).unwrap_or(DMat4::IDENTITY))
        .collect();
    (0..count)
        .map(|mut i| {
            // Walk up to the root (at most `count` steps, so a cycle ends).
            let mut world = local[i];
            for _ in 0..count {
                match parent[i] {
                    Some(p) => {
                        world = local[p] * world;
                        i = p;
                    }
                    None => break,
                }
            }
            world
        })
        .collect()
}

/// Each node's first parent (the first node listing it as a child, itself excluded).
fn parents(document: &gltf::Document) -> Vec<Option<usize>> {
    let mut parent: Vec<Option<usize>> = vec![None; document.nodes().len()];
    for node in document.nodes() {
        for child in node.children() {
            if child.index() != node.index() && parent[child.index()].is_none() {
                parent[child.index()] = Some(node.index());
            }
        }
    }
    parent
}

/// Checks, in time linear in the number of nodes, that no chain of first parents is deeper
/// than [`limits::MAX_NODE_DEPTH`] or closes a cycle. [`rest_worlds`] walks each node's chain
/// to its root, so once this passes it takes at most `MAX_NODE_DEPTH` products a node instead
/// of one a level of a chain 100,000 deep (quadratic: a minute before the walk's own check).
pub fn check_nesting(document: &gltf::Document) -> Result<(), String> {
    const UNKNOWN: usize = usize::MAX;
    const ON_CHAIN: usize = usize::MAX - 1;
    let parent = parents(document);
    let mut depth = vec![UNKNOWN; parent.len()];
    let mut chain = Vec::new();
    for start in 0..parent.len() {
        // Climb until a node of known depth or a root, then number the chain downwards: each
        // node is climbed through once over all starts.
        chain.clear();
        let mut at = start;
        let above = loop {
            match depth[at] {
                ON_CHAIN => return Err(format!("nodes[{at}]: its parents form a cycle")),
                UNKNOWN => {}
                known => break Some(known),
            }
            depth[at] = ON_CHAIN;
            chain.push(at);
            match parent[at] {
                Some(p) => at = p,
                None => break None,
            }
        };
        let top = above.map_or(0, |d| d + 1);
        for (d, &node) in (top..).zip(chain.iter().rev()) {
            if d > limits::MAX_NODE_DEPTH {
                return Err(format!(
                    "nodes[{node}]: nested more than {} deep",
                    limits::MAX_NODE_DEPTH
                ));
            }
            depth[node] = d;
        }
    }
    Ok(())
}

/// The pose of `node`'s mesh: its morph weights and, with a skin, its joint matrices.
pub fn node_pose(
    node: &gltf::Node,
    mesh: &gltf::Mesh,
    root: &gltf::json::Root,
    data: &BufferData,
    worlds: &[DMat4],
) -> Result<Pose, String> {
    let weights = node
        .weights()
        .or(mesh.weights())
        .map(<[f32]>::to_vec)
        .unwrap_or_default();
    let Some(skin) = node.skin() else {
        return Ok(Pose {
            weights,
            joints: Vec::new(),
        });
    };
    let path = format!("skins[{}]", skin.index());
    let json = &root.skins[skin.index()];
    let inverse_binds = match json.inverse_bind_matrices {
        Some(a) => accessor::read_floats::<16>(root, data, a.value())
            .map_err(|e| format!("{path}.inverseBindMatrices: {e}"))?,
        None => Vec::new(),
    };
    if !inverse_binds.is_empty() && inverse_binds.len() < json.joints.len() {
        return Err(format!(
            "{path}: {} inverse bind matrices for {} joints",
            inverse_binds.len(),
            json.joints.len()
        ));
    }
    let joints = json
        .joints
        .iter()
        .enumerate()
        .map(|(k, joint)| {
            let world = worlds.get(joint.value()).ok_or_else(|| {
                format!(
                    "{path}.joints[{k}]: nodes[{}] does not exist",
                    joint.value()
                )
            })?;
            let inverse_bind = inverse_binds.get(k).map_or(DMat4::IDENTITY, |m| {
                DMat4::from_cols_array(&m.map(f64::from))
            });
            Ok(*world * inverse_bind)
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Pose { weights, joints })
}

/// Applies morph targets at `weights` to the vertex attributes of a primitive.
pub fn apply_morph_targets(
    attributes: &Attributes,
    prim: &gltf::json::mesh::Primitive,
    weights: &[f32],
    positions: &mut [Vec3],
    normals: &mut [Vec3],
    tangents: &mut [Vec4],
) -> Result<(), String> {
    let (root, data, path) = (attributes.root, attributes.data, &attributes.path);
    let targets = prim.targets.as_deref().unwrap_or_default();
    for (k, target) in targets.iter().enumerate() {
        let w = weights.get(k).copied().unwrap_or(0.0);
        if w == 0.0 || !w.is_finite() {
            continue;
        }
        // The target's displacements of one attribute with `len` vertices, if it has them.
        let deltas =
            |a: Option<gltf::json::Index<gltf::json::Accessor>>, name: &str, len: usize| {
                let Some(a) = a.filter(|_| len > 0) else {
                    return Ok(Vec::new());
                };
                let d = accessor::read_floats::<3>(root, data, a.value())
                    .map_err(|e| format!("{path}.targets[{k}].{name}: {e}"))?;
                if d.len() != len {
                    return Err(format!(
                        "{path}.targets[{k}].{name}: count differs from the attribute's"
                    ));
                }
                Ok(d)
            };
        let moved = deltas(target.positions, "POSITION", positions.len())?;
        for (v, d) in positions.iter_mut().zip(moved) {
            *v += w * Vec3::from(d);
        }
        let moved = deltas(target.normals, "NORMAL", normals.len())?;
        for (v, d) in normals.iter_mut().zip(moved) {
            *v += w * Vec3::from(d);
        }
        let moved = deltas(target.tangents, "TANGENT", tangents.len())?;
        for (t, d) in tangents.iter_mut().zip(moved) {
            *t += w * Vec3::from(d).extend(0.0);
        }
    }
    Ok(())
}

/// Moves vertices by their skin: each is `Σ weight × joint matrix` of its (up to eight)
/// joints, normals by the inverse transpose of that blend.
pub fn apply_skin(
    attributes: &Attributes,
    joints: &[DMat4],
    positions: &mut [Vec3],
    normals: &mut [Vec3],
    tangents: &mut [Vec4],
) -> Result<(), String> {
    let mut blend = vec![DMat4::ZERO; positions.len()];
    let mut any = false;
    for set in 0..2 {
        let (Some(j), Some(w)) = (
            attributes.uints(&format!("JOINTS_{set}"))?,
            attributes.floats::<4>(&format!("WEIGHTS_{set}"))?,
        ) else {
            continue;
        };
        if j.len() != positions.len() || w.len() != positions.len() {
            return Err(format!(
                "{}: JOINTS_{set}/WEIGHTS_{set} count differs from POSITION count",
                attributes.path
            ));
        }
        for (v, (j, w)) in j.iter().zip(&w).enumerate() {
            for c in 0..4 {
                if w[c] == 0.0 {
                    continue;
                }
                let m = joints.get(j[c] as usize).ok_or_else(|| {
                    format!(
                        "{}: JOINTS_{set} {v} names joint {} of a skin with {}",
                        attributes.path,
                        j[c],
                        joints.len()
                    )
                })?;
                blend[v] += *m * w[c] as f64;
            }
        }
        any = true;
    }
    if !any {
        return Ok(());
    }
    for (v, m) in blend.iter().enumerate() {
        if *m == DMat4::ZERO {
            continue;
        }
        positions[v] = m.transform_point3(positions[v].as_dvec3()).as_vec3();
        let normal_matrix = m.inverse().transpose();
        if let Some(n) = normals.get_mut(v) {
            *n = normal_matrix
                .transform_vector3(n.as_dvec3())
                .normalize_or_zero()
                .as_vec3();
        }
        if let Some(t) = tangents.get_mut(v) {
            let xyz = m
                .transform_vector3(t.truncate().as_dvec3())
                .normalize_or_zero();
            *t = xyz.as_vec3().extend(t.w);
        }
    }
    Ok(())
}

/// The node's local transform, or why it cannot be used: a non-finite value, a zero
/// quaternion or a singular matrix. `precise` holds the values as written, in f64, when the
/// file could be read that way; otherwise gltf-json's f32 values are used.
pub fn node_matrix(
    node: &gltf::Node,
    precise: Option<&PreciseNode>,
) -> Result<DMat4, &'static str> {
    let f32_matrix = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => Some(matrix.map(|c| c.map(f64::from))),
        _ => None,
    };
    if let Some(matrix) = f32_matrix {
        let m = match precise.and_then(|p| p.matrix) {
            Some(m) => DMat4::from_cols_array(&m),
            None => DMat4::from_cols_array_2d(&matrix),
        };
        if !m.is_finite() {
            return Err("matrix is not finite");
        }
        if !m.inverse().is_finite() || m.determinant() == 0.0 {
            return Err("matrix is singular");
        }
        return Ok(m);
    }
    let (t, r, s) = node.transform().decomposed();
    let p = precise.cloned().unwrap_or_default();
    let t = DVec3::from(p.translation.unwrap_or(t.map(f64::from)));
    let r = DQuat::from_array(p.rotation.unwrap_or(r.map(f64::from)));
    let s = DVec3::from(p.scale.unwrap_or(s.map(f64::from)));
    if !(t.is_finite() && r.is_finite() && s.is_finite()) {
        return Err("translation, rotation or scale is not finite");
    }
    if r.length_squared() < 1e-24 {
        return Err("rotation is a zero quaternion");
    }
    Ok(DMat4::from_scale_rotation_translation(s, r.normalize(), t))
}
