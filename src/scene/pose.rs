//! The node graph's transforms: each node's local matrix, its parent, and the check that the
//! parent chains end (posing meshes and animation are in `scene::animation`).

use super::limits;
use super::validate::PreciseNode;
use glam::{DMat4, DQuat, DVec3};

/// Each node's first parent (the first node listing it as a child, itself excluded).
pub fn parents(document: &gltf::Document) -> Vec<Option<usize>> {
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
/// than [`limits::MAX_NODE_DEPTH`] or closes a cycle: the node walk and the animation's world
/// transforms follow the chains, which must end (and a chain 100,000 deep fails here in
/// linear time, not after a quadratic walk).
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
