//! Textures on the default OpenCL device (PoCL in CI): lookups through a test kernel against a
//! host reference of the glTF sampler (wrap modes, bilinear filtering, sRGB, texture
//! transforms), and renders for what only the whole path shows (sRGB albedo under a uniform
//! sky, normal-map orientation, alpha cut-outs and stochastic transparency in shadow rays).
//! Fixtures are tiny PNGs written by the tests into temporary glTF files.

mod common;

use common::{Gltf, Prim, render_exr};
use penumbra::cl::DeviceChoice;
use penumbra::render::Renderer;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

fn renderer() -> Renderer {
    let choice: DeviceChoice = common::test_device().parse().expect("a valid test device");
    Renderer::new(&choice).expect("the test's OpenCL device is available")
}

/// PNG bytes of RGBA texels, row by row from the top.
fn png(width: u32, height: u32, texels: &[[u8; 4]]) -> Vec<u8> {
    let raw: Vec<u8> = texels.iter().flatten().copied().collect();
    let image = image::RgbaImage::from_raw(width, height, raw).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    image.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// glTF sampler wrap codes.
const REPEAT: u32 = 10497;
const CLAMP: u32 = 33071;
const MIRROR: u32 = 33648;

/// Images, samplers and textures of a fixture, written into `Gltf::extra`.
#[derive(Default)]
struct TextureSet {
    images: Vec<Value>,
    samplers: Vec<Value>,
    textures: Vec<Value>,
}

impl TextureSet {
    /// Embeds a PNG in the binary buffer; returns the image index.
    fn embedded(&mut self, g: &mut Gltf, bytes: &[u8]) -> usize {
        let view = g.bytes_view(bytes);
        self.images
            .push(json!({"bufferView": view, "mimeType": "image/png"}));
        self.images.len() - 1
    }

    /// A texture of `image` with a sampler wrapping both axes by `wrap`.
    fn texture(&mut self, image: usize, wrap: u32) -> usize {
        self.samplers.push(json!({"wrapS": wrap, "wrapT": wrap}));
        self.textures
            .push(json!({"source": image, "sampler": self.samplers.len() - 1}));
        self.textures.len() - 1
    }

    fn finish(self, g: &mut Gltf) {
        g.extra.insert("images".into(), json!(self.images));
        g.extra.insert("samplers".into(), json!(self.samplers));
        g.extra.insert("textures".into(), json!(self.textures));
    }
}

/// A 2×2 quad in the XY plane facing +Z with glTF's usual UVs (u along +X, v down the image,
/// i.e. along −Y), or u mirrored along −X.
fn quad(g: &mut Gltf, material: usize, mirrored_u: bool, tangents: bool) -> usize {
    let positions = vec![
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let mut uvs = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    if mirrored_u {
        for uv in &mut uvs {
            uv[0] = 1.0 - uv[0];
        }
    }
    let mesh = g.mesh(vec![Prim {
        positions,
        normals: vec![[0.0, 0.0, 1.0]; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: Some(material),
        mode: 4,
    }]);
    let uv = g.float_accessor(&uvs);
    g.meshes[mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    if tangents {
        let t = g.float_accessor(&[[1.0f32, 0.0, 0.0, 1.0]; 4]);
        g.meshes[mesh]["primitives"][0]["attributes"]["TANGENT"] = json!(t);
    }
    mesh
}

/// A Lambertian (specularFactor 0) material; `extra` is merged into its JSON.
fn lambert(g: &mut Gltf, color: [f32; 4], extra: Value) -> usize {
    g.use_ext("KHR_materials_specular");
    let mut m = json!({
        "pbrMetallicRoughness": {"baseColorFactor": color, "metallicFactor": 0.0, "roughnessFactor": 1.0},
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}
    });
    merge(&mut m, extra);
    g.materials.push(m);
    g.materials.len() - 1
}

fn merge(dst: &mut Value, src: Value) {
    match (dst, src) {
        (Value::Object(d), Value::Object(s)) => {
            for (k, v) in s {
                merge(d.entry(k).or_insert(Value::Null), v);
            }
        }
        (d, s) => *d = s,
    }
}

fn srgb(v: u8) -> f32 {
    let c = v as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The glTF sampler on the host: wrap, then bilinear between texel centres.
fn reference(
    texels: &[[u8; 4]],
    w: i64,
    h: i64,
    wrap: u32,
    is_srgb: bool,
    st: [f32; 2],
) -> [f32; 4] {
    let fold = |i: i64, n: i64| -> i64 {
        match wrap {
            CLAMP => i.clamp(0, n - 1),
            MIRROR => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
            _ => i.rem_euclid(n),
        }
    };
    let decode = |t: [u8; 4]| -> [f32; 4] {
        let c = |v: u8| {
            if is_srgb { srgb(v) } else { v as f32 / 255.0 }
        };
        [c(t[0]), c(t[1]), c(t[2]), t[3] as f32 / 255.0]
    };
    let x = st[0] * w as f32 - 0.5;
    let y = st[1] * h as f32 - 0.5;
    let (fx, fy) = (x.floor(), y.floor());
    let (ax, ay) = (x - fx, y - fy);
    let at = |i: i64, j: i64| decode(texels[(fold(j, h) * w + fold(i, w)) as usize]);
    let (x0, y0) = (fx as i64, fy as i64);
    let (c00, c10, c01, c11) = (
        at(x0, y0),
        at(x0 + 1, y0),
        at(x0, y0 + 1),
        at(x0 + 1, y0 + 1),
    );
    let mut out = [0.0; 4];
    for k in 0..4 {
        let top = c00[k] + (c10[k] - c00[k]) * ax;
        let bottom = c01[k] + (c11[k] - c01[k]) * ax;
        out[k] = top + (bottom - top) * ay;
    }
    out
}

/// Deterministic pseudo-random numbers in [0, 1).
fn lcg(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A 4×4 texture with distinct channels per texel.
fn test_texels() -> Vec<[u8; 4]> {
    (0..16u8)
        .map(|i| [i * 15, 255 - i * 15, (i % 4) * 60 + 10, 255 - i * 7])
        .collect()
}

/// An 8×8 black-and-white checker (sRGB 0 and 255).
fn checker() -> Vec<[u8; 4]> {
    (0..64)
        .map(|i| {
            let v = if (i % 8 + i / 8) % 2 == 0 { 255 } else { 0 };
            [v, v, v, 255]
        })
        .collect()
}

/// KHR_texture_transform's matrix as the extension's text writes it, applied to uv.
fn transform(offset: [f32; 2], rotation: f32, scale: [f32; 2], uv: [f32; 2]) -> [f32; 2] {
    let (s, c) = rotation.sin_cos();
    let (x, y) = (uv[0] * scale[0], uv[1] * scale[1]);
    [c * x + s * y + offset[0], -s * x + c * y + offset[1]]
}

/// The transforms the lookup test uses: (offset, rotation, scale).
const TRANSFORMS: [([f32; 2], f32, [f32; 2]); 3] = [
    ([0.25, -0.125], 0.0, [1.0, 1.0]),
    ([0.0, 0.0], 0.0, [2.0, 0.5]),
    ([0.1, 0.3], 0.6, [1.5, 0.75]),
];

/// Materials 0–2: metallic-roughness (linear) textures of `test_texels` with repeat, clamp and
/// mirror; 3: a 1×1 base color of 128 gray and alpha 128; 4–6: base color checkers with the
/// transforms (the last one with a texCoord override). One texture per material, so texture
/// reference i belongs to material i.
fn lookup_fixture(dir: &Path) -> PathBuf {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let texels = test_texels();
    let image = t.embedded(&mut g, &png(4, 4, &texels));
    for wrap in [REPEAT, CLAMP, MIRROR] {
        let tex = t.texture(image, wrap);
        lambert(
            &mut g,
            [1.0; 4],
            json!({"pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": tex}}}),
        );
    }
    let gray = t.embedded(&mut g, &png(1, 1, &[[128, 128, 128, 128]]));
    let tex = t.texture(gray, REPEAT);
    lambert(
        &mut g,
        [1.0; 4],
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": tex}}}),
    );
    let check = t.embedded(&mut g, &png(8, 8, &checker()));
    g.use_ext("KHR_texture_transform");
    for (i, (offset, rotation, scale)) in TRANSFORMS.iter().enumerate() {
        let tex = t.texture(check, REPEAT);
        let mut x = json!({"offset": offset, "rotation": rotation, "scale": scale});
        if i == 2 {
            x["texCoord"] = json!(1);
        }
        lambert(
            &mut g,
            [1.0; 4],
            json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": tex, "extensions": {"KHR_texture_transform": x}}}}),
        );
    }
    t.finish(&mut g);
    let mesh = quad(&mut g, 0, false, false);
    g.node(json!({"mesh": mesh}));
    g.write_glb(dir, "lookups")
}

#[test]
fn lookups_wrap_filter_decode_srgb_and_transform_like_the_gltf_sampler() {
    let dir = tempfile::tempdir().unwrap();
    let scene = penumbra::scene::load(&lookup_fixture(dir.path())).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.texture_refs.len(), 7);
    use penumbra::scene::Wrap;
    let wraps: Vec<Wrap> = scene.texture_refs[..3].iter().map(|r| r.wrap_s).collect();
    assert_eq!(wraps, [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror]);
    assert!(!scene.texture_refs[0].srgb && scene.texture_refs[3].srgb);
    assert_eq!(scene.texture_refs[6].tex_coord, 1, "texCoord override");
    let mut r = renderer();
    r.load_scene(&scene, &[]).unwrap();
    let program = r.program().unwrap();
    assert!(program.features.textures);
    let buffers = r.scene_buffers().unwrap();
    let mut rnd = lcg(3);
    let mut queries = vec![];
    let mut expect = vec![];
    let texels = test_texels();
    for (reference_index, wrap) in [REPEAT, CLAMP, MIRROR].into_iter().enumerate() {
        for k in 0..400 {
            // Texel centres (exact texel values), then arbitrary points, mostly outside [0, 1].
            let st = if k < 64 {
                [(k % 8) as f32 * 0.25 - 0.875, (k / 8) as f32 * 0.25 - 0.875]
            } else {
                [rnd() * 4.6 - 1.8, rnd() * 4.6 - 1.8]
            };
            queries.push([
                st[0],
                st[1],
                f32::NEG_INFINITY,
                f32::from_bits(reference_index as u32),
            ]);
            expect.push(reference(&texels, 4, 4, wrap, false, st));
        }
    }
    // sRGB: a base color texel of 128 reads 0.2158605 linear; alpha stays linear.
    queries.push([0.3, 0.7, f32::NEG_INFINITY, f32::from_bits(3)]);
    let g = srgb(128);
    expect.push([g, g, g, 128.0 / 255.0]);
    // Transforms move the checker as the extension's matrix says.
    let check = checker();
    for (i, (offset, rotation, scale)) in TRANSFORMS.iter().enumerate() {
        for _ in 0..200 {
            let uv = [rnd() * 2.0 - 0.5, rnd() * 2.0 - 0.5];
            queries.push([
                uv[0],
                uv[1],
                f32::NEG_INFINITY,
                f32::from_bits(4 + i as u32),
            ]);
            let st = transform(*offset, *rotation, *scale, uv);
            expect.push(reference(&check, 8, 8, REPEAT, true, st));
        }
    }
    let got = program
        .sample_texture_test(&r.device, buffers, &queries)
        .unwrap();
    for (i, (g, e)) in got.iter().zip(&expect).enumerate() {
        for c in 0..4 {
            assert!(
                (g[c] - e[c]).abs() < 2e-4,
                "query {i} {:?}: device {g:?}, reference {e:?}",
                queries[i]
            );
        }
    }
    assert!((got[1200][0] - 0.2158605).abs() < 1e-6);
}

/// Samplers with magFilter NEAREST read one texel, and a minFilter without mipmaps keeps the
/// finest level whatever the footprint.
#[test]
fn nearest_samplers_read_one_texel_and_mipless_ones_stay_at_level_0() {
    const NEAREST: u32 = 9728;
    const LINEAR: u32 = 9729;
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let texels = test_texels();
    let image = t.embedded(&mut g, &png(4, 4, &texels));
    for (mag, min) in [(NEAREST, NEAREST), (LINEAR, LINEAR)] {
        t.samplers
            .push(json!({"wrapS": MIRROR, "wrapT": MIRROR, "magFilter": mag, "minFilter": min}));
        t.textures
            .push(json!({"source": image, "sampler": t.samplers.len() - 1}));
        let tex = t.textures.len() - 1;
        lambert(
            &mut g,
            [1.0; 4],
            json!({"pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": tex}}}),
        );
    }
    t.finish(&mut g);
    let mesh = quad(&mut g, 0, false, false);
    g.node(json!({"mesh": mesh}));
    let scene = penumbra::scene::load(&g.write_glb(dir.path(), "nearest")).unwrap();
    assert!(scene.texture_refs[0].nearest && !scene.texture_refs[0].mipmaps);
    assert!(!scene.texture_refs[1].nearest && !scene.texture_refs[1].mipmaps);
    let mut r = renderer();
    r.load_scene(&scene, &[]).unwrap();
    let decode = |t: [u8; 4]| t.map(|v| v as f32 / 255.0);
    let mut rnd = lcg(9);
    let mut queries = vec![];
    let mut expect = vec![];
    for _ in 0..500 {
        let st = [rnd() * 4.6 - 1.8, rnd() * 4.6 - 1.8];
        // A coarse footprint (level 3) must not matter: neither sampler has mipmaps.
        queries.push([st[0], st[1], 3.0, f32::from_bits(0)]);
        let mirror = |c: f32| {
            let m = ((c * 4.0).floor() as i64).rem_euclid(8);
            if m < 4 { m } else { 7 - m }
        };
        expect.push(decode(texels[(mirror(st[1]) * 4 + mirror(st[0])) as usize]));
        queries.push([st[0], st[1], 3.0, f32::from_bits(1)]);
        expect.push(reference(&texels, 4, 4, MIRROR, false, st));
    }
    let got = r
        .program()
        .unwrap()
        .sample_texture_test(&r.device, r.scene_buffers().unwrap(), &queries)
        .unwrap();
    for (i, (g, e)) in got.iter().zip(&expect).enumerate() {
        // Nearest reads are exact texel values; bilinear ones round a little.
        let tolerance = if i % 2 == 0 { 1e-6 } else { 2e-4 };
        for c in 0..4 {
            assert!(
                (g[c] - e[c]).abs() < tolerance,
                "query {i} {:?}: {g:?} vs {e:?}",
                queries[i]
            );
        }
    }
}

