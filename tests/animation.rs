//! Animation: every interpolation mode and a looping clip on fixtures the tests write; poses of
//! the shared animated scenes (Fox, CesiumMan, BrainStem, AnimatedMorphCube) against an
//! evaluation written here from the glTF JSON and buffer bytes alone (not the importer);
//! hostile animation data; and renders: an animated scene at time t against the same pose
//! baked into a static file, and a sequence's frames against single renders.

mod common;

use common::{Gltf, Prim, cuboid, penumbra, scenes_dir};
use glam::{DMat4, DQuat, DVec3, Vec3};
use penumbra::scene::{Scene, load, load_from_bytes};
use serde_json::{Value, json};
use std::path::Path;

/// Adds a SCALAR float accessor.
fn scalars(g: &mut Gltf, values: &[f32]) -> usize {
    let bytes: Vec<u8> = values.iter().flat_map(|f| f.to_le_bytes()).collect();
    let view = g.bytes_view(&bytes);
    g.accessors
        .push(json!({"bufferView": view, "componentType": 5126,
        "count": values.len(), "type": "SCALAR",
        "min": [values.iter().copied().fold(f32::INFINITY, f32::min)],
        "max": [values.iter().copied().fold(f32::NEG_INFINITY, f32::max)]}));
    g.accessors.len() - 1
}

/// A clip of one sampler driving `path` of `node`.
fn clip(name: &str, node: usize, path: &str, interp: &str, input: usize, output: usize) -> Value {
    json!({"name": name,
        "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
        "samplers": [{"input": input, "output": output, "interpolation": interp}]})
}

/// The fixture of every interpolation: one triangle node (0) with a mesh whose one morph
/// target lifts every vertex by 1 in z, and clips: "step", "linear", "cubic" (translation),
/// "turn" (rotation, the second key on the far hemisphere), "weights".
fn interpolation_fixture() -> Gltf {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![Prim::triangles(
        vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![0, 1, 2],
        0,
    )]);
    let up = g.float_accessor(&[[0.0, 0.0, 1.0]; 3]);
    g.meshes[m]["primitives"][0]["targets"] = json!([{"POSITION": up}]);
    g.node(json!({"mesh": m}));
    let times = scalars(&mut g, &[0.0, 1.0, 2.0]);
    let moves = g.float_accessor(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]]);
    let two = scalars(&mut g, &[0.0, 2.0]);
    // Cubic: in tangent, value, out tangent per key; x leaves 0 at 1.5 a second, arrives at 1
    // flat.
    let spline = g.float_accessor(&[
        [9.0, 9.0, 9.0],
        [0.0, 0.0, 0.0],
        [1.5, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [7.0, 7.0, 7.0],
    ]);
    let (s, c) = (
        std::f32::consts::FRAC_PI_4.sin(),
        std::f32::consts::FRAC_PI_4.cos(),
    );
    // Identity, then 90° about y written negated (the same rotation from the other side).
    let turn = g.float_accessor(&[[0.0, 0.0, 0.0, 1.0], [0.0, -s, 0.0, -c]]);
    let unit = scalars(&mut g, &[0.0, 1.0]);
    let weights = scalars(&mut g, &[0.0, 1.0]);
    g.extra.insert(
        "animations".into(),
        json!([
            clip("step", 0, "translation", "STEP", times, moves),
            clip("linear", 0, "translation", "LINEAR", times, moves),
            clip("cubic", 0, "translation", "CUBICSPLINE", two, spline),
            clip("turn", 0, "rotation", "LINEAR", unit, turn),
            clip("weights", 0, "weights", "LINEAR", unit, weights),
        ]),
    );
    g
}

/// The world position of vertex `v` of object 0 after posing `scene` at `t` of `clip`.
fn posed_vertex(scene: &mut Scene, clip: usize, t: f64, v: usize) -> DVec3 {
    let animation = scene.animation.clone();
    animation.apply(scene, Some(clip), t);
    let o = &scene.objects[0];
    o.world_from_object
        .transform_point3(o.mesh.positions[v].as_dvec3())
}

fn assert_near(got: DVec3, want: DVec3, what: &str) {
    assert!(
        (got - want).abs().max_element() < 1e-5,
        "{what}: got {got}, want {want}"
    );
}

