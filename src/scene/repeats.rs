//! Geometry that repeats itself exactly: triangles of a mesh that repeat another of the same
//! mesh, and nodes that place the same mesh with the same transform again. Neither changes the
//! image (the first surface a ray meets is the same), but every copy costs each ray through
//! it a triangle test that no tree can avoid: 10⁷ copies of one triangle, or 65,536 of them
//! placed 256 times, took minutes a sample. The importer drops the repeats with one warning.

use super::{AlphaMode, Material, Mesh};
use glam::DMat4;
use rayon::prelude::*;
use std::collections::HashSet;
use std::hash::BuildHasher;
use std::sync::Arc;

/// How the triangles of one material may repeat without changing the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Layering {
    /// Blended layers add up (two of alpha a cover 1 − (1 − a)²): never dropped.
    Blended,
    /// Alpha-tested: a repeat is dropped only when its texture coordinates and colours repeat
    /// too (they place the cut-out).
    Masked,
    /// Opaque, one face: a repeat with the opposite winding shows the other face, so it is
    /// kept.
    OneSided,
    /// Opaque, both faces alike: any order of the same corners repeats.
    TwoSided,
}

impl Layering {
    /// The layering of `material`'s triangles.
    pub(super) fn of(material: &Material) -> Self {
        match material.alpha {
            AlphaMode::Blend => Layering::Blended,
            AlphaMode::Mask(_) => Layering::Masked,
            AlphaMode::Opaque if material.double_sided => Layering::TwoSided,
            AlphaMode::Opaque => Layering::OneSided,
        }
    }
}

/// The meshes placed so far with their world transforms, to find nodes that place one again
/// where it already is.
#[derive(Default)]
pub(super) struct Placements {
    /// (mesh, world transform as bits, −0 read as +0).
    seen: HashSet<(usize, [u64; 16])>,
    /// Placements that repeated one before, and the node of the first.
    repeated: usize,
    first: String,
}

impl Placements {
    /// Whether node `at` placing `mesh` at `world` repeats an earlier placement (counted);
    /// otherwise it is remembered.
    pub(super) fn repeats(&mut self, mesh: &Arc<Mesh>, world: &DMat4, at: &str) -> bool {
        let bits = world.to_cols_array().map(|v| (v + 0.0).to_bits());
        let fresh = self.seen.insert((Arc::as_ptr(mesh) as usize, bits));
        if !fresh {
            if self.repeated == 0 {
                self.first = at.to_string();
            }
            self.repeated += 1;
        }
        !fresh
    }

    /// The one warning for every repeated placement, when there was one.
    pub(super) fn warning(&self) -> Option<String> {
        (self.repeated > 0).then(|| {
            format!(
                "{}: {} node(s) place a mesh again with the same world transform (the first \
                 here); left out",
                self.first, self.repeated
            )
        })
    }
}

/// Words describing one corner: position, then (for alpha-tested triangles) `TEXCOORD_0` and
/// `COLOR_0`, as bits (−0 read as +0).
type Corner = [u32; 9];

/// What makes a triangle the same as another: its corners in a canonical order, the parity of
/// the order they came in (0 when the winding does not matter) and its material.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Key {
    corners: [Corner; 3],
    parity: u32,
    material: u32,
}

/// The most distinct keys compared within one run of equal hashes: past it the run's other
/// triangles are kept, so that keys made to collide cannot make the search quadratic.
const MAX_KEYS_PER_HASH: usize = 16;

/// Drops the triangles of `mesh` (the file's element `what`) that repeat another, with one
/// warning giving their count.
pub(super) fn drop_repeated_triangles(
    mesh: &mut Mesh,
    layering: &[Layering],
    what: &str,
    warnings: &mut Vec<String>,
) {
    let before = mesh.indices.len();
    let dropped = mesh.drop_repeated_triangles(layering);
    if dropped > 0 {
        warnings.push(format!(
            "{what}: {dropped} of its {before} triangles repeat another exactly (the same \
             corners and material); dropped"
        ));
    }
}