#[test]
fn mip_levels_follow_the_footprint_and_average_in_linear_space() {
    let dir = tempfile::tempdir().unwrap();
    let scene = penumbra::scene::load(&lookup_fixture(dir.path())).unwrap();
    let mut r = renderer();
    r.load_scene(&scene, &[]).unwrap();
    // Reference 4 is the 8×8 checker moved by (0.25, -0.125): this uv reads the centre of its
    // white texel (0, 0). Footprint levels are per unit of UV area, and the 8×8 texture adds
    // log2(8) = 3, so -3 reads level 0; -2 and above read 4×4 and smaller levels, where every
    // texel is the linear mean of black and white, 0.5 (sRGB 188, read back as 0.5029).
    let q = |lod: f32| [-0.1875, 0.1875, lod, f32::from_bits(4)];
    let got = r
        .program()
        .unwrap()
        .sample_texture_test(
            &r.device,
            r.scene_buffers().unwrap(),
            &[q(-9.0), q(-3.0), q(-2.5), q(-2.0), q(0.0), q(9.0)],
        )
        .unwrap();
    let levels: Vec<f32> = got.iter().map(|g| g[0]).collect();
    let mean = srgb(188);
    let expect = [1.0, 1.0, 1.0, mean, mean, mean];
    for (g, e) in levels.iter().zip(expect) {
        assert!(
            (g - e).abs() < 1e-4,
            "levels read {levels:?}, expected {expect:?}"
        );
    }
}

