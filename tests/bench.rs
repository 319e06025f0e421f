//! The benchmark instruments measure what they claim: `bench trace` agrees with the host
//! traversal, `bench converge`'s error falls as samples grow (statistics with wide margins, no
//! timings), and its slopes against the Mitsuba reference are those of an unbiased estimator.
//! Everything runs on the CPU device (PoCL) at tiny sizes.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn penumbra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .env("PENUMBRA_DEVICE", "cpu")
        .output()
        .expect("the penumbra binary runs")
}

/// Runs penumbra, asserts success and parses the JSON line it printed on stdout.
fn penumbra_json(args: &[&str]) -> Value {
    let out = penumbra(args);
    assert!(
        out.status.success(),
        "penumbra {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or_else(|| panic!("no JSON in the output of {args:?}:\n{stdout}"));
    serde_json::from_str(line).expect("the summary is JSON")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("temporary paths are UTF-8")
}

fn repo_file(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Asserts a trace summary reports validated results and no disagreement.
fn assert_validated(summary: &Value) {
    assert_eq!(summary["mismatches"], 0, "{summary:#}");
    assert_eq!(summary["stack_overflows"], 0, "{summary:#}");
    let results = summary["results"].as_array().expect("results");
    assert_eq!(
        results.len(),
        3,
        "primary, diffuse and shadow rays: {summary:#}"
    );
    for r in results {
        let checked = r["validation"]["checked"].as_u64().unwrap();
        assert!(checked > 0, "{r:#}");
        assert_eq!(r["validation"]["mismatches"], 0, "{r:#}");
        assert!(r["rays_per_second"].as_f64().unwrap() > 0.0, "{r:#}");
    }
    assert!(summary["checked"].as_u64().unwrap() > 0);
}

#[test]
fn trace_agrees_with_the_host_traversal_on_the_cornell_box() {
    let summary = penumbra_json(&[
        "bench", "trace", "--width", "64", "--height", "48", "--json",
    ]);
    assert_validated(&summary);
    assert!(summary["triangles"].as_u64().unwrap() > 0);
    // Every ray of each set is checked at this size.
    assert_eq!(summary["checked"], 3 * 64 * 48, "{summary:#}");
}

#[test]
fn trace_agrees_with_the_host_traversal_on_a_generated_scene() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("spheres.glb");
    let made = penumbra_json(&["bench", "generate", "--triangles", "60000", "-o", s(&glb)]);
    assert_eq!(made["copies"], 3, "{made:#}");
    let summary = penumbra_json(&[
        "bench",
        "trace",
        s(&glb),
        "--width",
        "64",
        "--height",
        "48",
        "--runs",
        "2",
        "--json",
    ]);
    assert_validated(&summary);
    assert_eq!(summary["triangles"], made["triangles"]);
    // The camera is inside a closed room: every primary ray hits something.
    let primary = &summary["results"][0];
    assert_eq!(primary["hits"], primary["rays"], "{primary:#}");
}

#[test]
fn converge_error_falls_as_samples_grow() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference.exr");
    // A high-spp penumbra reference with its own seed.
    let out = penumbra(&[
        "render",
        s(&repo_file("assets/cornell-box.glb")),
        "-o",
        s(&reference),
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "4096",
        "--seed",
        "977",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (csv, plot) = (dir.path().join("c.csv"), dir.path().join("c.png"));
    let summary = penumbra_json(&[
        "bench",
        "converge",
        "--reference",
        s(&reference),
        "--configs",
        "mis,lights+rr",
        "--spp",
        "64",
        "--csv",
        s(&csv),
        "--plot",
        s(&plot),
        "--json",
    ]);
    let curves = summary["curves"].as_array().expect("curves");
    assert_eq!(curves.len(), 2);
    for c in curves {
        let steps = c["steps"].as_array().unwrap();
        let spp: Vec<u64> = steps.iter().map(|s| s["spp"].as_u64().unwrap()).collect();
        assert_eq!(spp, [1, 2, 4, 8, 16, 32, 64], "{c:#}");
        let relmse = |n: u64| {
            steps[spp.iter().position(|&x| x == n).unwrap()]["relmse"]
                .as_f64()
                .unwrap()
        };
        // 16× the samples: an unbiased estimator's relMSE falls 16×; ask for 2×.
        assert!(
            relmse(64) < 0.5 * relmse(4),
            "{}: relMSE {} at 64 spp, {} at 4 spp",
            c["config"],
            relmse(64),
            relmse(4)
        );
        let times: Vec<f64> = steps
            .iter()
            .map(|s| s["seconds"].as_f64().unwrap())
            .collect();
        assert!(
            times.windows(2).all(|w| w[1] >= w[0]),
            "time goes forward: {times:?}"
        );
    }
    let csv_text = std::fs::read_to_string(&csv).unwrap();
    assert!(csv_text.starts_with("config,spp,seconds,kernel_seconds,rmse,relmse,cpu_seconds\n"));
    assert_eq!(csv_text.lines().count(), 1 + 2 * 7);
    // The process's CPU seconds (the renderer's own cost on a shared machine) go forward too.
    for c in curves {
        let cpu: Vec<f64> = c["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["cpu_seconds"].as_f64().unwrap())
            .collect();
        assert!(cpu.windows(2).all(|w| w[1] >= w[0]), "{cpu:?}");
    }
    // With --adaptive the table ends with the time each curve takes to the adaptive run's
    // relMSE, and the ratio.
    let out = penumbra(&[
        "bench",
        "converge",
        "--reference",
        s(&reference),
        "--configs",
        "mis+rr",
        "--spp",
        "256",
        "--adaptive",
        "0.1",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success()
            && text
                .lines()
                .any(|l| { l.starts_with("mis+rr+adaptive: to relMSE") && l.contains("CPU s (") }),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png = std::fs::read(&plot).unwrap();
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 10_000,
        "a real plot"
    );
}

#[test]
fn converge_slopes_against_the_mitsuba_reference_are_unbiased() {
    let reference = repo_file("tests/references/cornell-box-mitsuba-64.exr");
    if !reference.exists() {
        eprintln!("skipped: {} is missing", reference.display());
        return;
    }
    // Same scene settings as the reference: 64×64, 8 bounces, hard shadows.
    let summary = penumbra_json(&[
        "bench",
        "converge",
        "--reference",
        s(&reference),
        "--bounces",
        "8",
        "--hard-shadows",
        "--configs",
        "mis,lights",
        "--spp",
        "256",
        "--json",
    ]);
    for c in summary["curves"].as_array().unwrap() {
        let slope = c["slope_spp"].as_f64().expect("a fitted slope");
        assert!(
            (-1.3..=-0.7).contains(&slope),
            "{}: slope {slope} against the Mitsuba reference (−1 expected)\n{c:#}",
            c["config"]
        );
    }
}

#[test]
fn frame_reports_every_stage() {
    for (kernel, expected) in [
        (
            "wavefront",
            &["generate", "extend", "shade", "connect", "accumulate"][..],
        ),
        ("megakernel", &["megakernel"][..]),
    ] {
        let summary = penumbra_json(&[
            "bench", "frame", "--kernel", kernel, "--width", "32", "--height", "24", "--spp", "2",
            "--json",
        ]);
        let stages = summary["stage_ms_per_frame"].as_object().expect("stages");
        for stage in expected {
            assert!(stages.contains_key(*stage), "{stage} missing: {summary:#}");
        }
        assert!(summary["samples_per_second"].as_f64().unwrap() > 0.0);
        assert!(summary["extension_rays"].as_u64().unwrap() >= 32 * 24 * 2);
    }
}

#[test]
fn converge_rejects_a_reference_of_another_size() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("r.exr");
    let out = penumbra(&[
        "render",
        s(&repo_file("assets/cornell-box.glb")),
        "-o",
        s(&reference),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
    ]);
    assert!(out.status.success());
    let out = penumbra(&[
        "bench",
        "converge",
        "--reference",
        s(&reference),
        "--width",
        "16",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("r.exr") && err.contains("8×8") && err.lines().count() == 1,
        "{err}"
    );
}
