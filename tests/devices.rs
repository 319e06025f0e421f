//! Several devices in one render (`render --device all|0,0`), on the test device opened twice
//! and on PoCL's CPU device listed twice (`POCL_DEVICES="pthread pthread"`): the devices share
//! the samples, and the EXR (RGB, or a shard's exact sums) is the one device's bit for bit;
//! the summary gives each device's samples, adding up to --spp. Lists that name no device, and
//! options that need one device, are refused in one line with exit code 2 before any work.

mod common;

use common::{channel_bits, output_dir, penumbra_env, render_exr_env, white_sphere_under_panel};
use serde_json::Value;
use std::path::Path;

/// PoCL with its CPU device twice: `--device all` finds two devices.
const TWO_POCL_DEVICES: (&str, &str) = ("POCL_DEVICES", "pthread pthread");

/// Renders `scene` into `out` (32×24 pixels, 12 spp) with `extra` options and `env`; the
/// summary.
fn render(scene: &Path, out: &Path, extra: &[&str], env: &[(&str, &str)]) -> Value {
    let size = ["--width", "32", "--height", "24", "--spp", "12"];
    render_exr_env(scene, out, &[&size[..], extra].concat(), env).0
}

/// The summary's devices: (index, samples), checking that the shares add up to 1 and the
/// samples to 12, that each device took some and says its speed.
fn shares(summary: &Value) -> Vec<(u64, u64)> {
    let devices = summary["devices"].as_array().expect("a devices list");
    let mut share = 0.0;
    let pairs: Vec<(u64, u64)> = devices
        .iter()
        .map(|d| {
            share += d["share"].as_f64().unwrap();
            assert!(d["samples_per_second"].as_f64().unwrap() > 0.0, "{d}");
            (d["index"].as_u64().unwrap(), d["samples"].as_u64().unwrap())
        })
        .collect();
    assert_eq!(pairs.iter().map(|p| p.1).sum::<u64>(), 12, "{summary}");
    assert!((share - 1.0).abs() < 1e-9, "{summary}");
    // Each device renders a first batch of its own, which measures it.
    assert!(pairs.iter().all(|p| p.1 > 0), "{summary}");
    pairs
}

#[test]
fn two_devices_render_the_one_device_image_bit_for_bit() {
    let dir = output_dir("devices_bit_for_bit");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    for kernel in ["megakernel", "wavefront"] {
        let k = ["--kernel", kernel];
        let one = dir.join(format!("{kernel}-one.exr"));
        let s = render(&scene, &one, &[&k[..], &["--device", "0"]].concat(), &[]);
        assert_eq!(s["devices"].as_array().unwrap().len(), 1, "{s}");
        let twice = dir.join(format!("{kernel}-twice.exr"));
        let s = render(
            &scene,
            &twice,
            &[&k[..], &["--device", "0,0"]].concat(),
            &[],
        );
        assert_eq!(shares(&s).iter().map(|p| p.0).collect::<Vec<_>>(), [0, 0]);
        assert_eq!(
            channel_bits(&twice),
            channel_bits(&one),
            "{kernel}: two devices' films summed differ from one device's"
        );
        // Another seed gives another image: the comparison can fail.
        let other = dir.join(format!("{kernel}-other-seed.exr"));
        render(&scene, &other, &[&k[..], &["--seed", "3"]].concat(), &[]);
        assert_ne!(channel_bits(&other), channel_bits(&one), "{kernel}");
    }
}

#[test]
fn every_device_and_shards_on_two_devices_match_one() {
    let dir = output_dir("devices_all_and_shards");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    let listed = penumbra_env(&["devices"], &[TWO_POCL_DEVICES]);
    let listed = String::from_utf8_lossy(&listed.stdout);
    let cpus = listed.lines().filter(|l| l.contains("[CPU]")).count();
    if cpus == 2 && listed.lines().filter(|l| l.contains(": ")).count() == 2 {
        let one = dir.join("one.exr");
        render(&scene, &one, &["--device", "0"], &[TWO_POCL_DEVICES]);
        let all = dir.join("all.exr");
        let s = render(&scene, &all, &["--device", "all"], &[TWO_POCL_DEVICES]);
        assert_eq!(shares(&s).iter().map(|p| p.0).collect::<Vec<_>>(), [0, 1]);
        assert!(s["device"].as_str().unwrap().contains(" + "), "{s}");
        assert_eq!(channel_bits(&all), channel_bits(&one));
    } else {
        eprintln!("POCL_DEVICES does not give two PoCL CPU devices here: `all` not checked");
    }
    // A shard rendered on two devices holds the one device's exact sums.
    let shard = ["--sample-start", "5"];
    let one = dir.join("shard-one.exr");
    render(
        &scene,
        &one,
        &[&shard[..], &["--device", "0"]].concat(),
        &[],
    );
    let twice = dir.join("shard-twice.exr");
    render(
        &scene,
        &twice,
        &[&shard[..], &["--device", "0,0"]].concat(),
        &[],
    );
    let film = channel_bits(&twice);
    assert!(film.iter().any(|(name, _)| name == "film.N_lo"), "a shard");
    assert_eq!(film, channel_bits(&one));
}

#[test]
fn devices_are_set_up_at_once_and_each_reports_its_setup() {
    let dir = output_dir("devices_setup");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    let out = dir.join("twice.exr");
    let o = penumbra_env(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "12",
            "--device",
            "0,0",
        ],
        &[],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let s: Value = serde_json::from_slice(&o.stdout).expect("one JSON line on stdout");
    // Each device built its own BVH and kernels, and says so.
    let devices = s["devices"].as_array().expect("a devices list");
    let mut sum_ms = 0.0;
    for d in devices {
        for key in ["bvh_build_ms", "kernel_build_ms", "setup_ms"] {
            assert!(d[key].as_f64().is_some_and(|ms| ms > 0.0), "{key}: {d}");
        }
        sum_ms += d["setup_ms"].as_f64().unwrap();
    }
    // The setups ran at once: together they took less than one after the other would have.
    let setup_ms = s["setup_ms"].as_f64().expect("setup_ms");
    assert!(
        setup_ms < sum_ms,
        "{setup_ms} ms against {sum_ms} ms one after the other"
    );
    assert_eq!(err.matches("compiling kernels").count(), 1, "{err}");
    // The line on stderr gives each device's setup.
    assert_eq!(err.matches("set up in").count(), 2, "{err}");
}

#[test]
fn bad_device_lists_are_refused_before_rendering() {
    let dir = output_dir("devices_refused");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    let out = dir.join("out.exr");
    for (device, extra, says) in [
        ("7", &[][..], "no OpenCL device"),
        ("0,x", &[], "'x' is not an index"),
        ("0,", &[], "'' is not an index"),
        ("0,7", &[], "no OpenCL device"),
        ("0,0", &["--aovs"], "--aovs renders on one device"),
        ("0,0", &["--noise-threshold", "0.1"], "--noise-threshold"),
        ("0,0", &["--denoise"], "--denoise renders on one device"),
        (
            "0,0",
            &["--shutter", "0.1"],
            "--shutter renders on one device",
        ),
    ] {
        let _ = std::fs::remove_file(&out);
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--device",
            device,
        ];
        args.extend_from_slice(extra);
        let o = penumbra_env(&args, &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?}: nothing is written");
    }
}