/// A large Lambertian floor with a uniform 128-gray base color texture, seen from above.
fn gray_floor(dir: &Path) -> PathBuf {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let gray = t.embedded(&mut g, &png(2, 2, &[[128, 128, 128, 255]; 4]));
    let tex = t.texture(gray, REPEAT);
    let m = lambert(
        &mut g,
        [1.0; 4],
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": tex}}}),
    );
    t.finish(&mut g);
    let mesh = quad(&mut g, m, false, false);
    // The quad faces +Z; turn it to face +Y and make it 2000 units wide.
    g.node(json!({"mesh": mesh, "rotation": common::LOOK_DOWN, "scale": [1000.0, 1000.0, 1.0]}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 1.0, 0.0], "rotation": common::LOOK_DOWN}));
    g.write_glb(dir, "floor")
}

fn mean(px: &[[f32; 3]], c: usize) -> f64 {
    px.iter().map(|p| p[c] as f64).sum::<f64>() / px.len() as f64
}

#[test]
fn an_srgb_128_floor_under_a_unit_sky_reflects_0_2158() {
    let dir = tempfile::tempdir().unwrap();
    let scene = gray_floor(dir.path());
    let out = dir.path().join("floor.exr");
    // A Lambertian floor under a uniform sky of radiance 1 (irradiance π) has radiance
    // albedo × E / π = albedo; every BSDF sample escapes, so there is no noise.
    let (summary, px) = render_exr(
        &scene,
        &out,
        &[
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "4",
            "--bounces",
            "0",
            "--env",
            "1",
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0);
    assert_eq!(summary["textures"], 1);
    for c in 0..3 {
        let m = mean(&px, c);
        assert!((m - 0.2158605).abs() < 1e-3, "channel {c}: {m}");
    }
}

/// A 2×2 quad facing the camera with a uniform normal map texel `normal`, lit by a directional
/// light of irradiance π travelling along `light` (unit).
fn normal_mapped(
    dir: &Path,
    name: &str,
    normal: [u8; 3],
    light_rotation: [f64; 4],
    mirrored_u: bool,
    tangents: bool,
) -> PathBuf {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let image = t.embedded(
        &mut g,
        &png(2, 2, &[[normal[0], normal[1], normal[2], 255]; 4]),
    );
    let tex = t.texture(image, REPEAT);
    let m = lambert(&mut g, [1.0; 4], json!({"normalTexture": {"index": tex}}));
    t.finish(&mut g);
    let mesh = quad(&mut g, m, mirrored_u, tangents);
    g.node(json!({"mesh": mesh}));
    g.lights
        .push(json!({"type": "directional", "intensity": std::f32::consts::PI}));
    g.node(
        json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": light_rotation}),
    );
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.4, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 3.0]}));
    g.write_glb(dir, name)
}

