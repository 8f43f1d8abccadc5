//! Every example scene cut at every statement boundary (and every token boundary) loads
//! or fails with an error; it never panics.

use crate::common::root;
use pbrt_sppm::parser::lexer::{Lexer, TokenKind};
use pbrt_sppm::scene::{LoadOptions, load_scene_from_bytes};
use std::path::{Path, PathBuf};

fn scene_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in ["pbrt-scenes/v3", "pbrt-scenes/v4", "tests/data/good"] {
        for e in std::fs::read_dir(root().join(dir)).unwrap().flatten() {
            if e.path().extension().is_some_and(|x| x == "pbrt") {
                files.push(e.path());
            }
        }
    }
    files.sort();
    files
}

/// (statement starts, all token boundaries) of a file.
fn boundaries(text: &[u8]) -> (Vec<usize>, Vec<usize>) {
    let (mut stmts, mut tokens) = (Vec::new(), Vec::new());
    let mut lexer = Lexer::new(text);
    while let Ok(Some(t)) = lexer.next_token() {
        let word = &text[t.start as usize..t.end as usize];
        if t.kind == TokenKind::Word && word[0].is_ascii_uppercase() {
            stmts.push(t.start as usize);
        }
        tokens.extend([t.start as usize, t.end as usize]);
    }
    stmts.push(text.len());
    (stmts, tokens)
}

fn load_prefix(path: &Path, text: &[u8], cut: usize) -> Result<bool, String> {
    let prefix = text[..cut].to_vec();
    std::panic::catch_unwind(|| load_scene_from_bytes(path, prefix, &LoadOptions::default()).is_ok())
        .map_err(|_| format!("{} cut at byte {cut} panicked", path.display()))
}

#[test]
fn truncated_scenes_never_panic() {
    let mut statement_cuts = 0;
    let mut loaded = 0;
    for path in scene_files() {
        let text = std::fs::read(&path).unwrap();
        let (stmts, tokens) = boundaries(&text);
        assert!(stmts.len() > 1, "{} has no statements", path.display());
        for &cut in &stmts {
            statement_cuts += 1;
            loaded += load_prefix(&path, &text, cut).unwrap_or_else(|e| panic!("{e}")) as usize;
        }
        for &cut in &tokens {
            load_prefix(&path, &text, cut).unwrap_or_else(|e| panic!("{e}"));
        }
    }
    assert!(statement_cuts > 200, "only {statement_cuts} statement cuts");
    assert!(loaded > 0 && loaded < statement_cuts, "some cuts load, some fail ({loaded}/{statement_cuts})");
}

#[test]
fn truncated_ply_files_never_panic() {
    let dir = crate::common::Scratch::new("plycut");
    let scene = dir.join("scene.pbrt");
    std::fs::write(&scene, "WorldBegin\nShape \"plymesh\" \"string filename\" \"cut.ply\"\n").unwrap();
    for source in ["icosphere.ply", "slab_be.ply"] {
        let bytes = std::fs::read(root().join("pbrt-scenes/v3/geometry").join(source)).unwrap();
        let mut loaded = 0;
        for cut in 0..=bytes.len() {
            std::fs::write(dir.join("cut.ply"), &bytes[..cut]).unwrap();
            let ok = std::panic::catch_unwind(|| crate::common::load_file(&scene).is_ok())
                .unwrap_or_else(|_| panic!("{source} cut at byte {cut} panicked"));
            loaded += ok as usize;
        }
        // Binary: only the whole file loads. ASCII: also the cuts that drop the final
        // newline or the last digit of the last index ("41" reads as "4").
        let expected = if source.ends_with("_be.ply") { 1 } else { 3 };
        assert_eq!(loaded, expected, "{source}");
    }
}

#[test]
fn truncated_gzip_scenes_never_panic_and_say_where() {
    use std::io::Write;
    let dir = crate::common::Scratch::new("gzcut");
    let text = std::fs::read(root().join("pbrt-scenes/v3/cornell-glass.pbrt")).unwrap();
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(&text).unwrap();
    let gz = enc.finish().unwrap();
    let path = dir.join("cut.pbrt.gz");
    let mut loaded = 0;
    let cuts: std::collections::BTreeSet<usize> = (0..=gz.len()).step_by(3).chain([gz.len()]).collect();
    for cut in cuts {
        std::fs::write(&path, &gz[..cut]).unwrap();
        let result = std::panic::catch_unwind(|| crate::common::load_file(&path))
            .unwrap_or_else(|_| panic!("gzip cut at byte {cut} panicked"));
        match result {
            Ok(_) => loaded += 1,
            // Every error is located: a cut gzip stream at the file's start.
            Err(e) => {
                assert!(e.one_line().starts_with(&format!("{}:1:1: error: ", path.display())), "{}", e.one_line())
            }
        }
    }
    // Only the whole stream loads (the empty file is an error too: no WorldBegin).
    assert_eq!(loaded, 1);
}
