//! Meshes that deform: a mesh's unposed vertices with their skin influences and morph
//! targets, posed at any weights and joint matrices (morph targets in the mesh's space, then
//! the skin: each vertex by `Σ weight × joint matrix`, normals by the cofactor of that blend,
//! tangents by the blend). Poses run over the vertices in parallel (rayon).

use super::super::Mesh;
use super::super::accessor::Attributes;
use glam::{DMat4, Mat3, Mat4, Vec3, Vec4};
use rayon::prelude::*;

/// What a deforming mesh is posed from, gathered primitive by primitive as the mesh is read.
#[derive(Clone, Debug, Default)]
pub struct RigData {
    /// Up to eight (joint, weight) influences a vertex (`JOINTS_0/1`, `WEIGHTS_0/1`); zero
    /// weights where a primitive has fewer sets or none.
    pub influences: Vec<[(u32, f32); 8]>,
    /// Whether some primitive has a skin set.
    pub skinned: bool,
    /// Morph target displacements, per target: (position, normal, tangent) a vertex, zero where
    /// a primitive lacks the attribute.
    pub targets: Vec<Vec<[Vec3; 3]>>,
}

impl RigData {
    /// Appends one primitive's influences and displacements for its `vertices` vertices (the
    /// mesh's vertices so far are `self.influences.len()`).
    pub fn read_primitive(
        &mut self,
        attributes: &Attributes,
        prim: &gltf::json::mesh::Primitive,
        vertices: usize,
    ) -> Result<(), String> {
        let base = self.influences.len();
        self.influences.resize(base + vertices, [(0, 0.0); 8]);
        for set in 0..2 {
            let (Some(j), Some(w)) = (
                attributes.uints(&format!("JOINTS_{set}"))?,
                attributes.floats::<4>(&format!("WEIGHTS_{set}"))?,
            ) else {
                continue;
            };
            if j.len() != vertices || w.len() != vertices {
                return Err(format!(
                    "{}: JOINTS_{set}/WEIGHTS_{set} count differs from POSITION count",
                    attributes.path
                ));
            }
            for (v, (j, w)) in j.iter().zip(&w).enumerate() {
                for c in 0..4 {
                    // A zero weight's joint is never read (files leave it 0 or anything).
                    let weight = if w[c].is_finite() { w[c] } else { 0.0 };
                    self.influences[base + v][4 * set + c] = (j[c], weight);
                }
            }
            self.skinned = true;
        }
        let (root, data, path) = (attributes.root, attributes.data, &attributes.path);
        let targets = prim.targets.as_deref().unwrap_or_default();
        if self.targets.len() < targets.len() {
            self.targets
                .resize(targets.len(), vec![[Vec3::ZERO; 3]; base]);
        }
        for (k, list) in self.targets.iter_mut().enumerate() {
            list.resize(base + vertices, [Vec3::ZERO; 3]);
            let Some(target) = targets.get(k) else {
                continue;
            };
            for (slot, (a, name)) in [
                (target.positions, "POSITION"),
                (target.normals, "NORMAL"),
                (target.tangents, "TANGENT"),
            ]
            .into_iter()
            .enumerate()
            {
                let Some(a) = a else { continue };
                let d = super::super::accessor::read_floats::<3>(root, data, a.value())
                    .map_err(|e| format!("{path}.targets[{k}].{name}: {e}"))?;
                if d.len() != vertices {
                    return Err(format!(
                        "{path}.targets[{k}].{name}: count differs from the attribute's"
                    ));
                }
                for (v, d) in d.into_iter().enumerate() {
                    let d = Vec3::from(d);
                    list[base + v][slot] = if d.is_finite() { d } else { Vec3::ZERO };
                }
            }
        }
        Ok(())
    }
}

/// A deforming mesh: its unposed form, what poses it, and its default morph weights.
#[derive(Debug)]
pub struct Rig {
    /// The mesh unposed (morph weights 0, no skin), tangents at its corners.
    pub base: Mesh,
    /// Influences and morph targets.
    pub data: RigData,
    /// The skin (index in `skins`), when the node has one and the mesh skin sets.
    pub skin: Option<usize>,
    /// The node's weights, else the mesh's (missing ones are 0).
    pub default_weights: Vec<f32>,
}

