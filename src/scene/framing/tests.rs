//! Tests of the first view: the robust bounds, the probe's two tracers, the view of an object,
//! of a room and of a lit scene, and the lights added to a view.

use super::probe::{Tracer, sphere_directions};
use super::subject_bounds::{centroid_percentiles, regular_sample_of, robust_bounds_windowed};
use super::*;
use crate::bvh::Ray;
use crate::scene::{Material, Mesh, Object};
use glam::DMat4;
use std::sync::Arc;

/// A box from `lo` to `hi` as 12 triangles; `inward` makes the faces look inside.
fn cuboid(lo: Vec3, hi: Vec3, inward: bool) -> Vec<[Vec3; 3]> {
    let c = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Quads as corner indices, counter-clockwise seen from outside.
    let quads = [
        [0, 2, 3, 1], // −Z
        [4, 5, 7, 6], // +Z
        [0, 4, 6, 2], // −X
        [1, 3, 7, 5], // +X
        [0, 1, 5, 4], // −Y
        [2, 6, 7, 3], // +Y
    ];
    let mut out = Vec::new();
    for q in quads {
        let (a, b, cc, d) = (c(q[0]), c(q[1]), c(q[2]), c(q[3]));
        if inward {
            out.push([a, cc, b]);
            out.push([a, d, cc]);
        } else {
            out.push([a, b, cc]);
            out.push([a, cc, d]);
        }
    }
    out
}

fn scene_of(parts: &[(Vec<[Vec3; 3]>, Material)]) -> Scene {
    let mut scene = Scene::default();
    for (i, (tris, material)) in parts.iter().enumerate() {
        let mut mesh = Mesh::default();
        for t in tris {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend_from_slice(t);
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.materials.push(i as u32);
        }
        scene.objects.push(Object {
            name: format!("part {i}"),
            world_from_object: DMat4::IDENTITY,
            visible: true,
            mesh: mesh.into(),
        });
        scene.materials.push(material.clone());
    }
    scene
}

fn point(position: DVec3, intensity: f32) -> Light {
    Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        position,
        direction: DVec3::NEG_Y,
        color: [1.0; 3],
        intensity,
        light_radius: 0.0,
    }
}

/// A finely split unit cube (so percentiles see many triangles) at the origin.
fn subject() -> Vec<[Vec3; 3]> {
    let mut tris = Vec::new();
    for i in 0..4 {
        for k in 0..4 {
            let lo = Vec3::new(i as f32 * 0.25 - 0.5, -0.5, k as f32 * 0.25 - 0.5);
            tris.extend(cuboid(lo, lo + Vec3::new(0.25, 1.0, 0.25), false));
        }
    }
    tris
}

#[test]
fn robust_bounds_ignore_a_stray_far_object() {
    let mut tris = subject();
    tris.extend(cuboid(Vec3::splat(1000.0), Vec3::splat(1000.1), false));
    let b = robust_bounds(&WorldTris::soup(&tris));
    assert!((b.min - DVec3::splat(-0.5)).length() < 1e-6, "{b:?}");
    assert!((b.max - DVec3::splat(0.5)).length() < 1e-6, "{b:?}");
}

/// A large scene's window placed from a regular sample gives the bounds that all the
/// triangles give: a floor of 20,000 triangles with a far-away speck, sampled down to 500
/// (and, as a check that the sample matters, the window of the first 500 alone is wrong).
#[test]
fn a_sampled_window_gives_the_bounds_of_all_triangles() {
    let mut tris = vec![];
    for i in 0..100 {
        for j in 0..100 {
            let (x, z) = (i as f32 * 0.1, j as f32 * 0.1 + 0.02 * (i % 3) as f32);
            let (a, b) = (Vec3::new(x, 0.0, z), Vec3::new(x + 0.1, 0.0, z));
            let (c, d) = (Vec3::new(x, 0.0, z + 0.1), Vec3::new(x + 0.1, 0.3, z + 0.1));
            tris.push([a, b, c]);
            tris.push([b, d, c]);
        }
    }
    tris.push([
        Vec3::splat(1e6),
        Vec3::splat(1e6) + Vec3::X,
        Vec3::splat(1e6) + Vec3::Y,
    ]);
    let all = WorldTris::soup(&tris);
    assert!(regular_sample_of(&all, all.len(), 500).is_none());
    let sample = regular_sample_of(&all, 1000, 500).unwrap();
    assert!(sample.len() <= 500 && sample.len() >= 450);
    let exact = robust_bounds(&all);
    assert!(exact.max.x < 11.0 && exact.min.x == 0.0);
    assert_eq!(robust_bounds_windowed(&all, &sample), exact);
    let first = WorldTris::soup(&tris[..500]);
    assert_ne!(robust_bounds_windowed(&all, &first), exact);
}

