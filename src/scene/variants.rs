//! `KHR_materials_variants`: named sets of materials for the same geometry. The importer keeps,
//! per primitive, its default material and its (variant, material) mappings; selecting a
//! variant rewrites the triangles' materials. Every variant's materials are imported and
//! uploaded, so the kernels' features cover them all and a switch needs no kernel build.

use super::Scene;
use serde_json::Value;
use std::ops::Range;

/// Triangles of a mesh (one glTF primitive) whose material a variant changes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VariantRange {
    /// The triangles: indices into `Mesh::indices`.
    pub triangles: Range<u32>,
    /// The material without a variant.
    pub default: u32,
    /// (variant, material) pairs.
    pub materials: Vec<(u32, u32)>,
}

/// The variant names of the root `KHR_materials_variants` object (`variant N` when unnamed).
pub(super) fn names(root_extension: Option<&Value>) -> Vec<String> {
    root_extension
        .and_then(|x| x.get("variants"))
        .and_then(Value::as_array)
        .map(|list| {
            list.iter()
                .enumerate()
                .map(|(i, v)| {
                    v.get("name")
                        .and_then(Value::as_str)
                        .map_or_else(|| format!("variant {i}"), str::to_string)
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The (variant, material) mappings of a primitive's `KHR_materials_variants` object; entries
/// naming a material that does not exist are left out with a warning (variants that do not
/// exist, by [`Mesh::keep_variants`](super::Mesh)).
pub(super) fn mappings(
    x: &Value,
    materials: usize,
    what: &str,
    warnings: &mut Vec<String>,
) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let Some(list) = x.get("mappings").and_then(Value::as_array) else {
        return out;
    };
    for (i, m) in list.iter().enumerate() {
        let material = m.get("material").and_then(Value::as_u64);
        let Some(material) = material.filter(|&m| (m as usize) < materials) else {
            warnings.push(format!(
                "{what}.extensions.KHR_materials_variants.mappings[{i}]: no such material, mapping ignored"
            ));
            continue;
        };
        for v in m
            .get("variants")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(Value::as_u64)
        {
            out.push((v.min(u32::MAX as u64) as u32, material as u32));
        }
    }
    out
}

impl super::Mesh {
    /// Drops the mappings to variants beyond the first `count`, with one warning.
    pub(super) fn keep_variants(&mut self, count: usize, what: &str, warnings: &mut Vec<String>) {
        let before: usize = self.variants.iter().map(|r| r.materials.len()).sum();
        for r in &mut self.variants {
            r.materials.retain(|&(v, _)| (v as usize) < count);
        }
        self.variants.retain(|r| !r.materials.is_empty());
        let after: usize = self.variants.iter().map(|r| r.materials.len()).sum();
        if after < before {
            warnings.push(format!(
                "{what}: KHR_materials_variants maps {} material(s) to variants that do not exist; ignored",
                before - after
            ));
        }
    }
}

impl Scene {
    /// Gives the triangles the materials of `variant` (an index into `variants`; `None`: the
    /// default materials).
    pub fn select_variant(&mut self, variant: Option<usize>) {
        // A mesh shared by several objects is rewritten once and stays shared.
        let mut done = std::collections::HashMap::new();
        for o in &mut self.objects {
            if o.mesh.variants.is_empty() {
                continue;
            }
            let key = std::sync::Arc::as_ptr(&o.mesh);
            if let Some((_, m)) = done.get(&key) {
                o.mesh = std::sync::Arc::clone(m);
                continue;
            }
            let mut mesh = (*o.mesh).clone();
            for r in &mesh.variants {
                let material = variant
                    .and_then(|v| r.materials.iter().find(|(x, _)| *x as usize == v))
                    .map_or(r.default, |&(_, m)| m);
                mesh.materials[r.triangles.start as usize..r.triangles.end as usize].fill(material);
            }
            // The old mesh is kept in `done` so that its address cannot be reused meanwhile.
            let old = std::mem::replace(&mut o.mesh, std::sync::Arc::new(mesh));
            done.insert(key, (old, std::sync::Arc::clone(&o.mesh)));
        }
        self.variant = variant;
    }

    /// The index of the variant called `name`; the error names the scene's variants.
    pub fn variant_named(&self, name: &str) -> Result<usize, String> {
        self.variants
            .iter()
            .position(|v| v == name)
            .ok_or_else(|| {
                if self.variants.is_empty() {
                    format!("{}: has no material variants (KHR_materials_variants), so --variant {name:?} does not apply", self.source)
                } else {
                    format!(
                        "{}: no variant {name:?}; its variants are {}",
                        self.source,
                        self.variants
                            .iter()
                            .map(|v| format!("{v:?}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                }
            })
    }
}
