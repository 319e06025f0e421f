//! A real scheduler runs shards: `scripts/slurm_shards_test.sh` starts a one-node Slurm on
//! localhost, submits a job array of four shards with `sbatch --array=0-3 --wait`
//! (`scripts/slurm_shards.sbatch`, the script docs/farm.md shows), merges them and compares the
//! merge with one render of all the samples, byte for byte. It needs root and Debian's
//! `slurm-wlm` and `munge` (`scripts/install_slurm.sh`, which `.ci/run` calls): without them the
//! test skips with a note, except under `CI=true`, where it fails.

mod common;

use common::{output_dir, test_device, white_sphere_under_panel};
use std::path::Path;
use std::process::Command;

/// Whether a command is on the PATH.
fn installed(command: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {command}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn a_slurm_job_array_of_four_shards_merges_into_one_render() {
    let missing: Vec<&str> = ["sbatch", "slurmctld", "slurmd", "munged"]
        .into_iter()
        .filter(|c| !installed(c))
        .collect();
    if !missing.is_empty() {
        let note = format!(
            "Slurm is not installed ({} missing: scripts/install_slurm.sh)",
            missing.join(", ")
        );
        assert!(std::env::var("CI").as_deref() != Ok("true"), "{note}");
        eprintln!("skipped: {note}");
        return;
    }
    let dir = output_dir("slurm_shards");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm_shards_test.sh");
    let o = Command::new("bash")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_penumbra"))
        .arg(&scene)
        .args(["3", "--width", "32", "--height", "24"])
        .env("PENUMBRA_DEVICE", test_device())
        .output()
        .expect("bash runs");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stdout}{stderr}");
    assert!(
        stdout.contains("merge into one render of 12 spp, byte for byte"),
        "{stdout}"
    );
}