/// The percentiles by histograms are those of sorting (value, weight) pairs and scanning
/// them (how they were found before), ties, signs and zeros of both signs included.
#[test]
fn centroid_percentiles_are_those_of_a_sort() {
    fn by_sort(tris: &[[Vec3; 3]], axis: usize, q: f64) -> f32 {
        let mut v: Vec<(f32, f32)> = tris
            .iter()
            .map(|t| (((t[0] + t[1] + t[2]) / 3.0)[axis], area(t).sqrt() + 1e-12))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let total: f64 = v.iter().map(|v| v.1 as f64).sum();
        let mut acc = 0.0;
        for &(x, w) in &v {
            acc += w as f64;
            if acc >= q * total {
                return x;
            }
        }
        v.last().unwrap().0
    }
    // A fixed scramble of (triangle, draw) to [0, 1).
    let r = |i: usize, k: usize| ((i * 2654435761 + k * 40503) % 997) as f32 / 997.0;
    for n in [8, 100, 5000] {
        let tris: Vec<[Vec3; 3]> = (0..n)
            .map(|i| {
                // Centroids on a coarse grid (many ties), some negative, some at ±0.
                let y = if i % 7 == 0 {
                    -0.0
                } else {
                    (r(i, 1) * 3.0).floor()
                };
                let c = Vec3::new((r(i, 0) * 8.0).floor() - 4.0, y, r(i, 2) * 1e3 - 500.0);
                let a = Vec3::new((r(i, 3) * 4.0).floor() + 1.0, 0.0, (r(i, 4) * 2.0).floor());
                let b = Vec3::new(0.0, (r(i, 5) * 4.0).floor() + 1.0, 1.0);
                [c + a, c + b, c - a - b]
            })
            .collect();
        let soup = WorldTris::soup(&tris);
        for (axis, p) in centroid_percentiles(&soup).into_iter().enumerate() {
            for (k, q) in [0.05, 0.95].into_iter().enumerate() {
                let expect = by_sort(&tris, axis, q);
                assert_eq!(p[k].to_bits(), expect.to_bits(), "n {n} axis {axis} q {q}");
            }
        }
    }
}

#[test]
fn a_small_model_fills_the_frame() {
    for size in [0.01f32, 1.0, 300.0] {
        let tris: Vec<[Vec3; 3]> = subject().iter().map(|t| t.map(|v| v * size)).collect();
        let b = robust_bounds(&WorldTris::soup(&tris));
        let cam = fit(&b, &[], DVec3::new(0.3, 0.4, 1.0).normalize(), 0.8, 1.6);
        // Project the corners: the widest one reaches 80–100% of the half-frame.
        let right = cam.forward.cross(cam.up);
        let tan_y = (cam.yfov * 0.5).tan();
        let mut fill = 0.0f64;
        for i in 0..8 {
            let p = DVec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            ) - cam.eye;
            let z = p.dot(cam.forward);
            assert!(z > 0.0);
            fill = fill
                .max(p.dot(cam.up).abs() / (z * tan_y))
                .max(p.dot(right).abs() / (z * tan_y * 1.6));
        }
        assert!((0.8..=0.901).contains(&fill), "size {size}: fill {fill}");
    }
}

#[test]
fn the_view_faces_the_light() {
    let scene = scene_of(&[(subject(), Material::default())]);
    let probe = Probe::new(&scene);
    for light_dir in [DVec3::X, DVec3::NEG_Z, DVec3::new(-1.0, 0.5, 0.2)] {
        let lamp = point(light_dir.normalize() * 5.0, 25.0);
        let d = lit_side(&probe, &[lamp]);
        assert!(
            d.dot(light_dir.normalize()) > 0.6,
            "light from {light_dir}, view from {d}"
        );
    }
}

#[test]
fn a_room_is_seen_from_inside_and_an_object_from_outside() {
    // A 6 × 2.7 × 4 m room with a table in it.
    let mut room = cuboid(Vec3::ZERO, Vec3::new(6.0, 2.7, 4.0), true);
    room.extend(cuboid(
        Vec3::new(2.5, 0.0, 1.5),
        Vec3::new(3.5, 0.75, 2.5),
        false,
    ));
    let scene = scene_of(&[(room, Material::default())]);
    let view = first_view(&scene, &[], None, 1.6);
    assert!(view.interior);
    let eye = view.camera.eye;
    assert!(
        (eye.y - EYE_HEIGHT).abs() < 1e-6 && eye.x > 0.0 && eye.x < 6.0 && eye.z > 0.0,
        "{eye} in {:?}",
        view.bounds
    );
    // It looks along the long (x) side of the room.
    assert!(
        view.camera.forward.x.abs() > 0.9,
        "{:?}",
        view.camera.forward
    );
    // The same box with faces out is a closed object: framed from outside.
    let closed = cuboid(Vec3::ZERO, Vec3::new(6.0, 2.7, 4.0), false);
    let view = first_view(&scene_of(&[(closed, Material::default())]), &[], None, 1.6);
    assert!(!view.interior);
    assert!(view.camera.eye.z > 4.0, "{}", view.camera.eye);
}

