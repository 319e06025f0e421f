//! Turning the host scene into the device's structs: triangles and shading data in BVH order,
//! materials, the light list with its selection table, and the camera.

use crate::bvh::Bvh;
use crate::cl::types::*;
use crate::scene::{
    AlphaMode, Camera, Light, LightKind, MAX_TEXTURE_SIDE, Material, Scene, WorldTriangle, Wrap,
    mip_chain, srgb_to_linear,
};
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// The scene as uploaded, kept on the host for picking and for tests.
pub struct HostScene {
    /// The BVH.
    pub bvh: Bvh,
    /// Triangles in BVH order.
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
}

fn f4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

fn luminance(c: [f32; 3]) -> f32 {
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
        textures2: [slot(m.textures.transmission), -1, -1, -1],
    }
}

fn slot(r: Option<u32>) -> i32 {
    r.map_or(-1, |r| r as i32)
}

impl HostScene {
    /// Orders the triangles as the BVH wants them and fills the device structs.
    pub fn new(world: &[WorldTriangle], bvh: Bvh, materials: &[Material]) -> Self {
        let mut emissive = Vec::new();
        let mut triangles = Vec::with_capacity(world.len());
        let mut shading = Vec::with_capacity(world.len());
        let mut vertices = Vec::with_capacity(world.len());
        let normal_mapped = world.iter().any(|t| t.tangents.is_some());
        let mut tangents = Vec::new();
        for (order, &index) in bvh.tri_indices.iter().enumerate() {
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
            triangles.push(GpuTriangle {
                v0: f4(t.v[0], f32::from_bits(t.material)),
                v1: f4(t.v[1], f32::from_bits(light as u32)),
                v2: f4(t.v[2], f32::from_bits(t.object)),
            });
            let smooth = if t.smooth { 1.0 } else { 0.0 };
            shading.push(GpuTriShading {
                n0: f4(t.n[0], smooth),
                n1: f4(t.n[1], 0.0),
                n2: f4(t.n[2], 0.0),
                uv01: [t.uv[0].x, t.uv[0].y, t.uv[1].x, t.uv[1].y],
                uv2: [t.uv[2].x, t.uv[2].y, t.uv1[0].x, t.uv1[0].y],
                uv1_12: [t.uv1[1].x, t.uv1[1].y, t.uv1[2].x, t.uv1[2].y],
            });
            if normal_mapped {
                let c = t.tangents.unwrap_or_default().map(|v| v.to_array());
                tangents.push(GpuTriTangents {
                    t0: c[0],
                    t1: c[1],
                    t2: c[2],
                });
            }
            vertices.push(t.v);
        }
        Self {
            bvh,
            triangles,
            vertices,
            shading,
            tangents,
            materials: materials.iter().map(gpu_material).collect(),
            emissive,
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

    /// The middle and the diagonal of the scene's box (from the BVH root's two children).
    pub fn bounds(&self) -> (Vec3, f32) {
        let (a, _) = self.bvh.child(0, 0);
        let (b, _) = self.bvh.child(0, 1);
        let u = a.union(b);
        if u.min.cmpgt(u.max).any() {
            return (Vec3::ZERO, 1.0);
        }
        ((u.min + u.max) * 0.5, (u.max - u.min).length())
    }

    /// The object index of a triangle in BVH order.
    pub fn object_of(&self, prim: u32) -> u32 {
        self.triangles[prim as usize].v2[3].to_bits()
    }
}

/// For each material, the mean linear luminance of its emissive texture (1 without one, at least
/// 10⁻³), so that the light table weighs textured emitters by what they emit on average.
pub fn emissive_texture_means(scene: &Scene) -> Vec<f32> {
    scene
        .materials
        .iter()
        .map(|m| {
            let Some(r) = m.textures.emissive.filter(|_| m.is_emissive()) else {
                return 1.0;
            };
            let r = &scene.texture_refs[r as usize];
            let image = &scene.images[r.image as usize];
            let sum: f64 = image
                .rgba
                .par_iter()
                .map(|t| {
                    let c = |v: u8| {
                        if r.srgb {
                            srgb_to_linear(v)
                        } else {
                            v as f32 / 255.0
                        }
                    };
                    luminance([c(t[0]), c(t[1]), c(t[2])]) as f64
                })
                .sum();
            ((sum / image.rgba.len().max(1) as f64) as f32).max(1e-3)
        })
        .collect()
}

/// The light list (emissive triangles first, so a triangle's light index is its position in
/// `HostScene::emissive`, then the punctual lights, then the environment map when
/// `env_luminance` (its mean luminance × intensity) is given) and its cumulative selection
/// table.
///
/// A light's probability is the mean of two tables: one in proportion to its emitted power
/// (4π I for a point light, π r² E for a sun over the scene's disc, π L A for a triangle), one
/// in proportion to an estimate of the irradiance it sends to the middle of the scene (I / d²,
/// E, π L̄ for the environment, L A / d², with d clamped below at 5 % of the diagonal). Power
/// alone made a default-rig sun, whose power grows with the scene's area, 40× less likely than
/// the key light while both lit surfaces about equally, and the rare sun samples showed as
/// speckle; irradiance alone suits a room's lights worse than power (the Cornell box's error
/// grew by a fifth). The mixture is never worse than half of either. Any positive weights keep
/// the estimator unbiased.
pub fn gpu_lights(
    lights: &[Light],
    host: &HostScene,
    env_luminance: Option<f32>,
) -> (Vec<GpuLight>, Vec<f32>) {
    let mut out = Vec::new();
    // (by irradiance at the middle, by power) per light.
    let mut weights: Vec<(f32, f32)> = Vec::new();
    let (center, diagonal) = host.bounds();
    let disc = std::f32::consts::PI * (0.5 * diagonal) * (0.5 * diagonal);
    let near = (0.05 * diagonal).max(1e-12);
    let inverse_square = |p: Vec3| 1.0 / (p - center).length_squared().max(near * near);
    for &(prim, area, power) in &host.emissive {
        let v = &host.vertices[prim as usize];
        let centroid = (v[0] + v[1] + v[2]) / 3.0;
        out.push(GpuLight {
            position: [0.0, 0.0, 0.0, f32::from_bits(LIGHT_TRIANGLE)],
            intensity: [0.0; 4],
            spot: [f32::from_bits(prim), area, 0.0, 0.0],
            extra: [0.0; 4],
        });
        // `power` is π L A (× 2 when double-sided), so power / π is the intensity scale L A.
        weights.push((
            power / std::f32::consts::PI * inverse_square(centroid),
            power,
        ));
    }
    let pi = std::f32::consts::PI;
    for l in lights {
        let color = l.color.map(|c| c * l.intensity);
        let y = luminance(color);
        let (kind, position, irradiance, power) = match l.kind {
            LightKind::Point => (
                LIGHT_POINT,
                l.position,
                y * inverse_square(l.position.as_vec3()),
                y * 4.0 * pi,
            ),
            LightKind::Spot { outer, .. } => (
                LIGHT_SPOT,
                l.position,
                y * inverse_square(l.position.as_vec3()),
                y * 2.0 * pi * (1.0 - outer.cos()).max(0.05),
            ),
            LightKind::Directional => (LIGHT_DIRECTIONAL, l.direction, y, y * disc),
        };
        if !(irradiance > 0.0 && irradiance.is_finite() && power.is_finite()) {
            continue;
        }
        let (cos_inner, cos_outer) = match l.kind {
            LightKind::Spot { inner, outer } => (inner.cos(), outer.cos()),
            _ => (1.0, -1.0),
        };
        let d = l.direction.as_vec3().normalize_or(Vec3::NEG_Y);
        out.push(GpuLight {
            position: f4(position.as_vec3(), f32::from_bits(kind)),
            intensity: [color[0], color[1], color[2], l.radius.max(0.0)],
            spot: f4(d, cos_outer),
            extra: [cos_inner, 0.0, 0.0, 0.0],
        });
        weights.push((irradiance, power));
    }
    if let Some(l) = env_luminance {
        let irradiance = pi * l;
        if irradiance > 0.0 && irradiance.is_finite() {
            out.push(GpuLight {
                position: [0.0, 0.0, 0.0, f32::from_bits(LIGHT_ENVIRONMENT)],
                ..GpuLight::default()
            });
            weights.push((irradiance, irradiance * disc));
        }
    }
    let total_irradiance: f32 = weights.iter().map(|w| w.0).sum();
    let total_power: f32 = weights.iter().map(|w| w.1).sum();
    let mut cdf = Vec::with_capacity(weights.len());
    let mut acc = 0.0;
    for (l, w) in out.iter_mut().zip(&weights) {
        let p = 0.5 * (w.0 / total_irradiance + w.1 / total_power);
        l.extra[1] = p;
        acc += p;
        cdf.push(acc);
    }
    if let Some(last) = cdf.last_mut() {
        *last = 1.0;
    }
    (out, cdf)
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

/// Textures as the device stores them: every (image, color space) pair used by a material
/// becomes one RGBA8 mip chain in a single texel buffer; materials point at `refs`.
#[derive(Clone, Debug, Default)]
pub struct TexturePack {
    /// One descriptor per texture.
    pub textures: Vec<GpuTexture>,
    /// One entry per `Scene::texture_refs` entry.
    pub refs: Vec<GpuTexRef>,
    /// RGBA8 texels (R in the low byte) of every level of every texture.
    pub texels: Vec<u32>,
    /// The largest side kept (smaller than [`MAX_TEXTURE_SIDE`] when the budget forced it).
    pub max_side: u32,
}

fn wrap_code(w: Wrap) -> i32 {
    match w {
        Wrap::Repeat => WRAP_REPEAT,
        Wrap::Clamp => WRAP_CLAMP,
        Wrap::Mirror => WRAP_MIRROR,
    }
}

impl TexturePack {
    /// Packs the scene's textures. Mip chains are box-filtered on the host (in linear space for
    /// sRGB textures); levels above [`MAX_TEXTURE_SIDE`] are dropped, and while the texels would
    /// exceed `budget_bytes` the largest side allowed is halved.
    pub fn new(scene: &Scene, budget_bytes: usize) -> Self {
        let mut keys: Vec<(u32, bool)> = Vec::new();
        let mut index: HashMap<(u32, bool), u32> = HashMap::new();
        for r in &scene.texture_refs {
            index.entry((r.image, r.srgb)).or_insert_with(|| {
                keys.push((r.image, r.srgb));
                keys.len() as u32 - 1
            });
        }
        // Texels of a chain whose level 0 is capped at `side`.
        let chain_texels = |w: u32, h: u32, side: u32| -> usize {
            let (mut w, mut h) = (w, h);
            while w > side || h > side {
                w = (w / 2).max(1);
                h = (h / 2).max(1);
            }
            let mut n = 0usize;
            loop {
                n += (w * h) as usize;
                if w == 1 && h == 1 {
                    return n;
                }
                w = (w / 2).max(1);
                h = (h / 2).max(1);
            }
        };
        let mut max_side = MAX_TEXTURE_SIDE;
        while max_side > 1 {
            let total: usize = keys
                .iter()
                .map(|&(i, _)| {
                    let im = &scene.images[i as usize];
                    chain_texels(im.width, im.height, max_side)
                })
                .sum();
            if total * 4 <= budget_bytes {
                break;
            }
            max_side /= 2;
        }
        let chains: Vec<Vec<crate::scene::MipLevel>> = keys
            .par_iter()
            .map(|&(i, srgb)| mip_chain(&scene.images[i as usize], srgb, max_side))
            .collect();
        let mut textures = Vec::with_capacity(chains.len());
        let mut texels = Vec::new();
        for (chain, &(_, srgb)) in chains.iter().zip(&keys) {
            textures.push(GpuTexture {
                offset: texels.len() as u32,
                width: chain[0].width,
                height: chain[0].height,
                flags: chain.len() as u32 | if srgb { TEXTURE_SRGB } else { 0 },
            });
            for level in chain {
                texels.extend(level.rgba.iter().map(|&t| u32::from_le_bytes(t)));
            }
        }
        let refs = scene
            .texture_refs
            .iter()
            .map(|r| {
                let [a, b] = r.transform.rows();
                let det = (a[0] * b[1] - a[1] * b[0]).abs().max(1e-12);
                GpuTexRef {
                    m0: [a[0], a[1], a[2], f32::from_bits(r.tex_coord)],
                    m1: [b[0], b[1], b[2], 0.5 * det.log2()],
                    info: [
                        index[&(r.image, r.srgb)] as i32,
                        wrap_code(r.wrap_s),
                        wrap_code(r.wrap_t),
                        if r.nearest { TEXREF_NEAREST } else { 0 }
                            | if r.mipmaps { 0 } else { TEXREF_NO_MIPS },
                    ],
                }
            })
            .collect();
        Self {
            textures,
            refs,
            texels,
            max_side,
        }
    }

    /// Bytes of texel memory on the device.
    pub fn bytes(&self) -> usize {
        self.texels.len() * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Image, TexTransform, TextureRef};
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
            radius: 0.0,
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
