//! glTF meshes into [`Mesh`]es, unposed: every primitive's attributes (accessors, Draco or
//! meshopt data, tangents) and, for a mesh that deforms, its skin influences and morph targets
//! ([`RigData`]); the primitives of a mesh one after the other; large meshes read ahead in
//! parallel while the node graph is walked.

use super::super::accessor::{self, Attributes, BufferData};
use super::super::animation::RigData;
use super::super::compression;
use super::super::repeats::{self, Layering};
use super::super::variants::{self, VariantRange};
use super::super::{Mesh, limits, tangents};
use super::colors::{pad_colors, read_colors};
use glam::{Vec2, Vec3, Vec4};
use gltf::json::validation::Checked;
use gltf::mesh::Mode;
use rayon::prelude::*;
use std::collections::HashMap;

/// A mesh read ahead of the node walk, with the warnings reading it gave, or why it failed.
pub(super) type ReadAhead = Result<(Mesh, Vec<String>), String>;

/// The meshes that the nodes under `roots` place without a pose of the node's own (no skin, no
/// morph targets), each read once, in parallel: what a scene of many distinct meshes spends
/// most of its loading on (a 64 M-triangle scene of 3,125 meshes). The node walk takes each
/// where it first places it, so the scene, its warnings and its errors are those of reading
/// them there. Meshes are taken in walk order while their triangles (from the accessors'
/// counts) stay within [`limits::MAX_TRIANGLES`]: a file over the limit still fails at the node
/// that crosses it, not after reading every mesh. Each loses its repeated triangles
/// ([`repeats`], `layering` by material).
pub(super) fn read_meshes_ahead(
    roots: &[gltf::Node],
    root: &gltf::json::Root,
    data: &BufferData,
    default_material: u32,
    normal_sets: &[Option<(u32, bool)>],
    variant_count: usize,
    layering: &[Layering],
) -> HashMap<usize, ReadAhead> {
    // The first node placing each mesh, depth first in document order, each node once.
    let mut seen = vec![false; root.nodes.len()];
    let mut stack: Vec<gltf::Node> = roots.iter().rev().cloned().collect();
    let mut first: Vec<gltf::Node> = vec![];
    let mut taken = std::collections::HashSet::new();
    let mut triangles = 0usize;
    while let Some(node) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            continue;
        }
        if let Some(mesh) = node.mesh()
            && !deforms(&node, &mesh)
            && taken.insert(mesh.index())
        {
            triangles += mesh
                .primitives()
                .map(|p| {
                    p.indices()
                        .or_else(|| p.get(&gltf::Semantic::Positions))
                        .map_or(0, |a| a.count() / 3)
                })
                .sum::<usize>();
            if triangles > limits::MAX_TRIANGLES {
                break;
            }
            first.push(node.clone());
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev());
    }
    if first.len() < 2 {
        return HashMap::new();
    }
    first
        .par_iter()
        .map(|node| {
            let mesh = node.mesh().expect("a node placing a mesh");
            let mut warnings = vec![];
            let read = import_mesh(
                &mesh,
                root,
                data,
                None,
                default_material,
                normal_sets,
                &mut warnings,
            )
            .map(|mut m| {
                let what = format!("meshes[{}]", mesh.index());
                m.keep_variants(variant_count, &what, &mut warnings);
                repeats::drop_repeated_triangles(&mut m, layering, &what, &mut warnings);
                m
            });
            (mesh.index(), read.map(|m| (m, warnings)))
        })
        .collect()
}

/// Whether `node` poses its mesh itself: a skin, or morph targets (whose weights a node or
/// an animation sets). Such a node gets its own copy of the mesh.
pub(super) fn deforms(node: &gltf::Node, mesh: &gltf::Mesh) -> bool {
    node.skin().is_some()
        || node.weights().is_some()
        || mesh.primitives().any(|p| p.morph_targets().len() > 0)
}

