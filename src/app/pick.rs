//! Picking: the object under the mouse, found by casting the pixel's primary ray through the
//! host BVH (the same one the device traverses).

use crate::bvh::Ray;
use crate::render::camera::primary_ray;
use crate::render::{HostScene, gpu_camera};
use crate::scene::Camera;
use glam::DVec3;

/// What a click hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pick {
    /// Index into `Scene::objects`.
    pub object: usize,
    /// The hit point in world space.
    pub point: DVec3,
}

/// The object seen through the point (fx, fy) of the image, both in [0, 1] from the top left,
/// along the primary ray the camera kernel makes (without jitter and lens), cast in the
/// scene's render space.
pub fn pick(host: &HostScene, camera: &Camera, aspect: f32, fx: f32, fy: f32) -> Option<Pick> {
    let ray = primary_ray(&gpu_camera(&host.space.camera(camera), aspect), fx, fy);
    let hit = host.intersect(&ray)?;
    let point = ray.origin + ray.direction * hit.t;
    Some(Pick {
        object: host.object_of(&hit) as usize,
        point: host.space.world_point(point),
    })
}

/// Rays per side of the grid [`seen_distance`] casts over the image.
const PROBE_GRID: usize = 5;

/// The distance to the first surface from `origin` along the unit `direction` (world space),
/// through the host BVH.
pub fn distance_along(host: &HostScene, origin: DVec3, direction: DVec3) -> Option<f64> {
    let o = host.space.point(origin);
    // A direction of one world unit in render space, so that t is in world units.
    let d = host.space.point(origin + direction) - o;
    let ray = Ray {
        origin: o,
        direction: d,
        tmin: 0.0,
        tmax: f32::INFINITY,
    };
    host.intersect(&ray).map(|h| f64::from(h.t))
}

/// How far what the camera sees is: the median distance of the surfaces a grid of primary
/// rays over the image hits; `None` when they all miss (an object seen from outside its
/// bounds against the sky counts only the rays that hit it).
pub fn seen_distance(host: &HostScene, camera: &Camera, aspect: f32) -> Option<f64> {
    let mut hits: Vec<f64> = Vec::new();
    for j in 0..PROBE_GRID {
        for i in 0..PROBE_GRID {
            let (fx, fy) = (
                (i as f32 + 0.5) / PROBE_GRID as f32,
                (j as f32 + 0.5) / PROBE_GRID as f32,
            );
            if let Some(p) = pick(host, camera, aspect, fx, fy) {
                hits.push((p.point - camera.eye).length());
            }
        }
    }
    hits.sort_by(f64::total_cmp);
    hits.get(hits.len() / 2).copied()
}

/// The centre of the world-space bounding box of `object`'s geometry.
pub fn object_center(scene: &crate::scene::Scene, object: usize) -> Option<DVec3> {
    let o = scene.objects.get(object)?;
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for p in &o.mesh.positions {
        let w = o.world_from_object.transform_point3(p.as_dvec3());
        min = min.min(w);
        max = max.max(w);
    }
    (min.is_finite() && max.is_finite()).then(|| 0.5 * (min + max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Mesh, Object, Scene};
    use glam::{DMat4, Vec3};

    /// Two unit quads facing +Z: object 0 at x = -2, object 1 at x = +2, and a hidden one in
    /// front of object 1.
    fn scene() -> Scene {
        let quad = Mesh {
            positions: vec![
                Vec3::new(-0.5, -0.5, 0.0),
                Vec3::new(0.5, -0.5, 0.0),
                Vec3::new(0.5, 0.5, 0.0),
                Vec3::new(-0.5, 0.5, 0.0),
            ],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            materials: vec![0, 0],
            ..Mesh::default()
        };
        let object = |name: &str, x: f64, z: f64, visible: bool| Object {
            name: name.into(),
            world_from_object: DMat4::from_translation(DVec3::new(x, 0.0, z)),
            visible,
            mesh: quad.clone().into(),
        };
        Scene {
            objects: vec![
                object("left", -2.0, 0.0, true),
                object("right", 2.0, 0.0, true),
                object("hidden", 2.0, 1.0, false),
            ],
            materials: vec![Material::default()],
            ..Scene::default()
        }
    }

    fn host(scene: &Scene) -> HostScene {
        HostScene::flat(scene.world_triangles(), &scene.materials)
    }

    #[test]
    fn clicks_find_the_object_under_the_pixel() {
        let scene = scene();
        let host = host(&scene);
        // Looking down -Z from z = 5 with a field of view that spans x in about [-4, 4].
        let cam = Camera::look_at("c", DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, 1.3);
        let aspect = 1.0;
        let half = (cam.yfov * 0.5).tan() as f32 * 5.0;
        let fx = |x: f32| 0.5 + 0.5 * x / half;
        let left = pick(&host, &cam, aspect, fx(-2.0), 0.5).unwrap();
        assert_eq!(left.object, 0);
        assert!((left.point - DVec3::new(-2.0, 0.0, 0.0)).length() < 1e-3);
        // The hidden quad in front of the right one is not in the BVH.
        let right = pick(&host, &cam, aspect, fx(2.0), 0.5).unwrap();
        assert_eq!(right.object, 1);
        assert!(pick(&host, &cam, aspect, 0.5, 0.5).is_none());
        // The top of the image looks up.
        assert!(pick(&host, &cam, aspect, fx(2.0), 0.0).is_none());
    }
}
