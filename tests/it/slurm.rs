//! A real one-node Slurm cluster (`tools/slurm/local-cluster.sh`: munged, slurmctld
//! and slurmd on localhost) runs the script `pbrt-sppm plan --slurm` prints: a
//! 4-shard job array and a merge job waiting on it. The merged image must equal the
//! single-machine render. Where Slurm cannot start, the test is skipped (under CI it
//! fails, unless `PBRT_SPPM_ALLOW_SKIP` allows `slurm`, as `.ci/run` does: a machine
//! may refuse to start the daemons).

use crate::common::{cannot_run, root};
use crate::shards::{assert_same_image, dir};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const TEST: &str = "slurm::a_four_shard_render_on_slurm_equals_the_single_machine_render";

/// Stops the cluster however the test ends.
struct Cluster(PathBuf);

impl Drop for Cluster {
    fn drop(&mut self) {
        let script = root().join("tools/slurm/local-cluster.sh");
        let _ = Command::new("sh").arg(script).arg("stop").arg(&self.0).status();
    }
}

fn start(d: &Path) -> Result<Cluster, String> {
    let dir = d.join("cluster");
    let script = root().join("tools/slurm/local-cluster.sh");
    let o = Command::new("sh").arg(script).arg("start").arg(&dir).arg("2").output().map_err(|e| e.to_string())?;
    let cluster = Cluster(dir);
    match o.status.code() {
        Some(0) => Ok(cluster),
        _ => Err(String::from_utf8_lossy(&o.stderr).trim().to_string()),
    }
}

fn logs(parts: &Path) -> String {
    let mut names: Vec<PathBuf> = std::fs::read_dir(parts)
        .map(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|e| e == "log")).collect()
        })
        .unwrap_or_default();
    names.sort();
    names.iter().map(|p| format!("{}:\n{}", p.display(), std::fs::read_to_string(p).unwrap_or_default())).collect()
}

#[test]
fn a_four_shard_render_on_slurm_equals_the_single_machine_render() {
    let d = dir("slurm");
    let cluster = match start(&d) {
        Ok(c) => c,
        Err(why) => return cannot_run("slurm", TEST, &format!("Slurm could not start: {why}")),
    };
    let conf = cluster.0.join("slurm.conf");
    let bin = env!("CARGO_BIN_EXE_pbrt-sppm");
    let plan = ["plan", "--slurm", "--passes", "8", "--shards", "4", "scene.pbrt", "--parts", "parts"];
    let o = Command::new(bin)
        .current_dir(&d)
        .args(plan)
        .args(["--outfile", "slurm.exr", "--write", "submit.sh"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let path = format!("{}:/usr/sbin", std::env::var("PATH").unwrap_or_default());
    let o = Command::new("sh")
        .arg("submit.sh")
        .current_dir(&d)
        .env("SLURM_CONF", &conf)
        .env("PATH", &path)
        .output()
        .unwrap();
    assert!(o.status.success(), "submitting failed: {}", String::from_utf8_lossy(&o.stderr));
    let deadline = Instant::now() + Duration::from_secs(240);
    while !d.join("slurm.exr").exists() {
        assert!(Instant::now() < deadline, "no merged image after 240 s; logs:\n{}", logs(&d.join("parts")));
        std::thread::sleep(Duration::from_millis(250));
    }
    let parts = std::fs::read_dir(d.join("parts")).unwrap().filter_map(|e| e.ok());
    let parts = parts.filter(|e| e.file_name().to_string_lossy().ends_with(".exr")).count();
    assert_eq!(parts, 4, "logs:\n{}", logs(&d.join("parts")));
    let single = ["render", "scene.pbrt", "--spp", "8", "--passes", "independent", "--outfile", "single.exr", "-q"];
    let o = Command::new(bin).current_dir(&d).args(single).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_same_image(&d.join("slurm.exr"), &d.join("single.exr"), 1e-6);
}
