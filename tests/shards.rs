//! Shards (`render --sample-start K --spp N`) and `penumbra merge`, on the test device with both
//! kernels: any split of samples 0…11 into 2, 3 or 4 uneven shards merges into the EXR that
//! one render of the 12 samples writes as a shard, byte for byte, and its RGB equals a plain
//! render's bit for bit; a range that does not start at 0 too; the cut-out background's alpha as
//! well. Merges of shards that do not belong together are refused in one line, exit 1.

mod common;

use common::{channel_bits, output_dir, penumbra, white_sphere_under_panel};
use std::path::{Path, PathBuf};

const KERNELS: [&str; 2] = ["megakernel", "wavefront"];

/// Renders samples `start`…`start + spp − 1` of `scene` (24×16 pixels unless `extra` gives a
/// width) into `out` as a shard (a plain render with `start` None); extra options after.
fn render(scene: &Path, out: &Path, start: Option<u32>, spp: u32, extra: &[&str]) {
    let spp = spp.to_string();
    let start = start.map(|s| s.to_string());
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--height",
        "16",
        "--spp",
        &spp,
    ];
    if !extra.contains(&"--width") {
        args.extend(["--width", "24"]);
    }
    if let Some(start) = &start {
        args.extend(["--sample-start", start.as_str()]);
    }
    args.extend_from_slice(extra);
    let o = penumbra(&args);
    assert!(
        o.status.success(),
        "render {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Runs `penumbra merge` of `shards` into `out`: the exit code and stderr.
fn merge(shards: &[&Path], out: &Path) -> (i32, String) {
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", out.to_str().unwrap()]);
    let o = penumbra(&args);
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The RGB(A) channels' bits of an EXR.
fn image_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    channel_bits(path)
        .into_iter()
        .filter(|(name, _)| ["R", "G", "B", "A"].contains(&name.as_str()))
        .collect()
}

#[test]
fn any_split_merges_into_one_render_bit_for_bit() {
    let dir = output_dir("shards_any_split");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    for kernel in KERNELS {
        let k = ["--kernel", kernel];
        let path = |name: &str| dir.join(format!("{kernel}-{name}.exr"));
        let whole = path("whole");
        render(&scene, &whole, Some(0), 12, &k);
        let plain = path("plain");
        render(&scene, &plain, None, 12, &k);
        // Six uneven shards; the splits below share some.
        let shard = |start: u32, spp: u32| -> PathBuf {
            let p = path(&format!("{start}+{spp}"));
            render(&scene, &p, Some(start), spp, &k);
            p
        };
        let (s0_5, s5_12, s0_1, s1_5, s1_3, s3_5) = (
            shard(0, 5),
            shard(5, 7),
            shard(0, 1),
            shard(1, 4),
            shard(1, 2),
            shard(3, 2),
        );
        let splits: [Vec<&Path>; 3] = [
            vec![&s5_12, &s0_5],
            vec![&s1_5, &s5_12, &s0_1],
            vec![&s3_5, &s0_1, &s5_12, &s1_3],
        ];
        let expected = std::fs::read(&whole).unwrap();
        for split in &splits {
            let out = path(&format!("merged-{}", split.len()));
            let (code, err) = merge(split, &out);
            assert_eq!(code, 0, "{kernel}: merge of {split:?} failed: {err}");
            assert!(
                std::fs::read(&out).unwrap() == expected,
                "{kernel}: the merge of {} shards differs from one render of samples 0…11",
                split.len()
            );
            assert_eq!(
                image_bits(&out),
                image_bits(&plain),
                "{kernel}: the merge of {} shards differs from a plain render's RGB",
                split.len()
            );
        }
        // The image is not the same as a shard's own: the test could fail.
        assert_ne!(image_bits(&s0_5), image_bits(&whole), "{kernel}");
    }
}

#[test]
fn shards_away_from_the_start_and_cut_out_backgrounds_merge_exactly() {
    let dir = output_dir("shards_offset_cutout");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    let t = ["--background", "transparent"];
    let whole = dir.join("whole.exr");
    render(&scene, &whole, Some(10), 9, &t);
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    render(&scene, &a, Some(10), 2, &t);
    render(&scene, &b, Some(12), 7, &t);
    let out = dir.join("merged.exr");
    let (code, err) = merge(&[&b, &a], &out);
    assert_eq!(code, 0, "{err}");
    let bits = channel_bits(&out);
    assert!(
        bits.iter().any(|(n, _)| n == "A"),
        "a cut-out background keeps its alpha"
    );
    assert_eq!(bits, channel_bits(&whole));
    // The PNG of a merge is written too (exposure metered on the merged image).
    let png = dir.join("merged.png");
    let (code, err) = merge(&[&a, &b], &png);
    assert_eq!(code, 0, "{err}");
    let img = image::open(&png).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (24, 16));
    assert!(
        img.pixels().any(|p| p[3] == 0) && img.pixels().any(|p| p[3] == 255),
        "the sky is transparent and the sphere opaque"
    );
}

#[test]
fn shards_that_do_not_belong_together_are_refused_in_one_line() {
    let dir = output_dir("shards_refused");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    let shard = |name: &str, start: u32, spp: u32, extra: &[&str]| -> PathBuf {
        let p = dir.join(name);
        render(&scene, &p, Some(start), spp, extra);
        p
    };
    let a = shard("a.exr", 0, 4, &[]);
    let overlapping = shard("overlapping.exr", 3, 4, &[]);
    let after_gap = shard("after-gap.exr", 6, 2, &[]);
    let other_seed = shard("other-seed.exr", 4, 2, &["--seed", "7"]);
    let other_bounces = shard("other-bounces.exr", 4, 2, &["--bounces", "1"]);
    let wider = shard("wider.exr", 4, 2, &["--width", "25"]);
    let plain = dir.join("plain.exr");
    render(&scene, &plain, None, 2, &[]);
    let damaged = dir.join("damaged.exr");
    let mut bytes = std::fs::read(&a).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&damaged, bytes).unwrap();
    let out = dir.join("out.exr");
    for (shards, says) in [
        (vec![&a, &overlapping], "overlap"),
        (vec![&after_gap, &a], "samples 4…5 are missing"),
        (vec![&a, &other_seed], "another scene or settings"),
        (vec![&a, &other_bounces], "another scene or settings"),
        (vec![&a, &wider], "25×16 pixels"),
        (vec![&a, &plain], "not a shard"),
        (vec![&a, &damaged], "damaged.exr"),
    ] {
        let paths: Vec<&Path> = shards.iter().map(|p| p.as_path()).collect();
        let (code, err) = merge(&paths, &out);
        assert_eq!(code, 1, "{paths:?}: {err}");
        assert!(
            err.contains(says),
            "{paths:?}: '{err}' does not say '{says}'"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert!(!out.exists(), "nothing written for {paths:?}");
    }
    // Usage errors: adaptive sampling and a time limit cannot make exact shards.
    let o = penumbra(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--sample-start",
        "4",
        "--noise-threshold",
        "0.1",
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
