//! Mesh triangles into the device's structs: vertices (with material, light and object in
//! their .w lanes), corner normals, texture coordinates, tangents and vertex colours; flat (world space, a list
//! of placed triangles at a time) or per mesh (object space, in its BLAS's order).

use super::structs::f4;
use crate::cl::types::*;
use crate::scene::{Material, Mesh, WorldTriangle};
use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// The area of the triangle with vertices `v`.
pub(super) fn triangle_area(v: &[Vec3; 3]) -> f32 {
    0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
}

/// `v` cut into consecutive parts of `sizes` elements (empty parts once `v` runs out: the
/// tangents of a scene without normal maps, the texture coordinates of one without textures).
pub(super) fn split_by<'a, T>(mut v: &'a mut [T], sizes: &[usize]) -> Vec<&'a mut [T]> {
    sizes
        .iter()
        .map(|&n| {
            let n = n.min(v.len());
            let (part, rest) = std::mem::take(&mut v).split_at_mut(n);
            v = rest;
            part
        })
        .collect()
}

/// One mesh's device structs for [`object_triangles`] to fill: triangles, corner normals,
/// texture coordinates (empty when no material samples a texture), tangents (empty when no
/// mesh is normal-mapped) and vertex colours (empty when no mesh has them).
pub(super) type MeshStructs<'a> = (
    (&'a mut [DeviceTriangle], &'a mut [DeviceTriShading]),
    (&'a mut [DeviceTriUvs], &'a mut [DeviceTriTangents]),
    &'a mut [DeviceTriColors],
);

/// Whether triangle `ti` of `m` (vertices `v`) is a light: an emissive material and a
/// nonzero object-space area.
fn emits(m: &Mesh, ti: u32, v: &[Vec3; 3], materials: &[Material]) -> bool {
    materials[m.materials[ti as usize] as usize].is_emissive() && triangle_area(v) > 0.0
}

/// One mesh's emissive triangles in the order `order` (index in that order, material), as
/// [`object_triangles`] finds them.
pub(super) fn emissive_triangles(
    m: &Mesh,
    order: &[u32],
    materials: &[Material],
) -> Vec<(u32, u32)> {
    if !m
        .materials
        .iter()
        .any(|&i| materials[i as usize].is_emissive())
    {
        return vec![];
    }
    order
        .iter()
        .enumerate()
        .filter(|&(_, &ti)| {
            let v = m.indices[ti as usize].map(|i| m.positions[i as usize]);
            emits(m, ti, &v, materials)
        })
        .map(|(k, &ti)| (k as u32, m.materials[ti as usize]))
        .collect()
}

/// Writes the device structs of one mesh's triangles in object space, in the order `order`,
/// to `out` (texture coordinates, tangents and colours unless their slices are empty); an
/// emissive triangle's `v1.w` counts the
/// mesh's emissive triangles ([`emissive_triangles`]).
pub(super) fn object_triangles(
    m: &Mesh,
    order: &[u32],
    materials: &[Material],
    ((tris, shading), (uvs, tangents), colors): MeshStructs,
) {
    let colored = !colors.is_empty();
    let normal_mapped = !tangents.is_empty();
    let textured = !uvs.is_empty();
    let mut emitters = 0;
    let corner = |a: &[Vec2], i: u32| a.get(i as usize).copied().unwrap_or(Vec2::ZERO);
    for (k, &ti) in order.iter().enumerate() {
        let idx = m.indices[ti as usize];
        let material = m.materials[ti as usize];
        let v = idx.map(|i| m.positions[i as usize]);
        let mut light = -1i32;
        if emits(m, ti, &v, materials) {
            light = emitters;
            emitters += 1;
        }
        let geometric = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        let smooth = !m.normals.is_empty();
        let n = if smooth {
            idx.map(|i| {
                let n = m.normals[i as usize].normalize_or_zero();
                if n == Vec3::ZERO { geometric } else { n }
            })
        } else {
            [geometric; 3]
        };
        let t = WorldTriangle {
            v,
            n,
            smooth,
            uv: idx.map(|i| corner(&m.uvs, i)),
            uv1: idx.map(|i| corner(&m.uvs1, i)),
            tangents: m.tangents.get(ti as usize).copied(),
            colors: (!m.colors.is_empty()).then(|| idx.map(|i| m.colors[i as usize])),
            material,
            object: 0,
        };
        let (tri, sh) = device_triangle(&t, light);
        tris[k] = tri;
        shading[k] = sh;
        if textured {
            uvs[k] = device_uvs(&t);
        }
        if normal_mapped {
            tangents[k] = device_tangents(&t);
        }
        if colored {
            colors[k] = device_colors(&t);
        }
    }
}

/// The flat form's device structs in object order, filled a list of [`WorldTriangle`]s at a
/// time.
#[derive(Default)]
pub(super) struct FlatStructs {
    pub(super) triangles: Vec<DeviceTriangle>,
    pub(super) shading: Vec<DeviceTriShading>,
    /// Filled when some material samples a texture (`keep_uvs`).
    pub(super) uvs: Vec<DeviceTriUvs>,
    /// Filled when tangents may be needed (`keep_tangents`).
    pub(super) tangents: Vec<DeviceTriTangents>,
    /// Filled when some mesh has vertex colours (`keep_colors`).
    pub(super) colors: Vec<DeviceTriColors>,
    pub(super) vertices: Vec<[Vec3; 3]>,
    keep_uvs: bool,
    keep_tangents: bool,
    keep_colors: bool,
    /// Whether some triangle added had tangents.
    pub(super) mapped: bool,
}