#[test]
fn normal_maps_tilt_towards_u_and_up_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let s = std::f64::consts::FRAC_PI_8.sin();
    let c = std::f64::consts::FRAC_PI_8.cos();
    // Light from +X at 45° (travelling along (-1, 0, -1)/√2), and from +Y at 45°.
    let from_x = [0.0, s, 0.0, c];
    let from_y = [-s, 0.0, 0.0, c];
    let flat = [128, 128, 255];
    let toward_u = [218, 128, 218];
    let away_u = [38, 128, 218];
    let up_image = [128, 218, 218];
    // Lambertian, albedo 1, irradiance π: radiance is the cosine between normal and light.
    // (name, normal texel, light rotation, u mirrored, file tangents, expected radiance)
    type Case = (&'static str, [u8; 3], [f64; 4], bool, bool, f64);
    let cases: [Case; 7] = [
        (
            "flat",
            flat,
            from_x,
            false,
            false,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        ("toward-u", toward_u, from_x, false, false, 1.0),
        ("away-u", away_u, from_x, false, false, 0.0),
        ("toward-u-file-tangents", toward_u, from_x, false, true, 1.0),
        // With u running along -X, "towards +u" faces away from the light.
        ("toward-u-mirrored", toward_u, from_x, true, false, 0.0),
        (
            "up-flat",
            flat,
            from_y,
            false,
            false,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        ("up-image", up_image, from_y, false, false, 1.0),
    ];
    for (name, normal, light, mirrored, tangents, expect) in cases {
        let scene = normal_mapped(dir.path(), name, normal, light, mirrored, tangents);
        let out = dir.path().join(format!("{name}.exr"));
        let (summary, px) = render_exr(
            &scene,
            &out,
            &[
                "--width",
                "8",
                "--height",
                "8",
                "--spp",
                "2",
                "--bounces",
                "0",
                "--hard-shadows",
            ],
        );
        assert_eq!(summary["nonfinite_samples"], 0);
        let m = mean(&px, 1);
        assert!(
            (m - expect).abs() < 0.015,
            "{name}: radiance {m}, expected {expect}"
        );
    }
}

/// A white metal quad facing the camera (head-on) whose uniform normal map leans 70° towards
/// +u, of roughness `roughness`, under a uniform sky of radiance 1 (`--env 1`).
fn steep_normal_mapped_mirror(dir: &Path, roughness: f32) -> PathBuf {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    // (sin 70°, 0, cos 70°) encoded as (n + 1) / 2.
    let image = t.embedded(&mut g, &png(2, 2, &[[248, 128, 171, 255]; 4]));
    let tex = t.texture(image, REPEAT);
    g.materials.push(json!({
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 1.0,
                                 "roughnessFactor": roughness},
        "normalTexture": {"index": tex}
    }));
    t.finish(&mut g);
    let mesh = quad(&mut g, 0, false, false);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.4, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 3.0]}));
    g.write_glb(dir, &format!("steep-mirror-{roughness}"))
}

