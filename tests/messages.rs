//! What the binary says on stderr, as a user reads it: a bad scene file is one error line
//! naming the real problem (another format, a cut-short GLB, an empty or missing file), the
//! viewer reports a missing file before a missing display, warnings and `log` records take the
//! `penumbra: warning: …` form, and a render ends with one line saying what it wrote.

mod common;

use common::{Gltf, penumbra_env, quad};
use std::path::Path;
use std::process::{Command, Output};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `penumbra render PATH -o PATH.out.png` with `more` options and `env` set.
fn render_with(path: &Path, more: &[&str], env: &[(&str, &str)]) -> Output {
    let out = path.with_extension("out.png");
    let mut args = vec![
        "render",
        path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(more);
    penumbra_env(&args, env)
}

/// Runs a small, quick `penumbra render PATH`.
fn render(path: &Path) -> Output {
    render_with(path, &["--width", "8", "--height", "8", "--spp", "1"], &[])
}

/// The output is exit code 1 and exactly one line, `penumbra: error: ` and then `expect`.
fn assert_error_line(o: &Output, expect: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    let line = err.trim_end();
    assert!(line.starts_with("penumbra: error: "), "{err}");
    assert!(line.ends_with(expect), "expected '… {expect}', got: {err}");
}

/// A one-quad scene as GLB bytes.
fn quad_glb() -> Vec<u8> {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![quad()]);
    g.node(serde_json::json!({"mesh": m}));
    g.glb()
}

#[test]
fn a_file_of_another_format_is_named_for_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let mut stl = vec![0u8; 84 + 50 * 2];
    stl[80] = 2;
    for (name, bytes, format) in [
        (
            "cube.obj",
            b"# exported\no Cube\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
            "a Wavefront OBJ",
        ),
        (
            "cube.gltf",
            b"ply\nformat ascii 1.0\nelement vertex 3\n".to_vec(),
            "a PLY file",
        ),
        (
            "cube.glb",
            b"Kaydara FBX Binary  \0\x1a\0".to_vec(),
            "an Autodesk FBX file",
        ),
        ("cube.stl", stl, "a binary STL file"),
        (
            "scene.usdz",
            b"PK\x03\x04\x14\0\0\0".to_vec(),
            "a zip archive",
        ),
        (
            "photo.glb",
            b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR".to_vec(),
            "a PNG image",
        ),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let o = render(&path);
        let err = stderr(&o);
        assert!(
            err.contains(&format!(
                "{} is not a glTF file (it looks like {format}",
                path.display()
            )),
            "{name}: {err}"
        );
        assert_error_line(&o, ")");
    }
}

#[test]
fn a_cut_short_or_empty_file_says_so() {
    let dir = tempfile::tempdir().unwrap();
    // A real GLB cut short, and a header that claims more than a download delivered.
    let glb = quad_glb();
    let cut = dir.path().join("cut.glb");
    std::fs::write(&cut, &glb[..glb.len() / 2]).unwrap();
    assert!(
        glb.len() / 2 < 1000,
        "the file's length has no thousands separator"
    );
    let o = render(&cut);
    assert_error_line(&o, &format!("bytes, the file has {}", glb.len() / 2));
    assert!(
        stderr(&o).contains("cut.glb is truncated: the GLB header says "),
        "{}",
        stderr(&o)
    );
    let mut claims = b"glTF".to_vec();
    claims.extend(2u32.to_le_bytes());
    claims.extend(1_234_567u32.to_le_bytes());
    claims.resize(512, 0);
    let partial = dir.path().join("partial.glb");
    std::fs::write(&partial, claims).unwrap();
    assert_error_line(
        &render(&partial),
        "partial.glb is truncated: the GLB header says 1,234,567 bytes, the file has 512",
    );

    let empty = dir.path().join("empty.gltf");
    std::fs::write(&empty, b"").unwrap();
    assert_error_line(&render(&empty), "empty.gltf is empty");

    let missing = dir.path().join("missing.glb");
    assert_error_line(&render(&missing), "missing.glb does not exist");
    assert_error_line(&render(dir.path()), "is a folder, not a glTF file");
}

/// Without a display, `penumbra missing.glb` and `penumbra view empty.glb` report the file,
/// not the display.
#[test]
fn the_viewer_reports_the_file_before_the_display() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.glb");
    let empty = dir.path().join("empty.glb");
    std::fs::write(&empty, b"").unwrap();
    let without_display = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("the binary runs")
    };
    let o = without_display(&[missing.to_str().unwrap()]);
    assert_error_line(&o, "missing.glb does not exist");
    let o = without_display(&["view", empty.to_str().unwrap()]);
    assert_error_line(&o, "empty.glb is empty");
    // A file that is there gets as far as the display.
    let glb = dir.path().join("quad.glb");
    std::fs::write(&glb, quad_glb()).unwrap();
    let err = stderr(&without_display(&["view", glb.to_str().unwrap()]));
    assert!(err.contains("penumbra render"), "{err}");
}

/// A scene's warnings and penumbra's own notes are `penumbra: warning: …`; a render ends with
/// one line naming the image, its size, spp and time, and the JSON summary stays on stdout.
#[test]
fn warnings_and_the_closing_line_share_one_form() {
    let dir = tempfile::tempdir().unwrap();
    // An optional extension penumbra does not read is a warning; no lights, another.
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![quad()]);
    g.node(serde_json::json!({"mesh": m}));
    g.use_ext("EXT_lights_ies");
    let scene = g.write_glb(dir.path(), "warns");
    let out = scene.with_extension("out.png");
    let small = [
        "--width", "16", "--height", "12", "--spp", "2", "--env", "none",
    ];
    let o = render_with(&scene, &small, &[]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    for line in err.lines() {
        assert!(line.starts_with("penumbra: "), "one form: {line}");
        assert!(!line.contains("[WARN"), "{line}");
    }
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("penumbra: warning: "))
        .collect();
    assert!(
        warnings.iter().any(|l| l.contains("EXT_lights_ies")),
        "{err}"
    );
    assert!(
        warnings.iter().any(|l| l.contains("default light rig")),
        "{err}"
    );
    let last = err.lines().last().unwrap_or("");
    let prefix = format!(
        "penumbra: wrote {}: 16×12 pixels, 2 spp, rendered in ",
        out.display()
    );
    assert!(last.starts_with(&prefix), "{err}");
    assert!(last.ends_with(" s in all)"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("the JSON summary on stdout");
    assert_eq!(summary["spp"], 2);

    // RUST_LOG still shows the program's debug records, in the same form.
    let o = render_with(&scene, &small, &[("RUST_LOG", "penumbra=info")]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("penumbra: info penumbra::")),
        "{err}"
    );
}

#[test]
fn a_reader_that_goes_away_ends_the_output_quietly() {
    // `penumbra devices | head -0`: the pipe is closed before the list is printed.
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("devices")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = stderr(&out);
    assert!(
        !err.contains("panicked") && !err.contains("backtrace"),
        "{err}"
    );
    // 141 as a Unix tool killed by SIGPIPE; 0 only if the list was written into the pipe's
    // buffer before it closed.
    assert!(
        matches!(out.status.code(), Some(141 | 0)),
        "{:?}: {err}",
        out.status
    );
}