#[test]
fn every_interpolation_mode_gives_the_keyframes_and_what_lies_between() {
    let g = interpolation_fixture();
    let mut scene = load_from_bytes(&g.glb(), None, "fixture").unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let names: Vec<(&str, f64)> = scene
        .animation
        .clips
        .iter()
        .map(|c| (c.name.as_str(), c.duration))
        .collect();
    assert_eq!(
        names,
        [
            ("step", 2.0),
            ("linear", 2.0),
            ("cubic", 2.0),
            ("turn", 1.0),
            ("weights", 1.0)
        ]
    );
    let x = DVec3::X;
    // STEP holds the earlier key until the next; before and after the keys, the ends.
    for (t, want) in [
        (-1.0, 0.0),
        (0.5, 0.0),
        (1.0, 1.0),
        (1.99, 1.0),
        (2.0, 3.0),
        (9.0, 3.0),
    ] {
        let p = posed_vertex(&mut scene, 0, t, 0);
        assert_near(p, x + DVec3::new(want, 0.0, 0.0), &format!("step at {t}"));
    }
    // LINEAR: straight between keys.
    for (t, want) in [(0.5, 0.5), (1.5, 2.0), (1.75, 2.5)] {
        let p = posed_vertex(&mut scene, 1, t, 0);
        assert_near(p, x + DVec3::new(want, 0.0, 0.0), &format!("linear at {t}"));
    }
    // CUBICSPLINE: the Hermite spline with tangents times the interval (2 s); the first
    // key's in tangent and the last's out tangent (9, 7) play no part.
    for t in [0.0, 0.5, 1.0, 1.5, 2.0] {
        let (dt, u) = (2.0, t / 2.0);
        let h10 = u * u * u - 2.0 * u * u + u;
        let h01 = -2.0 * u * u * u + 3.0 * u * u;
        let want = h10 * dt * 1.5 + h01 * 1.0;
        let p = posed_vertex(&mut scene, 2, t, 0);
        assert_near(p, x + DVec3::new(want, 0.0, 0.0), &format!("cubic at {t}"));
    }
    // Rotation: the shorter arc, so half way is 45° about +y (x = (1,0,0) goes to
    // (cos 45°, 0, −sin 45°)), not the long way round.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert_near(
        posed_vertex(&mut scene, 3, 0.5, 0),
        DVec3::new(h, 0.0, -h),
        "slerp",
    );
    assert_near(
        posed_vertex(&mut scene, 3, 1.0, 0),
        DVec3::new(0.0, 0.0, -1.0),
        "turn end",
    );
    // Weights: the morph target at the animated weight.
    for t in [0.0, 0.25, 1.0] {
        assert_near(
            posed_vertex(&mut scene, 4, t, 1),
            DVec3::new(0.0, 1.0, t),
            &format!("weights at {t}"),
        );
    }
    // Back at the rest pose: where the file placed it, weight 0.
    scene.animation.clone().apply(&mut scene, None, 0.0);
    assert_eq!(scene.objects[0].mesh.positions[1], Vec3::Y);
    assert_eq!(scene.objects[0].world_from_object, DMat4::IDENTITY);
}

#[test]
fn a_looping_clip_wraps_its_time_and_a_held_one_stops_at_its_ends() {
    let g = interpolation_fixture();
    let mut scene = load_from_bytes(&g.glb(), None, "fixture").unwrap();
    let animation = scene.animation.clone();
    // "linear" lasts 2 s: 2.5 s into a loop is 0.5 s into the clip, −0.5 s is 1.5 s.
    assert_eq!(animation.clip_time(1, 2.5, true), 0.5);
    assert_eq!(animation.clip_time(1, -0.5, true), 1.5);
    assert_eq!(animation.clip_time(1, 4.0, true), 0.0);
    assert_eq!(animation.clip_time(1, 2.5, false), 2.0);
    let t = animation.clip_time(1, 5.5, true);
    assert_near(
        posed_vertex(&mut scene, 1, t, 0),
        DVec3::new(3.0, 0.0, 0.0),
        "5.5 s into the loop (1.5 s: x = 2, vertex at 1 + 2)",
    );
}

