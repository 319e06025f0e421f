//! `penumbra bench stress`: the same image at any position and scale, and the robustness checks
//! behind it. Each check is a function here so that `tests/stress.rs` runs the same code with
//! fewer samples:
//!
//! - [`compare_moved`]: the bundled Cornell box moved and scaled, rendered, and compared block by
//!   block with the original (and the original with another seed, for the noise level);
//! - [`leaks`]: rays from inside a closed sphere, traced on the host and by `trace_closest`,
//!   with the sphere at the origin or far away, in raw f32 coordinates or rebased;
//! - [`reintersections`]: pbrt-v4's test: rays spawned from random triangles from 1e-8 to 1e8
//!   with the kernels' own hit point and offset (`spawn_test`) must not hit their triangle;
//! - [`grazing_occlusions`]: shadow rays leaving a tilted, tessellated plane at grazing angles
//!   must not hit the plane;
//! - [`acne`]: a plane lit by a sun at a grazing angle must be lit evenly (no dark pixels).

use super::device_line;
use crate::cl::types::{COUNTER_SLOTS, DeviceHit, DeviceRay};
use crate::cl::{Buffer, DeviceChoice};
use crate::date::today;
use crate::render::{RenderSettings, Renderer};
use crate::scene::{
    Camera, Light, LightKind, Material, Mesh, Object, RenderFrame, Scene, load_or_bundled,
};
use anyhow::Result;
use clap::Args;
use glam::{DMat4, DQuat, DVec3, Vec3};

/// Options of `bench stress`.
#[derive(Args, Debug, Clone)]
pub struct StressArgs {
    /// OpenCL device: gpu, cpu or an index from `penumbra devices` (default: first GPU, else
    /// first CPU; also PENUMBRA_DEVICE).
    #[arg(long)]
    pub device: Option<String>,
    /// Side of the Cornell box images compared.
    #[arg(long, default_value_t = 48)]
    pub size: u32,
    /// Samples per pixel of the Cornell box images.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Rays per leak test.
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: usize,
}

/// A small deterministic random generator (PCG-style LCG) for the checks.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A uniform unit vector.
    pub fn direction(&mut self) -> DVec3 {
        let z = 2.0 * self.uniform() - 1.0;
        let phi = std::f64::consts::TAU * self.uniform();
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// `scene` scaled by `scale` about the world origin, then moved by `offset`, in f64: objects,
/// lights (point and spot intensities × scale², so their irradiance stays), cameras and the
/// materials' volume lengths.
pub fn moved(scene: &Scene, scale: f64, offset: DVec3) -> Scene {
    let m = DMat4::from_translation(offset) * DMat4::from_scale(DVec3::splat(scale));
    let mut s = scene.clone();
    for o in &mut s.objects {
        o.world_from_object = m * o.world_from_object;
    }
    for l in &mut s.lights {
        l.position = m.transform_point3(l.position);
        if l.kind != LightKind::Directional {
            l.intensity = (l.intensity as f64 * scale * scale) as f32;
            l.light_radius = (l.light_radius as f64 * scale) as f32;
        }
    }
    for c in &mut s.cameras {
        c.eye = m.transform_point3(c.eye);
    }
    for mat in &mut s.materials {
        mat.thickness = (mat.thickness as f64 * scale) as f32;
        mat.attenuation_distance = (mat.attenuation_distance as f64 * scale) as f32;
    }
    s
}

/// Renders `scene` from its first camera with its own lights.
pub fn render(
    renderer: &mut Renderer,
    scene: &Scene,
    size: u32,
    spp: u32,
    seed: u32,
) -> Result<Vec<[f32; 3]>> {
    renderer.set_settings(&RenderSettings {
        width: size,
        height: size,
        bounces: 3,
        seed,
        ..RenderSettings::default()
    })?;
    renderer.load_scene(scene, &scene.lights)?;
    renderer.set_camera(&scene.cameras[0])?;
    renderer.render(spp)?;
    Ok(renderer.image()?)
}

/// Relative errors of the 8 × 8 block means of `image` against `reference` (both `size`²,
/// luminance-like sum of RGB): the mean over blocks and the worst block. A block's error is
/// measured against its reference mean, but at least a tenth of the image's mean, so that
/// nearly black blocks do not dominate.
pub fn block_errors(reference: &[[f32; 3]], image: &[[f32; 3]], size: u32) -> (f64, f64) {
    let block = 8usize;
    let n = size as usize;
    let sum = |p: &[f32; 3]| (p[0] + p[1] + p[2]) as f64;
    let floor = 0.1 * reference.iter().map(sum).sum::<f64>() / reference.len().max(1) as f64;
    let mut errors = Vec::new();
    for by in (0..n).step_by(block) {
        for bx in (0..n).step_by(block) {
            let (mut a, mut b) = (0.0, 0.0);
            for y in by..(by + block).min(n) {
                for x in bx..(bx + block).min(n) {
                    a += sum(&reference[y * n + x]);
                    b += sum(&image[y * n + x]);
                }
            }
            let cells = ((by + block).min(n) - by) * ((bx + block).min(n) - bx);
            let (a, b) = (a / cells as f64, b / cells as f64);
            errors.push((b - a).abs() / a.max(floor).max(f64::MIN_POSITIVE));
        }
    }
    let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    (mean, errors.iter().copied().fold(0.0, f64::max))
}

/// One moved or scaled copy of the Cornell box against the original.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Scale applied.
    pub scale: f64,
    /// Offset applied (along (1, 1, 1) / √3 … every axis gets it).
    pub offset: f64,
    /// Mean and worst block error of the copy against the original.
    pub error: (f64, f64),
}

