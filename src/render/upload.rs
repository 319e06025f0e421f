//! Turning the host scene into the device's structs: triangles and shading data in BVH order,
//! materials and the camera. The light list is built in `lights`, the textures in `textures`.

use crate::bvh::{Bvh, Hit, Ray, TwoLevel};
use crate::cl::types::*;
use crate::scene::{AlphaMode, Camera, Material, RenderFrame, WorldTriangle, robust_bounds};
use glam::Vec3;

/// The acceleration structure of the scene on the device, with its host reference.
#[derive(Clone, Debug)]
pub enum Accel {
    /// One BVH over the world-space triangles.
    Flat(Bvh),
    /// A BLAS per distinct mesh and a TLAS over the instances (render space).
    TwoLevel(TwoLevel),
}

impl Accel {
    /// "flat" or "two-level".
    pub fn name(&self) -> &'static str {
        match self {
            Accel::Flat(_) => "flat",
            Accel::TwoLevel(_) => "two-level",
        }
    }

    /// Nodes over both levels.
    pub fn node_count(&self) -> usize {
        match self {
            Accel::Flat(b) => b.nodes.len(),
            Accel::TwoLevel(t) => {
                t.tlas.nodes.len() + t.blases.iter().map(|b| b.bvh.nodes.len()).sum::<usize>()
            }
        }
    }

    /// The SAH cost of the flat BVH, or of the TLAS.
    pub fn sah_cost(&self) -> f32 {
        match self {
            Accel::Flat(b) => b.sah_cost,
            Accel::TwoLevel(t) => t.tlas.sah_cost,
        }
    }

    /// The deepest leaf: of the flat BVH, or the TLAS's depth plus the deepest BLAS's.
    pub fn depth(&self) -> u32 {
        match self {
            Accel::Flat(b) => b.depth,
            Accel::TwoLevel(t) => {
                t.tlas.depth + 1 + t.blases.iter().map(|b| b.bvh.depth).max().unwrap_or(0)
            }
        }
    }

    /// Distinct meshes and instances (1 and 0 for the flat BVH).
    pub fn instancing(&self) -> (usize, usize) {
        match self {
            Accel::Flat(_) => (1, 0),
            Accel::TwoLevel(t) => (t.blases.len(), t.instances.len()),
        }
    }
}

/// Where a two-level scene's parts sit on the device, to update instances in place.
#[derive(Clone, Debug, Default)]
pub struct InstanceLayout {
    /// The object each instance places (index in `Scene::objects`).
    pub objects: Vec<u32>,
    /// Each BLAS's root in the binary node array.
    pub roots: Vec<u32>,
    /// Each BLAS's root in the wide node array.
    pub wide_roots: Vec<u32>,
    /// Each BLAS's first object-space triangle.
    pub firsts: Vec<u32>,
}

impl InstanceLayout {
    /// The device instances of `two` in TLAS order.
    pub fn gpu_instances(&self, two: &TwoLevel) -> Vec<GpuInstance> {
        two.tlas
            .tri_indices
            .iter()
            .map(|&i| {
                let inst = &two.instances[i as usize];
                let b = inst.blas as usize;
                GpuInstance {
                    row0: inst.rows[0],
                    row1: inst.rows[1],
                    row2: inst.rows[2],
                    root: self.roots[b],
                    wide_root: self.wide_roots[b],
                    prim_offset: inst.prim_offset.wrapping_sub(self.firsts[b]),
                    flags: inst.mirrored as u32,
                }
            })
            .collect()
    }
}

/// The scene as uploaded, kept on the host for picking and for tests.
pub struct HostScene {
    /// The acceleration structure.
    pub accel: Accel,
    /// Two levels: where the instances' parts sit on the device (empty when flat).
    pub layout: InstanceLayout,
    /// Triangles in shading order: the flat BVH's, or instance by instance in BLAS order.
    pub triangles: Vec<GpuTriangle>,
    /// Vertices in BVH order (for the host traversal).
    pub vertices: Vec<[Vec3; 3]>,
    /// Shading data in BVH order.
    pub shading: Vec<GpuTriShading>,
    /// Tangents in BVH order; empty when no triangle is normal-mapped.
    pub tangents: Vec<GpuTriTangents>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emissive triangles (BVH order index, area, emitted power for selection).
    pub emissive: Vec<(u32, f32, f32)>,
    /// The map from world space to the render space the triangles are in.
    pub space: RenderFrame,
    /// The middle and the diagonal of the robust bounds of the triangles.
    middle: (Vec3, f32),
}

pub(super) fn f4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

