//! Replays every input that ever crashed a fuzz target (`tools/fuzz/regressions/<target>`)
//! and the committed seeds through the same entry points the fuzz targets call
//! (`pbrt_sppm::cli::fuzzing`): each must return without panicking.

use crate::common::root;

fn replay(target: &str, dirs: &[&str], run: fn(&[u8])) -> usize {
    let mut n = 0;
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(root().join(dir)) else { continue };
        let mut files: Vec<_> = entries.flatten().map(|e| e.path()).filter(|p| p.is_file()).collect();
        files.sort();
        for f in files.iter().filter(|f| !f.ends_with(".keep")) {
            let data = std::fs::read(f).unwrap();
            let ok = std::panic::catch_unwind(|| run(&data)).is_ok();
            assert!(ok, "{target} panicked on {}", f.display());
            n += 1;
        }
    }
    n
}

#[test]
fn every_input_that_crashed_a_fuzz_target_is_answered() {
    use pbrt_sppm::cli::fuzzing;
    let scenes = ["pbrt-scenes/v3", "pbrt-scenes/v4", "tests/data/good", "tests/data/bad"];
    let with = |t: &str, extra: &[&'static str]| -> Vec<String> {
        let mut v: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
        v.push(format!("tools/fuzz/regressions/{t}"));
        v
    };
    let run = |t: &str, extra: &[&'static str], f: fn(&[u8])| {
        let dirs = with(t, extra);
        replay(t, &dirs.iter().map(String::as_str).collect::<Vec<_>>(), f)
    };
    assert!(run("statements", &scenes, fuzzing::statements) > 250);
    assert!(run("builder", &scenes, fuzzing::builder) > 250);
    assert!(run("ply", &["pbrt-scenes/v3/geometry", "tests/data/bad"], fuzzing::ply) > 20);
    assert!(run("image", &["tools/fuzz/seeds/image"], fuzzing::image) >= 2);
    assert!(run("nanovdb", &["tests/data/nanovdb"], fuzzing::nanovdb) >= 1);
    assert!(run("ptex", &["pbrt-scenes/verify/textures"], fuzzing::ptex) >= 4);
    assert!(run("fourier", &["pbrt-scenes/verify/bsdfs"], fuzzing::fourier) >= 1);
    assert!(run("measured", &["pbrt-scenes/verify/bsdfs"], fuzzing::measured) >= 2);
}