#[test]
fn hostile_animation_data_warns_once_a_channel_and_keeps_the_good_ones() {
    let mut g = interpolation_fixture();
    let bad_times = scalars(&mut g, &[0.0, 1.0, 1.0]);
    let nan = g.float_accessor(&[[f32::NAN, 0.0, 0.0], [0.0, 0.0, 0.0]]);
    let short = g.float_accessor(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    let two = scalars(&mut g, &[0.0, 1.0]);
    let three = scalars(&mut g, &[0.0, 1.0, 2.0]);
    let good = g.float_accessor(&[[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]]);
    g.extra.insert(
        "animations".into(),
        json!([{"name": "hostile",
        "channels": [
            {"sampler": 7, "target": {"node": 0, "path": "translation"}},
            {"sampler": 0, "target": {"node": 0, "path": "scale"}},
            {"sampler": 1, "target": {"node": 0, "path": "scale"}},
            {"sampler": 2, "target": {"node": 0, "path": "scale"}},
            {"sampler": 3, "target": {"node": 42, "path": "scale"}},
            {"sampler": 4, "target": {"node": 0, "path": "translation"}},
            {"sampler": 5, "target": {"node": 0, "path": "scale"}},
        ],
        "samplers": [
            {"input": bad_times, "output": short},
            {"input": two, "output": nan},
            {"input": three, "output": short},
            {"input": two, "output": short},
            {"input": two, "output": good},
            {"input": 999, "output": good},
        ]}]),
    );
    let mut scene = load_from_bytes(&g.glb(), None, "hostile").unwrap();
    let warned: Vec<&String> = scene
        .warnings
        .iter()
        .filter(|w| w.starts_with("animations[0]"))
        .collect();
    for (c, why) in [
        (0, "sampler 7 does not exist"),
        (1, "does not come after"),
        (2, "not finite"),
        (3, "values for 3 keys"),
        (4, "node 42 does not exist"),
        (6, "accessor 999 does not exist"),
    ] {
        let at = format!("animations[0].channels[{c}]");
        let lines: Vec<_> = warned
            .iter()
            .filter(|w| {
                w.strip_prefix(&at)
                    .is_some_and(|r| r.starts_with([':', '.']))
            })
            .collect();
        assert_eq!(lines.len(), 1, "one warning for channel {c}: {warned:?}");
        assert!(lines[0].contains(why), "{}", lines[0]);
    }
    assert_eq!(warned.len(), 6, "{warned:?}");
    // The good channel (5) still plays.
    assert_near(
        posed_vertex(&mut scene, 0, 0.5, 0),
        DVec3::new(3.0, 0.0, 0.0),
        "the good channel half way",
    );
}

/// A glTF file read by hand: its JSON and binary chunk, and accessors read as f64 rows.
struct Raw {
    json: Value,
    bin: Vec<u8>,
}

impl Raw {
    fn open(path: &Path) -> Raw {
        let bytes = std::fs::read(path).unwrap();
        assert_eq!(&bytes[0..4], b"glTF", "{} is a GLB file", path.display());
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let json_len = word(12);
        let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        let bin_at = 20 + json_len;
        let bin_len = word(bin_at);
        Raw {
            json,
            bin: bytes[bin_at + 8..bin_at + 8 + bin_len].to_vec(),
        }
    }

    /// Accessor `index` as rows of components (floats, or normalized integers scaled).
    fn read(&self, index: usize) -> Vec<Vec<f64>> {
        let a = &self.json["accessors"][index];
        let count = a["count"].as_u64().unwrap() as usize;
        let width = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            t => panic!("type {t}"),
        };
        let kind = a["componentType"].as_u64().unwrap();
        let size = match kind {
            5126 => 4,
            5121 | 5120 => 1,
            5123 | 5122 => 2,
            k => panic!("component type {k}"),
        };
        let normalized = a["normalized"].as_bool().unwrap_or(false);
        let view = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let stride = view["byteStride"]
            .as_u64()
            .map_or(width * size, |s| s as usize);
        (0..count)
            .map(|i| {
                (0..width)
                    .map(|c| {
                        let at = start + i * stride + c * size;
                        let b = &self.bin[at..at + size];
                        match kind {
                            5126 => f32::from_le_bytes(b.try_into().unwrap()) as f64,
                            5121 if normalized => b[0] as f64 / 255.0,
                            5121 => b[0] as f64,
                            5123 if normalized => {
                                u16::from_le_bytes(b.try_into().unwrap()) as f64 / 65535.0
                            }
                            5123 => u16::from_le_bytes(b.try_into().unwrap()) as f64,
                            k => panic!("component type {k} here"),
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// Each node's local matrix at time `t` of animation `clip` (`None`: rest), by the glTF
    /// rules written out again: TRS, channels sampled (STEP, LINEAR with shortest-path slerp,
    /// CUBICSPLINE), matrices where given.
    fn locals(&self, clip: Option<usize>, t: f64) -> Vec<DMat4> {
        let nodes = self.json["nodes"].as_array().unwrap();
        let num = |v: &Value, n: usize, d: &[f64]| -> Vec<f64> {
            v.as_array()
                .map(|a| a.iter().map(|x| x.as_f64().unwrap()).collect())
                .unwrap_or_else(|| d[..n].to_vec())
        };
        let mut trs: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = nodes
            .iter()
            .map(|n| {
                (
                    num(&n["translation"], 3, &[0.0; 3]),
                    num(&n["rotation"], 4, &[0.0, 0.0, 0.0, 1.0]),
                    num(&n["scale"], 3, &[1.0; 3]),
                )
            })
            .collect();
        if let Some(c) = clip {
            let anim = &self.json["animations"][c];
            for ch in anim["channels"].as_array().unwrap() {
                let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
                let times: Vec<f64> = self
                    .read(s["input"].as_u64().unwrap() as usize)
                    .into_iter()
                    .map(|r| r[0])
                    .collect();
                let out = self.read(s["output"].as_u64().unwrap() as usize);
                let node = ch["target"]["node"].as_u64().unwrap() as usize;
                let path = ch["target"]["path"].as_str().unwrap();
                if path == "weights" {
                    continue;
                }
                let interp = s["interpolation"].as_str().unwrap_or("LINEAR");
                let v = sample(&times, &out, interp, path == "rotation", t);
                match path {
                    "translation" => trs[node].0 = v,
                    "rotation" => trs[node].1 = v,
                    _ => trs[node].2 = v,
                }
            }
        }
        nodes
            .iter()
            .zip(trs)
            .map(|(n, (t, r, s))| {
                if let Some(m) = n["matrix"].as_array() {
                    let m: Vec<f64> = m.iter().map(|x| x.as_f64().unwrap()).collect();
                    return DMat4::from_cols_slice(&m);
                }
                DMat4::from_scale_rotation_translation(
                    DVec3::from_slice(&s),
                    DQuat::from_slice(&r).normalize(),
                    DVec3::from_slice(&t),
                )
            })
            .collect()
    }

    /// World matrices from `locals`, down the children lists.
    fn worlds(&self, locals: &[DMat4]) -> Vec<DMat4> {
        let nodes = self.json["nodes"].as_array().unwrap();
        let mut worlds = locals.to_vec();
        fn down(n: usize, parent: DMat4, nodes: &[Value], locals: &[DMat4], out: &mut [DMat4]) {
            out[n] = parent * locals[n];
            for c in nodes[n]["children"].as_array().into_iter().flatten() {
                down(c.as_u64().unwrap() as usize, out[n], nodes, locals, out);
            }
        }
        let children: Vec<u64> = nodes
            .iter()
            .flat_map(|n| n["children"].as_array().cloned().unwrap_or_default())
            .map(|c| c.as_u64().unwrap())
            .collect();
        for n in 0..nodes.len() {
            if !children.contains(&(n as u64)) {
                down(n, DMat4::IDENTITY, nodes, locals, &mut worlds);
            }
        }
        worlds
    }
}

/// A channel's value at `t`: keys `times`, rows `out` (three a key for a cubic spline).
fn sample(times: &[f64], out: &[Vec<f64>], interp: &str, rotation: bool, t: f64) -> Vec<f64> {
    let cubic = interp == "CUBICSPLINE";
    let value = |k: usize| out[if cubic { 3 * k + 1 } else { k }].clone();
    let n = times.len();
    if t <= times[0] {
        return value(0);
    }
    if t >= times[n - 1] {
        return value(n - 1);
    }
    let k = (0..n - 1).find(|&k| times[k + 1] > t).unwrap();
    let (a, b) = (value(k), value(k + 1));
    let dt = times[k + 1] - times[k];
    let u = (t - times[k]) / dt;
    match interp {
        "STEP" => a,
        "CUBICSPLINE" => {
            let (m0, m1) = (&out[3 * k + 2], &out[3 * (k + 1)]);
            let v: Vec<f64> = (0..a.len())
                .map(|c| {
                    (2.0 * u.powi(3) - 3.0 * u * u + 1.0) * a[c]
                        + (u.powi(3) - 2.0 * u * u + u) * dt * m0[c]
                        + (-2.0 * u.powi(3) + 3.0 * u * u) * b[c]
                        + (u.powi(3) - u * u) * dt * m1[c]
                })
                .collect();
            if rotation {
                DQuat::from_slice(&v).normalize().to_array().to_vec()
            } else {
                v
            }
        }
        _ if rotation => {
            // Slerp written from its definition, along the shorter arc.
            let qa = DQuat::from_slice(&a);
            let mut qb = DQuat::from_slice(&b);
            let mut d = qa.dot(qb);
            if d < 0.0 {
                qb = -qb;
                d = -d;
            }
            let q = if d > 0.9999999 {
                qa.lerp(qb, u)
            } else {
                let th = d.acos();
                qa * (((1.0 - u) * th).sin() / th.sin()) + qb * ((u * th).sin() / th.sin())
            };
            q.normalize().to_array().to_vec()
        }
        _ => (0..a.len()).map(|c| a[c] + (b[c] - a[c]) * u).collect(),
    }
}

/// Checks the pose of `file` at several times of each of its clips against [`Raw`]'s own
/// evaluation: every joint's world matrix and, for each skinned object, the first
/// primitive's vertices at a few indices (`Σ weight × world(joint) × inverse bind × position`).
fn check_skinned_scene(relative: &str) {
    let Some(dir) = scenes_dir() else {
        eprintln!("PENUMBRA_SCENES not set: skipped");
        return;
    };
    let path = dir.join(relative);
    let raw = Raw::open(&path);
    let mut scene = load(&path).unwrap();
    let animation = scene.animation.clone();
    let clips = raw.json["animations"].as_array().unwrap().len();
    assert_eq!(animation.clips.len(), clips);
    let extent = scene.bounds().diagonal();
    let skins = raw.json["skins"].as_array().unwrap();
    let mut checked = 0;
    for c in 0..clips {
        let duration = animation.clips[c].duration;
        for t in [0.0, 0.37 * duration, 0.81 * duration] {
            let worlds = raw.worlds(&raw.locals(Some(c), t));
            let pose = animation.evaluate(Some(c), t);
            for skin in skins {
                for j in skin["joints"].as_array().unwrap() {
                    let j = j.as_u64().unwrap() as usize;
                    let (a, b) = (pose.worlds[j], worlds[j]);
                    let diff = (a - b)
                        .to_cols_array()
                        .iter()
                        .fold(0.0f64, |m, x| m.max(x.abs()));
                    assert!(
                        diff < 1e-6 * extent.max(1.0),
                        "clip {c} t {t} joint {j}: {a} vs {b}"
                    );
                }
            }
            animation.apply(&mut scene, Some(c), t);
            for d in &animation.objects {
                let node = &raw.json["nodes"][d.node];
                let Some(skin) = node["skin"].as_u64() else {
                    continue;
                };
                let skin = &skins[skin as usize];
                let prim =
                    &raw.json["meshes"][node["mesh"].as_u64().unwrap() as usize]["primitives"][0];
                let attr = |name: &str| prim["attributes"][name].as_u64().unwrap() as usize;
                let positions = raw.read(attr("POSITION"));
                let joints = raw.read(attr("JOINTS_0"));
                let weights = raw.read(attr("WEIGHTS_0"));
                let binds = raw.read(skin["inverseBindMatrices"].as_u64().unwrap() as usize);
                let names: Vec<usize> = skin["joints"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|j| j.as_u64().unwrap() as usize)
                    .collect();
                let n = positions.len();
                for v in [0, n / 3, n / 2, n - 1] {
                    let p = DVec3::from_slice(&positions[v]);
                    let mut want = DVec3::ZERO;
                    for k in 0..4 {
                        let w = weights[v][k];
                        if w == 0.0 {
                            continue;
                        }
                        let j = joints[v][k] as usize;
                        let m = worlds[names[j]] * DMat4::from_cols_slice(&binds[j]);
                        want += w * m.transform_point3(p);
                    }
                    let o = &scene.objects[d.object];
                    let got = o
                        .world_from_object
                        .transform_point3(o.mesh.positions[v].as_dvec3());
                    assert!(
                        (got - want).length() < 1e-4 * extent,
                        "{relative} clip {c} t {t:.3} vertex {v}: got {got}, want {want}"
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 0, "{relative}: some skinned vertex was checked");
}

#[test]
fn the_fox_follows_its_joints_in_every_clip() {
    check_skinned_scene("Fox/Fox.glb");
}

#[test]
fn cesium_man_follows_its_joints() {
    check_skinned_scene("khronos/CesiumMan/glTF-Binary/CesiumMan.glb");
}

#[test]
fn brain_stem_follows_its_joints() {
    check_skinned_scene("khronos/BrainStem/glTF-Binary/BrainStem.glb");
}

#[test]
fn the_morph_cube_follows_its_animated_weights() {
    let Some(dir) = scenes_dir() else {
        eprintln!("PENUMBRA_SCENES not set: skipped");
        return;
    };
    let path = dir.join("khronos/AnimatedMorphCube/glTF-Binary/AnimatedMorphCube.glb");
    let raw = Raw::open(&path);
    let mut scene = load(&path).unwrap();
    let animation = scene.animation.clone();
    let anim = &raw.json["animations"][0];
    let ch = &anim["channels"][0];
    assert_eq!(ch["target"]["path"], "weights");
    let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
    let times: Vec<f64> = raw
        .read(s["input"].as_u64().unwrap() as usize)
        .into_iter()
        .map(|r| r[0])
        .collect();
    let flat: Vec<f64> = raw
        .read(s["output"].as_u64().unwrap() as usize)
        .into_iter()
        .map(|r| r[0])
        .collect();
    let node = ch["target"]["node"].as_u64().unwrap() as usize;
    let prim = &raw.json["meshes"][raw.json["nodes"][node]["mesh"].as_u64().unwrap() as usize]["primitives"]
        [0];
    let targets = prim["targets"].as_array().unwrap();
    let per_key = targets.len();
    let rows: Vec<Vec<f64>> = flat.chunks(per_key).map(<[f64]>::to_vec).collect();
    let base = raw.read(prim["attributes"]["POSITION"].as_u64().unwrap() as usize);
    let deltas: Vec<Vec<Vec<f64>>> = targets
        .iter()
        .map(|t| raw.read(t["POSITION"].as_u64().unwrap() as usize))
        .collect();
    let d = animation
        .objects
        .iter()
        .find(|d| d.node == node)
        .expect("the morphed node is driven");
    let end = *times.last().unwrap();
    for t in [0.1 * end, 0.5 * end, 0.77 * end] {
        let interp = s["interpolation"].as_str().unwrap_or("LINEAR");
        let w = sample(&times, &rows, interp, false, t);
        animation.apply(&mut scene, Some(0), t);
        let mesh = &scene.objects[d.object].mesh;
        for v in [0, base.len() / 2, base.len() - 1] {
            let mut want = DVec3::from_slice(&base[v]);
            for (k, delta) in deltas.iter().enumerate() {
                want += w[k] * DVec3::from_slice(&delta[v]);
            }
            let got = mesh.positions[v].as_dvec3();
            assert!(
                (got - want).length() < 1e-5,
                "t {t} vertex {v}: {got} vs {want}"
            );
        }
    }
}

/// A lit room-less scene for renders: a floor, a box (node 1) that the clip "move" slides
/// along x (LINEAR from 0 at 0 s to 1 at 1 s) and turns (STEP: 90° about y from 0.5 s), a
/// camera and a point light. With `at`, the box is instead placed where the clip has it at
/// `at` seconds, and there is no clip (the values at 0.25 and 0.75 s are exact in binary).
fn render_fixture(at: Option<f64>) -> Gltf {
    let mut g = Gltf::default();
    let white = g.lambert([0.7; 3], [0.0; 3], 1.0, false);
    let (floor, floor_idx) = cuboid([-3.0, -0.1, -3.0], [3.0, 0.0, 3.0]);
    let f = g.mesh(vec![Prim::triangles(floor, floor_idx, white)]);
    g.node(json!({"mesh": f}));
    let (cube, cube_idx) = cuboid([-0.4, 0.0, -0.2], [0.4, 0.6, 0.2]);
    let c = g.mesh(vec![Prim::triangles(cube, cube_idx, white)]);
    // The quarter turn as the file's f32 keys hold it (what the baked node must say too).
    let (s, h) = (
        std::f32::consts::FRAC_1_SQRT_2,
        std::f32::consts::FRAC_1_SQRT_2,
    );
    match at {
        Some(t) => {
            let rotation = if t >= 0.5 {
                [0.0, f64::from(s), 0.0, f64::from(h)]
            } else {
                [0.0, 0.0, 0.0, 1.0]
            };
            g.node(json!({"mesh": c, "translation": [t, 0.0, 0.0], "rotation": rotation}))
        }
        None => g.node(json!({"mesh": c})),
    };
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.5, 1.5, 4.0], "rotation": [-0.17364818, 0.0, 0.0, 0.98480775]}));
    g.lights
        .push(json!({"type": "point", "intensity": 30.0, "color": [1.0, 1.0, 1.0]}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1.0, 3.0, 1.0]}));
    if at.is_none() {
        let times = scalars(&mut g, &[0.0, 1.0]);
        let moves = g.float_accessor(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
        let turn_times = scalars(&mut g, &[0.0, 0.5]);
        let turns = g.float_accessor(&[[0.0, 0.0, 0.0, 1.0], [0.0, s, 0.0, h]]);
        g.extra.insert(
            "animations".into(),
            json!([{"name": "move",
                "channels": [
                    {"sampler": 0, "target": {"node": 1, "path": "translation"}},
                    {"sampler": 1, "target": {"node": 1, "path": "rotation"}}],
                "samplers": [
                    {"input": times, "output": moves},
                    {"input": turn_times, "output": turns, "interpolation": "STEP"}]}]),
        );
    }
    g
}

/// Renders `scene` to `out` with `extra` options at a small size; the summary lines.
fn render(scene: &Path, out: &Path, extra: &[&str]) -> Vec<Value> {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend(["--width", "64", "--height", "48", "--spp", "4"]);
    args.extend(extra);
    let o = penumbra(&args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The animated scene at 0.75 s renders bit for bit like the same pose written as a static
/// file (same seed, same device): the box slid three quarters along and turned.
#[test]
fn an_animated_instant_renders_like_its_pose_baked_into_a_static_file() {
    let dir = tempfile::tempdir().unwrap();
    let animated = render_fixture(None).write_glb(dir.path(), "animated");
    let baked = render_fixture(Some(0.75)).write_glb(dir.path(), "baked");
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    let summary = &render(&animated, &a, &["--time", "0.75"])[0];
    assert_eq!(summary["clip"], "move");
    assert_eq!(summary["time"], 0.75);
    assert_eq!(summary["clips"], json!([{"name": "move", "duration": 1.0}]));
    render(&baked, &b, &[]);
    let (a, b) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert!(a == b, "the animated and the baked renders differ");
    // And the rest pose is another image: the box did move.
    let rest = dir.path().join("rest.exr");
    render(&animated, &rest, &[]);
    assert!(
        std::fs::read(&rest).unwrap() != a,
        "the rest pose differs from 0.75 s"
    );
}

/// A sequence renders each frame as a single render of that instant would (same seed), one
/// summary line a frame, files named by the frame number; a name without # is refused.
#[test]
fn a_sequence_renders_each_frame_as_its_instant() {
    let dir = tempfile::tempdir().unwrap();
    let scene = render_fixture(None).write_glb(dir.path(), "animated");
    let pattern = dir.path().join("f_##.exr");
    let lines = render(&scene, &pattern, &["--frames", "1..3", "--fps", "4"]);
    assert_eq!(lines.len(), 3);
    for (k, line) in lines.iter().enumerate() {
        assert_eq!(line["frame"], k + 1);
        assert_eq!(line["time"], (k + 1) as f64 / 4.0);
    }
    assert!(lines[1]["scene_update_ms"].as_f64().is_some());
    let single = dir.path().join("single.exr");
    render(&scene, &single, &["--time", "0.75"]);
    let frame3 = std::fs::read(dir.path().join("f_03.exr")).unwrap();
    assert!(
        frame3 == std::fs::read(&single).unwrap(),
        "frame 3 is the instant 0.75 s"
    );
    assert!(frame3 != std::fs::read(dir.path().join("f_01.exr")).unwrap());
    // No # in the name: one line, exit code 1, nothing rendered.
    let o = penumbra(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        "x.exr",
        "--frames",
        "0..2",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("needs #s"), "{err}");
    // An unknown clip names the clips there are.
    let o = penumbra(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        single.to_str().unwrap(),
        "--clip",
        "run",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("0 'move'"));
}

/// A glowing bar (x from -0.3 to 0.3) that the clip "slide" moves along +x by 0.6 a second
/// for 2 s (LINEAR), seen straight on from z = 3 against black, with no other light.
fn sliding_bar() -> Gltf {
    let mut g = Gltf::default();
    let glow = g.lambert([0.0; 3], [1.0; 3], 1.0, false);
    let (bar, bar_idx) = cuboid([-0.3, -0.2, -0.1], [0.3, 0.2, 0.1]);
    let b = g.mesh(vec![Prim::triangles(bar, bar_idx, glow)]);
    g.node(json!({"mesh": b}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.3, 0.0, 3.0]}));
    let times = scalars(&mut g, &[0.0, 2.0]);
    let moves = g.float_accessor(&[[0.0, 0.0, 0.0], [1.2, 0.0, 0.0]]);
    g.extra.insert(
        "animations".into(),
        json!([{"name": "slide",
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
            "samplers": [{"input": times, "output": moves}]}]),
    );
    g
}

/// The mean brightness of each column of the image's middle row band (64 × 48 pixels).
fn column_profile(px: &[[f32; 3]]) -> Vec<f64> {
    (0..64)
        .map(|x| {
            (20..28)
                .map(|y| px[y * 64 + x].iter().map(|&c| f64::from(c)).sum::<f64>())
                .sum::<f64>()
                / 8.0
        })
        .collect()
}

/// The first and last columns brighter than `level`.
fn lit_extent(profile: &[f64], level: f64) -> (usize, usize) {
    let lit: Vec<usize> = (0..profile.len()).filter(|&x| profile[x] > level).collect();
    (lit[0], *lit.last().unwrap())
}

/// With `--shutter 0.5` the bar (travelling half its width) is smeared from where it is at
/// 0 s to where it is at 0.5 s: the
/// blurred image is lit from the left edge of the first pose to the right edge of the last,
/// the columns the bar only crosses lie between black and its full brightness and fall off
/// across the travel, and the columns it covers all along are as bright as the still bar.
/// `--shutter 0` is the render without a shutter, bit for bit.
#[test]
fn a_shutter_smears_a_moving_bar_between_its_start_and_end() {
    let dir = tempfile::tempdir().unwrap();
    let scene = sliding_bar().write_glb(dir.path(), "bar");
    let opts = |extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = [
            "--width",
            "64",
            "--height",
            "48",
            "--spp",
            "32",
            "--background",
            "0,0,0",
            "--env",
            "none",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |name: &str, extra: &[&str]| {
        let o = opts(extra);
        let o: Vec<&str> = o.iter().map(String::as_str).collect();
        common::render_exr(&scene, &dir.path().join(name), &o)
    };
    let (_, start) = run("start.exr", &["--time", "0"]);
    let (_, end) = run("end.exr", &["--time", "0.5"]);
    let (summary, blur) = run("blur.exr", &["--time", "0", "--shutter", "0.5"]);
    assert_eq!(summary["shutter"], 0.5);
    let (start, end, blur) = (
        column_profile(&start),
        column_profile(&end),
        column_profile(&blur),
    );
    let full = start.iter().copied().fold(0.0, f64::max);
    let level = 0.02 * full;
    let (a0, a1) = lit_extent(&start, level);
    let (b0, b1) = lit_extent(&end, level);
    let (s0, s1) = lit_extent(&blur, level);
    eprintln!("start {a0}..{a1}, end {b0}..{b1}, blurred {s0}..{s1}");
    assert!(
        b0 > a0 + 5 && b0 + 4 < a1,
        "the bar moves half its width: {a0}..{a1} -> {b0}..{b1}"
    );
    assert!(
        s0.abs_diff(a0) <= 1 && s1.abs_diff(b1) <= 1,
        "smeared {s0}..{s1}"
    );
    // Covered all along (lit at the start and at the end): as bright as the still bar.
    let covered: Vec<f64> = blur[b0 + 1..a1].iter().map(|b| b / full).collect();
    assert!(covered.iter().all(|f| (f - 1.0).abs() < 0.1), "{covered:?}");
    // Crossed only: partly lit, less the further right (the bar arrives later).
    let crossed: Vec<f64> = blur[a1 + 2..b1 - 1].iter().map(|b| b / full).collect();
    assert!(crossed.len() >= 4, "{crossed:?}");
    assert!(crossed.iter().all(|&f| f > 0.03 && f < 0.97), "{crossed:?}");
    assert!(crossed[0] > crossed[crossed.len() - 1] + 0.3, "{crossed:?}");
    // A shutter of 0 is no shutter.
    run("none.exr", &["--time", "0.5"]);
    run("zero.exr", &["--time", "0.5", "--shutter", "0"]);
    assert!(
        std::fs::read(dir.path().join("none.exr")).unwrap()
            == std::fs::read(dir.path().join("zero.exr")).unwrap()
    );
}

/// Frames of the Fox after the first are brought up to date by refitting the flat BVH (the
/// summary says so), and each is bit for bit the single render of its instant, which loads
/// the pose afresh and builds its BVH anew (same seed, same device).
#[test]
fn the_foxs_refitted_frames_are_its_fresh_renders() {
    fox_frames_refit_as_fresh_renders("flat");
}

/// On two levels the Fox's skinned mesh has its BLAS refitted in its own space (the summary
/// says "refitted", not "reloaded"), and each frame is bit for bit its fresh render on two
/// levels, whose BLAS is built anew.
#[test]
fn the_foxs_frames_on_two_levels_refit_its_blas_and_are_its_fresh_renders() {
    fox_frames_refit_as_fresh_renders("two-level");
}

/// Renders frames 2 to 4 of the Fox's Run clip with `--bvh bvh`, checks that the later ones
/// were refits, and compares frames 3 and 4 with single renders of their instants.
fn fox_frames_refit_as_fresh_renders(bvh: &str) {
    let Some(scenes) = scenes_dir() else {
        eprintln!("skipped: PENUMBRA_SCENES is not set");
        return;
    };
    let fox = scenes.join("Fox/Fox.glb");
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("fox_#.exr");
    let lines = render(
        &fox,
        &pattern,
        &[
            "--frames", "2..4", "--fps", "5", "--clip", "Run", "--bvh", bvh,
        ],
    );
    assert_eq!(lines[0]["scene_update"], Value::Null);
    for line in &lines {
        assert_eq!(line["bvh"], bvh, "{line}");
    }
    for line in &lines[1..] {
        assert_eq!(line["scene_update"], "refitted", "{line}");
        // Only what the pose changed is written: the skinned mesh's triangles, shading data
        // and BLAS nodes, the TLAS, the instances, materials and lights (not the textures'
        // mip chains, nor the texture coordinates of a reload).
        let (written, scene) = (&line["scene_update_bytes"], &line["device_bytes"]);
        let (written, scene) = (written.as_u64().unwrap(), scene.as_u64().unwrap());
        assert!(written > 0 && written * 20 < scene, "{line}");
    }
    for frame in [3, 4] {
        let single = dir.path().join(format!("single_{frame}.exr"));
        let time = format!("{}", f64::from(frame) / 5.0);
        render(
            &fox,
            &single,
            &["--time", &time, "--clip", "Run", "--bvh", bvh],
        );
        assert!(
            std::fs::read(dir.path().join(format!("fox_{frame}.exr"))).unwrap()
                == std::fs::read(&single).unwrap(),
            "frame {frame} differs from its fresh render"
        );
    }
}

/// A morph target that stretches a row of small triangles to half again its length, every
/// other one sliding 1 along it: the refitted BVH's leaves and nodes then span the stretch,
/// its cost passes the bound and the frame is built again ("rebuilt"), while a stretch of a
/// thousandth stays a refit; both frames render as their fresh loads do.
#[test]
fn a_stretching_pose_rebuilds_the_bvh_past_the_refit_bound() {
    stretch_rebuilds_past_the_bound("flat");
}

/// [`a_stretching_pose_rebuilds_the_bvh_past_the_refit_bound`] on two levels: the morphed
/// mesh's BLAS is refitted in its own space, and built anew past the bound.
#[test]
fn a_stretching_pose_on_two_levels_rebuilds_the_blas_past_the_refit_bound() {
    stretch_rebuilds_past_the_bound("two-level");
}

/// Renders the stretching strip's frames 0 to 2 with `--bvh bvh`: frame 1 a refit, frame 2 a
/// rebuild, each its fresh render.
fn stretch_rebuilds_past_the_bound(bvh: &str) {
    let mut g = Gltf::default();
    let white = g.lambert([0.7; 3], [0.0; 3], 1.0, false);
    // 200 small triangles in a row along x (0.01 apart); the target slides every other one
    // by 1 along x.
    let (mut positions, mut indices, mut slide) = (vec![], vec![], vec![]);
    for i in 0..200u32 {
        let x = i as f32 * 0.01;
        positions.extend([[x, 0.0, 0.0], [x + 0.008, 0.0, 0.0], [x, 0.3, 0.0]]);
        indices.extend([3 * i, 3 * i + 1, 3 * i + 2]);
        let dx = if i % 2 == 0 { 0.0 } else { 1.0 };
        slide.extend([[dx, 0.0, 0.0]; 3]);
    }
    let m = g.mesh(vec![Prim::triangles(positions, indices, white)]);
    let target = g.float_accessor(&slide);
    g.meshes[m]["primitives"][0]["targets"] = json!([{"POSITION": target}]);
    g.node(json!({"mesh": m, "weights": [0.0]}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [1.0, 2.0, 8.0]}));
    g.lights
        .push(json!({"type": "point", "intensity": 300.0, "color": [1.0, 1.0, 1.0]}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1.0, 3.0, 4.0]}));
    // Weight 0 at 0 s, 0.001 at 1 s (a slide of 0.001: a refit), 1 from 2 s (the clip lasts
    // 3 s, so that 2 s does not wrap to its start).
    let times = scalars(&mut g, &[0.0, 1.0, 2.0, 3.0]);
    let weights = scalars(&mut g, &[0.0, 0.001, 1.0, 1.0]);
    g.extra.insert(
        "animations".into(),
        json!([{"name": "stretch",
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            "samplers": [{"input": times, "output": weights}]}]),
    );
    let dir = tempfile::tempdir().unwrap();
    let scene = g.write_glb(dir.path(), "strip");
    let lines = render(
        &scene,
        &dir.path().join("s_#.exr"),
        &["--frames", "0..2", "--fps", "1", "--bvh", bvh],
    );
    assert_eq!(lines[2]["bvh"], bvh);
    assert_eq!(lines[1]["scene_update"], "refitted");
    assert_eq!(lines[2]["scene_update"], "rebuilt");
    for frame in [1, 2] {
        let single = dir.path().join(format!("single_{frame}.exr"));
        render(
            &scene,
            &single,
            &["--time", &frame.to_string(), "--bvh", bvh],
        );
        assert!(
            std::fs::read(dir.path().join(format!("s_{frame}.exr"))).unwrap()
                == std::fs::read(&single).unwrap(),
            "frame {frame} differs from its fresh render"
        );
    }
}

/// On two levels, a morphed small mesh (at most 64 triangles: its instance's triangles are
/// world-space pieces of the TLAS) that glows, and a larger morphed mesh beside it: each
/// later frame is written in place ("refitted", far fewer bytes than the scene holds: the
/// morphed meshes' ranges, their pieces and the light table measured again) and is bit for
/// bit its fresh render.
#[test]
fn morphed_small_and_glowing_meshes_on_two_levels_are_written_in_place_as_fresh_renders() {
    let mut g = Gltf::default();
    let glow = g.lambert([0.2; 3], [4.0, 3.0, 2.0], 1.0, true);
    let white = g.lambert([0.7; 3], [0.0; 3], 1.0, false);
    // A strip of `n` quads along x, `width` wide, its far edge 0.5 up, with a target lifting
    // that edge by `lift` (its triangles stretch a little, none slides: a refit).
    let strip = |g: &mut Gltf, n: u32, width: f32, z: f32, lift: f32, material: usize| {
        let (mut positions, mut indices, mut target) = (vec![], vec![], vec![]);
        for i in 0..=n {
            let x = i as f32 * width / n as f32;
            positions.extend([[x, 0.0, z], [x, 0.5, z - 0.5]]);
            target.extend([[0.0, 0.0, 0.0], [0.0, lift, 0.0]]);
        }
        for i in 0..n {
            let v = 2 * i;
            indices.extend([v, v + 2, v + 1, v + 1, v + 2, v + 3]);
        }
        let m = g.mesh(vec![Prim::triangles(positions, indices, material)]);
        let target = g.float_accessor(&target);
        g.meshes[m]["primitives"][0]["targets"] = json!([{"POSITION": target}]);
        g.node(json!({"mesh": m, "weights": [0.0]}))
    };
    let small = strip(&mut g, 16, 2.0, 0.0, 0.15, glow); // 32 triangles
    let large = strip(&mut g, 100, 3.0, 1.5, -0.15, white); // 200 triangles
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.01}}));
    g.node(
        json!({"camera": 0, "translation": [1.5, 2.5, 5.0], "rotation": [-0.25, 0.0, 0.0, 0.968]}),
    );
    let times = scalars(&mut g, &[0.0, 1.0, 2.0, 3.0]);
    let weights = scalars(&mut g, &[0.0, 0.5, 1.0, 1.0]);
    let channel = |node: usize| json!({"sampler": 0, "target": {"node": node, "path": "weights"}});
    g.extra.insert(
        "animations".into(),
        json!([{"name": "lift",
            "channels": [channel(small), channel(large)],
            "samplers": [{"input": times, "output": weights}]}]),
    );
    let dir = tempfile::tempdir().unwrap();
    let scene = g.write_glb(dir.path(), "strips");
    let args = ["--bvh", "two-level"];
    let lines = render(
        &scene,
        &dir.path().join("s_#.exr"),
        &[&["--frames", "0..2", "--fps", "1"][..], &args[..]].concat(),
    );
    for line in &lines[1..] {
        assert_eq!(line["bvh"], "two-level", "{line}");
        assert_eq!(line["scene_update"], "refitted", "{line}");
        let written = line["scene_update_bytes"].as_u64().unwrap();
        let scene = line["device_bytes"].as_u64().unwrap();
        assert!(written > 0 && written < scene, "{line}");
    }
    // The strips moved: each frame differs from the one before.
    let image = |frame: u32| std::fs::read(dir.path().join(format!("s_{frame}.exr"))).unwrap();
    assert!(image(0) != image(1) && image(1) != image(2));
    for frame in [1, 2] {
        let single = dir.path().join(format!("single_{frame}.exr"));
        let time = frame.to_string();
        render(
            &scene,
            &single,
            &[&["--time", &time][..], &args[..]].concat(),
        );
        assert!(
            std::fs::read(dir.path().join(format!("s_{frame}.exr"))).unwrap()
                == std::fs::read(&single).unwrap(),
            "frame {frame} differs from its fresh render"
        );
    }
}
