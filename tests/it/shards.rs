//! Independent passes, shards and merging: any split of a render's passes, merged,
//! gives the single-machine render; parts that do not belong together are refused
//! with the files named; the Slurm and Kubernetes scripts split passes as the plan
//! says.

use pbrt_sppm::imageio::read_image;
use pbrt_sppm::integrators::passes::{self, PassMode};
use pbrt_sppm::integrators::sppm::Sppm;
use pbrt_sppm::render::RenderScene;
use std::path::Path;
use std::process::{Command, Output};

pub const SCENE: &str = r#"LookAt 0 2 -4  0 0.5 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "image" "integer xresolution" [ 32 ] "integer yresolution" [ 24 ] "string filename" "film.exr"
Integrator "sppm" "integer numiterations" [ 6 ] "float radius" [ 0.15 ] "integer photonsperiteration" [ 3000 ]
WorldBegin
LightSource "point" "point from" [ 0 3 0 ] "color I" [ 8 8 8 ]
AttributeBegin
  Translate 0 0.6 0
  Material "glass" "float index" [ 1.5 ]
  Shape "sphere" "float radius" [ 0.6 ]
AttributeEnd
Material "matte" "color Kd" [ .6 .6 .6 ]
Shape "trianglemesh" "point P" [ -5 0 -5  5 0 -5  5 0 5  -5 0 5 ] "integer indices" [ 0 2 1  0 3 2 ]
"#;

pub fn dir(name: &str) -> crate::common::Scratch {
    crate::common::scratch("shards", name, &[("scene.pbrt", SCENE)])
}

fn run(d: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pbrt-sppm")).current_dir(d).args(args).output().unwrap()
}

