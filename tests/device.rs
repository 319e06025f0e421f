//! Device tests on the default OpenCL device (PoCL in CI): struct layouts, traversal agreement
//! with the host, a furnace scene with a known answer, the one-sided emission rule, determinism.

mod common;

use common::{Gltf, Prim, render_exr, sphere};
use glam::{DMat4, Vec3};
use penumbra::bvh::Ray;
use penumbra::cl::types::{COUNT_OVERFLOW, COUNTER_SLOTS, DeviceHit, DeviceRay, layouts};
use penumbra::cl::{Buffer, DeviceChoice};
use penumbra::render::Renderer;
use penumbra::scene::{Material, Mesh, Object, RenderFrame, Scene};
use serde_json::json;

/// A renderer that uploads both node arrays: these tests trace through either.
fn renderer() -> Renderer {
    let choice: DeviceChoice = common::test_device().parse().expect("a valid test device");
    let mut r = Renderer::new(&choice).expect("the test's OpenCL device is available");
    r.set_node_forms(penumbra::render::NodeForms::BOTH).unwrap();
    r
}

/// A scene of random small triangles in a 10-unit cube, plus a large floor.
fn random_scene(n: usize) -> Scene {
    let mut s = 5u64;
    let mut r = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut mesh = Mesh::default();
    for i in 0..n {
        let c = Vec3::new(r(), r(), r()) * 10.0;
        for _ in 0..3 {
            mesh.positions
                .push(c + (Vec3::new(r(), r(), r()) - 0.5) * 0.7);
        }
        let b = 3 * i as u32;
        mesh.indices.push([b, b + 1, b + 2]);
        mesh.materials.push(0);
    }
    let b = mesh.positions.len() as u32;
    mesh.positions.extend([
        Vec3::new(-5.0, 0.0, -5.0),
        Vec3::new(15.0, 0.0, -5.0),
        Vec3::new(15.0, 0.0, 15.0),
        Vec3::new(-5.0, 0.0, 15.0),
    ]);
    mesh.indices.extend([[b, b + 2, b + 1], [b, b + 3, b + 2]]);
    mesh.materials.extend([0, 0]);
    Scene {
        source: "random".into(),
        objects: vec![Object {
            name: "random".into(),
            world_from_object: DMat4::IDENTITY,
            visible: true,
            mesh: mesh.into(),
        }],
        materials: vec![Material::default()],
        ..Scene::default()
    }
}

#[test]
fn layout_probe_agrees_with_every_shared_rust_struct() {
    let mut r = renderer();
    r.load_scene(&random_scene(4), &[]).unwrap();
    let probed = r.program().unwrap().probe_layout(&r.device).unwrap();
    let mut at = 0;
    for (name, size, fields) in layouts() {
        assert_eq!(probed[at] as usize, size, "sizeof({name}) on the device");
        at += 1;
        for (field, offset) in fields {
            assert_eq!(
                probed[at] as usize, offset,
                "offsetof({name}, {field}) on the device"
            );
            at += 1;
        }
    }
    assert_eq!(
        probed[at],
        u32::MAX,
        "the probe wrote exactly the fields listed"
    );
}

#[test]
fn kernel_traversal_equals_host_traversal() {
    check_kernel_traversal(3000);
}

#[test]
fn kernel_traversal_equals_host_traversal_with_merged_leaves() {
    // Large enough for the CPU's wide BVH to merge small subtrees into leaves of up to four
    // triangles, which the wide kernels test in float4 lanes.
    let n = penumbra::bvh::MERGE_MIN_TRIANGLES + 1000;
    check_kernel_traversal(n);
}

