//! Two-level traversal on the device: instances of one mesh placed with identity, scaled,
//! mirrored and rotated-and-mirrored transforms are as leak-free as the flat BVH, the device
//! finds the host reference's hits, and a scene of instances renders the same image with
//! `--bvh flat` and `--bvh two-level`.

mod common;

use common::{Gltf, Prim, render_exr, sphere};
use glam::{DMat4, DQuat, DVec3, Vec3};
use penumbra::bvh::{Ray, SMALL_MESH};
use penumbra::cl::types::{COUNT_OVERFLOW, COUNTER_SLOTS, DeviceHit, DeviceRay};
use penumbra::cl::{Buffer, DeviceChoice};
use penumbra::render::{BvhChoice, KernelChoice, NodeForms, Renderer};
use penumbra::scene::{Material, Mesh, Object, RenderFrame, Scene};
use serde_json::json;
use std::f32::consts::FRAC_1_SQRT_2;

/// A renderer that uploads both node arrays: these tests trace through either.
fn renderer() -> Renderer {
    let choice: DeviceChoice = common::test_device().parse().expect("a valid test device");
    let mut r = Renderer::new(&choice).expect("the test's OpenCL device is available");
    r.set_node_forms(penumbra::render::NodeForms::BOTH).unwrap();
    r
}

/// The leak tests' closed cube as a mesh.
fn closed_cube(n: usize) -> Mesh {
    Mesh::soup(&penumbra::bvh::closed_cube(n))
}

/// Identity, moved, non-uniformly scaled, mirrored, rotated-and-mirrored, and far away.
fn placements() -> Vec<DMat4> {
    vec![
        DMat4::IDENTITY,
        DMat4::from_translation(DVec3::new(5.0, -2.0, 3.0)),
        DMat4::from_scale_rotation_translation(
            DVec3::new(0.3, 2.0, 5.0),
            DQuat::IDENTITY,
            DVec3::new(-6.0, 1.0, 0.5),
        ),
        DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)) * DMat4::from_translation(DVec3::X * 3.0),
        DMat4::from_scale_rotation_translation(
            DVec3::new(-0.5, 1.5, 0.75),
            DQuat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.7),
            DVec3::new(0.0, 7.0, -4.0),
        ),
        DMat4::from_scale_rotation_translation(
            DVec3::new(1e-3, 1e-3, 2e-3),
            DQuat::from_euler(glam::EulerRot::XYZ, -0.9, 0.2, 0.4),
            DVec3::new(3e3, -1e3, 2e3),
        ),
    ]
}

fn cube_scene(n: usize) -> Scene {
    // One mesh shared by every node, as the importer shares a glTF mesh.
    let mesh = std::sync::Arc::new(closed_cube(n));
    Scene {
        source: "cubes".into(),
        objects: placements()
            .into_iter()
            .enumerate()
            .map(|(i, m)| Object {
                name: format!("cube {i}"),
                world_from_object: m,
                visible: true,
                mesh: mesh.clone(),
            })
            .collect(),
        materials: vec![Material::default()],
        ..Scene::default()
    }
}

/// Traces `rays` with the four tracing kernels: (closest binary, any binary, closest wide,
/// any wide), and the overflow count.
fn trace_all(r: &Renderer, rays: &[DeviceRay]) -> ([Vec<DeviceHit>; 2], [Vec<u32>; 2], u32) {
    let ray_buf = Buffer::from_slice(&r.device, rays).unwrap();
    let mut counters = Buffer::<u32>::new(&r.device, COUNTER_SLOTS).unwrap();
    counters.clear(&r.device).unwrap();
    let program = r.program().unwrap();
    let scene = r.scene_buffers().unwrap();
    let hits = [(); 2].map(|_| Buffer::<DeviceHit>::new(&r.device, rays.len()).unwrap());
    let occluded = [(); 2].map(|_| Buffer::<u32>::new(&r.device, rays.len()).unwrap());
    program
        .trace_closest(&r.device, scene, &ray_buf, &hits[0], &counters)
        .unwrap();
    program
        .trace_any(&r.device, scene, &ray_buf, &occluded[0], &counters)
        .unwrap();
    program
        .trace_closest_wide(&r.device, scene, &ray_buf, &hits[1], &counters)
        .unwrap();
    program
        .trace_any_wide(&r.device, scene, &ray_buf, &occluded[1], &counters)
        .unwrap();
    let overflow = counters.read(&r.device).unwrap()[COUNT_OVERFLOW];
    (
        hits.map(|h| h.read(&r.device).unwrap()),
        occluded.map(|o| o.read(&r.device).unwrap()),
        overflow,
    )
}