pub(super) fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The device form of a material.
pub fn gpu_material(m: &Material) -> GpuMaterial {
    let flags = if m.double_sided {
        MATERIAL_DOUBLE_SIDED
    } else {
        0
    } | if m.unlit { MATERIAL_UNLIT } else { 0 };
    GpuMaterial {
        base_color: m.base_color,
        emission: [
            m.emission[0],
            m.emission[1],
            m.emission[2],
            f32::from_bits(flags),
        ],
        params: [m.metallic, m.roughness, m.ior, m.specular_factor],
        specular: [
            m.specular_color[0],
            m.specular_color[1],
            m.specular_color[2],
            m.transmission,
        ],
        volume: [
            m.attenuation_color[0],
            m.attenuation_color[1],
            m.attenuation_color[2],
            m.attenuation_distance,
        ],
        alpha: [
            match m.alpha {
                AlphaMode::Mask(c) => c,
                _ => 0.5,
            },
            f32::from_bits(match m.alpha {
                AlphaMode::Opaque => ALPHA_OPAQUE,
                AlphaMode::Mask(_) => ALPHA_MASK,
                AlphaMode::Blend => ALPHA_BLEND,
            }),
            m.thickness,
            m.normal_scale,
        ],
        textures: [
            slot(m.textures.base_color),
            slot(m.textures.metallic_roughness),
            slot(m.textures.normal),
            slot(m.textures.emissive),
        ],
        textures2: [
            slot(m.textures.transmission),
            -1,
            slot(m.textures.sheen_color),
            slot(m.textures.sheen_roughness),
        ],
        coat: [
            m.clearcoat,
            m.clearcoat_roughness,
            m.clearcoat_normal_scale,
            0.0,
        ],
        textures3: [
            slot(m.textures.clearcoat),
            slot(m.textures.clearcoat_roughness),
            slot(m.textures.clearcoat_normal),
            -1,
        ],
        sheen: [
            m.sheen_color[0],
            m.sheen_color[1],
            m.sheen_color[2],
            m.sheen_roughness,
        ],
        aniso: [
            m.anisotropy,
            m.anisotropy_rotation.cos(),
            m.anisotropy_rotation.sin(),
            m.dispersion,
        ],
        iridescence: [
            m.iridescence,
            m.iridescence_ior,
            m.iridescence_thickness[0],
            m.iridescence_thickness[1],
        ],
        diffuse_transmission: [
            m.diffuse_transmission_color[0],
            m.diffuse_transmission_color[1],
            m.diffuse_transmission_color[2],
            m.diffuse_transmission,
        ],
        textures4: [
            slot(m.textures.anisotropy),
            slot(m.textures.iridescence),
            slot(m.textures.iridescence_thickness),
            slot(m.textures.diffuse_transmission),
        ],
        textures5: [slot(m.textures.diffuse_transmission_color), -1, -1, -1],
    }
}

fn slot(r: Option<u32>) -> i32 {
    r.map_or(-1, |r| r as i32)
}

impl HostScene {
    /// Orders the triangles as the BVH wants them and fills the device structs.
    pub fn new(world: &[WorldTriangle], bvh: Bvh, materials: &[Material]) -> Self {
        let order = bvh.tri_indices.clone();
        Self::ordered(world, &order, Accel::Flat(bvh), materials)
    }

    /// Fills the device structs from `world` taken in `order` (indices into `world`), for
    /// traversal by `accel`.
    pub fn ordered(
        world: &[WorldTriangle],
        order: &[u32],
        accel: Accel,
        materials: &[Material],
    ) -> Self {
        let mut emissive = Vec::new();
        let mut triangles = Vec::with_capacity(world.len());
        let mut shading = Vec::with_capacity(world.len());
        let mut vertices = Vec::with_capacity(world.len());
        let normal_mapped = world.iter().any(|t| t.tangents.is_some());
        let mut tangents = Vec::new();
        for (order, &index) in order.iter().enumerate() {
            let t = &world[index as usize];
            let m = &materials[t.material as usize];
            let mut light = -1i32;
            let area = 0.5 * (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length();
            if m.is_emissive() && area > 0.0 {
                let sides = if m.double_sided { 2.0 } else { 1.0 };
                let power = luminance(m.emission) * area * std::f32::consts::PI * sides;
                light = emissive.len() as i32;
                emissive.push((order as u32, area, power));
            }
            let (tri, sh, tan) = device_triangle(t, light);
            triangles.push(tri);
            shading.push(sh);
            if normal_mapped {
                tangents.push(tan);
            }
            vertices.push(t.v);
        }
        let corners: Vec<[glam::DVec3; 3]> =
            world.iter().map(|t| t.v.map(Vec3::as_dvec3)).collect();
        let b = robust_bounds(&corners);
        let middle = if b.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (b.center().as_vec3(), b.diagonal() as f32)
        };
        Self {
            accel,
            layout: InstanceLayout::default(),
            triangles,
            vertices,
            shading,
            tangents,
            materials: materials.iter().map(gpu_material).collect(),
            emissive,
            space: RenderFrame::default(),
            middle,
        }
    }