/// Binary and 4-wide BVH kernels alike find the host traversal's hits in a scene of `n`
/// random triangles.
fn check_kernel_traversal(n: usize) {
    let mut r = renderer();
    // In world coordinates (no render frame): the rays below are made in world space.
    r.load_scene_in(&random_scene(n), &[], RenderFrame::default())
        .unwrap();
    let host = r.host_scene().unwrap();
    let mut s = 17u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut rays = vec![];
    for _ in 0..20000 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 14.0 - 2.0;
        let d = (Vec3::new(rnd(), rnd(), rnd()) - 0.5).normalize();
        rays.push((o, d, 0.0, f32::INFINITY));
    }
    for i in 0..3000 {
        // Axis-parallel rays, both directions.
        let o = Vec3::new(rnd(), rnd(), rnd()) * 10.0;
        let mut d = Vec3::ZERO;
        d[i % 3] = if i % 2 == 0 { 1.0 } else { -1.0 };
        rays.push((o - d * 20.0, d, 0.0, f32::INFINITY));
    }
    for t in host.vertices.iter().take(3000) {
        // Grazing rays in the plane of a triangle, and rays along the floor plane.
        let d = (t[1] - t[0]).normalize();
        rays.push(((t[0] + t[1]) * 0.5 - d * 5.0, d, 0.0, f32::INFINITY));
    }
    for i in 0..1000 {
        let x = i as f32 * 0.01;
        rays.push((Vec3::new(x, 0.0, -6.0), Vec3::Z, 0.0, f32::INFINITY));
        // Short rays that end before the first hit.
        rays.push((Vec3::new(x, 5.0, 5.0), Vec3::NEG_Y, 0.0, 0.5 + x * 0.1));
    }
    let gpu_rays: Vec<DeviceRay> = rays
        .iter()
        .map(|(o, d, tmin, tmax)| DeviceRay {
            origin: [o.x, o.y, o.z, *tmin],
            direction: [d.x, d.y, d.z, *tmax],
        })
        .collect();
    let ray_buf = Buffer::from_slice(&r.device, &gpu_rays).unwrap();
    let hits = Buffer::<DeviceHit>::new(&r.device, rays.len()).unwrap();
    let occluded = Buffer::<u32>::new(&r.device, rays.len()).unwrap();
    let mut counters = Buffer::<u32>::new(&r.device, COUNTER_SLOTS).unwrap();
    counters.clear(&r.device).unwrap();
    let program = r.program().unwrap();
    let scene = r.scene_buffers().unwrap();
    program
        .trace_closest(&r.device, scene, &ray_buf, &hits, &counters)
        .unwrap();
    program
        .trace_any(&r.device, scene, &ray_buf, &occluded, &counters)
        .unwrap();
    // The 4-wide BVH (the megakernel's) must find the same hits.
    let wide_hits = Buffer::<DeviceHit>::new(&r.device, rays.len()).unwrap();
    let wide_occluded = Buffer::<u32>::new(&r.device, rays.len()).unwrap();
    program
        .trace_closest_wide(&r.device, scene, &ray_buf, &wide_hits, &counters)
        .unwrap();
    program
        .trace_any_wide(&r.device, scene, &ray_buf, &wide_occluded, &counters)
        .unwrap();
    let hits = hits.read(&r.device).unwrap();
    let occluded = occluded.read(&r.device).unwrap();
    let wide_hits = wide_hits.read(&r.device).unwrap();
    let wide_occluded = wide_occluded.read(&r.device).unwrap();
    assert_eq!(
        counters.read(&r.device).unwrap()[COUNT_OVERFLOW],
        0,
        "no stack overflow"
    );
    let mut hit_count = 0;
    for (i, (o, d, tmin, tmax)) in rays.iter().enumerate() {
        let ray = Ray {
            origin: *o,
            direction: *d,
            tmin: *tmin,
            tmax: *tmax,
        };
        let expect = host.intersect(&ray);
        hit_count += expect.is_some() as usize;
        for (got, occluded) in [(hits[i], occluded[i]), (wide_hits[i], wide_occluded[i])] {
            match expect {
                Some(h) => {
                    assert_eq!(got.prim, h.prim, "ray {i}: device hit {got:?}, host {h:?}");
                    assert_eq!(got.t, h.t, "ray {i}");
                    assert!(
                        (got.u - h.u).abs() < 1e-6 && (got.v - h.v).abs() < 1e-6,
                        "ray {i}"
                    );
                }
                None => assert_eq!(got.prim, u32::MAX, "ray {i}: device hit, host missed"),
            }
            assert_eq!(
                occluded == 1,
                expect.is_some(),
                "ray {i}: any-hit disagrees"
            );
        }
    }
    assert!(
        hit_count > rays.len() / 10,
        "the test rays hit something ({hit_count})"
    );
}

/// Builds a closed sphere with a Lambertian, emissive material. Inward-facing single-sided
/// emitters light the inside; a camera at the center sees Le / (1 - albedo) once paths are long.
fn furnace(dir: &std::path::Path, albedo: f32, le: f32, inward: bool) -> std::path::PathBuf {
    let name = if inward { "furnace" } else { "furnace-outward" };
    furnace_scene(dir, name, albedo, le, inward, [0.0; 3], 1.0)
}