/// Reads `mesh` unposed; with `rig`, its skin influences and morph targets too.
pub(super) fn import_mesh(
    mesh: &gltf::Mesh,
    root: &gltf::json::Root,
    data: &BufferData,
    mut rig: Option<&mut RigData>,
    default_material: u32,
    normal_sets: &[Option<(u32, bool)>],
    warnings: &mut Vec<String>,
) -> Result<Mesh, String> {
    let mut out = Mesh::default();
    for prim in mesh.primitives() {
        let what = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            warnings.push(format!("{what}: mode {mode:?} is not triangles, skipped"));
            continue;
        }
        let json = &root.meshes[mesh.index()].primitives[prim.index()];
        let draco = compression::decode_draco(root, data, json, &what)?;
        if let Some(d) = &draco
            && let Some(w) = compression::draco_count_mismatch(root, json, d, &what)
        {
            warnings.push(w);
        }
        let attributes = Attributes {
            root,
            data,
            accessors: json
                .attributes
                .iter()
                .filter_map(|(k, v)| match k {
                    Checked::Valid(s) => Some((s.to_string(), v.value())),
                    Checked::Invalid => None,
                })
                .collect(),
            draco,
            path: what.clone(),
        };
        let positions: Vec<Vec3> = attributes
            .floats::<3>("POSITION")?
            .ok_or_else(|| format!("{what}: POSITION is missing"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("{what}: POSITION {i} is not finite"));
        }
        let normals: Vec<Vec3> = attributes
            .floats::<3>("NORMAL")?
            .unwrap_or_default()
            .into_iter()
            .map(|n| {
                let n = Vec3::from(n);
                if n.is_finite() { n } else { Vec3::ZERO }
            })
            .collect();
        if !normals.is_empty() && normals.len() != positions.len() {
            return Err(format!("{what}: NORMAL count differs from POSITION count"));
        }
        let read_uvs = |set: u32| -> Result<Vec<Vec2>, String> {
            Ok(attributes
                .floats::<2>(&format!("TEXCOORD_{set}"))?
                .unwrap_or_default()
                .into_iter()
                .map(Vec2::from)
                .collect())
        };
        let uvs = read_uvs(0)?;
        let uvs1 = read_uvs(1)?;
        for (set, list) in [(0, &uvs), (1, &uvs1)] {
            if !list.is_empty() && list.len() != positions.len() {
                return Err(format!(
                    "{what}: TEXCOORD_{set} count differs from POSITION count"
                ));
            }
        }
        let colors = read_colors(&attributes, positions.len())?;
        let material = prim
            .material()
            .index()
            .map_or(default_material, |i| i as u32);
        let normal_set = normal_sets.get(material as usize).copied().flatten();
        let file_tangents: Vec<Vec4> = match normal_set {
            Some(_) => attributes
                .floats::<4>("TANGENT")?
                .unwrap_or_default()
                .into_iter()
                .map(Vec4::from)
                .collect(),
            None => Vec::new(),
        };
        if !file_tangents.is_empty() && file_tangents.len() != positions.len() {
            return Err(format!("{what}: TANGENT count differs from POSITION count"));
        }
        if let Some(rig) = rig.as_deref_mut() {
            rig.read_primitive(&attributes, json, positions.len())?;
        }
        let flat: Vec<u32> = match (&attributes.draco, json.indices) {
            (Some(d), _) => d.indices.clone(),
            (None, Some(a)) => bytemuck::cast_vec(
                accessor::read_uints::<1>(root, data, a.value())
                    .map_err(|e| format!("{what}.indices: {e}"))?,
            ),
            (None, None) => (0..positions.len() as u32).collect(),
        };
        if let Some(&bad) = flat.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!(
                "{what}: index {bad} is out of range ({} vertices)",
                positions.len()
            ));
        }
        // The triangles: the index list read in place (as triples) or unrolled from a strip or
        // a fan, and the list freed at once.
        let triangles: Vec<[u32; 3]> = match mode {
            Mode::Triangles => bytemuck::cast_slice(&flat[..flat.len() / 3 * 3]).to_vec(),
            Mode::TriangleStrip => (2..flat.len())
                .map(|i| {
                    if i % 2 == 0 {
                        [flat[i - 2], flat[i - 1], flat[i]]
                    } else {
                        [flat[i - 1], flat[i - 2], flat[i]]
                    }
                })
                .collect(),
            _ => (2..flat.len())
                .map(|i| [flat[0], flat[i - 1], flat[i]])
                .collect(),
        };
        drop(flat);
        let base = out.positions.len() as u32;
        // Tangents at the corners of normal-mapped triangles: the file's, else MikkTSpace's.
        let tangents: Vec<[Vec4; 3]> = match normal_set {
            None => Vec::new(),
            Some(_) if !file_tangents.is_empty() => triangles
                .iter()
                .map(|tri| tri.map(|i| file_tangents[i as usize]))
                .collect(),
            Some((set, normal_map)) => {
                let set_uvs = if set == 1 { &uvs1 } else { &uvs };
                if set_uvs.is_empty() {
                    // An anisotropic material without texture coordinates takes an arbitrary
                    // frame about the normal (kernels/shared/path.h).
                    if normal_map {
                        warnings.push(format!(
                            "{what}: the normal map's TEXCOORD_{set} is missing, normal map ignored"
                        ));
                    }
                    Vec::new()
                } else {
                    tangents::generate(&positions, &normals, set_uvs, &triangles)
                }
            }
        };
        let count = triangles.len();
        pad_attribute(&mut out.tangents, out.indices.len(), tangents, count);
        // Keep the per-vertex arrays aligned when only some primitives have normals or UVs.
        // The first primitive's arrays become the mesh's (moved, not copied).
        let vertices = positions.len();
        pad_attribute(&mut out.normals, base as usize, normals, vertices);
        pad_attribute(&mut out.uvs, base as usize, uvs, vertices);
        pad_attribute(&mut out.uvs1, base as usize, uvs1, vertices);
        pad_colors(&mut out.colors, base as usize, colors, vertices);
        append(&mut out.positions, positions);
        if base == 0 {
            append(&mut out.indices, triangles);
        } else {
            out.indices
                .extend(triangles.iter().map(|t| t.map(|i| i + base)));
        }
        if let Some(x) = prim.extension_value("KHR_materials_variants") {
            let start = out.materials.len() as u32;
            out.variants.push(VariantRange {
                triangles: start..start + count as u32,
                default: material,
                materials: variants::mappings(x, default_material as usize, &what, warnings),
            });
        }
        out.materials.extend(std::iter::repeat_n(material, count));
    }
    Ok(out)
}

/// Appends `new` to `dst`: moved when `dst` is empty (a mesh's first primitive), else copied.
pub(super) fn append<T: Copy>(dst: &mut Vec<T>, new: Vec<T>) {
    if dst.is_empty() {
        *dst = new;
    } else {
        dst.extend_from_slice(&new);
    }
}

/// Appends `new` to `dst`, zero-filling where either side lacks the attribute, so that `dst`
/// stays empty only while no primitive has it.
pub(super) fn pad_attribute<T: Copy + Default>(
    dst: &mut Vec<T>,
    old_len: usize,
    new: Vec<T>,
    new_len: usize,
) {
    if dst.is_empty() && new.is_empty() {
        return;
    }
    dst.resize(old_len, T::default());
    if new.is_empty() {
        dst.extend(std::iter::repeat_n(T::default(), new_len));
    } else {
        append(dst, new);
    }
}