/// Renders the bundled Cornell box with seed 1 (the reference) and seed 2 (the noise level),
/// then each (scale, offset) copy with seed 2, and compares each with the reference. Returns
/// the noise level and the comparisons.
pub fn compare_moved(
    renderer: &mut Renderer,
    cases: &[(f64, f64)],
    size: u32,
    spp: u32,
) -> Result<((f64, f64), Vec<Comparison>)> {
    let scene = load_or_bundled(None)?;
    let reference = render(renderer, &scene, size, spp, 1)?;
    let again = render(renderer, &scene, size, spp, 2)?;
    let noise = block_errors(&reference, &again, size);
    let mut out = Vec::new();
    for &(scale, offset) in cases {
        let copy = moved(&scene, scale, DVec3::splat(offset));
        let image = render(renderer, &copy, size, spp, 2)?;
        out.push(Comparison {
            scale,
            offset,
            error: block_errors(&reference, &image, size),
        });
    }
    Ok((noise, out))
}

/// A closed unit sphere (an octahedron subdivided `levels` times, vertices shared, facing out).
pub fn sphere_mesh(levels: u32) -> Mesh {
    let mut positions = vec![
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut mids = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = mid(a, b, &mut positions);
            let bc = mid(b, c, &mut positions);
            let ca = mid(c, a, &mut positions);
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    Mesh {
        materials: vec![0; tris.len()],
        positions,
        indices: tris,
        ..Mesh::default()
    }
}

fn one_object(name: &str, mesh: Mesh, world_from_object: DMat4, material: Material) -> Scene {
    Scene {
        source: name.into(),
        objects: vec![Object {
            name: name.into(),
            world_from_object,
            visible: true,
            mesh: mesh.into(),
        }],
        materials: vec![material],
        ..Scene::default()
    }
}

/// Leaked rays (host, device) out of `rays` rays from random points inside a closed sphere of
/// `radius` centred at `center`, in random directions. With `rebase` the scene goes to the
/// device as `render` sends it (around its middle); without, in raw world coordinates (f32).
pub fn leaks(
    renderer: &mut Renderer,
    center: DVec3,
    radius: f64,
    rays: usize,
    rebase: bool,
) -> Result<(usize, usize)> {
    let world_from_object =
        DMat4::from_translation(center) * DMat4::from_scale(DVec3::splat(radius));
    let scene = one_object(
        "sphere",
        sphere_mesh(5),
        world_from_object,
        Material::default(),
    );
    let space = if rebase {
        RenderFrame::around(&scene.bounds())
    } else {
        RenderFrame::default()
    };
    // The device rays go through the binary nodes, on any device.
    renderer.set_node_forms(crate::render::NodeForms::BOTH)?;
    renderer.load_scene_in(&scene, &[], space)?;
    let mut rng = Rng::new(rays as u64 ^ center.x.to_bits());
    let gpu_rays: Vec<DeviceRay> = (0..rays)
        .map(|_| {
            let o = space.point(center + rng.direction() * (0.5 * radius * rng.uniform()));
            let d = rng.direction().as_vec3();
            DeviceRay {
                origin: [o.x, o.y, o.z, 0.0],
                direction: [d.x, d.y, d.z, f32::INFINITY],
            }
        })
        .collect();
    let host = renderer.host_scene().expect("the sphere was loaded");
    let host_leaks = gpu_rays
        .iter()
        .filter(|r| {
            let ray = crate::bvh::Ray {
                origin: Vec3::from_slice(&r.origin[..3]),
                direction: Vec3::from_slice(&r.direction[..3]),
                tmin: 0.0,
                tmax: f32::INFINITY,
            };
            host.intersect(&ray).is_none()
        })
        .count();
    let device = &renderer.device;
    let ray_buf = Buffer::from_slice(device, &gpu_rays)?;
    let hits = Buffer::<DeviceHit>::new(device, rays)?;
    let mut counters = Buffer::<u32>::new(device, COUNTER_SLOTS)?;
    counters.clear(device)?;
    let program = renderer.program().expect("the kernels were built");
    let scene = renderer.scene_buffers().expect("the sphere was loaded");
    program.trace_closest(device, scene, &ray_buf, &hits, &counters)?;
    let device_leaks = hits
        .read(device)?
        .iter()
        .filter(|h| h.prim == u32::MAX)
        .count();
    Ok((host_leaks, device_leaks))
}

/// A random point of the cube [−10, 10]³ times 10^exponent.
fn random_vertex(rng: &mut Rng, exponent: f64) -> Vec3 {
    let s = 10f64.powf(exponent);
    DVec3::new(
        (rng.uniform() * 20.0 - 10.0) * s,
        (rng.uniform() * 20.0 - 10.0) * s,
        (rng.uniform() * 20.0 - 10.0) * s,
    )
    .as_vec3()
}

/// pbrt-v4's reintersection test on the device: for each decade 10^e, e = −8 … 8, `cases`
/// random triangles with coordinates in [−10, 10] × 10^e (half of them moved away from the
/// origin by up to 10³ times their size, a quarter lying in a coordinate plane), a random point on each (the kernels' hit point) and a
/// random direction; the spawned ray (the kernels' offset) must not hit its own triangle.
/// Returns (exponent, rays that re-hit) per decade. The kernels must have been built.
pub fn reintersections(renderer: &Renderer, cases: usize) -> Result<Vec<(i32, usize)>> {
    let mut rng = Rng::new(11);
    let mut out = Vec::new();
    for e in -8..=8 {
        let c = reintersection_cases(&mut rng, e, cases);
        let program = renderer.program().expect("the kernels were built");
        let hits = program.spawn_test(&renderer.device, &c.verts, &c.groups, &c.bary, &c.dirs)?;
        out.push((e, hits.iter().filter(|&&h| h > 0).count()));
    }
    Ok(out)
}

/// Inputs of `Program::spawn_test`.
#[derive(Clone, Debug, Default)]
pub struct SpawnCases {
    /// Triangle vertices, three per triangle (xyz).
    pub verts: Vec<[f32; 4]>,
    /// (spawning triangle, first triangle traced, count, unused).
    pub groups: Vec<[u32; 4]>,
    /// Barycentrics of the spawn point.
    pub bary: Vec<[f32; 2]>,
    /// Direction (xyz) and tmax (w).
    pub dirs: Vec<[f32; 4]>,
}

/// The cases of [`reintersections`] for the decade 10^e.
pub fn reintersection_cases(rng: &mut Rng, e: i32, cases: usize) -> SpawnCases {
    let mut c = SpawnCases::default();
    for i in 0..cases {
        let shift = if i % 2 == 0 {
            Vec3::ZERO
        } else {
            let up = 3.0 * rng.uniform();
            random_vertex(rng, e as f64 + up)
        };
        let mut v = [0, 1, 2].map(|_| random_vertex(rng, e as f64) + shift);
        if i % 4 == 2 {
            // In a coordinate plane (the point has no rounding error across it).
            let axis = i / 4 % 3;
            v.iter_mut().for_each(|p| p[axis] = 0.0);
        }
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        if n.length() <= 0.0 || !n.is_finite() {
            continue;
        }
        let (mut u, mut w) = (rng.uniform() as f32, rng.uniform() as f32);
        if u + w > 1.0 {
            (u, w) = (1.0 - u, 1.0 - w);
        }
        let k = c.verts.len() as u32 / 3;
        c.groups.push([k, k, 1, 0]);
        c.verts.extend(v.map(|p| [p.x, p.y, p.z, 0.0]));
        c.bary.push([u, w]);
        let d = rng.direction().as_vec3();
        c.dirs.push([d.x, d.y, d.z, f32::INFINITY]);
    }
    c
}

/// A square of `side` × `side` quads (2 triangles each) spanning [−1, 1]² in the xz plane,
/// facing +y.
pub fn plane_mesh(side: u32) -> Mesh {
    let mut m = Mesh::default();
    let n = side + 1;
    for j in 0..n {
        for i in 0..n {
            let f = |k: u32| 2.0 * k as f32 / side as f32 - 1.0;
            m.positions.push(Vec3::new(f(i), 0.0, f(j)));
        }
    }
    for j in 0..side {
        for i in 0..side {
            let a = j * n + i;
            m.indices.push([a, a + n, a + 1]);
            m.indices.push([a + 1, a + n, a + n + 1]);
        }
    }
    m.materials = vec![0; m.indices.len()];
    m
}

/// A tilted plane's placement: rotated off the axes, scaled by `scale`, moved by `offset`.
fn tilted(scale: f64, offset: f64) -> DMat4 {
    DMat4::from_translation(DVec3::splat(offset))
        * DMat4::from_quat(DQuat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, 0.2))
        * DMat4::from_scale(DVec3::splat(scale))
}