/// The furnace sphere with its camera inside, both moved to `translation` and scaled by `scale`.
fn furnace_scene(
    dir: &std::path::Path,
    name: &str,
    albedo: f32,
    le: f32,
    inward: bool,
    translation: [f64; 3],
    scale: f64,
) -> std::path::PathBuf {
    let mut g = Gltf::default();
    let m = g.lambert([albedo; 3], [1.0; 3], le, false);
    let (positions, normals, indices) = sphere(1.0, 24, 48, inward);
    let mesh = g.mesh(vec![Prim {
        positions,
        normals,
        indices,
        material: Some(m),
        mode: 4,
    }]);
    let sphere_node = g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.0001}}));
    let camera_node = g.node(json!({"camera": 0, "translation": [0.0, 0.0, 0.3]}));
    g.node(json!({
        "children": [sphere_node, camera_node],
        "translation": translation,
        "scale": [scale, scale, scale]
    }));
    g.write_glb(dir, name)
}

#[test]
fn the_furnace_holds_far_from_the_origin_and_at_small_scale() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.exr");
    let args = [
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "64",
        "--bounces",
        "40",
    ];
    for (name, translation, scale) in [
        ("far", [1.0e4, -2.0e4, 1.5e4], 1.0),
        ("tiny", [0.0, 0.0, 0.0], 1.0e-3),
        ("huge", [3.0e3, 0.0, 0.0], 1.0e3),
    ] {
        let scene = furnace_scene(dir.path(), name, 0.5, 1.0, true, translation, scale);
        let (summary, px) = render_exr(&scene, &out, &args);
        let m = common::mean_gray(&px);
        assert!(
            (m - 2.0).abs() < 0.04,
            "{name}: furnace mean {m}, expected 2.0"
        );
        assert_eq!(summary["nonfinite_samples"], 0, "{name}");
    }
}

#[test]
fn furnace_sphere_converges_to_le_over_one_minus_albedo() {
    let dir = tempfile::tempdir().unwrap();
    let scene = furnace(dir.path(), 0.5, 1.0, true);
    let out = dir.path().join("f.exr");
    // 0.5^42 is far below the noise, so 40 bounces reach the closed-form answer.
    let (summary, px) = render_exr(
        &scene,
        &out,
        &[
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "64",
            "--bounces",
            "40",
        ],
    );
    let m = common::mean_gray(&px);
    assert!((m - 2.0).abs() < 0.03, "furnace mean {m}, expected 2.0");
    assert_eq!(summary["nonfinite_samples"], 0);
    // Direct light only: emission seen plus one reflection of it, Le (1 + albedo).
    let (_, px) = render_exr(
        &scene,
        &out,
        &[
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "64",
            "--bounces",
            "0",
        ],
    );
    let m = common::mean_gray(&px);
    assert!((m - 1.5).abs() < 0.02, "direct-only mean {m}, expected 1.5");
}

#[test]
fn single_sided_emitters_do_not_emit_from_their_back() {
    let dir = tempfile::tempdir().unwrap();
    // Facing outwards, the sphere shows its back to the camera inside: nothing is lit.
    let scene = furnace(dir.path(), 0.5, 1.0, false);
    let out = dir.path().join("f.exr");
    let (_, px) = render_exr(
        &scene,
        &out,
        &[
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "8",
            "--bounces",
            "3",
        ],
    );
    // Facing inwards the same sphere reads 2.0; sliver triangles at the poles, whose winding
    // rounding can flip, may leak a trace, so allow a millionth of that.
    let m = common::mean_gray(&px);
    assert!(m < 2e-6, "back faces emitted: mean {m}");
}

#[test]
fn same_seed_gives_the_same_image_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let a = dir.path().join("a.exr");
    let b = dir.path().join("b.exr");
    let c = dir.path().join("c.exr");
    let args = [
        "--width",
        "40",
        "--height",
        "40",
        "--spp",
        "6",
        "--bounces",
        "3",
    ];
    let (_, pa) = render_exr(&scene, &a, &args);
    let (_, pb) = render_exr(&scene, &b, &args);
    assert_eq!(
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        "same seed, same file"
    );
    assert_eq!(pa, pb);
    let mut other = args.to_vec();
    other.extend(["--seed", "7"]);
    let (_, pc) = render_exr(&scene, &c, &other);
    assert_ne!(pa, pc, "another seed gives another noise pattern");
}