#[test]
fn the_sky_reaches_into_a_room_without_a_ceiling_and_not_into_a_closed_one() {
    let camera = Camera::look_at(
        "inside",
        DVec3::new(0.5, 1.4, 1.5),
        DVec3::new(-0.5, 1.0, -2.0),
        0.9,
    );
    let mut room = cuboid(Vec3::new(-3.0, 0.0, -2.0), Vec3::new(3.0, 2.7, 2.0), true);
    let closed = first_view(
        &scene_of(&[(room.clone(), Material::default())]),
        &[],
        Some(&camera),
        1.5,
    );
    assert!(
        closed.coverage == 1.0 && closed.sky_fraction == 0.0,
        "{closed:?}"
    );
    assert!(!closed.environment_reaches());
    room.truncate(10); // the ceiling (+Y) is the last quad
    let open = first_view(
        &scene_of(&[(room, Material::default())]),
        &[],
        Some(&camera),
        1.5,
    );
    assert!(open.sky_fraction > 0.05, "{open:?}");
    assert!(open.environment_reaches());
}

#[test]
fn a_lamp_over_the_subject_lights_the_view_and_a_tiny_glow_does_not() {
    let floor = vec![
        [
            Vec3::new(-5.0, -0.5, -5.0),
            Vec3::new(-5.0, -0.5, 5.0),
            Vec3::new(5.0, -0.5, 5.0),
        ],
        [
            Vec3::new(-5.0, -0.5, -5.0),
            Vec3::new(5.0, -0.5, 5.0),
            Vec3::new(5.0, -0.5, -5.0),
        ],
    ];
    let parts = [
        (subject(), Material::default()),
        (floor, Material::default()),
    ];
    let scene = scene_of(&parts);
    let lamp = point(DVec3::new(1.0, 4.0, 2.0), 20.0);
    let view = first_view(&scene, &[lamp], None, 1.5);
    assert!(view.lit, "{view:?}");
    assert!(view.coverage > 0.3, "{view:?}");
    let view = first_view(&scene, &[], None, 1.5);
    assert!(!view.lit && view.lit_fraction == 0.0, "{view:?}");

    // A small, very bright glowing cube inside a closed housing lights nothing.
    let glow_material = Material {
        emission: [500.0; 3],
        ..Material::default()
    };
    let glow = cuboid(Vec3::new(0.55, 0.2, 0.55), Vec3::new(0.6, 0.25, 0.6), false);
    let housing = cuboid(
        Vec3::new(0.52, 0.17, 0.52),
        Vec3::new(0.63, 0.28, 0.63),
        true,
    );
    let mut parts = parts.to_vec();
    parts.push((glow, glow_material));
    parts.push((
        housing.iter().map(|t| [t[0], t[2], t[1]]).collect(),
        Material::default(),
    ));
    let view = first_view(&scene_of(&parts), &[], None, 1.5);
    assert!(!view.lit, "{view:?}");
}

/// A room of shared meshes: a table mesh placed four times (scaled, rotated, mirrored),
/// a glass pane, a glowing panel and a lamp-lit subject, with the placed objects' meshes
/// shared as the importer shares them.
fn instanced_room() -> Scene {
    let mut room = cuboid(Vec3::ZERO, Vec3::new(6.0, 2.7, 4.0), true);
    room.extend(cuboid(
        Vec3::new(0.2, 0.0, 0.2),
        Vec3::new(0.4, 2.0, 0.4),
        false,
    ));
    let table = cuboid(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 0.75, 0.5), false);
    let pane = cuboid(Vec3::new(4.0, 0.5, 3.0), Vec3::new(5.0, 2.0, 3.02), false);
    let panel = cuboid(Vec3::new(2.5, 2.6, 1.5), Vec3::new(3.5, 2.65, 2.5), false);
    let glass = Material {
        transmission: 1.0,
        ..Material::default()
    };
    let glow = Material {
        emission: [4.0; 3],
        ..Material::default()
    };
    let mut scene = scene_of(&[
        (room, Material::default()),
        (pane, glass),
        (panel, glow),
        (table, Material::default()),
    ]);
    let table = scene.objects[3].clone();
    let placements = [
        DMat4::from_translation(DVec3::new(1.5, 0.0, 1.0)),
        DMat4::from_translation(DVec3::new(4.5, 0.0, 1.2))
            * DMat4::from_rotation_y(0.7)
            * DMat4::from_scale(DVec3::new(1.3, 0.8, 0.6)),
        // Mirrored: its triangles' corners swap in world space.
        DMat4::from_translation(DVec3::new(2.0, 0.0, 3.0))
            * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)),
    ];
    scene.objects[3].world_from_object = DMat4::from_translation(DVec3::new(3.0, 0.0, 2.0));
    for (i, m) in placements.into_iter().enumerate() {
        scene.objects.push(Object {
            name: format!("table {i}"),
            world_from_object: m,
            ..table.clone()
        });
    }
    // A hidden one is left out of both.
    scene.objects.push(Object {
        name: "hidden".into(),
        world_from_object: DMat4::from_translation(DVec3::new(3.0, 1.5, 2.0)),
        visible: false,
        ..table
    });
    scene
}