/// Rays from each instance's centre towards every vertex and edge midpoint of its cube (in
/// world space), the hardest directions for a watertight test: each must hit its own cube,
/// through all four tracing kernels, and the binary ones must find the host reference's hits.
fn assert_no_leaks(r: &Renderer, placements: &[DMat4], n: usize) {
    let host = r.host_scene().unwrap();
    let cube = closed_cube(n);
    let mut rays = vec![];
    let mut owner = vec![];
    for (i, m) in placements.iter().enumerate() {
        let centre = m.transform_point3(DVec3::ZERO);
        for t in &cube.indices {
            for k in 0..3 {
                let a = cube.positions[t[k] as usize].as_dvec3();
                let b = cube.positions[t[(k + 1) % 3] as usize].as_dvec3();
                for target in [a, (a + b) * 0.5] {
                    let d = (m.transform_point3(target) - centre).as_vec3();
                    let o = centre.as_vec3();
                    rays.push(DeviceRay {
                        origin: [o.x, o.y, o.z, 0.0],
                        direction: [d.x, d.y, d.z, f32::INFINITY],
                    });
                    owner.push(i as u32);
                }
            }
        }
    }
    let ([hits, wide_hits], [occluded, wide_occluded], overflow) = trace_all(r, &rays);
    assert_eq!(overflow, 0, "no stack overflow");
    let mut leaks = 0;
    for (i, ray) in rays.iter().enumerate() {
        for (h, occ) in [(hits[i], occluded[i]), (wide_hits[i], wide_occluded[i])] {
            let inside = h.prim != u32::MAX && host.object_of(&h) == owner[i];
            if !inside || occ != 1 {
                leaks += 1;
            }
        }
        let host_ray = Ray {
            origin: Vec3::from_slice(&ray.origin[..3]),
            direction: Vec3::from_slice(&ray.direction[..3]),
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        let expect = host.intersect(&host_ray).expect("the host finds the cube");
        assert_eq!(
            (hits[i].prim, hits[i].instance, hits[i].t),
            (expect.prim, expect.instance, expect.t),
            "ray {i}"
        );
        assert_eq!(wide_hits[i].t, expect.t, "ray {i} (wide)");
    }
    assert!(rays.len() > 1000);
    assert_eq!(leaks, 0, "rays leaked out of {} (twice each)", rays.len());
}

#[test]
fn no_ray_leaks_out_of_scaled_or_mirrored_instances_on_the_device() {
    // A cube of 432 triangles is entered in object space; one of 48 is small, its triangles
    // tested in world space as pieces of the top level (`TwoLevel::braid`).
    for n in [6, 2] {
        let mut r = renderer();
        r.set_bvh_choice(BvhChoice::TwoLevel);
        r.set_small_mesh(Some(SMALL_MESH));
        let scene = cube_scene(n);
        // World coordinates: the rays are made in world space.
        let stats = r
            .load_scene_in(&scene, &[], RenderFrame::default())
            .unwrap();
        assert_eq!(stats.bvh, "two-level");
        assert_eq!((stats.meshes, stats.instances), (1, placements().len()));
        assert_no_leaks(&r, &placements(), n);
    }
}

#[test]
fn moving_instances_updates_the_device_in_place() {
    let mut r = renderer();
    r.set_bvh_choice(BvhChoice::TwoLevel);
    r.set_small_mesh(Some(SMALL_MESH));
    let mut scene = cube_scene(6);
    let stats = r
        .load_scene_in(&scene, &[], RenderFrame::default())
        .unwrap();
    // Move every other cube, one of them also rescaled and mirrored the other way.
    let mut moved = placements();
    for (i, m) in moved.iter_mut().enumerate().filter(|(i, _)| i % 2 == 1) {
        *m = DMat4::from_translation(DVec3::new(0.5, -20.0 * i as f64, 2.0)) * *m;
        if i == 3 {
            *m *= DMat4::from_scale(DVec3::new(-2.0, 0.5, 1.0));
        }
        scene.objects[i].world_from_object = *m;
    }
    let update = r
        .move_instances(&scene)
        .unwrap()
        .expect("moving instances of a two-level scene needs no reload");
    assert_eq!(update.moved, 3);
    let buffers = r.scene_buffers().unwrap();
    assert_eq!(buffers.bytes(), stats.device_bytes, "no buffer grew");
    // Written: the TLAS's slots (binary and wide nodes, 64 and 128 bytes) and the instances
    // (112 bytes each), nothing else: the cube's triangles stay in object space.
    let n = placements().len();
    let tlas = (n - 1) * (64 + 128) + n * 112;
    assert_eq!(update.bytes, tlas, "{update:?}");
    assert_no_leaks(&r, &moved, 6);
    // Hiding a cube is an update too: it leaves the TLAS (no buffer grows), and a ray from its
    // centre finds nothing, on the device and on the host; shown again, it is whole.
    scene.objects[0].visible = false;
    let hidden = r
        .move_instances(&scene)
        .unwrap()
        .expect("hiding an instance needs no reload");
    assert_eq!(hidden.moved, 1);
    assert_eq!(r.scene_buffers().unwrap().bytes(), stats.device_bytes);
    let ray = DeviceRay {
        origin: [0.0; 4],
        direction: [1.0, 0.0, 0.0, f32::INFINITY],
    };
    let ([hits, wide_hits], [occluded, _], _) = trace_all(&r, &[ray]);
    assert_eq!(
        (hits[0].prim, wide_hits[0].prim, occluded[0]),
        (u32::MAX, u32::MAX, 0)
    );
    let host_ray = Ray {
        origin: Vec3::ZERO,
        direction: Vec3::X,
        tmin: 0.0,
        tmax: f32::INFINITY,
    };
    assert_eq!(r.host_scene().unwrap().intersect(&host_ray), None);
    scene.objects[0].visible = true;
    r.move_instances(&scene)
        .unwrap()
        .expect("showing an instance needs no reload");
    assert_no_leaks(&r, &moved, 6);
    // Other geometry is a reload.
    std::sync::Arc::make_mut(&mut scene.objects[1].mesh)
        .indices
        .pop();
    assert_eq!(r.move_instances(&scene).unwrap(), None);
}

#[test]
fn moving_a_small_instance_moves_its_world_space_pieces() {
    // Cubes of 48 triangles are small: each triangle is a piece of the top level, tested in
    // world space from a copy that a move rewrites.
    let mut r = renderer();
    r.set_bvh_choice(BvhChoice::TwoLevel);
    r.set_small_mesh(Some(SMALL_MESH));
    let mut scene = cube_scene(2);
    r.load_scene_in(&scene, &[], RenderFrame::default())
        .unwrap();
    let mut moved = placements();
    moved[1] = DMat4::from_translation(DVec3::new(0.0, 30.0, 0.0))
        * moved[1]
        * DMat4::from_scale(DVec3::new(1.0, -2.0, 1.0));
    scene.objects[1].world_from_object = moved[1];
    let update = r
        .move_instances(&scene)
        .unwrap()
        .expect("moving a small instance needs no reload");
    assert_eq!(update.moved, 1);
    // The TLAS's slots for one piece per triangle, and the moved cube's 48 copies (48 bytes).
    let pieces = placements().len() * 48;
    let bytes = (pieces - 1) * (64 + 128) + pieces * 112 + 48 * 48;
    assert_eq!(update.bytes, bytes, "{update:?}");
    assert_no_leaks(&r, &moved, 2);
}

#[test]
fn two_levels_find_the_flat_bvhs_hits() {
    // The same scene both ways: every hit at the same distance on the same object (the
    // shading order differs, so triangles are compared by object and distance); cubes of 192
    // triangles, and small ones of 48 (world-space pieces of the top level).
    for n in [4, 2] {
        same_hits_both_ways(n);
    }
}

fn same_hits_both_ways(n: usize) {
    let scene = cube_scene(n);
    let mut rays = vec![];
    let mut s = 3u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    for _ in 0..20000 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 24.0 - 12.0;
        let d = (Vec3::new(rnd(), rnd(), rnd()) - 0.5).normalize();
        rays.push(DeviceRay {
            origin: [o.x, o.y, o.z, 0.0],
            direction: [d.x, d.y, d.z, f32::INFINITY],
        });
    }
    let mut results = vec![];
    for choice in [BvhChoice::Flat, BvhChoice::TwoLevel] {
        let mut r = renderer();
        r.set_bvh_choice(choice);
        r.set_small_mesh(Some(SMALL_MESH));
        r.load_scene_in(&scene, &[], RenderFrame::default())
            .unwrap();
        let ([hits, _], [occluded, _], _) = trace_all(&r, &rays);
        let host = r.host_scene().unwrap();
        let objects: Vec<Option<u32>> = hits
            .iter()
            .map(|h| (h.prim != u32::MAX).then(|| host.object_of(h)))
            .collect();
        results.push((hits, objects, occluded));
    }
    let (flat, two) = (&results[0], &results[1]);
    let mut hit = 0;
    for i in 0..rays.len() {
        assert_eq!(flat.1[i], two.1[i], "ray {i}: object");
        assert_eq!(flat.2[i], two.2[i], "ray {i}: occlusion");
        if flat.1[i].is_some() {
            hit += 1;
            let (a, b) = (flat.0[i].t, two.0[i].t);
            assert!(
                (a - b).abs() <= 1e-5 * a.abs().max(1.0),
                "ray {i}: {a} vs {b}"
            );
        }
    }
    assert!(hit > 500, "the rays hit the cubes ({hit})");
}