/// A white furnace: a white metal (Fresnel 1 at every angle) under a uniform sky of radiance 1
/// reflects radiance 1 wherever its reflections escape to the sky. Seen head-on, a normal 70°
/// off the geometric one mirrors the view 50° below the surface: without the bent shading
/// normal every such path ended there, black (the rims of shiny normal-mapped surfaces). With
/// it the mirror reflects just above the surface, radiance exactly 1; a glossy lobe about that
/// grazing direction still loses what falls below the surface.
#[test]
fn a_white_metal_with_a_steep_normal_map_stays_white_in_a_furnace() {
    let dir = tempfile::tempdir().unwrap();
    for (roughness, least) in [(0.0, 0.998), (0.1, 0.9)] {
        let scene = steep_normal_mapped_mirror(dir.path(), roughness);
        for kernel in ["wavefront", "megakernel"] {
            let out = dir.path().join(format!("steep-{roughness}-{kernel}.exr"));
            let (summary, px) = render_exr(
                &scene,
                &out,
                &[
                    "--kernel",
                    kernel,
                    "--width",
                    "16",
                    "--height",
                    "16",
                    "--spp",
                    "64",
                    "--bounces",
                    "4",
                    "--env",
                    "1",
                ],
            );
            assert_eq!(summary["nonfinite_samples"], 0);
            let m = mean(&px, 1);
            assert!(
                m > least && m < 1.002,
                "roughness {roughness}, {kernel}: mean radiance {m}, expected in ({least}, 1]"
            );
        }
    }
}

/// A white floor (y = 0) under a red quad (y = 1, |x|, |z| < 1) with `occluder` as the red
/// material's extra JSON, lit straight from above; the camera looks down from y = 5 and sees
/// x, z in ±1.5 on the floor.
fn shadowed_floor(dir: &Path, name: &str, alpha_texture: bool, occluder: Value) -> PathBuf {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let mut occluder = occluder;
    if alpha_texture {
        // Alpha 0 for u < 0.5, 1 beyond, along u (+X).
        let image = t.embedded(
            &mut g,
            &png(
                4,
                1,
                &[[255, 255, 255, 0], [255, 255, 255, 0], [255; 4], [255; 4]],
            ),
        );
        let tex = t.texture(image, CLAMP);
        merge(
            &mut occluder,
            json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": tex}}}),
        );
    }
    let white = lambert(&mut g, [1.0; 4], json!({}));
    let red = lambert(&mut g, [1.0, 0.0, 0.0, 1.0], occluder);
    t.finish(&mut g);
    let face_up = common::LOOK_DOWN;
    let floor = quad(&mut g, white, false, false);
    g.node(json!({"mesh": floor, "rotation": face_up, "scale": [3.0, 3.0, 1.0]}));
    let top = quad(&mut g, red, false, false);
    g.node(json!({"mesh": top, "rotation": face_up, "translation": [0.0, 1.0, 0.0]}));
    g.lights
        .push(json!({"type": "directional", "intensity": std::f32::consts::PI}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": face_up}));
    let yfov = 2.0 * (1.5f64 / 5.0).atan();
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 5.0, 0.0], "rotation": face_up}));
    g.write_glb(dir, name)
}

/// Pixels of a `side`² image whose ray crosses the occluder's plane (y = 1) within
/// |x|, |z| < 0.75 (the floor behind, within ±0.94, is all in the quad's shadow): the camera
/// sees ±1.5 at the floor, so ±1.2 at the occluder.
fn under_occluder(side: usize) -> Vec<usize> {
    let mut out = vec![];
    for j in 0..side {
        for i in 0..side {
            let x = (-1.0 + 2.0 * (i as f64 + 0.5) / side as f64) * 1.2;
            let z = (-1.0 + 2.0 * (j as f64 + 0.5) / side as f64) * 1.2;
            if x.abs() < 0.75 && z.abs() < 0.75 {
                out.push(j * side + i);
            }
        }
    }
    out
}

#[test]
fn masked_cut_outs_let_camera_and_shadow_rays_through() {
    let dir = tempfile::tempdir().unwrap();
    let side = 40;
    let size = side.to_string();
    let args = [
        "--width",
        &size,
        "--height",
        &size,
        "--spp",
        "4",
        "--bounces",
        "0",
        "--hard-shadows",
    ];
    let region = under_occluder(side);
    let fractions = |px: &[[f32; 3]]| {
        let lit = region.iter().filter(|&&i| px[i][1] > 0.9).count();
        let red = region
            .iter()
            .filter(|&&i| px[i][0] > 0.9 && px[i][1] < 0.05)
            .count();
        (
            lit as f64 / region.len() as f64,
            red as f64 / region.len() as f64,
        )
    };
    // Opaque: the red quad hides the floor.
    let scene = shadowed_floor(dir.path(), "opaque", true, json!({}));
    let (_, px) = render_exr(&scene, &dir.path().join("o.exr"), &args);
    assert_eq!(fractions(&px), (0.0, 1.0));
    // Masked at 0.5: the half with alpha below the cutoff (u < 0.5, x < 0) shows the floor, lit,
    // so shadow rays passed the cut-out too.
    let scene = shadowed_floor(
        dir.path(),
        "mask",
        true,
        json!({"alphaMode": "MASK", "alphaCutoff": 0.5}),
    );
    let (summary, px) = render_exr(&scene, &dir.path().join("m.exr"), &args);
    assert_eq!(summary["nonfinite_samples"], 0);
    let (lit, red) = fractions(&px);
    assert!((0.45..0.55).contains(&lit), "lit floor fraction {lit}");
    assert!((0.45..0.55).contains(&red), "red quad fraction {red}");
}

