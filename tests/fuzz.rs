//! A fuzz harness on stable Rust: mutates small glTF scenes, with knowledge of their structure
//! (the JSON tree: deleted and replaced values, dangling indices, huge counts, bad enums,
//! non-finite numbers, duplicated children) and byte by byte (the GLB container, the JSON text
//! and the binary chunk), and runs the loader in-process under `catch_unwind` (posing every
//! animation clip of what loads).
//!
//! A failure is a panic, a load slower than [`SLOW`], or a loaded scene that breaks what the
//! renderer relies on (finite geometry, factors in range, indices in range, non-negative
//! finite light). Each failing input is saved in `tests/fuzz-corpus/` and replayed by
//! `the_corpus_replays_cleanly` from then on.
//!
//! An input that hangs (one load past [`HANG`]) is saved by a watchdog thread, which then ends
//! the process. One that kills the process (a crash in a C/C++ decoder, memory exhausted) is
//! left in `target/tmp/fuzz-last-input`; the next run saves it as `died-….glb` in the corpus.
//!
//! `PENUMBRA_FUZZ_SECONDS` sets the run time (default 60), `PENUMBRA_FUZZ_SEED` the seed
//! (default: from the clock, printed). Long runs print progress every five minutes; every run
//! ends with a summary line (`fuzz summary: …`: executions, inputs per second, distinct
//! failures, new corpus entries). Seeds: the bundled Cornell box, textured quads whose texture
//! is KTX2 (ETC1S and UASTC, `KHR_texture_basisu`), WebP (`EXT_texture_webp`) and PNG, and with
//! `PENUMBRA_SCENES` set, the shared Cubes, CornellBox and Fox.

mod common;

use common::{ktx2_fixture, textured_quad};
use penumbra::scene::{BUNDLED_SCENE, LightKind, Scene, limits, load_from_bytes};
use serde_json::{Value, json};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A load slower than this counts as a failure (a hang in the making).
const SLOW: Duration = Duration::from_secs(20);

/// A load still running after this is a hang: the watchdog saves the input and ends the run.
const HANG: Duration = Duration::from_secs(120);

/// splitmix64: small, fast and good enough to pick mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
}

/// A GLB split into its JSON document and binary chunk.
struct Glb {
    json: Value,
    bin: Vec<u8>,
}

fn split_glb(bytes: &[u8]) -> Option<Glb> {
    let u32_at = |at: usize| Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?));
    let json_len = u32_at(12)? as usize;
    let json = serde_json::from_slice(bytes.get(20..20 + json_len)?).ok()?;
    let bin_at = 20 + json_len;
    let bin = match u32_at(bin_at) {
        Some(len) => bytes.get(bin_at + 8..bin_at + 8 + len as usize)?.to_vec(),
        None => Vec::new(),
    };
    Some(Glb { json, bin })
}

/// The same scene as a `.gltf` with its buffer in a data URI (exercises the JSON text and
/// data URIs).
fn as_gltf(glb: &Glb) -> Vec<u8> {
    let mut json = glb.json.clone();
    if let Some(b) = json
        .get_mut("buffers")
        .and_then(|b| b.get_mut(0))
        .and_then(Value::as_object_mut)
    {
        b.insert(
            "uri".into(),
            json!(format!(
                "data:application/octet-stream;base64,{}",
                base64::encode(&glb.bin)
            )),
        );
    }
    serde_json::to_vec(&json).unwrap_or_default()
}

/// The seed inputs: (name, GLB bytes).
fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = vec![("cornell-box.glb".to_string(), BUNDLED_SCENE.to_vec())];
    let rgba = ktx2_fixture("rgba.png");
    let webp = {
        let image = image::load_from_memory(&rgba).unwrap();
        let mut bytes = Vec::new();
        image
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::WebP,
            )
            .unwrap();
        bytes
    };
    for (name, image, mime, extension) in [
        (
            "ktx2-etc1s.glb",
            ktx2_fixture("etc1s-alpha.ktx2"),
            "image/ktx2",
            Some("KHR_texture_basisu"),
        ),
        (
            "ktx2-uastc.glb",
            ktx2_fixture("uastc.ktx2"),
            "image/ktx2",
            Some("KHR_texture_basisu"),
        ),
        ("webp.glb", webp, "image/webp", Some("EXT_texture_webp")),
        ("png.glb", rgba, "image/png", None),
    ] {
        out.push((
            name.to_string(),
            textured_quad(&image, mime, extension).glb(),
        ));
    }
    if let Some(dir) = std::env::var_os("PENUMBRA_SCENES").map(PathBuf::from) {
        for f in [
            "Cubes/Cubes.glb",
            "CornellBox/CornellBox.glb",
            "Fox/Fox.glb",
        ] {
            if let Ok(b) = std::fs::read(dir.join(f)) {
                out.push((f.to_string(), b));
            }
        }
    }
    out
}