#[test]
fn instances_render_the_same_image_both_ways() {
    // A sphere mesh placed five times (scaled, squashed, mirrored) and a floor, lit by an
    // emissive quad: the flat BVH and two levels must render the same image.
    let dir = common::output_dir("instances_render_the_same_image_both_ways");
    let mut g = Gltf::default();
    let grey = g.lambert([0.7, 0.7, 0.7], [0.0; 3], 0.0, false);
    let lamp = g.lambert([0.0; 3], [1.0; 3], 20.0, true);
    let (pos, nrm, idx) = sphere(1.0, 16, 24, false);
    let ball = g.mesh(vec![Prim {
        positions: pos,
        normals: nrm,
        indices: idx,
        material: Some(grey),
        mode: 4,
    }]);
    let mut floor = common::quad();
    floor.material = Some(grey);
    let floor = g.mesh(vec![floor]);
    let mut light = common::quad();
    light.material = Some(lamp);
    let light = g.mesh(vec![light]);
    g.node(
        json!({"mesh": floor, "scale": [20.0, 20.0, 1.0], "translation": [-10.0, 0.0, 10.0],
                  "rotation": common::LOOK_DOWN}),
    );
    g.node(
        json!({"mesh": light, "scale": [3.0, 3.0, 1.0], "translation": [-1.5, 8.0, -1.5],
                  "rotation": [FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2]}),
    );
    for (i, (s, x)) in [
        ([1.0, 1.0, 1.0], -4.0),
        ([0.5, 2.0, 0.5], -1.5),
        ([-1.0, 1.0, 1.0], 1.0),
        ([1.5, 0.5, -1.0], 4.0),
        ([0.7, 0.7, 0.7], 6.5),
    ]
    .into_iter()
    .enumerate()
    {
        g.node(json!({"mesh": ball, "scale": s, "translation": [x, 1.2, i as f32 * 0.3]}));
    }
    let scene = g.write_glb(&dir, "balls.glb");
    let args = |bvh: &'static str| {
        vec![
            "--width",
            "64",
            "--height",
            "48",
            "--spp",
            "16",
            "--bounces",
            "3",
            "--bvh",
            bvh,
        ]
    };
    let (flat_summary, flat) = render_exr(&scene, &dir.join("flat.exr"), &args("flat"));
    let (two_summary, two) = render_exr(&scene, &dir.join("two.exr"), &args("two-level"));
    assert_eq!(flat_summary["bvh"], "flat");
    assert_eq!(two_summary["bvh"], "two-level");
    assert_eq!(two_summary["instances"], 7);
    assert_eq!(two_summary["meshes"], 3);
    assert_eq!(flat_summary["triangles"], two_summary["triangles"]);
    assert!(two_summary["device_bytes"].as_u64().unwrap() > 0);
    // The hit points differ by rounding only (barycentrics found in object space), so paths
    // may part after many bounces in a rare pixel; the images agree to within noise.
    let diff: f64 = flat
        .iter()
        .zip(&two)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs() as f64).sum::<f64>() / 3.0)
        .sum::<f64>()
        / flat.len() as f64;
    let mean = common::mean_gray(&flat);
    assert!(mean > 0.01, "the scene is lit ({mean})");
    assert!(
        diff <= 0.01 * mean,
        "mean absolute difference {diff} against a mean of {mean}"
    );
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()).max(1e-3);
    let same = flat
        .iter()
        .zip(&two)
        .filter(|(a, b)| (0..3).all(|c| close(a[c], b[c])))
        .count();
    assert!(
        same * 10 >= flat.len() * 9,
        "{same} of {} pixels agree to 1e-3",
        flat.len()
    );
}