impl FlatStructs {
    pub(super) fn new(
        capacity: usize,
        keep_tangents: bool,
        keep_uvs: bool,
        keep_colors: bool,
    ) -> Self {
        let if_kept = |keep: bool| if keep { capacity } else { 0 };
        Self {
            triangles: Vec::with_capacity(capacity),
            shading: Vec::with_capacity(capacity),
            uvs: Vec::with_capacity(if_kept(keep_uvs)),
            tangents: Vec::with_capacity(if_kept(keep_tangents)),
            colors: Vec::with_capacity(if_kept(keep_colors)),
            vertices: Vec::with_capacity(capacity),
            keep_uvs,
            keep_tangents,
            keep_colors,
            mapped: false,
        }
    }

    /// These lists emptied for another pose of the same triangles, their memory kept: the
    /// texture coordinates and colours, which a pose does not change, are not made again.
    pub(super) fn cleared(mut self, capacity: usize, keep_tangents: bool) -> Self {
        self.triangles.clear();
        self.triangles.reserve(capacity);
        self.shading.clear();
        self.shading.reserve(capacity);
        self.vertices.clear();
        self.vertices.reserve(capacity);
        self.tangents.clear();
        if keep_tangents {
            self.tangents.reserve(capacity);
        }
        Self {
            uvs: Vec::new(),
            colors: Vec::new(),
            keep_uvs: false,
            keep_colors: false,
            keep_tangents,
            mapped: false,
            ..self
        }
    }

    pub(super) fn add(&mut self, world: Vec<WorldTriangle>) {
        use std::mem::take;
        self.mapped |= world.iter().any(|t| t.tangents.is_some());
        // Each triangle's structs made once, and unzipped into the lists in order.
        let structs = world.par_iter().map(|t| device_triangle(t, -1));
        let mut lists = (take(&mut self.triangles), take(&mut self.shading));
        lists.par_extend(structs);
        (self.triangles, self.shading) = lists;
        if self.keep_uvs {
            self.uvs.par_extend(world.par_iter().map(device_uvs));
        }
        if self.keep_tangents {
            self.tangents
                .par_extend(world.par_iter().map(device_tangents));
        }
        if self.keep_colors {
            self.colors.par_extend(world.par_iter().map(device_colors));
        }
        self.vertices.par_extend(world.par_iter().map(|t| t.v));
    }
}

/// A triangle's vertices and corner normals on the device; `light` is its index among the
/// emissive triangles (-1: none). A flat-shaded triangle's normals are zero (the kernels then
/// take its geometric normal).
fn device_triangle(t: &WorldTriangle, light: i32) -> (DeviceTriangle, DeviceTriShading) {
    device_shape(&t.v, &t.n, t.smooth, [t.material, light as u32, t.object])
}

/// [`device_triangle`] of a triangle's corners `v`, corner normals `n` (`smooth`: from the
/// file) and its material, light and object (the `.w` lanes' bits).
#[inline]
pub(super) fn device_shape(
    v: &[Vec3; 3],
    n: &[Vec3; 3],
    smooth: bool,
    [material, light, object]: [u32; 3],
) -> (DeviceTriangle, DeviceTriShading) {
    let n = if smooth {
        n.map(|n| n.to_array())
    } else {
        [[0.0; 3]; 3]
    };
    (
        DeviceTriangle {
            v0: f4(v[0], f32::from_bits(material)),
            v1: f4(v[1], f32::from_bits(light)),
            v2: f4(v[2], f32::from_bits(object)),
        },
        DeviceTriShading { n },
    )
}

/// A triangle's texture coordinates on the device.
fn device_uvs(t: &WorldTriangle) -> DeviceTriUvs {
    DeviceTriUvs {
        uv01: [t.uv[0].x, t.uv[0].y, t.uv[1].x, t.uv[1].y],
        uv2: [t.uv[2].x, t.uv[2].y, t.uv1[0].x, t.uv1[0].y],
        uv1_12: [t.uv1[1].x, t.uv1[1].y, t.uv1[2].x, t.uv1[2].y],
    }
}

/// A triangle's vertex colours on the device (white without).
fn device_colors(t: &WorldTriangle) -> DeviceTriColors {
    let c = t.colors.unwrap_or([Vec4::ONE; 3]).map(|v| v.to_array());
    DeviceTriColors {
        c0: c[0],
        c1: c[1],
        c2: c[2],
    }
}

/// A triangle's tangents on the device (zero without).
fn device_tangents(t: &WorldTriangle) -> DeviceTriTangents {
    tangents_of(t.tangents)
}

/// [`device_tangents`] of a triangle's tangents.
#[inline]
pub(super) fn tangents_of(tangents: Option<[Vec4; 3]>) -> DeviceTriTangents {
    let c = tangents.unwrap_or_default().map(|v| v.to_array());
    DeviceTriTangents {
        t0: c[0],
        t1: c[1],
        t2: c[2],
    }
}