    /// Scales each emissive triangle's selection power by its material's factor in
    /// `per_material` (see [`emissive_texture_means`]).
    pub fn scale_emitter_power(&mut self, per_material: &[f32]) {
        for (prim, _, power) in &mut self.emissive {
            let material = self.triangles[*prim as usize].v0[3].to_bits() as usize;
            *power *= per_material.get(material).copied().unwrap_or(1.0);
        }
    }

    /// The middle and the diagonal of the scene's robust box (a lone far-away object does not
    /// count, see [`robust_bounds`]), in render space.
    pub fn bounds(&self) -> (Vec3, f32) {
        self.middle
    }

    /// Replaces the triangles from shading position `at` on with `world` (the same triangles
    /// moved, in the same order: their light indices stay); returns the range written.
    pub fn rewrite(&mut self, at: usize, world: &[WorldTriangle]) -> std::ops::Range<usize> {
        for (k, t) in world.iter().enumerate() {
            let light = self.triangles[at + k].v1[3].to_bits() as i32;
            let (tri, sh, tan) = device_triangle(t, light);
            self.triangles[at + k] = tri;
            self.shading[at + k] = sh;
            if !self.tangents.is_empty() {
                self.tangents[at + k] = tan;
            }
            self.vertices[at + k] = t.v;
        }
        at..at + world.len()
    }

    /// The closest hit along `ray` (render space): `prim` in shading order, as the device
    /// reports it.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        match &self.accel {
            Accel::Flat(b) => b.intersect(ray, &self.vertices),
            Accel::TwoLevel(t) => t.shading_hit(ray),
        }
    }

    /// Whether anything blocks `ray` within its interval.
    pub fn occluded(&self, ray: &Ray) -> bool {
        match &self.accel {
            Accel::Flat(b) => b.occluded(ray, &self.vertices),
            Accel::TwoLevel(t) => t.occluded(ray),
        }
    }

    /// The object index of a triangle in BVH order.
    pub fn object_of(&self, prim: u32) -> u32 {
        self.triangles[prim as usize].v2[3].to_bits()
    }
}

/// A triangle's device structs; `light` is its index among the emissive triangles (-1: none).
fn device_triangle(t: &WorldTriangle, light: i32) -> (GpuTriangle, GpuTriShading, GpuTriTangents) {
    let smooth = if t.smooth { 1.0 } else { 0.0 };
    let c = t.tangents.unwrap_or_default().map(|v| v.to_array());
    (
        GpuTriangle {
            v0: f4(t.v[0], f32::from_bits(t.material)),
            v1: f4(t.v[1], f32::from_bits(light as u32)),
            v2: f4(t.v[2], f32::from_bits(t.object)),
        },
        GpuTriShading {
            n0: f4(t.n[0], smooth),
            n1: f4(t.n[1], 0.0),
            n2: f4(t.n[2], 0.0),
            uv01: [t.uv[0].x, t.uv[0].y, t.uv[1].x, t.uv[1].y],
            uv2: [t.uv[2].x, t.uv[2].y, t.uv1[0].x, t.uv1[0].y],
            uv1_12: [t.uv1[1].x, t.uv1[1].y, t.uv1[2].x, t.uv1[2].y],
        },
        GpuTriTangents {
            t0: c[0],
            t1: c[1],
            t2: c[2],
        },
    )
}