/// Values that break assumptions: boundaries, huge counts, non-finite floats (1e39 overflows
/// f32), wrong types, bad enums, hostile URIs.
fn interesting(rng: &mut Rng, doc_len: usize) -> Value {
    let pick = [
        json!(0),
        json!(1),
        json!(-1),
        json!(2),
        json!(3),
        json!(4),
        json!(255),
        json!(65535),
        json!(4_294_967_295u64),
        json!(4_294_967_296u64),
        json!(1u64 << 40),
        json!(doc_len),
        json!(1e39),
        json!(-1e39),
        json!(1e-45),
        json!(0.5),
        json!(-0.0),
        json!(3.15),
        json!(1e300),
        json!(""),
        json!("x"),
        json!("/dev/zero"),
        json!("../../../../../../../../dev/zero"),
        json!("zero.bin"),
        json!("small.bin"),
        json!("."),
        json!("data:"),
        json!("data:application/octet-stream;base64,!!!!"),
        json!("data:image/png;base64,iVBORw0KGgo="),
        json!("%FF%FE"),
        json!("file:///etc/passwd"),
        json!("http://example.com/x.bin"),
        json!(null),
        json!(true),
        json!([]),
        json!({}),
        json!([0.0, 0.0, 0.0, 0.0]),
        json!(vec![0.0; 16]),
        json!([1e39, 0.0, 0.0]),
        json!(5120),
        json!(5121),
        json!(5123),
        json!(5125),
        json!(5126),
        json!(34962),
        json!(9729),
        json!(9987),
        json!(33071),
        json!("SCALAR"),
        json!("VEC3"),
        json!("MAT4"),
        json!("MASK"),
        json!("BLEND"),
        json!("spot"),
        json!("directional"),
        json!("orthographic"),
        json!("perspective"),
        json!("image/png"),
        json!("image/ktx2"),
        json!("image/webp"),
        json!("KHR_texture_basisu"),
        json!("EXT_texture_webp"),
        json!("KHR_materials_sheen"),
        json!("EXT_meshopt_compression"),
    ];
    pick[rng.below(pick.len())].clone()
}