/// The probe over quick BLASes and a top level finds, ray for ray, the triangle and
/// distance that one tree over the world triangles finds (closest and any hit, with and
/// without glass), and the same first view.
#[test]
fn the_two_level_probe_finds_what_one_tree_over_the_world_finds() {
    let scene = instanced_room();
    let two = Probe::new(&scene);
    let flat = Probe::flat(&scene);
    assert!(matches!(two.tracer, Tracer::TwoLevel { .. }));
    assert!(matches!(flat.tracer, Tracer::Flat { .. }));
    assert_eq!(two.tris.to_vecs(), flat.tris.to_vecs());
    let centre = DVec3::new(3.0, 1.2, 2.0);
    let mut hits = 0;
    for (k, d) in sphere_directions(2000).enumerate() {
        // From points all over the room, some inside the tables.
        let o = centre
            + DVec3::new(
                (k % 7) as f64 - 3.0,
                (k % 5) as f64 * 0.3 - 0.6,
                (k % 3) as f64 - 1.0,
            ) * 0.5;
        // The probes work in the render frame.
        let ray = Ray {
            origin: two.frame.point(o),
            direction: d.as_vec3(),
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        for (any, opaque) in [(false, false), (false, true), (true, true)] {
            let (a, b) = (two.trace(&ray, any, opaque), flat.trace(&ray, any, opaque));
            if any {
                assert_eq!(a.is_some(), b.is_some(), "ray {k}");
            } else {
                assert_eq!(a, b, "ray {k} opaque {opaque}");
                hits += a.is_some() as usize;
            }
        }
    }
    assert!(hits > 3000, "{hits}");
    let lamp = point(DVec3::new(3.0, 2.2, 2.0), 5.0);
    for lights in [vec![], vec![lamp]] {
        let a = first_view_in_frame(&two, &lights, None, 1.6);
        let b = first_view_in_frame(&flat, &lights, None, 1.6);
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
    }
    assert!(first_view_with(&two, &[], None, 1.6).interior);
}

/// The probe's world triangles, read from each object's vertices, are those of
/// [`Scene::flatten`] one by one (vertices, material, order), mirrored and hidden objects
/// and a dropped triangle (an absurd vertex) included; reads by index and by range agree.
#[test]
fn world_triangles_are_the_flattened_ones() {
    let mut scene = instanced_room();
    let mut far = (*scene.objects[1].mesh).clone();
    far.positions[0] = Vec3::splat(1e38);
    scene.objects[1].mesh = Arc::new(far);
    scene.objects[1].world_from_object = DMat4::from_scale(DVec3::splat(1e10));
    let frame = crate::scene::RenderFrame::default();
    let flat = scene.flatten(&frame);
    assert!(flat.dropped > 0);
    let world = WorldTris::new(scene.world_objects(&frame));
    let (tris, materials) = world.to_vecs();
    assert_eq!(tris.len(), flat.triangles.len());
    for (i, t) in flat.triangles.iter().enumerate() {
        assert_eq!((tris[i], materials[i]), (t.v, t.material), "triangle {i}");
        assert_eq!((world.get(i), world.material(i)), (t.v, t.material));
    }
    let mut seen = vec![];
    world.visit(5..tris.len() - 3, |i, t, _| seen.push((i, t)));
    let expect: Vec<_> = (5..tris.len() - 3).map(|i| (i, tris[i])).collect();
    assert_eq!(seen, expect);
}

/// The first view leaves its quick BLASes in the scene, one per distinct visible mesh,
/// and the renderer's plan takes them for those meshes.
#[test]
fn the_first_view_leaves_its_quick_blases_for_the_renderer() {
    let scene = instanced_room();
    first_view(&scene, &[], None, 1.6);
    let kept = scene.take_quick_blases();
    assert_eq!(kept.len(), 4);
    for (mesh, blas) in &kept {
        let fresh = crate::bvh::quick_blas(&mesh.positions, &mesh.indices);
        assert!(blas.triangles().eq(fresh.triangles()));
        assert!(scene.objects.iter().any(|o| Arc::ptr_eq(&o.mesh, mesh)));
    }
    assert!(scene.take_quick_blases().is_empty());
}

#[test]
fn an_added_light_shows_in_view_near_the_camera() {
    let cam = Camera::look_at("c", DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO, 0.8);
    let l = light_near_camera(&cam, 10.0, "added");
    let p = l.position - cam.eye;
    let z = p.dot(cam.forward);
    assert!(z > 0.0 && z < 5.0, "{p}");
    // Inside the field of view.
    assert!(p.dot(cam.up).abs() / z < (0.4f64).tan(), "{p}");
    // Irradiance about 1 at the subject.
    let d2 = (l.position - DVec3::ZERO).length_squared();
    assert!((l.intensity as f64 / d2 - 1.0).abs() < 1e-3);
}

/// A box open towards +z (the inside of a 2-unit cube without its front, faces inward) with a
/// short and a tall block on its floor and a lamp under its ceiling: a Cornell box. A viewer
/// shows it from the open side, looking in, lit by its lamp.
fn cornell() -> (Scene, Light) {
    let mut walls = cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), true);
    walls.drain(2..4); // the +z quad (the second) is the opening
    let mut blocks = cuboid(
        Vec3::new(-0.6, -1.0, -0.1),
        Vec3::new(-0.1, -0.4, 0.4),
        false,
    );
    blocks.extend(cuboid(
        Vec3::new(0.1, -1.0, -0.7),
        Vec3::new(0.6, 0.2, -0.2),
        false,
    ));
    let scene = scene_of(&[(walls, Material::default()), (blocks, Material::default())]);
    (scene, point(DVec3::new(0.0, 0.9, 0.0), 4.0))
}