#[test]
fn blended_surfaces_pass_camera_and_shadow_rays_with_probability_one_minus_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let side = 24;
    let size = side.to_string();
    let scene = shadowed_floor(
        dir.path(),
        "blend",
        false,
        json!({"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 0.4]}}),
    );
    let (summary, px) = render_exr(
        &scene,
        &dir.path().join("b.exr"),
        &[
            "--width",
            &size,
            "--height",
            &size,
            "--spp",
            "64",
            "--bounces",
            "0",
            "--hard-shadows",
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0);
    // Green comes only from the white floor, seen with probability 0.6 and lit with 0.6.
    let region = under_occluder(side);
    let g = region.iter().map(|&i| px[i][1] as f64).sum::<f64>() / region.len() as f64;
    assert!((g - 0.36).abs() < 0.02, "mean green under the quad {g}");
    // Red: the quad itself (0.4 × 1 × cos) plus the floor behind it (0.36).
    let r = region.iter().map(|&i| px[i][0] as f64).sum::<f64>() / region.len() as f64;
    assert!((r - 0.76).abs() < 0.03, "mean red under the quad {r}");
}

#[test]
fn images_load_from_glb_views_data_uris_and_files_and_unused_ones_are_not_read() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = png(4, 4, &test_texels());
    std::fs::write(dir.path().join("tex ture.png"), &bytes).unwrap();
    let data_uri = {
        const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::from("data:image/png;base64,");
        for c in bytes.chunks(3) {
            let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
            let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
            for i in 0..4 {
                s.push(if i <= c.len() {
                    T[(n >> (18 - 6 * i)) as usize & 63] as char
                } else {
                    '='
                });
            }
        }
        s
    };
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let view = t.embedded(&mut g, &bytes);
    t.images.push(json!({"uri": data_uri}));
    t.images.push(json!({"uri": "tex%20ture.png"}));
    // Referenced by no material: must not be read.
    t.images.push(json!({"uri": "missing.png"}));
    for image in [view, 1, 2] {
        let tex = t.texture(image, REPEAT);
        lambert(
            &mut g,
            [1.0; 4],
            json!({"emissiveTexture": {"index": tex}, "emissiveFactor": [1.0, 1.0, 1.0]}),
        );
    }
    t.finish(&mut g);
    let mesh = quad(&mut g, 0, false, false);
    g.node(json!({"mesh": mesh}));
    let path = g.write_gltf(dir.path(), "sources");
    let scene = penumbra::scene::load(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.images.len(), 3);
    let texels = test_texels();
    for image in &scene.images {
        assert_eq!((image.width, image.height), (4, 4));
        assert_eq!(image.rgba, texels, "{}", image.name);
    }
    // A broken image is a warning, and its slot falls back to the factor.
    std::fs::write(dir.path().join("tex ture.png"), b"not a png").unwrap();
    let scene = penumbra::scene::load(&path).unwrap();
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("tex%20ture.png"),
        "{:?}",
        scene.warnings
    );
    assert!(scene.materials[2].textures.emissive.is_none());
}

#[test]
fn a_texture_can_read_texcoord_1() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    // Four white texels, then four black: u < 0.4375 reads white, u > 0.5625 black.
    let mut texels = vec![[255u8; 4]; 4];
    texels.extend([[0, 0, 0, 255]; 4]);
    let image = t.embedded(&mut g, &png(8, 1, &texels));
    let tex = t.texture(image, CLAMP);
    let m = lambert(
        &mut g,
        [0.0, 0.0, 0.0, 1.0],
        json!({"emissiveFactor": [1.0, 1.0, 1.0], "emissiveTexture": {"index": tex, "texCoord": 1}}),
    );
    t.finish(&mut g);
    let mesh = quad(&mut g, m, false, false);
    // TEXCOORD_0 reads black everywhere; TEXCOORD_1 carries the real coordinates.
    let uv1 = g.meshes[mesh]["primitives"][0]["attributes"]["TEXCOORD_0"].clone();
    let uv0 = g.float_accessor(&[[0.9f32, 0.5]; 4]);
    g.meshes[mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv0);
    g.meshes[mesh]["primitives"][0]["attributes"]["TEXCOORD_1"] = uv1;
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.4, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 3.0]}));
    let scene = g.write_glb(dir.path(), "uv1");
    let (_, px) = render_exr(
        &scene,
        &dir.path().join("uv1.exr"),
        &[
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "4",
            "--bounces",
            "0",
        ],
    );
    // The camera sees x in ±0.61 of the quad, u = (x + 1) / 2 in 0.2..0.8: the left two
    // columns (u below 0.35) are white, the right two (above 0.65) black.
    for row in px.chunks(8) {
        assert!(row[0][1] > 0.99 && row[1][1] > 0.99, "{row:?}");
        assert!(row[6][1] < 0.01 && row[7][1] < 0.01, "{row:?}");
    }
}

