//! The device form of a material and of the camera, and the small conversions the uploads
//! share.

use crate::cl::types::*;
use crate::scene::{AlphaMode, Camera, Material};
use glam::Vec3;

/// `v` with `w` as its fourth lane.
pub(in crate::render) fn f4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// The luminance of a linear Rec. 709 colour.
pub(in crate::render) fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The device form of a material.
pub fn gpu_material(m: &Material) -> DeviceMaterial {
    let flags = if m.double_sided {
        MATERIAL_DOUBLE_SIDED
    } else {
        0
    } | if m.unlit { MATERIAL_UNLIT } else { 0 };
    DeviceMaterial {
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

/// Whether some material samples a texture: only then do the kernels read texture coordinates
/// (`HAS_TEXTURES` comes from the materials in use, a subset), and only then are they uploaded.
pub fn samples_textures(materials: &[Material]) -> bool {
    materials.iter().any(|m| m.textures.any())
}

/// The device camera for an aspect ratio (width / height).
pub fn gpu_camera(c: &Camera, aspect: f32) -> DeviceCamera {
    let forward = c.forward.normalize().as_vec3();
    let right = c.forward.cross(c.up).normalize().as_vec3();
    let up = right.cross(forward).normalize();
    let h = (c.yfov as f32 * 0.5).tan();
    DeviceCamera {
        origin: f4(c.eye.as_vec3(), 0.0),
        forward: f4(forward, 1.0),
        right: f4(right * h * aspect, 0.0),
        up: f4(up * h, 0.0),
    }
}
