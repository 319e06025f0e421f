//! Turning the host scene into the device's structs: the acceleration structure and the
//! instances' layout (`accel`), the scene as uploaded with its emissive triangles
//! (`host_scene`), the triangles' device structs (`triangles`), and materials and the camera
//! (`structs`). The light list is built in `lights`, the textures in `textures`.

mod accel;
mod host_scene;
mod repose;
mod structs;
mod triangles;

pub use accel::{Accel, InstanceLayout, piece_copies};
pub use host_scene::{FlatRefit, HostScene, PosedMesh, render_middle};
pub use repose::CHUNK;
pub(super) use structs::{f4, luminance};
pub use structs::{gpu_camera, gpu_material, samples_textures};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cl::types::*;
    use crate::render::lights::gpu_lights;
    use crate::render::textures::TexturePack;
    use crate::scene::{Image, TexTransform, TextureRef};
    use crate::scene::{Light, LightKind, MAX_TEXTURE_SIDE, Scene, Wrap};
    use crate::scene::{Material, WorldTriangle};
    use glam::Vec3;
    use std::sync::Arc;

    /// A 10-unit floor centred at the origin, as the host would upload it.
    fn floor() -> HostScene {
        let v = [
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, -5.0),
        ];
        let world = vec![WorldTriangle {
            v,
            n: [Vec3::Y; 3],
            ..WorldTriangle::default()
        }];
        HostScene::flat(world, &[Material::default()])
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
        let (device, cdf) = gpu_lights(&lights, &host, None);
        assert_eq!(device.len(), 2);
        eprintln!("bounds {:?} {:?}", host.bounds(), device);
        let sun_power = 2.0 * std::f32::consts::PI * 50.0;
        let point_power = 800.0 * 4.0 * std::f32::consts::PI;
        let expect = 0.5 * (0.5 + sun_power / (sun_power + point_power));
        assert!(
            (device[0].extra[1] - expect).abs() < 1e-4,
            "{:?}",
            device[0].extra
        );
        assert!((device[0].extra[1] + device[1].extra[1] - 1.0).abs() < 1e-6);
        assert_eq!(*cdf.last().unwrap(), 1.0);
        // A light at the middle counts as 5 % of the diagonal away (I / 0.5 here), not as
        // infinitely bright.
        let close = [
            light(LightKind::Directional, glam::DVec3::ZERO, 1.0),
            light(LightKind::Point, glam::DVec3::ZERO, 1.0),
        ];
        let (device, _) = gpu_lights(&close, &host, None);
        let pi = std::f32::consts::PI;
        let expect = 0.5 * (2.0 / 3.0 + 4.0 * pi / (4.0 * pi + 50.0 * pi));
        assert!(
            (device[1].extra[1] - expect).abs() < 1e-4,
            "{:?}",
            device[1].extra
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