/// The same scene moved by 10⁵ and 10⁷ and scaled by 10⁻³ and 10³ (its lamp's intensity by
/// scale², so its light is the same) gets the same first view as at the origin: the camera in
/// the same place relative to the scene, the same interior and light decisions and the same
/// key irradiance (which sets the exposure). At 10⁵ the world-space probe judged the shared
/// Cornell box unlit (lit fraction 0.61 against 0.83).
#[test]
fn a_moved_or_scaled_scene_gets_the_same_first_view() {
    let (scene, lamp) = cornell();
    let at_origin = first_view(&scene, std::slice::from_ref(&lamp), None, 4.0 / 3.0);
    assert!(at_origin.lit && !at_origin.interior, "{at_origin:?}");
    assert!(at_origin.camera.eye.z > 1.0, "{at_origin:?}");
    let relative = |v: &FirstView, scale: f64, offset: DVec3| (v.camera.eye - offset) / scale;
    for (scale, offset) in [
        (1.0, DVec3::splat(1e5)),
        (1.0, DVec3::new(1e7, -1e7, 1e7)),
        (1e-3, DVec3::ZERO),
        (1e3, DVec3::ZERO),
        (1e3, DVec3::splat(1e7)),
    ] {
        let m = DMat4::from_translation(offset) * DMat4::from_scale(DVec3::splat(scale));
        let mut moved = scene.clone();
        for o in &mut moved.objects {
            o.world_from_object = m * o.world_from_object;
        }
        let lamp = Light {
            position: m.transform_point3(lamp.position),
            intensity: (lamp.intensity as f64 * scale * scale) as f32,
            ..lamp.clone()
        };
        let v = first_view(&moved, &[lamp], None, 4.0 / 3.0);
        let case = format!("scale {scale}, offset {offset}: {v:?}");
        assert_eq!(
            (v.lit, v.interior),
            (at_origin.lit, at_origin.interior),
            "{case}"
        );
        let eye = relative(&v, scale, offset);
        assert!(
            (eye - at_origin.camera.eye).length() < 1e-3,
            "{case}: eye {eye}"
        );
        assert!(
            v.camera.forward.dot(at_origin.camera.forward) > 1.0 - 1e-6,
            "{case}"
        );
        assert!(
            (v.lit_fraction - at_origin.lit_fraction).abs() < 0.02,
            "{case}"
        );
        assert!(
            (v.key_irradiance / at_origin.key_irradiance - 1.0).abs() < 0.02,
            "{case}"
        );
        assert!((v.coverage - at_origin.coverage).abs() < 0.02, "{case}");
    }
}