/// A step from a value to one of its children.
#[derive(Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn all_paths(v: &Value, path: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    if out.len() > 20_000 {
        return;
    }
    out.push(path.clone());
    match v {
        Value::Object(o) => {
            for (k, c) in o {
                path.push(Step::Key(k.clone()));
                all_paths(c, path, out);
                path.pop();
            }
        }
        // Long arrays of numbers (matrices, min/max) are visited by their first elements.
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate().take(64) {
                path.push(Step::Index(i));
                all_paths(c, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

fn at_mut<'a>(v: &'a mut Value, path: &[Step]) -> Option<&'a mut Value> {
    let mut at = v;
    for s in path {
        at = match (s, at) {
            (Step::Key(k), Value::Object(o)) => o.get_mut(k)?,
            (Step::Index(i), Value::Array(a)) => a.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(at)
}

/// One structure-aware mutation of the document.
fn mutate_json(doc: &mut Value, rng: &mut Rng) {
    let mut paths = Vec::new();
    all_paths(doc, &mut Vec::new(), &mut paths);
    let path = paths[rng.below(paths.len())].clone();
    let doc_len = paths.len();
    let other = paths[rng.below(paths.len())].clone();
    let donor = at_mut(doc, &other).map(|v| v.clone());
    match rng.below(8) {
        // Delete the value from its parent.
        0 => {
            if let Some((last, parent)) = path.split_last()
                && let Some(p) = at_mut(doc, parent)
            {
                match (last, p) {
                    (Step::Key(k), Value::Object(o)) => {
                        o.remove(k);
                    }
                    (Step::Index(i), Value::Array(a)) if *i < a.len() => {
                        a.remove(*i);
                    }
                    _ => {}
                }
            }
        }
        // Replace it with an interesting value.
        1 | 2 => {
            if let Some(v) = at_mut(doc, &path) {
                *v = interesting(rng, doc_len);
            }
        }
        // Nudge a number: off by one (dangling indices), scaled, negated.
        3 => {
            if let Some(v) = at_mut(doc, &path)
                && let Some(n) = v.as_f64()
            {
                let k = rng.below(5);
                *v = match k {
                    0 => json!(n + 1.0),
                    1 => json!(n - 1.0),
                    2 => json!(n * 1000.0),
                    3 => json!(-n),
                    _ => json!(n + 100.0),
                };
                if let Some(i) = v.as_f64()
                    && i.fract() == 0.0
                    && i.abs() < 9e15
                {
                    *v = json!(i as i64);
                }
            }
        }
        // Splice in a value from elsewhere in the document.
        4 => {
            if let (Some(v), Some(d)) = (at_mut(doc, &path), donor) {
                *v = d;
            }
        }
        // Duplicate array elements (children listed twice, repeated primitives).
        5 => {
            if let Some(Value::Array(a)) = at_mut(doc, &path)
                && !a.is_empty()
            {
                let times = 1 + rng.below(3);
                for _ in 0..times {
                    let e = a[rng.below(a.len())].clone();
                    a.push(e);
                }
            }
        }
        // Make every node list the next one twice (a graph bomb), or add a cycle.
        6 => {
            if let Some(Value::Array(nodes)) = doc.get_mut("nodes") {
                let n = nodes.len();
                if n > 1 {
                    let i = rng.below(n);
                    let j = rng.below(n);
                    if let Some(o) = nodes[i].as_object_mut() {
                        o.insert("children".into(), json!([j, j]));
                    }
                }
            }
        }
        // Add an extension object or a required extension.
        _ => {
            if let Some(v) = at_mut(doc, &path)
                && let Some(o) = v.as_object_mut()
            {
                let ext = [
                    "KHR_texture_transform",
                    "KHR_materials_ior",
                    "KHR_materials_volume",
                    "KHR_lights_punctual",
                    "KHR_texture_basisu",
                    "EXT_texture_webp",
                ][rng.below(6)];
                o.insert(
                    "extensions".into(),
                    json!({ext: {"ior": 0.0, "offset": [1e39, 0], "thicknessFactor": -1, "light": 7, "source": rng.below(3)}}),
                );
            } else if let Some(o) = doc.as_object_mut() {
                o.insert(
                    "extensionsRequired".into(),
                    json!(["KHR_mesh_quantization"]),
                );
            }
        }
    }
}

/// Interesting 32-bit words for the binary chunk: NaN, ±inf, huge and boundary values.
const WORDS: [u32; 8] = [
    0x7FC0_0000,
    0x7F80_0000,
    0xFF80_0000,
    0xFFFF_FFFF,
    0x7F7F_FFFF,
    0x8000_0000,
    0x0000_0000,
    0x0001_0000,
];

/// Byte-level mutations: flipped bits, interesting words, cut or repeated ranges.
fn mutate_bytes(bytes: &mut Vec<u8>, rng: &mut Rng) {
    if bytes.is_empty() {
        bytes.push(0);
    }
    match rng.below(6) {
        0 => {
            let i = rng.below(bytes.len());
            bytes[i] ^= 1 << rng.below(8);
        }
        1 => {
            let i = rng.below(bytes.len()) & !3;
            let w = WORDS[rng.below(WORDS.len())].to_le_bytes();
            for (k, b) in w.iter().enumerate() {
                if let Some(x) = bytes.get_mut(i + k) {
                    *x = *b;
                }
            }
        }
        2 => {
            let i = rng.below(bytes.len());
            bytes.truncate(i);
        }
        3 => {
            let i = rng.below(bytes.len());
            let n = rng.below(64).min(bytes.len() - i);
            let copy = bytes[i..i + n].to_vec();
            let at = rng.below(bytes.len());
            bytes.splice(at..at, copy);
        }
        4 => {
            let i = rng.below(bytes.len());
            let n = rng.below(64).min(bytes.len() - i);
            bytes.drain(i..i + n);
        }
        _ => {
            let i = rng.below(bytes.len());
            bytes[i] = rng.next() as u8;
        }
    }
}

/// One input made from a seed; the name says how.
fn make_input(seed: &[u8], rng: &mut Rng) -> (&'static str, Vec<u8>) {
    let Some(mut glb) = split_glb(seed) else {
        let mut b = seed.to_vec();
        mutate_bytes(&mut b, rng);
        return ("bytes", b);
    };
    match rng.below(10) {
        0..=5 => {
            for _ in 0..1 + rng.below(3) {
                mutate_json(&mut glb.json, rng);
            }
            if rng.chance(30) {
                ("json", as_gltf(&glb))
            } else {
                ("json", penumbra::bench::generate::glb(&glb.json, &glb.bin))
            }
        }
        6 | 7 => {
            for _ in 0..1 + rng.below(8) {
                mutate_bytes(&mut glb.bin, rng);
            }
            ("bin", penumbra::bench::generate::glb(&glb.json, &glb.bin))
        }
        8 => {
            let mut b = as_gltf(&glb);
            for _ in 0..1 + rng.below(4) {
                mutate_bytes(&mut b, rng);
            }
            ("text", b)
        }
        _ => {
            let mut b = seed.to_vec();
            for _ in 0..1 + rng.below(4) {
                mutate_bytes(&mut b, rng);
            }
            ("bytes", b)
        }
    }
}

/// A folder the inputs' relative URIs resolve in: a small regular file and a link to
/// /dev/zero.
fn uri_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("small.bin"), [7u8; 64]).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.bin")).unwrap();
    dir
}

/// Poses `scene` at a few instants of each of its clips (before, inside and far past the
/// keys): mutated animation data must not make a pose panic.
fn pose_every_clip(mut scene: Scene) {
    let animation = scene.animation.clone();
    for clip in 0..animation.clips.len() {
        for t in [-1.0, 0.37, 1e9] {
            animation.apply(&mut scene, Some(clip), t);
        }
    }
}

/// What the renderer relies on in a loaded scene.
fn check(s: &Scene) -> Result<(), String> {
    let fin = |v: f32| v.is_finite();
    if s.triangle_count() > limits::MAX_TRIANGLES {
        return Err("more triangles than the limit".into());
    }
    for (i, o) in s.objects.iter().enumerate() {
        let m = &o.mesh;
        let n = m.positions.len();
        if m.indices.iter().flatten().any(|&v| v as usize >= n) {
            return Err(format!("object {i}: index out of range"));
        }
        if m.materials.len() != m.indices.len()
            || m.materials.iter().any(|&k| k as usize >= s.materials.len())
        {
            return Err(format!("object {i}: material out of range"));
        }
        for (what, len) in [
            ("normals", m.normals.len()),
            ("uvs", m.uvs.len()),
            ("uvs1", m.uvs1.len()),
        ] {
            if len != 0 && len != n {
                return Err(format!("object {i}: {what} do not match the positions"));
            }
        }
        if !m.tangents.is_empty() && m.tangents.len() != m.indices.len() {
            return Err(format!("object {i}: tangents do not match the triangles"));
        }
    }
    for t in s.world_triangles() {
        if !t.v.iter().all(|v| v.is_finite()) || !t.n.iter().all(|n| n.is_finite()) {
            return Err(format!(
                "object {}: a non-finite vertex or normal",
                t.object
            ));
        }
    }
    for (i, m) in s.materials.iter().enumerate() {
        let unit = |v: f32| (0.0..=1.0).contains(&v);
        let ok = m.base_color.iter().all(|&c| unit(c))
            && unit(m.metallic)
            && unit(m.roughness)
            && unit(m.transmission)
            && m.emission.iter().all(|&e| fin(e) && e >= 0.0)
            && fin(m.ior)
            && m.ior > 0.0
            && m.specular_color.iter().all(|&c| fin(c) && c >= 0.0)
            && unit(m.specular_factor)
            && fin(m.thickness)
            && m.thickness >= 0.0
            && m.attenuation_color.iter().all(|&c| unit(c))
            && m.attenuation_distance > 0.0
            && fin(m.normal_scale);
        if !ok {
            return Err(format!("material {i} is out of range: {m:?}"));
        }
        let t = &m.textures;
        for r in [
            t.base_color,
            t.metallic_roughness,
            t.normal,
            t.emissive,
            t.transmission,
        ]
        .into_iter()
        .flatten()
        {
            match s.texture_refs.get(r as usize) {
                Some(tr) if (tr.image as usize) < s.images.len() => {}
                _ => return Err(format!("material {i}: texture {r} out of range")),
            }
        }
    }
    for l in &s.lights {
        let ok = l.color.iter().all(|&c| fin(c) && c >= 0.0)
            && fin(l.intensity)
            && l.intensity >= 0.0
            && l.position.is_finite()
            && l.direction.is_finite();
        let cone = match l.kind {
            LightKind::Spot { inner, outer } => {
                0.0 <= inner && inner < outer && outer <= std::f32::consts::FRAC_PI_2
            }
            _ => true,
        };
        if !ok || !cone {
            return Err(format!("light {:?} is out of range", l.name));
        }
    }
    for c in &s.cameras {
        let ok = c.eye.is_finite()
            && c.forward.is_finite()
            && c.up.is_finite()
            && c.yfov > 0.0
            && c.yfov < std::f64::consts::PI;
        if !ok {
            return Err(format!("camera {:?} is out of range", c.name));
        }
    }
    Ok(())
}

/// Set while the loader runs (on any thread, rayon's included): its panics are failures
/// reported with their input, so the panic hook keeps them off stderr.
static IN_LOADER: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Loads `bytes` in-process; `Err` describes a failure (a panic, a broken scene, too slow).
fn run_one(bytes: &[u8], base: &Path) -> Result<(), String> {
    let start = Instant::now();
    IN_LOADER.store(true, std::sync::atomic::Ordering::Relaxed);
    let result = catch_unwind(AssertUnwindSafe(|| {
        load_from_bytes(bytes, Some(base), "fuzz input").inspect(|s| pose_every_clip(s.clone()))
    }));
    IN_LOADER.store(false, std::sync::atomic::Ordering::Relaxed);
    let elapsed = start.elapsed();
    let outcome = match result {
        Err(panic) => Err(format!(
            "panic: {}",
            panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("?")
        )),
        Ok(Err(message)) if message.contains('\n') => Err(format!("multi-line error: {message}")),
        Ok(Err(_)) => Ok(()),
        Ok(Ok(scene)) => check(&scene),
    };
    if outcome.is_ok() && elapsed > SLOW {
        return Err(format!("slow: {elapsed:?}"));
    }
    outcome
}

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-corpus")
}