/// The cubes of `cube_scene(4)` under a lamp, and a camera that sees them.
fn lit_cubes() -> (Scene, penumbra::scene::Light, penumbra::scene::Camera) {
    let light = penumbra::scene::Light {
        name: "lamp".into(),
        kind: penumbra::scene::LightKind::Point,
        position: DVec3::new(0.5, 9.0, 2.0),
        direction: DVec3::NEG_Y,
        color: [1.0; 3],
        intensity: 400.0,
        light_radius: 0.0,
    };
    let camera = penumbra::scene::Camera::look_at(
        "test",
        DVec3::new(2.0, 3.0, 22.0),
        DVec3::new(0.0, 1.0, 0.0),
        0.9,
    );
    (cube_scene(4), light, camera)
}

#[test]
fn a_quick_first_image_gives_way_to_the_image_of_the_sah_trees() {
    // The viewer opens a large scene with quick BLASes and swaps the SAH ones in when they are
    // built: from the swap on, the image is the one of a scene loaded with SAH BLASes alone.
    let (scene, light, camera) = lit_cubes();
    let settings = penumbra::render::RenderSettings {
        width: 48,
        height: 32,
        bounces: 3,
        ..Default::default()
    };
    let open = |quick: bool| {
        let mut r = renderer();
        r.set_bvh_choice(BvhChoice::TwoLevel);
        r.set_quick_first(quick.then_some(0));
        r.set_settings(&settings).unwrap();
        r.load_scene_in(&scene, std::slice::from_ref(&light), RenderFrame::default())
            .unwrap();
        r.set_camera(&camera).unwrap();
        r
    };
    // Each BLAS's SAH cost: which trees the device has.
    let blas_costs = |r: &Renderer| match r.accel() {
        Some(penumbra::render::Accel::TwoLevel(t)) => {
            t.blases.iter().map(|b| b.bvh.sah_cost).collect::<Vec<_>>()
        }
        _ => panic!("two levels"),
    };
    let mut plain = open(false);
    assert!(!plain.sah_pending());
    let sah_costs = blas_costs(&plain);
    plain.render(4).unwrap();
    let want = plain.image().unwrap();
    let mut r = open(true);
    assert!(
        r.sah_pending(),
        "the SAH BLASes build behind the quick ones"
    );
    assert_ne!(blas_costs(&r), sah_costs, "quick BLASes first");
    // Frames on the quick trees: the same surfaces, lit the same.
    r.render(4).unwrap();
    let first = r.image().unwrap();
    let mean = common::mean_gray(&want);
    assert!(mean > 0.01, "the cubes are lit ({mean})");
    assert!((common::mean_gray(&first) - mean).abs() <= 0.05 * mean);
    let t = std::time::Instant::now();
    let stats = loop {
        if let Some(s) = r.swap_in_sah(&scene, std::slice::from_ref(&light)).unwrap() {
            break s;
        }
        assert!(t.elapsed().as_secs() < 60, "the SAH BLASes are built");
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    assert!(!r.sah_pending());
    assert_eq!(stats.bvh, "two-level");
    assert_eq!(blas_costs(&r), sah_costs, "the SAH BLASes swapped in");
    // The swap restarted the film: the same samples as the plain load, bit for bit.
    assert_eq!(r.samples(), 0);
    r.render(4).unwrap();
    let got = r.image().unwrap();
    assert!(
        got == want,
        "the image after the swap is the SAH trees' image"
    );
}

#[test]
fn a_device_gets_the_node_array_its_kernels_traverse() {
    // The megakernel (a CPU device's) walks the wide nodes alone, the wavefront (a GPU's) the
    // binary ones: the other array is not uploaded, and the image is the one of a device
    // that has both. Switching kernels uploads the missing array.
    let (scene, light, camera) = lit_cubes();
    let settings = penumbra::render::RenderSettings {
        width: 32,
        height: 24,
        bounces: 2,
        ..Default::default()
    };
    for bvh in [BvhChoice::Flat, BvhChoice::TwoLevel] {
        let open = |forms: Option<NodeForms>| {
            let choice: DeviceChoice = common::test_device().parse().unwrap();
            let mut r = Renderer::new(&choice).unwrap();
            r.set_kernel(KernelChoice::Megakernel).unwrap();
            if let Some(forms) = forms {
                r.set_node_forms(forms).unwrap();
            }
            r.set_bvh_choice(bvh);
            r.set_settings(&settings).unwrap();
            r.load_scene_in(&scene, std::slice::from_ref(&light), RenderFrame::default())
                .unwrap();
            r.set_camera(&camera).unwrap();
            r
        };
        let mut lean = open(None);
        let mut full = open(Some(NodeForms::BOTH));
        let (l, f) = (lean.scene_buffers().unwrap(), full.scene_buffers().unwrap());
        assert_eq!(l.forms, NodeForms::for_kernels(true), "{bvh:?}");
        assert_eq!(f.forms, NodeForms::BOTH);
        assert_eq!(
            l.nodes.len(),
            1,
            "{bvh:?}: a placeholder for the binary nodes"
        );
        assert_eq!(l.wide_nodes.len(), f.wide_nodes.len());
        assert!(f.nodes.len() > 1);
        assert_eq!(l.bytes() + f.nodes.bytes() - l.nodes.bytes(), f.bytes());
        // Nothing traces through the missing array.
        let ray = DeviceRay {
            origin: [0.0, 0.0, 30.0, 0.0],
            direction: [0.0, 0.0, -1.0, f32::INFINITY],
        };
        let rays = Buffer::from_slice(&lean.device, &[ray]).unwrap();
        let hits = Buffer::<DeviceHit>::new(&lean.device, 1).unwrap();
        let counters = Buffer::<u32>::new(&lean.device, COUNTER_SLOTS).unwrap();
        let program = lean.program().unwrap();
        assert!(
            program
                .trace_closest(&lean.device, l, &rays, &hits, &counters)
                .is_err()
        );
        program
            .trace_closest_wide(&lean.device, l, &rays, &hits, &counters)
            .unwrap();
        if bvh == BvhChoice::TwoLevel {
            // A moved instance's TLAS goes to the wide nodes alone.
            let mut moved = scene.clone();
            moved.objects[1].world_from_object = DMat4::from_translation(DVec3::new(0.5, 2.0, 1.0))
                * moved.objects[1].world_from_object;
            let update = lean.move_instances(&moved).unwrap().unwrap();
            full.move_instances(&moved).unwrap().unwrap();
            let n = placements().len();
            assert_eq!(update.bytes, (n - 1) * 128 + n * 112, "{update:?}");
        }
        for kernel in [KernelChoice::Megakernel, KernelChoice::Wavefront] {
            lean.set_kernel(kernel).unwrap();
            full.set_kernel(kernel).unwrap();
            lean.render(2).unwrap();
            full.render(2).unwrap();
            assert!(
                lean.image().unwrap() == full.image().unwrap(),
                "{bvh:?} {kernel:?}: the same image"
            );
        }
        // The wavefront's binary nodes came with the switch.
        let l = lean.scene_buffers().unwrap();
        assert_eq!(l.forms, NodeForms::BOTH);
        assert_eq!(l.bytes(), full.scene_buffers().unwrap().bytes());
    }
}