impl Mesh {
    /// Drops every triangle that repeats an earlier one of the mesh exactly (see [`Layering`]
    /// for what counts as a repeat), keeping the first; returns how many went. Meshes with
    /// `KHR_materials_variants` are left alone (a variant may give two repeats different
    /// materials).
    pub(super) fn drop_repeated_triangles(&mut self, layering: &[Layering]) -> usize {
        let n = self.indices.len();
        if n < 2 || !self.variants.is_empty() {
            return 0;
        }
        let seed = std::hash::RandomState::new().hash_one(0u8);
        // Sort the triangles by a hash of their corners under a seed the file cannot know:
        // repeats end up next to each other, the first of each in front.
        let mut order: Vec<(u64, u32)> = (0..n as u32)
            .into_par_iter()
            .map(|t| (self.corner_hash(t as usize, seed), t))
            .collect();
        order.retain(|&(_, t)| {
            let material = self.materials[t as usize] as usize;
            layering.get(material) != Some(&Layering::Blended)
        });
        order.par_sort_unstable();
        let mut keep = vec![true; n];
        let mut dropped = 0;
        for run in order.chunk_by(|a, b| a.0 == b.0).filter(|r| r.len() > 1) {
            // Distinct keys that share a hash stay apart: each is kept once.
            let mut firsts: Vec<Key> = Vec::new();
            for &(_, t) in run {
                let key = self.repeat_key(t as usize, layering).expect("keyed above");
                if firsts.contains(&key) {
                    keep[t as usize] = false;
                    dropped += 1;
                } else if firsts.len() < MAX_KEYS_PER_HASH {
                    firsts.push(key);
                }
            }
        }
        if dropped > 0 {
            retain_kept(&mut self.indices, &keep);
            retain_kept(&mut self.materials, &keep);
            retain_kept(&mut self.tangents, &keep);
        }
        dropped
    }