/// Shadow rays from random points of a tilted 8 × 8-quad plane (scaled by `scale`, moved by
/// `offset`, then brought into render space as `render` does) towards directions `elevation`
/// radians above it, as long as the plane is wide: the number of `rays` that hit the plane
/// (false occlusion). The kernels must have been built.
pub fn grazing_occlusions(
    renderer: &Renderer,
    scale: f64,
    offset: f64,
    elevation: f64,
    rays: usize,
) -> Result<usize> {
    let scene = one_object(
        "plane",
        plane_mesh(8),
        tilted(scale, offset),
        Material::default(),
    );
    let space = RenderFrame::around(&scene.bounds());
    let tris = scene.flatten(&space).triangles;
    let verts: Vec<[f32; 4]> = tris
        .iter()
        .flat_map(|t| t.v.map(|p| [p.x, p.y, p.z, 0.0]))
        .collect();
    let normal = (tris[0].v[1] - tris[0].v[0])
        .cross(tris[0].v[2] - tris[0].v[0])
        .normalize()
        .as_dvec3();
    let tangent = (tris[0].v[1] - tris[0].v[0]).normalize().as_dvec3();
    let bitangent = normal.cross(tangent);
    let width = (space.length(2.0 * scale) * 2.0) as f64;
    let mut rng = Rng::new(23);
    let (mut groups, mut bary, mut dirs) = (vec![], vec![], vec![]);
    for _ in 0..rays {
        let t = (rng.uniform() * tris.len() as f64) as usize;
        groups.push([t as u32, 0, tris.len() as u32, 0]);
        let (mut u, mut w) = (rng.uniform() as f32, rng.uniform() as f32);
        if u + w > 1.0 {
            (u, w) = (1.0 - u, 1.0 - w);
        }
        bary.push([u, w]);
        let phi = std::f64::consts::TAU * rng.uniform();
        let along = tangent * phi.cos() + bitangent * phi.sin();
        let d = (along * elevation.cos() + normal * elevation.sin()).as_vec3();
        dirs.push([d.x, d.y, d.z, width as f32]);
    }
    let program = renderer.program().expect("the kernels were built");
    let hits = program.spawn_test(&renderer.device, &verts, &groups, &bary, &dirs)?;
    Ok(hits.iter().filter(|&&h| h > 0).count())
}