/// A hollow block (a cavity in its middle, like a shoe's) and two blocks with the middle of
/// their bounds in the gap between them are objects, framed from outside (the old test, from
/// the middle alone, took both for rooms); a room is still seen from inside.
#[test]
fn a_hollow_object_or_a_gap_is_not_an_interior() {
    let mut hollow = cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), false);
    hollow.extend(cuboid(Vec3::splat(-0.4), Vec3::splat(0.4), true));
    let mut pair = cuboid(
        Vec3::new(-2.0, -1.0, -1.0),
        Vec3::new(-0.05, 1.0, 1.0),
        false,
    );
    pair.extend(cuboid(
        Vec3::new(0.05, -1.0, -1.0),
        Vec3::new(2.0, 1.0, 1.0),
        false,
    ));
    for (name, tris) in [("hollow", hollow), ("pair", pair)] {
        let scene = scene_of(&[(tris, Material::default())]);
        let probe = Probe::new(&scene);
        // From the middle alone both look like rooms.
        assert_eq!(
            classify_shell(&probe, probe.bounds.center()),
            Shell::Interior,
            "{name}"
        );
        assert_eq!(classify_model(&probe), Shell::Object, "{name}");
        let view = first_view(&scene, &[], None, 1.5);
        let b = view.bounds;
        let e = view.camera.eye;
        let inside = (0..3).all(|i| e[i] > b.min[i] && e[i] < b.max[i]);
        assert!(!view.interior && !inside, "{name}: {view:?}");
    }
    let room = cuboid(Vec3::ZERO, Vec3::new(6.0, 2.7, 4.0), true);
    let probe = Probe::new(&scene_of(&[(room, Material::default())]));
    assert_eq!(classify_model(&probe), Shell::Interior);
}

/// A board (2 × 1.5, 0.04 thick) whose face looks along +x is seen facing it, straight on,
/// from +x (its face, not its back: the back is single-sided and faces away); a closed board
/// standing across z is seen from glTF's front, +z. A board lying on the ground is not seen
/// straight down (a plan) but from above and aside as before. (The lit-side search, from 14°
/// or 29° above, saw boards 22–45° off axis.)
#[test]
fn a_flat_subject_is_seen_facing_it() {
    let face = |lo: Vec3, hi: Vec3, drop: std::ops::Range<usize>| {
        let mut t = cuboid(lo, hi, false);
        t.drain(drop);
        t
    };
    // Standing, facing +x: the −x quad (the third) left out, so its back shows nothing.
    let standing = face(Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.04, 1.5, 1.0), 4..6);
    let view = first_view(
        &scene_of(&[(standing, Material::default())]),
        &[],
        None,
        1.5,
    );
    assert!(view.camera.forward.dot(DVec3::NEG_X) > 0.999, "{view:?}");
    let closed = cuboid(Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 1.5, 0.04), false);
    let view = first_view(&scene_of(&[(closed, Material::default())]), &[], None, 1.5);
    assert!(view.camera.forward.dot(DVec3::NEG_Z) > 0.999, "{view:?}");
    // Lying, facing up: the −y quad (the fifth) left out.
    let lying = face(
        Vec3::new(-1.0, 0.0, -0.75),
        Vec3::new(1.0, 0.04, 0.75),
        8..10,
    );
    let probe = Probe::new(&scene_of(&[(lying, Material::default())]));
    assert!(flat_facing(&probe, &[]).is_none());
    // A cube is not flat: seen from above and aside as before.
    let probe = Probe::new(&scene_of(&[(subject(), Material::default())]));
    assert!(flat_facing(&probe, &[]).is_none());
}