/// `KHR_materials_clearcoat` is read from the material's extension object: its factors, its
/// three textures with their texCoord, `KHR_texture_transform` and normal scale, and tangents
/// are made for its normal texture; nothing warns.
#[test]
fn clearcoat_factors_textures_and_transforms_are_read() {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let image = t.embedded(&mut g, &png(4, 4, &test_texels()));
    let coat = t.texture(image, REPEAT);
    let rough = t.texture(image, CLAMP);
    let normal = t.texture(image, MIRROR);
    g.use_ext("KHR_materials_clearcoat");
    g.use_ext("KHR_texture_transform");
    let m = lambert(
        &mut g,
        [1.0; 4],
        json!({"extensions": {"KHR_materials_clearcoat": {
            "clearcoatFactor": 0.75,
            "clearcoatTexture": {"index": coat, "texCoord": 1},
            "clearcoatRoughnessFactor": 0.25,
            "clearcoatRoughnessTexture": {"index": rough, "extensions": {"KHR_texture_transform":
                {"offset": [0.5, 0.25], "rotation": 0.3, "scale": [2.0, 3.0]}}},
            "clearcoatNormalTexture": {"index": normal, "scale": 0.5}
        }}}),
    );
    t.finish(&mut g);
    let mesh = quad(&mut g, m, false, false);
    g.node(json!({"mesh": mesh}));
    let dir = tempfile::tempdir().unwrap();
    let s = penumbra::scene::load(&g.write_glb(dir.path(), "coat")).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let mat = &s.materials[m];
    assert_eq!(
        (
            mat.clearcoat,
            mat.clearcoat_roughness,
            mat.clearcoat_normal_scale
        ),
        (0.75, 0.25, 0.5)
    );
    let refs = |slot: Option<u32>| &s.texture_refs[slot.expect("a texture") as usize];
    assert_eq!(refs(mat.textures.clearcoat).tex_coord, 1);
    let r = refs(mat.textures.clearcoat_roughness);
    assert_eq!(
        (r.transform.offset, r.transform.rotation, r.transform.scale),
        ([0.5, 0.25], 0.3, [2.0, 3.0])
    );
    assert!(!r.srgb);
    assert!(mat.textures.clearcoat_normal.is_some() && mat.textures.normal.is_none());
    let world = s.world_triangles();
    assert!(
        world.iter().all(|t| t.tangents.is_some()),
        "tangents for the coat's normals"
    );
}

/// `KHR_materials_anisotropy` is read: strength, rotation and the texture with its texCoord
/// and `KHR_texture_transform`; tangents are made for the anisotropic material (it has no
/// normal map) and nothing warns.
#[test]
fn anisotropy_strength_rotation_and_texture_are_read() {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let image = t.embedded(&mut g, &png(4, 4, &test_texels()));
    let tex = t.texture(image, REPEAT);
    g.use_ext("KHR_materials_anisotropy");
    g.use_ext("KHR_texture_transform");
    let m = lambert(
        &mut g,
        [1.0; 4],
        json!({"extensions": {"KHR_materials_anisotropy": {
            "anisotropyStrength": 0.6,
            "anisotropyRotation": 1.25,
            "anisotropyTexture": {"index": tex, "extensions": {"KHR_texture_transform":
                {"offset": [0.25, 0.5], "rotation": 0.2, "scale": [3.0, 2.0]}}}
        }}}),
    );
    t.finish(&mut g);
    let mesh = quad(&mut g, m, false, false);
    g.node(json!({"mesh": mesh}));
    let dir = tempfile::tempdir().unwrap();
    let s = penumbra::scene::load(&g.write_glb(dir.path(), "aniso")).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let mat = &s.materials[m];
    assert_eq!((mat.anisotropy, mat.anisotropy_rotation), (0.6, 1.25));
    let r = &s.texture_refs[mat.textures.anisotropy.expect("a texture") as usize];
    assert_eq!(r.tex_coord, 0);
    assert_eq!(
        (r.transform.offset, r.transform.rotation, r.transform.scale),
        ([0.25, 0.5], 0.2, [3.0, 2.0])
    );
    assert!(!r.srgb, "the direction is data, not color");
    let world = s.world_triangles();
    assert!(
        world.iter().all(|t| t.tangents.is_some()),
        "tangents for the anisotropy direction"
    );
    let device = penumbra::render::gpu_material(mat);
    assert_eq!(device.aniso[0], 0.6);
    assert!(
        (device.aniso[1] - 1.25f32.cos()).abs() < 1e-6
            && (device.aniso[2] - 1.25f32.sin()).abs() < 1e-6
    );
    assert_eq!(device.textures4[0], mat.textures.anisotropy.unwrap() as i32);
}