/// A tilted 8 × 8-quad Lambertian plane (scaled by `scale`, moved by `offset`) lit by a sun
/// `elevation` radians above it with hard shadows, seen straight on, direct light only: every
/// pixel should read albedo / π × sin(elevation). Returns the pixels more than 1 % off (acne)
/// out of `size`².
pub fn acne(
    renderer: &mut Renderer,
    scale: f64,
    offset: f64,
    elevation: f64,
    size: u32,
) -> Result<usize> {
    let albedo = 0.5;
    let material = Material {
        base_color: [albedo, albedo, albedo, 1.0],
        specular_factor: 0.0,
        ..Material::default()
    };
    let m = tilted(scale, offset);
    let mut scene = one_object("plane", plane_mesh(8), m, material);
    let normal = m.transform_vector3(DVec3::Y).normalize();
    let tangent = m.transform_vector3(DVec3::X).normalize();
    let to_sun = tangent * elevation.cos() + normal * elevation.sin();
    scene.lights = vec![Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        position: DVec3::ZERO,
        direction: -to_sun,
        color: [1.0; 3],
        intensity: 1.0,
        light_radius: 0.0,
    }];
    let center = m.transform_point3(DVec3::ZERO);
    let eye = center + normal * (3.0 * scale);
    scene.cameras = vec![Camera::look_at("above", eye, center, 0.4)];
    if scene.cameras[0].up.is_nan() {
        scene.cameras[0] = Camera::look_at("above", eye, center + tangent * 1e-3 * scale, 0.4);
    }
    renderer.set_settings(&RenderSettings {
        width: size,
        height: size,
        bounces: 0,
        ..RenderSettings::default()
    })?;
    renderer.load_scene(&scene, &scene.lights)?;
    renderer.set_camera(&scene.cameras[0])?;
    renderer.render(4)?;
    let expected = albedo as f64 / std::f64::consts::PI * elevation.sin();
    Ok(renderer
        .image()?
        .iter()
        .filter(|p| ((p[1] as f64) - expected).abs() > 0.01 * expected)
        .count())
}