/// FNV-1a, to name corpus files by content.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Saves a failing input in the corpus, named by its kind and content; returns the path.
fn save(kind: &str, input: &[u8]) -> PathBuf {
    let ext = if input.starts_with(b"glTF") {
        "glb"
    } else {
        "gltf"
    };
    let file = corpus_dir().join(format!("{kind}-{:016x}.{ext}", fnv(input)));
    std::fs::create_dir_all(corpus_dir()).unwrap();
    std::fs::write(&file, input).unwrap();
    file
}

/// Milliseconds since the Unix epoch.
fn now_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

/// When the load in progress started (ms since the epoch; 0 between loads), for the watchdog.
static LOAD_STARTED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Watches for a load that runs past [`HANG`]: saves the input being run (`last`) in the
/// corpus and ends the process with a failure.
fn watchdog(last: PathBuf) {
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_secs(1));
            let started = LOAD_STARTED.load(std::sync::atomic::Ordering::Relaxed);
            if started != 0 && now_ms().saturating_sub(started) > HANG.as_millis() as u64 {
                let input = std::fs::read(&last).unwrap_or_default();
                let file = save("hang", &input);
                let _ = std::fs::remove_file(&last);
                eprintln!(
                    "fuzz: a load ran past {HANG:?} (a hang); saved as {}\n\
                     fuzz summary: stopped by the hang",
                    file.display()
                );
                std::process::exit(101);
            }
        }
    });
}