impl Rig {
    /// Checks that every influence names a joint of a skin of `joints` joints.
    pub fn check_joints(&self, joints: usize, path: &str) -> Result<(), String> {
        if self.skin.is_none() {
            return Ok(());
        }
        for (v, set) in self.data.influences.iter().enumerate() {
            for &(j, w) in set {
                if w != 0.0 && j as usize >= joints {
                    return Err(format!(
                        "{path}: vertex {v} names joint {j} of a skin with {joints}"
                    ));
                }
            }
        }
        Ok(())
    }

    /// Writes the mesh posed at morph `weights` and skin `joints` (world from bind space, one
    /// a joint; empty without a skin) into `out`'s positions, normals and tangents; `out` is
    /// the base mesh or an earlier pose of it.
    pub fn pose_into(&self, weights: &[f32], joints: &[DMat4], out: &mut Mesh) {
        let joints: Vec<Mat4> = joints.iter().map(DMat4::as_mat4).collect();
        let skin = self.skin.is_some() && self.data.skinned && !joints.is_empty();
        // The targets with a weight, with it.
        let active: Vec<(f32, &[[Vec3; 3]])> = self
            .data
            .targets
            .iter()
            .enumerate()
            .filter_map(|(k, d)| {
                let w = weights.get(k).copied().unwrap_or(0.0);
                (w != 0.0 && w.is_finite()).then_some((w, d.as_slice()))
            })
            .collect();
        let base = &self.base;
        let normals = !base.normals.is_empty();
        let blend = |v: usize| -> Option<Mat4> {
            let mut m = Mat4::ZERO;
            for &(j, w) in &self.data.influences[v] {
                if w != 0.0 {
                    m += joints[j as usize] * w;
                }
            }
            (m != Mat4::ZERO).then_some(m)
        };
        let pose_vertex = |v: usize| -> (Vec3, Vec3) {
            let mut p = base.positions[v];
            let mut n = if normals { base.normals[v] } else { Vec3::ZERO };
            for &(w, d) in &active {
                p += w * d[v][0];
                n += w * d[v][1];
            }
            if skin && let Some(m) = blend(v) {
                p = m.transform_point3(p);
                n = normal_matrix(&m) * n;
            }
            (p, n.normalize_or_zero())
        };
        let count = base.positions.len();
        out.positions.resize(count, Vec3::ZERO);
        if normals {
            out.normals.resize(count, Vec3::ZERO);
            out.positions
                .par_iter_mut()
                .zip(out.normals.par_iter_mut())
                .enumerate()
                .for_each(|(v, (p, n))| (*p, *n) = pose_vertex(v));
        } else {
            out.positions
                .par_iter_mut()
                .enumerate()
                .for_each(|(v, p)| *p = pose_vertex(v).0);
        }
        if !base.tangents.is_empty() {
            out.tangents = base
                .indices
                .par_iter()
                .zip(&base.tangents)
                .map(|(tri, corners)| {
                    std::array::from_fn(|c| {
                        let v = tri[c] as usize;
                        let t = corners[c];
                        let mut xyz = t.truncate();
                        for &(w, d) in &active {
                            xyz += w * d[v][2];
                        }
                        if skin && let Some(m) = blend(v) {
                            xyz = m.transform_vector3(xyz);
                        }
                        let xyz = xyz.normalize_or_zero();
                        if t == Vec4::ZERO { t } else { xyz.extend(t.w) }
                    })
                })
                .collect();
        }
    }
}

/// The matrix that carries normals under `m`: the cofactor of its upper 3×3 (the inverse
/// transpose times the determinant), negated for a mirroring `m` so normals keep their side.
fn normal_matrix(m: &Mat4) -> Mat3 {
    let a = Mat3::from_mat4(*m);
    let cof = Mat3::from_cols(
        a.y_axis.cross(a.z_axis),
        a.z_axis.cross(a.x_axis),
        a.x_axis.cross(a.y_axis),
    );
    if a.determinant() < 0.0 { -cof } else { cof }
}