/// A board of labelled squares in front of a cyclorama, as TransmissionRoughnessTest is built:
/// a board 2 × 1.5 and 0.04 thick standing across z, six coloured squares (each its own
/// object) on its front, and behind and under it one object, a floor sweeping up into a back
/// wall, whose bounds hold the board. A viewer shows the board facing it, every square
/// in the frame. The backdrop is the one object whose bounds hold every other's: it does not
/// count against the flat-subject rule (counted, the scene's bounds, 6 × 3 × 5, are no board,
/// and the lit-side search sees the board from some 25° above and aside).
#[test]
fn a_board_before_a_backdrop_is_seen_facing_it() {
    let board = cuboid(
        Vec3::new(-1.0, 0.0, -0.02),
        Vec3::new(1.0, 1.5, 0.02),
        false,
    );
    let mut parts = vec![(board, Material::default())];
    for i in 0..6 {
        let lo = Vec3::new(
            -0.9 + 0.6 * (i % 3) as f32,
            0.15 + 0.7 * (i / 3) as f32,
            0.02,
        );
        let label = Material {
            base_color: [0.2 + 0.15 * i as f32, 0.8 - 0.1 * i as f32, 0.3, 1.0],
            ..Material::default()
        };
        parts.push((cuboid(lo, lo + Vec3::new(0.5, 0.5, 0.01), false), label));
    }
    // The cyclorama: a floor sweeping up into the back wall in eight steps of a quarter circle.
    let sweep = |k: usize| {
        let a = k as f32 / 8.0 * std::f32::consts::FRAC_PI_2;
        (-2.0 - a.sin(), 1.0 - a.cos())
    };
    let mut backdrop = Vec::new();
    let mut strip = |(z0, y0): (f32, f32), (z1, y1): (f32, f32)| {
        let [a, b, c, d] = [
            Vec3::new(-3.0, y0, z0),
            Vec3::new(3.0, y0, z0),
            Vec3::new(3.0, y1, z1),
            Vec3::new(-3.0, y1, z1),
        ];
        backdrop.extend([[a, b, c], [a, c, d]]);
    };
    strip((2.0, 0.0), (-2.0, 0.0));
    for k in 0..8 {
        strip(sweep(k), sweep(k + 1));
    }
    strip((-3.0, 1.0), (-3.0, 3.0));
    parts.push((backdrop, Material::default()));
    let scene = scene_of(&parts);

    // Counted, the backdrop makes the scene no board; left out, the board and its squares are.
    let probe = Probe::new(&scene);
    let e = probe.bounds.max - probe.bounds.min;
    assert!(e.min_element() > FLAT_RATIO * e.max_element(), "{e:?}");
    let rest = probe
        .frame
        .world_bounds(&without_backdrop(&probe).expect("the cyclorama is a backdrop"));
    assert!(
        (rest.min - DVec3::new(-1.0, 0.0, -0.02)).length() < 1e-4,
        "{rest:?}"
    );
    assert!(
        (rest.max - DVec3::new(1.0, 1.5, 0.03)).length() < 1e-4,
        "{rest:?}"
    );

    let aspect = 4.0 / 3.0;
    let view = first_view(&scene, &[], None, aspect);
    let c = &view.camera;
    // Facing the board: looking along −z within 2°.
    assert!(
        c.forward.dot(DVec3::NEG_Z) > 2f64.to_radians().cos(),
        "{view:?}"
    );
    // All of the board in the frame.
    let right = c.forward.cross(c.up).normalize();
    let up = right.cross(c.forward);
    let tan_y = (c.yfov * 0.5).tan();
    for i in 0..8 {
        let corner = DVec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { 0.0 } else { 1.5 },
            if i & 4 == 0 { -0.02 } else { 0.03 },
        );
        let q = corner - c.eye;
        let depth = q.dot(c.forward);
        assert!(
            depth > 0.0
                && q.dot(right).abs() <= tan_y * aspect * depth
                && q.dot(up).abs() <= tan_y * depth,
            "the board's corner {corner} is out of the frame: {c:?}"
        );
    }
}

/// A metal cube on a white floor under a lamp: the lamp lights the view, but most of what the
/// cube mirrors is the world, black without an environment, so the view asks for one (as a
/// fill: a viewer shows the cube mirroring the neutral room and the floor lit by the lamp). The same
/// cube and lamp inside a closed room mirror the lit walls: the room keeps its own light. A
/// white cube instead of the metal one asks for nothing.
#[test]
fn metal_its_lights_do_not_surround_asks_for_the_environment() {
    let metal = Material {
        metallic: 1.0,
        roughness: 0.1,
        ..Material::default()
    };
    let floor = cuboid(
        Vec3::new(-3.0, -0.6, -3.0),
        Vec3::new(3.0, -0.5, 3.0),
        false,
    );
    let lamp = point(DVec3::new(1.0, 3.0, 2.0), 20.0);
    let open = [
        (subject(), metal.clone()),
        (floor.clone(), Material::default()),
    ];
    let view = first_view(&scene_of(&open), std::slice::from_ref(&lamp), None, 1.5);
    assert!(view.lit && view.environment_reaches(), "{view:?}");
    assert!(
        view.shiny_share > 0.3 && view.shine_needs_environment(),
        "{view:?}"
    );
    assert!(view.key_irradiance > 0.0, "{view:?}");

    let white = [
        (subject(), Material::default()),
        (floor.clone(), Material::default()),
    ];
    let view = first_view(&scene_of(&white), std::slice::from_ref(&lamp), None, 1.5);
    assert!(view.lit && view.shiny_share == 0.0 && !view.shine_needs_environment());

    let room = cuboid(Vec3::splat(-4.0), Vec3::splat(4.0), true);
    let camera = Camera::look_at("inside", DVec3::new(0.0, 1.0, 3.5), DVec3::ZERO, 0.9);
    let closed = [
        (subject(), metal),
        (floor, Material::default()),
        (room, Material::default()),
    ];
    let view = first_view(&scene_of(&closed), &[lamp], Some(&camera), 1.5);
    assert!(view.lit && view.shiny_share >= MIN_SHINY_SHARE, "{view:?}");
    assert!(
        !view.environment_reaches() && !view.shine_needs_environment(),
        "{view:?}"
    );
}

