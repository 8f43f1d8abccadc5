//! The last word of `cargo test`: the tests of `tests/it` that could not run on this
//! machine, and why (`SKIPPED: ...`), counted as ignored. They are listed by `cargo
//! test`'s process, the parent of both binaries (see `tests/it/common.rs`); the list
//! is removed once printed.

use std::path::Path;

fn main() {
    // SAFETY: getppid has no preconditions.
    let parent = unsafe { libc::getppid() };
    let list = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("skipped-tests-{parent}.txt"));
    let text = std::fs::read_to_string(&list).unwrap_or_default();
    let _ = std::fs::remove_file(&list);
    let mut skipped: Vec<&str> = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        if !skipped.contains(&line) {
            skipped.push(line);
        }
    }
    println!();
    if skipped.is_empty() {
        println!("test summary: no test was skipped");
    } else {
        println!("test summary: skipped, since this machine lacks what they need (CI=true makes them fail):");
        for s in &skipped {
            println!("SKIPPED: {s}");
        }
    }
    println!();
    println!(
        "test result: ok. 0 passed; 0 failed; {} ignored; 0 measured; 0 filtered out; finished in 0.00s",
        skipped.len()
    );
    println!();
}