/// `KHR_materials_iridescence` is read: factor, film IOR, thickness range and both textures
/// (the thickness texture with its `KHR_texture_transform`); nothing warns.
#[test]
fn iridescence_factors_and_textures_are_read() {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let image = t.embedded(&mut g, &png(4, 4, &test_texels()));
    let factor = t.texture(image, REPEAT);
    let thickness = t.texture(image, CLAMP);
    g.use_ext("KHR_materials_iridescence");
    g.use_ext("KHR_texture_transform");
    let m = lambert(
        &mut g,
        [1.0; 4],
        json!({"extensions": {"KHR_materials_iridescence": {
            "iridescenceFactor": 0.8,
            "iridescenceTexture": {"index": factor},
            "iridescenceIor": 1.6,
            "iridescenceThicknessMinimum": 150.0,
            "iridescenceThicknessMaximum": 650.0,
            "iridescenceThicknessTexture": {"index": thickness, "extensions": {"KHR_texture_transform":
                {"scale": [2.0, 2.0]}}}
        }}}),
    );
    // Defaults: a film of 1.3 and 100..400 nm.
    let d = lambert(
        &mut g,
        [1.0; 4],
        json!({"extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 1.0}}}),
    );
    t.finish(&mut g);
    let mesh = quad(&mut g, m, false, false);
    g.node(json!({"mesh": mesh}));
    let dir = tempfile::tempdir().unwrap();
    let s = penumbra::scene::load(&g.write_glb(dir.path(), "film")).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let mat = &s.materials[m];
    assert_eq!(
        (
            mat.iridescence,
            mat.iridescence_ior,
            mat.iridescence_thickness
        ),
        (0.8, 1.6, [150.0, 650.0])
    );
    assert!(mat.textures.iridescence.is_some());
    let r = &s.texture_refs[mat.textures.iridescence_thickness.expect("a texture") as usize];
    assert_eq!(r.transform.scale, [2.0, 2.0]);
    let def = &s.materials[d];
    assert_eq!(
        (
            def.iridescence,
            def.iridescence_ior,
            def.iridescence_thickness
        ),
        (1.0, 1.3, [100.0, 400.0])
    );
    let device = penumbra::render::gpu_material(mat);
    assert_eq!(device.iridescence, [0.8, 1.6, 150.0, 650.0]);
    assert_eq!(
        device.textures4[1],
        mat.textures.iridescence.unwrap() as i32
    );
    assert_eq!(
        device.textures4[2],
        mat.textures.iridescence_thickness.unwrap() as i32
    );
}

/// `KHR_materials_dispersion` is read (20 / Abbe number, no upper bound; a negative one is
/// the default 0) and packed in the anisotropy lane's `.w`; only the negative one warns. It makes a
/// material dispersive only on a transmitting volume.
#[test]
fn dispersion_is_read() {
    let mut g = Gltf::default();
    for e in [
        "KHR_materials_dispersion",
        "KHR_materials_transmission",
        "KHR_materials_volume",
    ] {
        g.use_ext(e);
    }
    let glass = |g: &mut Gltf, dispersion: Value, thickness: f32| {
        lambert(
            g,
            [1.0; 4],
            json!({"extensions": {
                "KHR_materials_dispersion": dispersion,
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_volume": {"thicknessFactor": thickness}
            }}),
        )
    };
    let prism = glass(&mut g, json!({"dispersion": 0.4}), 1.0);
    let rutile = glass(&mut g, json!({"dispersion": 2.04}), 1.0);
    let default = glass(&mut g, json!({}), 1.0);
    let negative = glass(&mut g, json!({"dispersion": -1.0}), 1.0);
    let thin = glass(&mut g, json!({"dispersion": 0.4}), 0.0);
    let mesh = quad(&mut g, prism, false, false);
    g.node(json!({"mesh": mesh}));
    let dir = tempfile::tempdir().unwrap();
    let s = penumbra::scene::load(&g.write_glb(dir.path(), "dispersion")).unwrap();
    // The negative dispersion is out of the specification's range: one warning, for it alone.
    assert_eq!(
        s.warnings,
        [format!(
            "materials[{negative}]: dispersion -1 is negative or not finite, 0 is used"
        )]
    );
    let d: Vec<f32> = [prism, rutile, default, negative, thin]
        .iter()
        .map(|&m| s.materials[m].dispersion)
        .collect();
    assert_eq!(d, [0.4, 2.04, 0.0, 0.0, 0.4]);
    assert!(s.materials[prism].is_dispersive());
    assert!(!s.materials[default].is_dispersive());
    assert!(
        !s.materials[thin].is_dispersive(),
        "no volume, no dispersion"
    );
    assert_eq!(
        penumbra::render::gpu_material(&s.materials[rutile]).aniso[3],
        2.04
    );
}

/// `KHR_materials_diffuse_transmission` is read: factor and color with their textures (the
/// color texture is sRGB, the factor texture's alpha is data); only the out-of-range colour warns.
#[test]
fn diffuse_transmission_factors_and_textures_are_read() {
    let mut g = Gltf::default();
    let mut t = TextureSet::default();
    let image = t.embedded(&mut g, &png(4, 4, &test_texels()));
    let factor = t.texture(image, REPEAT);
    let color = t.texture(image, MIRROR);
    g.use_ext("KHR_materials_diffuse_transmission");
    let m = lambert(
        &mut g,
        [1.0; 4],
        json!({"extensions": {"KHR_materials_diffuse_transmission": {
            "diffuseTransmissionFactor": 0.35,
            "diffuseTransmissionTexture": {"index": factor},
            "diffuseTransmissionColorFactor": [0.9, 0.5, 2.0],
            "diffuseTransmissionColorTexture": {"index": color, "texCoord": 1}
        }}}),
    );
    t.finish(&mut g);
    let mesh = quad(&mut g, m, false, false);
    g.node(json!({"mesh": mesh}));
    let dir = tempfile::tempdir().unwrap();
    let s = penumbra::scene::load(&g.write_glb(dir.path(), "leaf")).unwrap();
    // The colour's 2 is out of the specification's range: one warning, for it alone.
    assert_eq!(
        s.warnings,
        [format!(
            "materials[{m}]: diffuseTransmissionColorFactor 2 is out of range, 1 is used"
        )]
    );
    let mat = &s.materials[m];
    assert_eq!(mat.diffuse_transmission, 0.35);
    assert_eq!(
        mat.diffuse_transmission_color,
        [0.9, 0.5, 1.0],
        "clamped to 1"
    );
    let refs = |slot: Option<u32>| &s.texture_refs[slot.expect("a texture") as usize];
    assert!(!refs(mat.textures.diffuse_transmission).srgb);
    let c = refs(mat.textures.diffuse_transmission_color);
    assert!(c.srgb && c.tex_coord == 1);
    let device = penumbra::render::gpu_material(mat);
    assert_eq!(device.diffuse_transmission, [0.9, 0.5, 1.0, 0.35]);
    assert_eq!(
        device.textures4[3],
        mat.textures.diffuse_transmission.unwrap() as i32
    );
    assert_eq!(
        device.textures5[0],
        mat.textures.diffuse_transmission_color.unwrap() as i32
    );
}