/// Runs every check and prints a Markdown table for docs/benchmarks.md.
pub fn run(args: &StressArgs) -> Result<()> {
    let choice =
        DeviceChoice::from_arg_or_env(args.device.as_deref()).map_err(anyhow::Error::msg)?;
    let mut renderer = Renderer::new(&choice)?;
    println!(
        "penumbra bench stress, {}, {}",
        today(),
        device_line(&renderer.device)
    );
    println!();
    println!("| check | case | result |");
    println!("|---|---|---|");
    let mut cases = Vec::new();
    for scale in [1e-4, 1e-2, 1.0, 1e2, 1e4] {
        for offset in [0.0, 1e3, 1e5, 1e7] {
            if scale != 1.0 || offset != 0.0 {
                cases.push((scale, offset));
            }
        }
    }
    let (noise, comparisons) = compare_moved(&mut renderer, &cases, args.size, args.spp)?;
    println!(
        "| Cornell box, {0}² px, {1} spp | original, another seed (noise) | mean {2:.2} %, worst block {3:.1} % |",
        args.size,
        args.spp,
        100.0 * noise.0,
        100.0 * noise.1
    );
    for c in &comparisons {
        println!(
            "| Cornell box vs original | ×{:e}, moved {:e} | mean {:.2} %, worst block {:.1} % |",
            c.scale,
            c.offset,
            100.0 * c.error.0,
            100.0 * c.error.1
        );
    }
    for (offset, rebase) in [(0.0, false), (1e3, false), (1e5, false), (1e7, true)] {
        let (host, device) = leaks(&mut renderer, DVec3::splat(offset), 1.0, args.rays, rebase)?;
        println!(
            "| closed sphere (32768 triangles) seen from inside, {} rays | centre at {:e}{} | leaked: host {}, device {} |",
            args.rays,
            offset,
            if rebase { ", rebased" } else { ", raw f32" },
            host,
            device
        );
    }
    let per_decade = 20_000;
    let re = reintersections(&renderer, per_decade)?;
    let total: usize = re.iter().map(|r| r.1).sum();
    println!(
        "| spawned rays re-hitting their triangle (pbrt-v4 reintersect), {} per decade | 1e-8 … 1e8 | {} of {} |",
        per_decade,
        total,
        per_decade * re.len()
    );
    for (scale, offset) in [(1e-4, 0.0), (1.0, 0.0), (1e4, 1e7)] {
        for degrees in [0.1f64, 1.0, 10.0] {
            let n = grazing_occlusions(&renderer, scale, offset, degrees.to_radians(), 100_000)?;
            println!(
                "| shadow rays falsely occluded by a tilted plane | ×{scale:e}, moved {offset:e}, {degrees}° | {n} of 100000 |"
            );
        }
    }
    for (scale, offset) in [(1e-4, 0.0), (1.0, 0.0), (1e4, 1e7)] {
        for degrees in [1.0f64, 5.0] {
            let n = acne(&mut renderer, scale, offset, degrees.to_radians(), 64)?;
            println!(
                "| acne: pixels > 1 % off on a plane lit at a grazing angle | ×{scale:e}, moved {offset:e}, sun at {degrees}° | {n} of 4096 |"
            );
        }
    }
    Ok(())
}