#[test]
fn fuzz_the_loader() {
    let seconds: u64 = std::env::var("PENUMBRA_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let seed: u64 = std::env::var("PENUMBRA_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(1, |d| d.as_nanos() as u64)
        });
    eprintln!("fuzz: seed {seed}, {seconds} s (PENUMBRA_FUZZ_SEED, PENUMBRA_FUZZ_SECONDS)");
    let mut rng = Rng(seed);
    let seeds = seeds();
    let base = uri_folder();
    // The input being run, so that one which kills the process (a crash, out of memory) is
    // not lost: a run that ends normally removes it, so one found here killed its run.
    let last = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-last-input");
    let (mut runs, mut failures, mut new_entries) = (0u64, Vec::new(), Vec::new());
    let mut seen = std::collections::HashSet::new();
    if let Ok(input) = std::fs::read(&last) {
        seen.insert("died".to_string());
        let file = save("died", &input);
        eprintln!(
            "fuzz: the previous run died while loading {} (a crash, memory exhausted, or it \
             was stopped); saved as {}",
            last.display(),
            file.display()
        );
        failures.push(format!("{}: the previous run died on it", file.display()));
        new_entries.push(file);
    }
    watchdog(last.clone());
    let quiet = std::env::var_os("PENUMBRA_FUZZ_VERBOSE").is_none();
    if quiet {
        let report = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_LOADER.load(std::sync::atomic::Ordering::Relaxed) {
                report(info);
            }
        }));
    }
    let start = Instant::now();
    let deadline = start + Duration::from_secs(seconds);
    let mut next_progress = start + Duration::from_secs(300);
    let mut kinds = std::collections::BTreeMap::<&str, u64>::new();
    while Instant::now() < deadline {
        let (name, seed_bytes) = &seeds[rng.below(seeds.len())];
        let (kind, input) = make_input(seed_bytes, &mut rng);
        let _ = std::fs::write(&last, &input);
        runs += 1;
        *kinds.entry(kind).or_default() += 1;
        LOAD_STARTED.store(now_ms(), std::sync::atomic::Ordering::Relaxed);
        let outcome = run_one(&input, base.path());
        LOAD_STARTED.store(0, std::sync::atomic::Ordering::Relaxed);
        if let Err(why) = outcome {
            // One saved input per kind of failure (the message without its numbers).
            let class: String = why
                .chars()
                .filter(|c| !c.is_ascii_digit())
                .take(80)
                .collect();
            if !seen.insert(class) {
                failures.push(format!("(not saved, like one above) {why}"));
                continue;
            }
            let file = save(kind, &input);
            eprintln!(
                "fuzz: {name} ({kind}) fails: {why}\n      saved as {}",
                file.display()
            );
            failures.push(format!("{}: {why}", file.display()));
            new_entries.push(file);
        }
        if Instant::now() >= next_progress {
            next_progress += Duration::from_secs(300);
            eprintln!(
                "fuzz: {:.0} s, {runs} inputs, {} distinct failures",
                start.elapsed().as_secs_f64(),
                seen.len()
            );
        }
    }
    let _ = std::fs::remove_file(&last);
    if quiet {
        let _ = std::panic::take_hook();
    }
    let elapsed = start.elapsed().as_secs_f64();
    eprintln!(
        "fuzz summary: seed {seed}, {runs} executions in {elapsed:.0} s ({:.1} inputs/s; {}), \
         {} failing inputs, {} distinct failures, {} new corpus entries{}",
        runs as f64 / elapsed.max(1e-9),
        kinds
            .iter()
            .map(|(k, n)| format!("{k} {n}"))
            .collect::<Vec<_>>()
            .join(", "),
        failures.len(),
        seen.len(),
        new_entries.len(),
        new_entries
            .iter()
            .map(|f| format!("\n  {}", f.display()))
            .collect::<String>()
    );
    assert!(runs > 0);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_corpus_replays_cleanly() {
    let base = uri_folder();
    let Ok(entries) = std::fs::read_dir(corpus_dir()) else {
        return;
    };
    let mut failures = Vec::new();
    let mut count = 0;
    for e in entries.flatten() {
        let bytes = std::fs::read(e.path()).unwrap();
        count += 1;
        if let Err(why) = run_one(&bytes, base.path()) {
            failures.push(format!("{}: {why}", e.path().display()));
        }
    }
    eprintln!("replayed {count} corpus inputs");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