/// The bundled Cornell box, and the shared one when PENUMBRA_SCENES is set, moved 10⁵ away
/// keep the first view they get at the origin: lit by their own lamp (the shared one was
/// judged unlit there, lit fraction 0.61 against 0.83, and got the studio environment), the
/// camera in the same place relative to the box.
#[test]
fn a_cornell_box_moved_far_away_is_still_lit_by_its_lamp() {
    let mut paths = vec![None];
    match std::env::var_os("PENUMBRA_SCENES") {
        Some(dir) => paths.push(Some(
            std::path::PathBuf::from(dir).join("CornellBox/CornellBox.glb"),
        )),
        None => eprintln!("PENUMBRA_SCENES is not set: the bundled Cornell box alone"),
    }
    for path in paths {
        let scene = crate::scene::load_or_bundled(path.as_deref()).unwrap();
        let offset = DVec3::splat(1e5);
        let moved = crate::bench::stress::moved(&scene, 1.0, offset);
        let a = first_view(&scene, &scene.lights, None, 4.0 / 3.0);
        let b = first_view(&moved, &moved.lights, None, 4.0 / 3.0);
        let case = format!("{path:?}: {a:?} against {b:?}");
        assert!(a.lit && b.lit, "{case}");
        assert!((a.lit_fraction - b.lit_fraction).abs() < 0.01, "{case}");
        let size = a.bounds.diagonal();
        assert!(
            (b.camera.eye - offset - a.camera.eye).length() < 1e-6 * size,
            "{case}"
        );
    }
}

/// `n` copies of one triangle in the z = 0 plane, as one mesh placed `copies` times.
fn coincident(n: usize, copies: usize) -> Scene {
    let mesh = Arc::new(Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        indices: vec![[0, 1, 2]; n],
        materials: vec![0; n],
        ..Default::default()
    });
    let mut scene = Scene::default();
    for i in 0..copies {
        scene.objects.push(Object {
            name: format!("copy {i}"),
            world_from_object: DMat4::IDENTITY,
            visible: true,
            mesh: mesh.clone(),
        });
    }
    scene.materials.push(Material::default());
    scene
}

/// Whether `camera` is finite and sees the point `p` near the middle of its frame.
fn looks_at(camera: &Camera, p: DVec3) -> bool {
    let finite = camera.eye.is_finite() && camera.forward.is_finite();
    let to = (p - camera.eye).normalize();
    finite && to.dot(camera.forward) > 0.95
}

#[test]
fn coincident_triangles_are_framed_by_their_own_extent() {
    // Every centroid in one place once gave a window of no width, bounds of a point and a
    // camera of NaN direction.
    let view = first_view(&coincident(1000, 1), &[], None, 1.5);
    let b = view.bounds;
    assert!(
        b.max.x - b.min.x > 0.99 && b.max.y - b.min.y > 0.99,
        "{b:?}"
    );
    assert!(
        looks_at(&view.camera, DVec3::new(0.5, 0.5, 0.0)),
        "{:?}",
        view.camera
    );
    assert_eq!(view.unprobed_cost, None);
    assert!(view.coverage > 0.0);
}

#[test]
fn triangles_too_entangled_for_the_probe_are_framed_without_it() {
    // 10⁵ copies of one triangle: each probe ray would test all of them (some 40,000 rays of
    // 10⁵ tests); the same through 64 coincident instances of 2,048.
    for (n, copies) in [(100_000, 1), (2048, 64)] {
        let scene = coincident(n, copies);
        let view = first_view(&scene, &[], None, 1.5);
        let cost = view.unprobed_cost.expect("the probe was skipped");
        let triangles = (n * copies) as f64;
        assert!(
            cost > 0.5 * triangles && cost < 2.0 * triangles,
            "{n}×{copies}: {cost}"
        );
        assert!(
            looks_at(&view.camera, DVec3::new(0.5, 0.5, 0.0)),
            "{:?}",
            view.camera
        );
        assert!(!view.lit && view.environment_reaches());
    }
    // Well below the bound, the probe runs.
    let view = first_view(&coincident(1000, 4), &[], None, 1.5);
    assert_eq!(view.unprobed_cost, None);
}