/// The device camera for an aspect ratio (width / height).
pub fn gpu_camera(c: &Camera, aspect: f32) -> GpuCamera {
    let forward = c.forward.normalize().as_vec3();
    let right = c.forward.cross(c.up).normalize().as_vec3();
    let up = right.cross(forward).normalize();
    let h = (c.yfov as f32 * 0.5).tan();
    GpuCamera {
        origin: f4(c.eye.as_vec3(), 0.0),
        forward: f4(forward, 1.0),
        right: f4(right * h * aspect, 0.0),
        up: f4(up * h, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lights::gpu_lights;
    use crate::render::textures::TexturePack;
    use crate::scene::{Image, TexTransform, TextureRef};
    use crate::scene::{Light, LightKind, MAX_TEXTURE_SIDE, Scene, Wrap};
    use std::sync::Arc;

    /// A 10-unit floor centred at the origin, as the host would upload it.
    fn floor() -> HostScene {
        let v = [
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, -5.0),
        ];
        let world = [WorldTriangle {
            v,
            n: [Vec3::Y; 3],
            ..WorldTriangle::default()
        }];
        let bvh = crate::bvh::build(&[v]);
        HostScene::new(&world, bvh, &[Material::default()])
    }

    fn light(kind: LightKind, position: glam::DVec3, intensity: f32) -> Light {
        Light {
            name: "l".into(),
            kind,
            position,
            direction: glam::DVec3::NEG_Y,
            color: [1.0; 3],
            intensity,
            light_radius: 0.0,
        }
    }

    #[test]
    fn lights_that_light_the_scene_equally_are_not_starved() {
        let host = floor();
        // A sun of irradiance 2 and a point light 20 units up with I / d² = 2 at the middle.
        // By power alone the sun would get 3 %; the mixture gives it half of the irradiance
        // table's 50 % plus half of that.
        let lights = [
            light(LightKind::Directional, glam::DVec3::ZERO, 2.0),
            light(LightKind::Point, glam::DVec3::new(0.0, 20.0, 0.0), 800.0),
        ];
        let (gpu, cdf) = gpu_lights(&lights, &host, None);
        assert_eq!(gpu.len(), 2);
        eprintln!("bounds {:?} {:?}", host.bounds(), gpu);
        let sun_power = 2.0 * std::f32::consts::PI * 50.0;
        let point_power = 800.0 * 4.0 * std::f32::consts::PI;
        let expect = 0.5 * (0.5 + sun_power / (sun_power + point_power));
        assert!(
            (gpu[0].extra[1] - expect).abs() < 1e-4,
            "{:?}",
            gpu[0].extra
        );
        assert!((gpu[0].extra[1] + gpu[1].extra[1] - 1.0).abs() < 1e-6);
        assert_eq!(*cdf.last().unwrap(), 1.0);
        // A light at the middle counts as 5 % of the diagonal away (I / 0.5 here), not as
        // infinitely bright.
        let close = [
            light(LightKind::Directional, glam::DVec3::ZERO, 1.0),
            light(LightKind::Point, glam::DVec3::ZERO, 1.0),
        ];
        let (gpu, _) = gpu_lights(&close, &host, None);
        let pi = std::f32::consts::PI;
        let expect = 0.5 * (2.0 / 3.0 + 4.0 * pi / (4.0 * pi + 50.0 * pi));
        assert!(
            (gpu[1].extra[1] - expect).abs() < 1e-4,
            "{:?}",
            gpu[1].extra
        );
    }

    fn scene_with(sides: &[u32]) -> Scene {
        let images = sides
            .iter()
            .map(|&s| {
                Arc::new(Image {
                    name: format!("{s}"),
                    width: s,
                    height: s / 2,
                    rgba: vec![[200, 100, 50, 255]; (s * s / 2) as usize],
                })
            })
            .collect();
        let texture_refs = (0..sides.len() as u32)
            .flat_map(|image| {
                [false, true].map(|srgb| TextureRef {
                    image,
                    srgb,
                    wrap_s: Wrap::Repeat,
                    wrap_t: Wrap::Mirror,
                    tex_coord: 0,
                    nearest: false,
                    mipmaps: true,
                    transform: TexTransform::default(),
                })
            })
            .collect();
        Scene {
            images,
            texture_refs,
            ..Scene::default()
        }
    }

    #[test]
    fn textures_pack_their_mip_chains_one_after_another() {
        let pack = TexturePack::new(&scene_with(&[8, 4]), usize::MAX);
        // Each image twice (linear and sRGB): 8×4 → 4×2 → 2×1 → 1×1, and 4×2 → 2×1 → 1×1.
        assert_eq!(pack.textures.len(), 4);
        let big = 32 + 8 + 2 + 1;
        let small = 8 + 2 + 1;
        assert_eq!(pack.texels.len(), 2 * big + 2 * small);
        assert_eq!(pack.textures[1].offset, big as u32);
        assert_eq!(pack.textures[0].flags, 4);
        assert_eq!(pack.textures[1].flags, 4 | TEXTURE_SRGB);
        assert_eq!(pack.refs[3].info, [3, WRAP_REPEAT, WRAP_MIRROR, 0]);
        assert_eq!(pack.bytes(), pack.texels.len() * 4);
        assert_eq!(pack.texels[0], u32::from_le_bytes([200, 100, 50, 255]));
    }

    #[test]
    fn a_tight_budget_halves_the_largest_side() {
        // Two 64×32 chains (linear and sRGB) of 2048 + 512 + 128 + 32 + 8 + 2 + 1 texels each.
        let full = TexturePack::new(&scene_with(&[64]), usize::MAX);
        assert_eq!(full.max_side, MAX_TEXTURE_SIDE);
        let budget = full.bytes() / 2;
        let pack = TexturePack::new(&scene_with(&[64]), budget);
        assert!(pack.bytes() <= budget);
        assert_eq!(pack.max_side, 32);
        assert_eq!((pack.textures[0].width, pack.textures[0].height), (32, 16));
    }
}