    /// A 64-bit hash of triangle `t`'s corner positions in any order and its material under
    /// `seed`: a multiply–xorshift mix of its 10 words (a keyed SipHash of the whole [`Key`]
    /// took as long as the rest of the load). Keys that differ only in winding, texture
    /// coordinates or colours meet in one run and are told apart there.
    fn corner_hash(&self, t: usize, seed: u64) -> u64 {
        let bits = |v: f32| (v + 0.0).to_bits();
        let mut corners = self.indices[t].map(|v| self.positions[v as usize].to_array().map(bits));
        corners.sort_unstable();
        let words = corners.iter().flatten().chain([&self.materials[t]]);
        let mut h = seed;
        for &w in words {
            h = (h ^ u64::from(w)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            h ^= h >> 29;
        }
        h
    }

    /// The key of triangle `t`, or `None` when it is never dropped.
    fn repeat_key(&self, t: usize, layering: &[Layering]) -> Option<Key> {
        let material = self.materials[t];
        let layering = layering
            .get(material as usize)
            .copied()
            .unwrap_or(Layering::OneSided);
        if layering == Layering::Blended {
            return None;
        }
        let bits = |v: f32| (v + 0.0).to_bits();
        let corner = |v: u32| -> Corner {
            let v = v as usize;
            let p = self.positions[v];
            let mut c = [bits(p.x), bits(p.y), bits(p.z), 0, 0, 0, 0, 0, 0];
            if layering == Layering::Masked {
                if let Some(uv) = self.uvs.get(v) {
                    c[3..5].copy_from_slice(&[bits(uv.x), bits(uv.y)]);
                }
                if let Some(color) = self.colors.get(v) {
                    c[5..9].copy_from_slice(&color.to_array().map(bits));
                }
            }
            c
        };
        let mut corners = self.indices[t].map(corner);
        // Sort the three corners, counting swaps: an odd count reverses the winding.
        let mut swaps = 0;
        for (a, b) in [(0, 1), (1, 2), (0, 1)] {
            if corners[a] > corners[b] {
                corners.swap(a, b);
                swaps += 1;
            }
        }
        let parity = if layering == Layering::TwoSided {
            0
        } else {
            swaps % 2
        };
        Some(Key {
            corners,
            parity,
            material,
        })
    }
}

/// Keeps the entries of `list` (one a triangle, or none) whose `keep` is set.
fn retain_kept<T>(list: &mut Vec<T>, keep: &[bool]) {
    if list.len() == keep.len() {
        let mut kept = keep.iter();
        list.retain(|_| *kept.next().expect("one flag a triangle"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};

    fn mesh(tris: &[[Vec3; 3]], materials: &[u32]) -> Mesh {
        Mesh {
            materials: materials.to_vec(),
            ..Mesh::soup(tris)
        }
    }

    const A: Vec3 = Vec3::ZERO;
    const B: Vec3 = Vec3::X;
    const C: Vec3 = Vec3::Y;
    const D: Vec3 = Vec3::Z;

    #[test]
    fn a_rotated_repeat_goes_and_the_first_stays() {
        let mut m = mesh(&[[A, B, C], [A, B, D], [B, C, A], [C, A, B]], &[0; 4]);
        let firsts = m.indices[..2].to_vec();
        assert_eq!(m.drop_repeated_triangles(&[Layering::OneSided]), 2);
        assert_eq!(m.indices, firsts);
        assert_eq!(m.materials, vec![0, 0]);
    }

    #[test]
    fn the_other_face_stays_unless_both_faces_are_alike() {
        // [C, B, A] is [A, C, B] rotated: the back face twice.
        let tris = [[A, B, C], [A, C, B], [C, B, A]];
        let mut one = mesh(&tris, &[0; 3]);
        assert_eq!(one.drop_repeated_triangles(&[Layering::OneSided]), 1);
        assert_eq!(one.indices, vec![[0, 1, 2], [3, 4, 5]]);
        let mut two = mesh(&tris, &[0; 3]);
        assert_eq!(two.drop_repeated_triangles(&[Layering::TwoSided]), 2);
    }

    #[test]
    fn another_material_or_a_blend_is_not_a_repeat() {
        let mut m = mesh(&[[A, B, C], [A, B, C], [A, B, C]], &[0, 1, 1]);
        assert_eq!(
            m.drop_repeated_triangles(&[Layering::OneSided, Layering::OneSided]),
            1
        );
        assert_eq!(m.materials, vec![0, 1]);
        let mut m = mesh(&[[A, B, C], [A, B, C]], &[0, 0]);
        assert_eq!(m.drop_repeated_triangles(&[Layering::Blended]), 0);
    }

    #[test]
    fn masked_repeats_must_repeat_their_texture_coordinates_too() {
        let mut m = mesh(&[[A, B, C], [A, B, C], [A, B, C]], &[0; 3]);
        m.uvs = vec![Vec2::ZERO; 9];
        m.uvs[3] = Vec2::ONE;
        assert_eq!(m.drop_repeated_triangles(&[Layering::Masked]), 1);
        assert_eq!(m.indices, vec![[0, 1, 2], [3, 4, 5]]);
    }

    #[test]
    fn per_triangle_tangents_follow_their_triangles_and_variants_keep_all() {
        let mut m = mesh(&[[A, B, C], [A, B, C], [A, B, D]], &[0; 3]);
        m.tangents = (0..3).map(|i| [glam::Vec4::splat(i as f32); 3]).collect();
        assert_eq!(m.drop_repeated_triangles(&[Layering::OneSided]), 1);
        assert_eq!(m.tangents[1][0].x, 2.0);
        let mut m = mesh(&[[A, B, C], [A, B, C]], &[0; 2]);
        m.variants.push(Default::default());
        assert_eq!(m.drop_repeated_triangles(&[Layering::OneSided]), 0);
    }
}