fn ok(d: &Path, args: &[&str]) {
    let o = run(d, args);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// Exit code 1 and the message on stderr.
pub fn error(d: &Path, args: &[&str]) -> String {
    let o = run(d, args);
    assert_eq!(o.status.code(), Some(1), "{args:?} should fail: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn shard(d: &Path, range: &str, threads: &str) -> String {
    let part = format!("p{}.part.exr", range.replace("..", "-"));
    ok(d, &["render", "scene.pbrt", "--pass-range", range, "--partial", &part, "--nthreads", threads, "-q"]);
    part
}

/// Every pixel within `rel` of the other image's, relatively.
pub fn assert_same_image(a: &Path, b: &Path, rel: f32) {
    let (a, b) = (read_image(a).unwrap(), read_image(b).unwrap());
    assert_eq!((a.width, a.height), (b.width, b.height));
    let mut nonzero = 0;
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        for c in 0..3 {
            let tol = rel * p[c].abs().max(q[c].abs());
            assert!((p[c] - q[c]).abs() <= tol, "pixel {i} channel {c}: {} against {}", p[c], q[c]);
            nonzero += (p[c] != 0.0) as usize;
        }
    }
    assert!(nonzero > a.pixels.len(), "the images are nearly black: the comparison proves little");
}

#[test]
fn every_split_of_the_passes_merges_to_the_single_machine_render() {
    let d = dir("splits");
    ok(&d, &["render", "scene.pbrt", "--passes", "independent", "--outfile", "single.exr", "-q"]);
    let splits: [&[&str]; 4] =
        [&["0..6"], &["0..1", "1..2", "2..3", "3..4", "4..5", "5..6"], &["4..6", "0..1", "1..4"], &["0..3", "3..6"]];
    for (n, split) in splits.iter().enumerate() {
        // Thread counts differ between shards: they must not change a pass.
        let parts: Vec<String> = split.iter().enumerate().map(|(i, r)| shard(&d, r, ["1", "2"][i % 2])).collect();
        let out = format!("merged{n}.exr");
        let mut args = vec!["merge", "--outfile", &out];
        args.extend(parts.iter().map(String::as_str));
        ok(&d, &args);
        assert_same_image(&d.join(&out), &d.join("single.exr"), 1e-6);
    }
}

#[test]
fn merging_is_idempotent_and_merged_parts_merge_again() {
    let d = dir("idempotent");
    let (a, b, c) = (shard(&d, "0..2", "2"), shard(&d, "2..5", "2"), shard(&d, "5..6", "2"));
    ok(&d, &["merge", &a, &b, &c, "--outfile", "once.exr", "--partial", "ab.part.exr"]);
    ok(&d, &["merge", &a, &b, &c, "--outfile", "twice.exr"]);
    let bits = |f: &str| read_image(&d.join(f)).unwrap().pixels.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits("once.exr"), bits("twice.exr"));
    // A merged part is a part: merged alone it gives the same image.
    ok(&d, &["merge", "ab.part.exr", "--outfile", "again.exr"]);
    assert_eq!(bits("once.exr"), bits("again.exr"));
    // A re-run shard is the same file's pixels: given twice, it counts once.
    std::fs::copy(d.join(&b), d.join("rerun.part.exr")).unwrap();
    let o = run(&d, &["merge", &a, &b, "rerun.part.exr", &c, "--outfile", "dup.exr"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("counted once"));
    assert_eq!(bits("once.exr"), bits("dup.exr"));
}

#[test]
fn parts_that_do_not_belong_together_are_refused_by_name() {
    let d = dir("refused");
    let (a, b) = (shard(&d, "0..3", "2"), shard(&d, "3..6", "2"));
    let over = shard(&d, "2..4", "2");
    let e = error(&d, &["merge", &a, &over, &b, "--outfile", "x.exr"]);
    assert!(e.contains("both hold passes 2..3") && e.contains(&a) && e.contains(&over), "{e}");
    let e = error(&d, &["merge", &a, "--outfile", "x.exr"]);
    assert!(e.contains("passes 3..6 of 0..6 are in no part"), "{e}");
    ok(&d, &["merge", &a, "--outfile", "gappy.exr", "--allow-gaps"]);
    assert_eq!(read_image(&d.join("gappy.exr")).unwrap().meta.samples_per_pixel, Some(3));
    // Other settings, another scene.
    let photons = "other.part.exr";
    ok(&d, &["render", "scene.pbrt", "--pass-range", "3..6", "--partial", photons, "--photons", "2000", "-q"]);
    let e = error(&d, &["merge", &a, photons, "--outfile", "x.exr"]);
    assert!(e.contains("photons") && e.contains(photons), "{e}");
    std::fs::write(d.join("scene2.pbrt"), SCENE.replace("color I\" [ 8 8 8 ]", "color I\" [ 9 9 9 ]")).unwrap();
    ok(&d, &["render", "scene2.pbrt", "--pass-range", "3..6", "--partial", "s2.part.exr", "-q"]);
    let e = error(&d, &["merge", &a, "s2.part.exr", "--outfile", "x.exr"]);
    assert!(e.contains("s2.part.exr") && e.contains("scene"), "{e}");
    // Not a part, a damaged part, no part at all.
    ok(&d, &["render", "scene.pbrt", "--spp", "1", "--outfile", "image.exr", "-q"]);
    assert!(error(&d, &["merge", "image.exr", "--outfile", "x.exr"]).contains("not a part"));
    let bytes = std::fs::read(d.join(&a)).unwrap();
    for cut in [bytes.len() / 2, 300, 10] {
        std::fs::write(d.join("cut.part.exr"), &bytes[..cut]).unwrap();
        assert!(error(&d, &["merge", "cut.part.exr", "--outfile", "x.exr"]).contains("cut.part.exr"));
    }
    assert!(error(&d, &["merge", "none.part.exr", "--outfile", "x.exr"]).contains("none.part.exr"));
    assert!(!d.join("x.exr").exists());
}

#[test]
fn bad_pass_options_are_clear_errors() {
    let d = dir("options");
    let cases: [(&[&str], &str); 7] = [
        (&["--pass-range", "4..2"], "empty"),
        (&["--pass-range", "2..9"], "does not fit in the render's 6 passes"),
        (&["--pass-range", "x"], "not a pass range"),
        (&["--passes", "classic", "--pass-range", "0..2"], "need independent passes"),
        (&["--alpha", "0.5"], "--passes independent"),
        (&["--passes", "independent", "--alpha", "1.5"], "between 0 and 1"),
        (&["--passes", "independent", "--photon-sampling", "adaptive"], "Markov chains"),
    ];
    for (args, says) in cases {
        let mut all = vec!["render", "scene.pbrt", "--outfile", "o.exr"];
        all.extend(args);
        let o = run(&d, &all);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(matches!(o.status.code(), Some(1 | 2)) && e.contains(says), "{args:?}: {e}");
    }
    let e = error(&d, &["render", "scene.pbrt", "--pass-range", "0..2", "--partial", "p.png"]);
    assert!(e.contains("must end in .exr"), "{e}");
    assert!(!d.join("o.exr").exists(), "a refused render wrote its image");
}

#[test]
fn each_independent_pass_gathers_with_the_radius_of_its_index() {
    let rs = RenderScene::new(&crate::common::scene(SCENE));
    let alpha = 0.5;
    let mut sppm = Sppm::new(&rs, 6, 500, 0.15, 0, Default::default())
        .and_then(|s| s.with_passes(PassMode::Independent { alpha }, 2))
        .unwrap();
    for pass in 2..5 {
        sppm.iterate();
        let want = passes::radius(0.15f32 as f64, alpha, pass);
        assert!(sppm.pixels.iter().all(|p| p.radius == want), "pass {pass}");
    }
    assert_eq!(sppm.passes_done(), 3);
    // r_5² = r_1² (1+α)/2 (2+α)/3 (3+α)/4 (4+α)/5, worked by hand for α = 1/2.
    let ratio = passes::radius(0.15, alpha, 4) / 0.15;
    assert!((ratio - (0.75f64 * 2.5 / 3.0 * 0.875 * 0.9).sqrt()).abs() < 1e-12, "{ratio}");
}

#[test]
fn independent_passes_converge_to_the_classic_image() {
    let d = dir("converge");
    let common = ["--spp", "48", "--photons", "20000", "-q"];
    let mut classic = vec!["render", "scene.pbrt", "--outfile", "classic.exr"];
    classic.extend(common);
    ok(&d, &classic);
    let mut ind = vec!["render", "scene.pbrt", "--outfile", "independent.exr", "--passes", "independent"];
    ind.extend(common);
    ok(&d, &ind);
    let mean = |f: &str| {
        let img = read_image(&d.join(f)).unwrap();
        img.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / img.pixels.len() as f64
    };
    let (c, i) = (mean("classic.exr"), mean("independent.exr"));
    assert!((c / i - 1.0).abs() < 0.03, "classic mean {c}, independent {i}");
}

/// The shard arithmetic of the Slurm batch script and of the Kubernetes manifest,
/// run by the shell with a stand-in for pbrt-sppm that prints its arguments.
#[test]
fn the_batch_scripts_split_passes_as_the_plan_does() {
    let d = dir("scripts");
    let fake = d.join("pbrt-sppm");
    std::fs::write(&fake, "#!/bin/sh\necho \"$@\"\n").unwrap();
    Command::new("chmod").arg("+x").arg(&fake).status().unwrap();
    let root = crate::common::root();
    let manifest = std::fs::read_to_string(root.join("tools/k8s/shards.yaml")).unwrap();
    let k8s: String = manifest
        .split("- |\n")
        .nth(1)
        .unwrap()
        .lines()
        .take_while(|l| l.starts_with("              ") || l.is_empty())
        .map(|l| format!("{}\n", l.trim_start()))
        .collect();
    let (n, k) = (10u32, 4u32);
    for i in 0..k {
        let want = pbrt_sppm::cli::farm::shard_range(i, n, k);
        let want =
            format!("--pass-range {}..{} --partial parts/part-{}-{}.exr", want.start, want.end, want.start, want.end);
        let slurm = Command::new("sh")
            .arg(root.join("tools/slurm/shard.sbatch"))
            .args([fake.to_str().unwrap(), "s.pbrt", &n.to_string(), &k.to_string(), "parts", "--photons", "7"])
            .env("SLURM_ARRAY_TASK_ID", i.to_string())
            .output()
            .unwrap();
        let slurm = String::from_utf8_lossy(&slurm.stdout);
        assert!(slurm.contains(&want) && slurm.contains("--spp 10 --passes independent"), "{slurm}");
        assert!(slurm.trim_end().ends_with("--photons 7"), "{slurm}");
        let path = format!("{}:{}", d.display(), std::env::var("PATH").unwrap_or_default());
        let pod = Command::new("sh")
            .args(["-c", &k8s])
            .current_dir(&d)
            .env("PATH", path)
            .env("JOB_COMPLETION_INDEX", i.to_string())
            .envs([("SCENE", "s.pbrt"), ("PASSES", "10"), ("SHARDS", "4"), ("PARTS", "parts"), ("EXTRA", "")])
            .output()
            .unwrap();
        let pod = String::from_utf8_lossy(&pod.stdout);
        assert!(pod.contains(&want) && pod.contains("--spp 10 --passes independent"), "{pod}");
    }
}

#[test]
fn plan_prints_a_job_array_and_a_merge_that_waits_for_it() {
    let d = dir("plan");
    let o = run(&d, &["plan", "--slurm", "--passes", "10", "--shards", "4", "scene.pbrt", "--", "--photons", "5000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("# shard passes: 0..2 2..5 5..7 7..10"), "{s}");
    assert!(s.contains("sbatch --parsable --array=0-3 --cpus-per-task=1"), "{s}");
    assert!(s.contains("\"$parts\" --photons 5000)"), "{s}");
    assert!(s.contains("--dependency=afterok:\"$array\""), "{s}");
    assert!(s.contains(pbrt_sppm::cli::farm::SHARD_SBATCH) && s.contains(pbrt_sppm::cli::farm::MERGE_SBATCH));
    let check = Command::new("sh").args(["-n", "-c", &s]).status().unwrap();
    assert!(check.success(), "the script is not valid sh");
    ok(&d, &["plan", "--slurm", "--passes", "4", "--shards", "2", "scene.pbrt", "--write", "submit.sh"]);
    // A scene in another folder: its parts and image still go to the current folder,
    // and the script names every path without `..`.
    std::fs::create_dir_all(d.join("elsewhere")).unwrap();
    std::fs::copy(d.join("scene.pbrt"), d.join("elsewhere/away.pbrt")).unwrap();
    let o = run(
        &d.join("elsewhere/.."),
        &["plan", "--slurm", "--passes", "4", "--shards", "2", "elsewhere/../elsewhere/away.pbrt"],
    );
    let s = String::from_utf8_lossy(&o.stdout);
    let root = std::fs::canonicalize(&d).unwrap_or(d.to_path_buf());
    assert!(o.status.success() && !s.contains("/../") && !s.contains("/./"), "{s}");
    assert!(
        s.contains(&format!("parts='{}/away.parts'", root.display()))
            || s.contains(&format!("parts={}/away.parts", root.display())),
        "{s}"
    );
    assert!(std::fs::read_to_string(d.join("submit.sh")).unwrap().contains("--array=0-1"));
    let e = error(&d, &["plan", "--slurm", "--passes", "3", "--shards", "4", "scene.pbrt"]);
    assert!(e.contains("empty"), "{e}");
    let e = error(&d, &["plan", "--slurm", "--passes", "8", "--shards", "2", "scene.pbrt", "--", "--spp", "3"]);
    assert!(e.contains("--spp cannot be given to the shards"), "{e}");
    let e = error(&d, &["plan", "--slurm", "--passes", "8", "--shards", "2", "scene.pbrt", "--", "--bogus"]);
    assert!(e.contains("--bogus"), "{e}");
    std::fs::write(d.join("bad.pbrt"), "WorldBegin\nShape \"sphere\" \"float radius\" [ -1 2 ]\n").unwrap();
    let e = error(&d, &["plan", "--slurm", "--passes", "8", "--shards", "2", "bad.pbrt"]);
    assert!(e.contains("bad.pbrt:2:"), "{e}");
}

#[test]
fn a_shard_stopped_early_and_resumed_writes_the_same_part() {
    let d = dir("resume");
    let whole = shard(&d, "1..5", "2");
    let range = ["render", "scene.pbrt", "--pass-range", "1..5", "--partial", "r.part.exr", "-q"];
    let mut first = range.to_vec();
    first.extend(["--checkpoint", "c.ckpt", "--time-limit", "0.000001"]);
    ok(&d, &first);
    // Stopped after one pass: the part says so, and merge would report the gap.
    let e = error(&d, &["merge", "r.part.exr", "--outfile", "x.exr"]);
    assert!(e.contains("passes 0..1,2..6 of 0..6"), "{e}");
    let mut resumed = range.to_vec();
    resumed.extend(["--resume", "c.ckpt"]);
    ok(&d, &resumed);
    ok(&d, &["merge", "r.part.exr", "--outfile", "r.exr", "--allow-gaps"]);
    ok(&d, &["merge", &whole, "--outfile", "w.exr", "--allow-gaps"]);
    let bits = |f: &str| read_image(&d.join(f)).unwrap().pixels.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits("r.exr"), bits("w.exr"));
    // The checkpoint belongs to its pass range.
    let mut other = vec!["render", "scene.pbrt", "--pass-range", "2..5", "--partial", "o.part.exr"];
    other.extend(["--resume", "c.ckpt"]);
    assert!(error(&d, &other).contains("pass-range 1..5"));
}
