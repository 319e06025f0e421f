//! Every scene in PENUMBRA_SCENES (the meshopt-compressed one included) renders without an
//! error and without non-finite samples. Skipped (with a note) when PENUMBRA_SCENES is not
//! set; fails when it is set but empty or names no folder of scenes.

mod common;

use common::{output_dir, penumbra, scenes_dir};
use std::path::PathBuf;

fn scene_files() -> Vec<PathBuf> {
    let Some(dir) = scenes_dir() else {
        if let Some(v) = std::env::var_os("PENUMBRA_SCENES") {
            assert!(!v.is_empty(), "PENUMBRA_SCENES is set but empty");
            panic!("PENUMBRA_SCENES={} is not a folder", v.to_string_lossy());
        }
        eprintln!("PENUMBRA_SCENES is not set: skipping the shared scenes");
        return vec![];
    };
    let mut files = vec![];
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        if !entry.path().is_dir() {
            continue;
        }
        for f in std::fs::read_dir(entry.path()).unwrap().flatten() {
            let p = f.path();
            if matches!(p.extension().and_then(|e| e.to_str()), Some("glb" | "gltf")) {
                files.push(p);
            }
        }
    }
    assert!(
        !files.is_empty(),
        "PENUMBRA_SCENES={}: no .glb or .gltf file in its subfolders",
        dir.display()
    );
    files.sort();
    files
}

#[test]
fn every_shared_scene_renders_cleanly() {
    let out = output_dir("scenes");
    let files = scene_files();
    for scene in &files {
        let name = scene.file_stem().unwrap().to_string_lossy().to_string();
        let image = out.join(format!("{name}.png"));
        let o = penumbra(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            image.to_str().unwrap(),
            "--width",
            "48",
            "--height",
            "36",
            "--spp",
            "2",
            "--bounces",
            "2",
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(o.status.success(), "{name}: {err}");
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(summary["nonfinite_samples"], 0, "{name}: {summary}");
        assert!(summary["triangles"].as_u64().unwrap() > 0, "{name}");
        eprintln!("{name}: ok ({} triangles)", summary["triangles"]);
    }
}
