//! `pbrt-bench converge`: error against wall time, ours beside pbrt-v3 and pbrt-v4.
//!
//! ```text
//! pbrt-bench converge [SCENE.pbrt[@half] ...] [--runs 3] [--iterations 4,16,64]
//!                     [--reference-iterations N] [--peers DIR] [--out DIR] [--nthreads 2]
//!                     [--ours-args "--photon-sampling adaptive"] [--doc README.md]
//!                     [--reference-args "--integrator vcm"]
//! ```
//! For each scene, every round runs each peer found in `--peers` (`pbrt-v3`, `pbrt-v4`)
//! once per iteration count of the ladder (default: the scene's count over 4, over 2 and
//! as written), with the scene's SPPM and again with `bdpt` and with `path` in its place
//! (`volpath` for a scene with media, still labelled "path"; same `maxdepth`) at the samples per pixel that take as long as each SPPM rung
//! (measured in the first round from runs at 1 and 4 samples), then ours once with a time limit just past the slowest peer run of that
//! round, writing `ERRORS.csv`. Times are whole processes (loading, rendering, writing);
//! our per-iteration times get the same loading and writing time added. With `--runs R`
//! rounds, each figure is the median over the rounds, with the range beside it.
//!
//! Error is relMSE against a reference that neither side's samples are part of: ours at
//! `--reference-iterations` (default 32 × the longest rung), rendered as two halves with
//! seeds of their own and averaged. The reference's own noise adds to every relMSE
//! against it (E[(x − y)²] = E[(x − truth)²] + Var(y) for independent x and y); the
//! halves' difference measures it (Var(y) = E[(a − b)²]/4), and the table's first line
//! gives it, so a ratio near the floor can be read for what it is. A
//! pbrt reference would flatter pbrt: pbrt's samples do not depend on the iteration
//! count, so its short run is the start of its long one. The peer rows show how far each
//! peer's mean sits from the reference's, so a systematic difference is visible.
//! pbrt-v4 does not read v3 files; it renders `pbrt-v4 --upgrade`'s translation, against
//! a reference we render from that same translation.
//!
//! "ours" is, at each peer time, the error of the image our run held then: the last
//! iteration finished by that time. The ratio ours/peer is the headline: below 1/3 meets
//! the project's target. The scene files are rewritten into `--out` (iteration count,
//! `@half` resolution) beside links to everything else in the scene's folder, so
//! relative paths still resolve. References are cached in `--out/refs` under a hash of
//! the rewritten file, the reference's options and our binary (a rebuilt renderer
//! renders its own); delete them to rebuild.
//!
//! `--ours-args` passes options to our timed runs only (not to the reference), so one
//! of our settings can be set beside the peers; give each setting its own `--out`.
//! `--reference-args` passes options to the reference render: an SPPM reference keeps
//! SPPM's bias, which counts against the methods that converge to the scene's image
//! (bdpt, path, vcm); `--reference-args "--integrator vcm"` removes it (at a cost to
//! SPPM's figures).
//! `--doc FILE` writes the suite table (one row per scene) between `<!-- BEGIN converge -->`
//! and `<!-- END converge -->` in FILE (with `--ours-args A`: the section `converge A`).
//!
//! Per scene this writes `converge.md` (the table), one `ERRORS.csv`-shaped file per
//! renderer and `converge.png` (all curves, log-log).

use crate::plot::{Series, draw, read_columns};
use pbrt_sppm::imageio::{RgbImage, metrics, read_image, write_text};
use pbrt_sppm::integrators::{ErrorRow, errors_csv};
use pbrt_sppm::parser::lexer::{Lexer, Token, TokenKind, decode_string};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Instant;

type Res<T> = Result<T, String>;

/// `pbrt-bench converge --help`.
pub const HELP: &str = "\
Usage: pbrt-bench converge [SCENE.pbrt[@half] ...] [OPTIONS]

Error (relMSE) against wall time: each round runs pbrt-v3 and pbrt-v4 (those found in
--peers) with the scene's SPPM at each iteration count of the ladder, and with bdpt and
path (volpath with media) at the samples that take as long, then ours with a time limit
just past the slowest peer run; all against a reference of ours with seeds of its own
(two halves, averaged; their difference gives the reference's own noise, in the table).
Without scenes: the README's suite. @half renders at half resolution.
  --runs N                    rounds; every figure is the median over them (default 3)
  --iterations A,B,C          the ladder (default: the scene's count over 4, over 2, as written)
  --reference-iterations N    the reference's iterations (default 32 x the longest rung)
  --reference-args \"ARGS\"     options for the reference render (e.g. \"--integrator bdpt\")
  --ours-args \"ARGS\"          options for our timed runs only (e.g. \"--integrator vcm\")
  --peers DIR                 where pbrt-v3 and pbrt-v4 are (default ../shared/peers)
  --out DIR                   tables, ERRORS.csv files, plots, cached references (default target/converge)
  --nthreads N                threads for every run, ours and pbrt's (default 2)
  --doc FILE                  write the suite table into FILE between <!-- BEGIN converge --> and <!-- END converge -->
";

/// A scene of the suite, at its own or at half resolution.
struct SceneSpec {
    path: PathBuf,
    half: bool,
}

struct Options {
    scenes: Vec<SceneSpec>,
    runs: usize,
    ladder: Option<Vec<u32>>,
    reference_iterations: Option<u32>,
    peers: PathBuf,
    out: PathBuf,
    nthreads: usize,
    /// Extra options for our timed runs.
    ours_args: Vec<String>,
    /// Extra options for the reference render (`--reference-args "--integrator vcm"`).
    reference_args: Vec<String>,
    /// `--doc FILE`: write the suite table into FILE's `converge` section.
    doc: Option<PathBuf>,
}

#[derive(Clone, Copy, PartialEq)]
enum PeerKind {
    V3,
    V4,
}

/// Which of pbrt's integrators a peer runs.
#[derive(Clone, Copy, PartialEq)]
enum Method {
    /// As the scene asks (SPPM), at the ladder's iteration counts.
    Sppm,
    /// `bdpt` or `path` in its place, at the sample counts that take the SPPM runs' time.
    Bdpt,
    Path,
}

struct Peer {
    kind: PeerKind,
    exe: PathBuf,
    method: Method,
}

impl Peer {
    fn name(&self) -> String {
        let version = match self.kind {
            PeerKind::V3 => "pbrt-v3",
            PeerKind::V4 => "pbrt-v4",
        };
        match self.method {
            Method::Sppm => version.into(),
            Method::Bdpt => format!("{version} bdpt"),
            Method::Path => format!("{version} path"),
        }
    }
}

/// One scene rewritten for every renderer.
struct Prepared {
    label: String,
    dir: PathBuf,
    ladder: Vec<u32>,
    /// Our input: the scene at its resolution, iterations as written.
    ours: PathBuf,
    /// pbrt-v3's inputs, one per rung (pbrt-v3 has no iteration flag).
    v3: Vec<PathBuf>,
    /// pbrt-v4's input (the upgraded file for a v3 scene).
    v4: Option<PathBuf>,
    /// Our reference for `ours` and `v3`, its file, and the one for `v4`.
    reference: RgbImage,
    reference_file: PathBuf,
    /// The reference's own relMSE (its noise), which every figure against it contains.
    reference_noise: Option<f64>,
    reference_iterations: u32,
    reference_v4: Option<RgbImage>,
    /// The scene's own iteration count and photons per iteration, for the suite table.
    iterations: u32,
    photons: u64,
    /// The Integrator's `maxdepth`, which bdpt and path runs keep.
    max_depth: u32,
}

/// A point on a curve: median seconds over the rounds, their range, and relMSE.
#[derive(Clone, Copy)]
struct Point {
    iterations: u32,
    seconds: f64,
    low: f64,
    high: f64,
    relmse: f64,
    /// The image's mean over the reference's (peers only).
    mean_ratio: f64,
}

pub fn main(args: &[String]) -> ExitCode {
    let result = options(args).and_then(|o| {
        let ours = our_binary()?;
        if let Some(doc) = &o.doc {
            // A missing section fails now, not after the measuring.
            read_doc_section(doc, &doc_section(&o))?;
        }
        let peers = find_peers(&o.peers);
        let (mut summary, mut suite) = (String::new(), String::from(SUITE_HEADER));
        for spec in &o.scenes {
            let (line, row) = bench_scene(&o, spec, &ours, &peers)?;
            summary.push_str(&line);
            suite.push_str(&row);
        }
        println!("\n## Summary (ours/peer relMSE at the peer's wall time)\n\n{summary}");
        println!("\n## Suite table\n\n{suite}");
        match &o.doc {
            Some(doc) => write_doc_section(doc, &doc_section(&o), &suite),
            None => Ok(()),
        }
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pbrt-bench converge: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn options(args: &[String]) -> Res<Options> {
    let mut o = Options {
        scenes: Vec::new(),
        runs: 3,
        ladder: None,
        reference_iterations: None,
        peers: PathBuf::from("../shared/peers"),
        out: PathBuf::from("target/converge"),
        nthreads: 2,
        ours_args: Vec::new(),
        reference_args: Vec::new(),
        doc: None,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--runs" => o.runs = positive(a, value()?)? as usize,
            "--nthreads" => o.nthreads = positive(a, value()?)? as usize,
            "--reference-iterations" => o.reference_iterations = Some(positive(a, value()?)?),
            "--iterations" => {
                let v: Res<Vec<u32>> = value()?.split(',').map(|s| positive(a, s)).collect();
                o.ladder = Some(v?);
            }
            "--peers" => o.peers = PathBuf::from(value()?),
            "--out" => o.out = PathBuf::from(value()?),
            "--ours-args" => o.ours_args = value()?.split_whitespace().map(String::from).collect(),
            "--reference-args" => o.reference_args = value()?.split_whitespace().map(String::from).collect(),
            "--doc" => o.doc = Some(PathBuf::from(value()?)),
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s => {
                let (path, half) = s.strip_suffix("@half").map_or((s, false), |p| (p, true));
                o.scenes.push(SceneSpec { path: PathBuf::from(path), half });
            }
        }
    }
    if o.scenes.is_empty() {
        o.scenes = default_suite();
    }
    // Peers run inside the scene's folder under --out: their paths must not be relative.
    o.out = std::path::absolute(&o.out).map_err(|e| format!("--out {}: {e}", o.out.display()))?;
    Ok(o)
}

fn positive(flag: &str, s: &str) -> Res<u32> {
    s.trim().parse::<u32>().ok().filter(|&n| n > 0).ok_or_else(|| format!("{flag}: '{s}' is not a positive integer"))
}

/// The bundled scenes, and caustic-glass f16-9a (full and half) when the shared scenes are there.
fn default_suite() -> Vec<SceneSpec> {
    let mut v: Vec<SceneSpec> = ["v3/sppm-bench", "v3/cornell-glass", "v3/caustic-ring", "verify/v3-caustic"]
        .iter()
        .map(|n| SceneSpec { path: PathBuf::from(format!("pbrt-scenes/{n}.pbrt")), half: false })
        .collect();
    let f16 = PathBuf::from("../shared/scenes/pbrt-v3-scenes/caustic-glass/f16-9a.pbrt");
    if f16.exists() {
        v.push(SceneSpec { path: f16.clone(), half: true });
        v.push(SceneSpec { path: f16, half: false });
    }
    for n in ["keyhole", "doorway", "pool", "window"] {
        v.push(SceneSpec { path: PathBuf::from(format!("pbrt-scenes/v3/{n}.pbrt")), half: false });
    }
    v
}

fn our_binary() -> Res<PathBuf> {
    let exe = std::env::current_exe().map_err(|e| format!("where am I: {e}"))?;
    let ours = exe.with_file_name("pbrt-sppm");
    if ours.exists() {
        Ok(ours)
    } else {
        Err(format!("{} is missing: build it with `cargo build --release`", ours.display()))
    }
}

/// pbrt-v3 and pbrt-v4 as found, each with SPPM first (its times set the other
/// methods' budgets), then bdpt and path.
fn find_peers(dir: &Path) -> Vec<Peer> {
    let mut found = Vec::new();
    for (kind, name) in [(PeerKind::V3, "pbrt-v3"), (PeerKind::V4, "pbrt-v4")] {
        // Absolute: peers run inside the scene's folder.
        if let Some(exe) = dir.join(name).canonicalize().ok().filter(|e| e.is_file()) {
            found.push((kind, exe));
        } else {
            println!("{}: not found, left out", dir.join(name).display());
        }
    }
    let mut peers = Vec::new();
    for method in [Method::Sppm, Method::Bdpt, Method::Path] {
        peers.extend(found.iter().map(|(kind, exe)| Peer { kind: *kind, exe: exe.clone(), method }));
    }
    peers
}

/// Rewrites, renders references, runs the rounds and reports one scene.
fn bench_scene(o: &Options, spec: &SceneSpec, ours: &Path, peers: &[Peer]) -> Res<(String, String)> {
    let p = prepare(o, spec, ours, peers)?;
    println!("\n## {}\n", p.label);
    let rounds = run_rounds(o, &p, ours, peers)?;
    report(o, &p, peers, &rounds)
}

/// Every round's measurements: per peer and rung (seconds, relMSE, mean ratio), which
/// peers rendered the scene, and our per-iteration curves.
struct Rounds {
    peer_runs: Vec<Vec<Vec<(f64, f64, f64)>>>,
    working: Vec<bool>,
    our_runs: Vec<Vec<(u32, f64, f64)>>,
    /// Per peer and rung, the count it runs: SPPM's iterations, or the samples per
    /// pixel that took bdpt or path as long as SPPM's rung (set in the first round).
    counts: Vec<Vec<u32>>,
}

/// Alternates peers and ours, round after round, so drift in the machine's speed
/// touches both sides alike.
fn run_rounds(o: &Options, p: &Prepared, ours: &Path, peers: &[Peer]) -> Res<Rounds> {
    let mut r = Rounds {
        peer_runs: vec![vec![Vec::new(); p.ladder.len()]; peers.len()],
        working: vec![true; peers.len()],
        our_runs: Vec::new(),
        counts: peers.iter().map(|_| p.ladder.clone()).collect(),
    };
    for round in 0..o.runs {
        let mut slowest: f64 = 0.0;
        for (k, peer) in peers.iter().enumerate() {
            if round == 0 && peer.method != Method::Sppm && r.working[k] {
                match calibrate(p, peer, sppm_times(peers, &r, peer.kind), o.nthreads) {
                    Ok(counts) => r.counts[k] = counts,
                    Err(e) => {
                        println!("{}: {e}; left out of this scene", peer.name());
                        r.working[k] = false;
                    }
                }
            }
            for rung in 0..p.ladder.len() {
                if !r.working[k] {
                    break;
                }
                let n = r.counts[k][rung];
                match run_peer(p, peer, rung, n, o.nthreads) {
                    Ok(m) => {
                        slowest = slowest.max(m.0);
                        r.peer_runs[k][rung].push(m);
                    }
                    Err(e) => {
                        println!("{}: {e}; left out of this scene", peer.name());
                        r.working[k] = false;
                    }
                }
            }
        }
        let budget = (slowest > 0.0).then_some(slowest * 1.1);
        r.our_runs.push(run_ours(o, p, ours, budget)?);
    }
    Ok(r)
}

/// The first round's wall times of the same pbrt's SPPM, per rung (empty if it failed).
fn sppm_times(peers: &[Peer], r: &Rounds, kind: PeerKind) -> Vec<f64> {
    let k = peers.iter().position(|q| q.kind == kind && q.method == Method::Sppm);
    match k.filter(|&k| r.working[k]) {
        Some(k) => r.peer_runs[k].iter().filter_map(|runs| runs.first().map(|m| m.0)).collect(),
        None => Vec::new(),
    }
}

/// The samples per pixel at which a bdpt or path peer takes each SPPM rung's time:
/// from runs at 1 and 4 samples, a fixed cost plus a cost per sample.
fn calibrate(p: &Prepared, peer: &Peer, times: Vec<f64>, nthreads: usize) -> Res<Vec<u32>> {
    if times.len() != p.ladder.len() {
        return Err("no SPPM times of the same pbrt to match".into());
    }
    let t1 = run_peer(p, peer, 0, 1, nthreads)?.0;
    let t4 = run_peer(p, peer, 0, 4, nthreads)?.0;
    let per_sample = ((t4 - t1) / 3.0).max(1e-4);
    let fixed = (t1 - per_sample).max(0.0);
    Ok(times.iter().map(|t| (((t - fixed) / per_sample).round() as u32).max(1)).collect())
}

/// The table (printed and written), the CSVs and the plot; returns the summary line
/// and the scene's row of the suite table.
fn report(o: &Options, p: &Prepared, peers: &[Peer], rounds: &Rounds) -> Res<(String, String)> {
    let our_curve = our_curve(&rounds.our_runs);
    let mut table = format!(
        "{}: {} rounds, {} threads, reference ours at {} iterations{}, another seed{}{}\n\n\
         | renderer | iterations | seconds (range) | relMSE | mean / reference | ours at that time | ours / peer |\n\
         |---|---|---|---|---|---|---|\n",
        p.label,
        o.runs,
        o.nthreads,
        p.reference_iterations,
        if o.reference_args.is_empty() { String::new() } else { format!(" with {}", o.reference_args.join(" ")) },
        if o.ours_args.is_empty() { String::new() } else { format!("; ours with {}", o.ours_args.join(" ")) },
        p.reference_noise.map_or(String::new(), |e| format!(
            "; the reference's own noise (from its two halves), which every relMSE below contains: {e:.3e}"
        ))
    );
    let mut series = vec![curve_series("ours", &our_curve)];
    let mut ratios = Vec::new();
    let top = p.ladder.iter().max().copied().unwrap_or(p.iterations);
    let mut row = format!("| `{}` | {} × {} |", p.label, top, thousands(p.photons));
    let mut cells = [" — | — | — |".to_string(), " — | — | — |".to_string()];
    let mut others: Vec<(String, Option<Point>)> = Vec::new();
    for (k, peer) in peers.iter().enumerate().filter(|(k, _)| rounds.working[*k]) {
        let runs = &rounds.peer_runs[k];
        let points: Vec<Point> = rounds.counts[k].iter().zip(runs).map(|(&n, r)| median_point(n, r)).collect();
        for pt in &points {
            let at = our_error_at(&our_curve, pt.seconds);
            let ratio = at.map(|e| e / pt.relmse);
            ratios.extend(ratio);
            let _ = writeln!(
                table,
                "| {} | {} | {:.2} ({:.2}–{:.2}) | {:.3e} | {:.4} | {} | {} |",
                peer.name(),
                pt.iterations,
                pt.seconds,
                pt.low,
                pt.high,
                pt.relmse,
                pt.mean_ratio,
                at.map_or("not yet".into(), |e| format!("{e:.3e}")),
                ratio.map_or("—".into(), |r| format!("{r:.2}"))
            );
        }
        match peer.method {
            Method::Sppm => cells[(peer.kind == PeerKind::V4) as usize] = suite_cells(&points, &our_curve),
            _ => others.push((peer.name(), points.last().copied())),
        }
        write_csv(&p.dir.join(format!("{}.csv", peer.name().replace(' ', "-"))), &points)?;
        series.push(curve_series(&peer.name(), &points));
    }
    for pt in [our_curve.first(), our_curve.last()].into_iter().flatten() {
        let _ = writeln!(
            table,
            "| ours | {} | {:.2} ({:.2}–{:.2}) | {:.3e} | | | |",
            pt.iterations, pt.seconds, pt.low, pt.high, pt.relmse
        );
    }
    write_csv(&p.dir.join("ours.csv"), &our_curve)?;
    draw(&series, "seconds (whole process)", "relmse", &p.dir.join("converge.png"))?;
    write_text(&p.dir.join("converge.md"), &table).map_err(|e| e.to_string())?;
    println!("{table}");
    row.push_str(&cells.concat());
    row.push_str(&best_other_cell(&others, &our_curve));
    row.push('\n');
    Ok((summary_line(&p.label, &ratios), row))
}

/// The suite table's columns: the scene, then per peer its time and relMSE at the
/// scene's own iteration count, ours at that time, and ours over its error per rung.
const SUITE_HEADER: &str = "| scene | iterations × photons | pbrt-v3: s, relMSE | ours at that time | ours / pbrt-v3 | \
                            pbrt-v4: s, relMSE | ours at that time | ours / pbrt-v4 | \
                            best pbrt bdpt/path at the top rung's time | ours / it |\n\
                            |---|---|---|---|---|---|---|---|---|---|\n";

/// The suite table's last two cells: the bdpt or path peer with the least error at
/// the top rung (the time of its pbrt's SPPM run as written), and ours over it.
fn best_other_cell(others: &[(String, Option<Point>)], our_curve: &[Point]) -> String {
    let best =
        others.iter().filter_map(|(name, pt)| pt.map(|pt| (name, pt))).min_by(|a, b| a.1.relmse.total_cmp(&b.1.relmse));
    let Some((name, pt)) = best else { return " — | — |".into() };
    let ours = our_error_at(our_curve, pt.seconds).map(|e| e / pt.relmse);
    format!(
        " {name}: {} spp, {:.2} s, {:.2e} | {} |",
        pt.iterations,
        pt.seconds,
        pt.relmse,
        ours.map_or("—".into(), |r| format!("{r:.2}"))
    )
}

/// One peer's three cells of the suite table.
fn suite_cells(points: &[Point], our_curve: &[Point]) -> String {
    let Some(last) = points.last() else { return " — | — | — |".into() };
    let ratio = |pt: &Point| our_error_at(our_curve, pt.seconds).map(|e| e / pt.relmse);
    let ratios: Vec<String> = points.iter().map(|pt| ratio(pt).map_or("—".into(), |r| format!("{r:.2}"))).collect();
    let ours = our_error_at(our_curve, last.seconds).map_or("—".into(), |e| format!("{e:.2e}"));
    format!(" {:.2} s, {:.2e} | {ours} | {} |", last.seconds, last.relmse, ratios.join(", "))
}

/// 65536 as 65,536.
fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The section `--doc` writes: `converge`, or with `--ours-args` `converge <args>`.
fn doc_section(o: &Options) -> String {
    if o.ours_args.is_empty() { "converge".into() } else { format!("converge {}", o.ours_args.join(" ")) }
}

/// Puts `text` between `<!-- BEGIN name -->` and `<!-- END name -->` in `path`,
/// through a temporary file (see `tools/docsection.py`, its Python twin).
fn write_doc_section(path: &Path, name: &str, text: &str) -> Res<()> {
    let (head, tail) = read_doc_section(path, name)?;
    let (begin, end) = (format!("<!-- BEGIN {name} -->"), format!("<!-- END {name} -->"));
    write_text(path, &format!("{head}{begin}\n{}\n{end}{tail}", text.trim_end())).map_err(|e| e.to_string())
}

/// What `path` holds before and after section `name` (an error when it has none).
fn read_doc_section(path: &Path, name: &str) -> Res<(String, String)> {
    let doc = std::fs::read_to_string(path).map_err(|e| format!("--doc {}: {e}", path.display()))?;
    let (begin, end) = (format!("<!-- BEGIN {name} -->"), format!("<!-- END {name} -->"));
    let Some((head, rest)) = doc.split_once(&begin) else {
        return Err(format!("--doc {}: no section {begin} ... {end}", path.display()));
    };
    let Some((_, tail)) = rest.split_once(&end) else {
        return Err(format!("--doc {}: no {end} after {begin}", path.display()));
    };
    Ok((head.to_string(), tail.to_string()))
}

fn summary_line(label: &str, ratios: &[f64]) -> String {
    if ratios.is_empty() {
        return format!("- {label}: no peer to compare with\n");
    }
    let (lo, hi) = ratios.iter().fold((f64::MAX, f64::MIN), |(a, b), &r| (a.min(r), b.max(r)));
    format!("- {label}: {lo:.2}–{hi:.2}\n")
}

fn curve_series(label: &str, points: &[Point]) -> Series {
    Series { label: label.into(), points: points.iter().map(|p| (p.seconds, p.relmse)).collect() }
}

fn write_csv(path: &Path, points: &[Point]) -> Res<()> {
    let rows: Vec<ErrorRow> = points
        .iter()
        .map(|p| ErrorRow {
            iteration: p.iterations,
            seconds: p.seconds,
            photons: 0,
            mse: 0.0,
            rmse: 0.0,
            relmse: p.relmse,
        })
        .collect();
    write_text(path, &errors_csv(&rows)).map_err(|e| e.to_string())
}

/// The median time (and range) over rounds; relMSE and mean of the median-time round.
fn median_point(iterations: u32, runs: &[(f64, f64, f64)]) -> Point {
    let mut v = runs.to_vec();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mid = v.get(v.len() / 2).copied().unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    Point {
        iterations,
        seconds: mid.0,
        low: v.first().map_or(f64::NAN, |r| r.0),
        high: v.last().map_or(f64::NAN, |r| r.0),
        relmse: mid.1,
        mean_ratio: mid.2,
    }
}

/// Our error at a wall time: that of the last iteration finished by then.
fn our_error_at(curve: &[Point], seconds: f64) -> Option<f64> {
    curve.iter().take_while(|p| p.seconds <= seconds).last().map(|p| p.relmse)
}

/// Per iteration, the median whole-process time over our rounds (relMSE is the same in
/// every round: the image is deterministic). Only iterations every round reached: a
/// median over fewer rounds there would let the curve step back in time.
fn our_curve(runs: &[Vec<(u32, f64, f64)>]) -> Vec<Point> {
    let common = runs.iter().map(Vec::len).min().unwrap_or(0);
    (0..common)
        .map(|i| {
            let at: Vec<(f64, f64, f64)> = runs.iter().map(|r| (r[i].1, r[i].2, f64::NAN)).collect();
            median_point(runs[0][i].0, &at)
        })
        .collect()
}

/// Makes the scene's folder in `--out`, its rewritten files and the references.
fn prepare(o: &Options, spec: &SceneSpec, ours: &Path, peers: &[Peer]) -> Res<Prepared> {
    let src = std::fs::read_to_string(&spec.path).map_err(|e| format!("{}: {e}", spec.path.display()))?;
    let stem = spec.path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let label = if spec.half { format!("{stem}@half") } else { stem.clone() };
    let dir = o.out.join(&label);
    link_folder(&spec.path, &dir)?;
    let at_res = rewrite(&src, None, spec.half).map_err(|e| format!("{}: {e}", spec.path.display()))?;
    let ours_file = dir.join(format!("{stem}.converge.pbrt"));
    write_text(&ours_file, &at_res).map_err(|e| e.to_string())?;
    let (written, photons, syntax, max_depth) = scene_facts(&ours_file)?;
    let ladder = o.ladder.clone().unwrap_or_else(|| default_ladder(written));
    let mut v3 = Vec::new();
    for &n in &ladder {
        let f = dir.join(format!("{stem}.converge.{n}.pbrt"));
        write_text(&f, &rewrite(&at_res, Some(n), false)?).map_err(|e| e.to_string())?;
        v3.push(f);
    }
    let top = ladder.iter().max().copied().unwrap_or(1);
    let reference_iterations = o.reference_iterations.unwrap_or(32 * top);
    let reference = render_reference(o, ours, &ours_file, &at_res, reference_iterations)?;
    let v4 = match peers.iter().find(|p| p.kind == PeerKind::V4) {
        Some(_) if syntax == pbrt_sppm::parser::Syntax::V4 => Some(ours_file.clone()),
        Some(peer) => v4_upgrade(&peer.exe, &ours_file, &dir, &stem)?,
        None => None,
    };
    let reference_v4 = match &v4 {
        Some(f) if f != &ours_file => {
            let text = std::fs::read_to_string(f).map_err(|e| e.to_string())?;
            Some(render_reference(o, ours, f, &text, reference_iterations)?.image)
        }
        Some(_) => Some(reference.image.clone()),
        None => None,
    };
    Ok(Prepared {
        label,
        dir,
        ladder,
        ours: ours_file,
        v3,
        v4,
        reference_noise: reference.noise,
        reference_file: reference.path,
        reference: reference.image,
        reference_iterations,
        reference_v4,
        iterations: written,
        photons,
        max_depth,
    })
}

/// N/4, N/2 and N (distinct, at least 1).
fn default_ladder(n: u32) -> Vec<u32> {
    let mut v = vec![(n / 4).max(1), (n / 2).max(1), n.max(1)];
    v.dedup();
    v
}

/// The scene's iteration count, photons per iteration, syntax and maxdepth (one load
/// serves all).
fn scene_facts(file: &Path) -> Res<(u32, u64, pbrt_sppm::parser::Syntax, u32)> {
    let opts = pbrt_sppm::scene::LoadOptions::default();
    let scene = pbrt_sppm::scene::load_scene(file, &opts).map_err(|e| e.one_line())?;
    let i = &scene.integrator;
    Ok((i.iterations, i.photons_per_iteration, scene.syntax, i.max_depth))
}

/// `dir` gets a link to every entry of the scene's folder (so `Include`, meshes and
/// textures resolve as they did), except earlier rewritten files.
fn link_folder(scene: &Path, dir: &Path) -> Res<()> {
    let folder = scene.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let folder = folder.canonicalize().map_err(|e| format!("{}: {e}", folder.display()))?;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let entries = std::fs::read_dir(&folder).map_err(|e| format!("{}: {e}", folder.display()))?;
    for entry in entries.flatten() {
        let link = dir.join(entry.file_name());
        if link.symlink_metadata().is_ok() {
            continue;
        }
        symlink(&entry.path(), &link).map_err(|e| format!("{}: {e}", link.display()))?;
    }
    Ok(())
}

#[cfg(unix)]
fn symlink(target: &Path, link: &Path) -> std::io::Result<()> {
    std::os::unix::fs::symlink(target, link)
}

#[cfg(not(unix))]
fn symlink(target: &Path, link: &Path) -> std::io::Result<()> {
    std::fs::copy(target, link).map(|_| ())
}

/// pbrt-v4's translation of a v3 scene, if it can render it.
fn v4_upgrade(v4: &Path, file: &Path, dir: &Path, stem: &str) -> Res<Option<PathBuf>> {
    let out = output(Command::new(v4).arg("--upgrade").arg(file.file_name().unwrap_or_default()).current_dir(dir))?;
    if !out.status.success() {
        println!("pbrt-v4 --upgrade failed: {}", error_line(&out.stderr));
        return Ok(None);
    }
    let upgraded = dir.join(format!("{stem}.converge.v4.pbrt"));
    std::fs::write(&upgraded, &out.stdout).map_err(|e| format!("{}: {e}", upgraded.display()))?;
    // One iteration first: a translation pbrt-v4 refuses is not worth a reference.
    let trial = output(
        Command::new(v4)
            .args(["--quiet", "--nthreads", "1", "--spp", "1", "--outfile", "trial-v4.exr"])
            .arg(&upgraded)
            .current_dir(dir),
    )?;
    if !trial.status.success() {
        println!("pbrt-v4 cannot render its translation: {}", error_line(&trial.stderr));
        return Ok(None);
    }
    Ok(Some(upgraded))
}

/// Runs a command to completion with no input, its output captured.
fn output(cmd: &mut Command) -> Res<std::process::Output> {
    let exe = cmd.get_program().to_string_lossy().into_owned();
    cmd.stdin(Stdio::null()).output().map_err(|e| format!("{exe}: {e}"))
}

/// Our reference for `file`: two renders of half the iterations each, with seeds of
/// their own, averaged. Their difference measures the reference's own noise, which
/// every relMSE against it contains: E[(x − y)²] = E[(x − truth)²] + Var(y) for an
/// image x independent of the reference y, and Var(y) = E[(a − b)²]/4 for the mean y of
/// two independent halves a and b. Cached under `--out/refs` by the scene's text, the
/// iterations, `--reference-args` and our binary's bytes (a rebuilt renderer renders a
/// new reference rather than reusing an older estimator's).
fn render_reference(o: &Options, ours: &Path, file: &Path, text: &str, n: u32) -> Res<Reference> {
    let binary = std::fs::read(ours).map_err(|e| format!("{}: {e}", ours.display()))?;
    let key = pbrt_sppm::sampling::hash(&[
        fnv(text.as_bytes()),
        n as u64,
        fnv(o.reference_args.join(" ").as_bytes()),
        fnv(&binary),
    ]);
    let refs = o.out.join("refs");
    let halves_dir = refs.join("halves");
    std::fs::create_dir_all(&halves_dir).map_err(|e| format!("{}: {e}", halves_dir.display()))?;
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let path = refs.join(format!("{stem}-{n}-{key:016x}.exr"));
    let counts = [n.div_ceil(2), n / 2];
    let mut halves = Vec::new();
    for (k, &count) in counts.iter().enumerate().filter(|(_, c)| **c > 0) {
        let half = halves_dir.join(format!("{stem}-{n}-{key:016x}-{k}.exr"));
        if !half.exists() {
            println!("rendering the reference {} (part {} of 2, {count} iterations)", path.display(), k + 1);
            let t = Instant::now();
            render_part(o, ours, file, count, 1_000_003 + k as u64, &half)?;
            println!("  {:.1} s", t.elapsed().as_secs_f64());
        }
        halves.push(read_image(&half).map_err(|e| format!("{}: {e}", half.display()))?);
    }
    let (image, noise) = average(&halves)?;
    if !path.exists() {
        pbrt_sppm::imageio::write_exr(&path, &image).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(Reference { path, image, noise })
}

/// A reference and its own relMSE (None when it was rendered in one part).
struct Reference {
    path: PathBuf,
    image: RgbImage,
    noise: Option<f64>,
}

fn render_part(o: &Options, ours: &Path, file: &Path, n: u32, seed: u64, out: &Path) -> Res<()> {
    let status = Command::new(ours)
        .arg("render")
        .arg(file)
        .args(["--quiet", "--seed", &seed.to_string(), "--spp", &n.to_string()])
        .args(["--nthreads", &o.nthreads.to_string()])
        .args(&o.reference_args)
        .arg("--outfile")
        .arg(out)
        .stdin(Stdio::null())
        .status()
        .map_err(|e| format!("{}: {e}", ours.display()))?;
    if !status.success() {
        return Err(format!("the reference render of {} failed", file.display()));
    }
    Ok(())
}

/// The mean of a reference's parts, and the relMSE the mean has against the truth by
/// its noise alone: per channel ((a − b)/2)² over the mean's square + 0.01, as
/// `metrics::relmse` weighs it.
fn average(parts: &[RgbImage]) -> Res<(RgbImage, Option<f64>)> {
    let [a, b] = parts else { return Ok((parts[0].clone(), None)) };
    if a.pixels.len() != b.pixels.len() {
        return Err("the reference's two parts differ in size".into());
    }
    let mut mean = a.clone();
    let mut noise = 0.0;
    for (m, q) in mean.pixels.iter_mut().zip(&b.pixels) {
        for c in 0..3 {
            let (x, y) = (m[c] as f64, q[c] as f64);
            let mid = 0.5 * (x + y);
            noise += (0.5 * (x - y)).powi(2) / (mid * mid + 0.01);
            m[c] = mid as f32;
        }
    }
    Ok((mean, Some(noise / (3 * a.pixels.len()).max(1) as f64)))
}

fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf29ce484222325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100000001b3))
}

/// The line of a program's output that says what went wrong: the first with "error",
/// else the last (clap ends with a pointer to `--help`).
fn error_line(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let error = text.lines().find(|l| l.contains("error"));
    error.or_else(|| text.lines().rev().find(|l| !l.trim().is_empty())).unwrap_or("").to_string()
}

/// One peer run: (wall seconds, relMSE, mean / reference mean).
fn run_peer(p: &Prepared, peer: &Peer, rung: usize, n: u32, nthreads: usize) -> Res<(f64, f64, f64)> {
    let out = p.dir.join(format!("{}-{n}.exr", peer.name().replace(' ', "-")));
    let mut cmd = Command::new(&peer.exe);
    cmd.args(["--quiet", "--nthreads", &nthreads.to_string(), "--outfile"]).arg(&out);
    let reference = match (peer.kind, peer.method) {
        (PeerKind::V3, Method::Sppm) => {
            cmd.arg(&p.v3[rung]);
            &p.reference
        }
        (PeerKind::V3, method) => {
            cmd.arg(method_input(&p.ours, method, p.max_depth, Some(n))?);
            &p.reference
        }
        (PeerKind::V4, method) => {
            let file = p.v4.as_ref().ok_or("no input pbrt-v4 reads")?;
            let file = match method {
                Method::Sppm => file.clone(),
                _ => method_input(file, method, p.max_depth, None)?,
            };
            cmd.args(["--spp", &n.to_string()]).arg(file);
            p.reference_v4.as_ref().ok_or("no pbrt-v4 reference")?
        }
    };
    let _ = std::fs::remove_file(&out);
    let t = Instant::now();
    let done = output(cmd.current_dir(&p.dir))?;
    let seconds = t.elapsed().as_secs_f64();
    if !done.status.success() {
        return Err(format!("exit {:?}: {}", done.status.code(), error_line(&done.stderr)));
    }
    let img = read_image(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let (e, m) = compare(&img, reference)?;
    Ok((seconds, e, m))
}

/// relMSE and the ratio of mean values (all channels) against the reference.
fn compare(img: &RgbImage, reference: &RgbImage) -> Res<(f64, f64)> {
    if (img.width, img.height) != (reference.width, reference.height) {
        return Err(format!(
            "the image is {}x{}, the reference {}x{}",
            img.width, img.height, reference.width, reference.height
        ));
    }
    let mean = |px: &[[f32; 3]]| px.iter().map(|p| p.iter().map(|&c| c as f64).sum::<f64>()).sum::<f64>();
    let ratio = mean(&img.pixels) / mean(&reference.pixels).max(1e-300);
    Ok((metrics::relmse(&img.pixels, &reference.pixels), ratio))
}

/// One run of ours: per iteration (iteration, whole-process seconds, relMSE).
fn run_ours(o: &Options, p: &Prepared, ours: &Path, budget: Option<f64>) -> Res<Vec<(u32, f64, f64)>> {
    let csv = p.dir.join("ours-errors.csv");
    let top = p.ladder.iter().max().copied().unwrap_or(1);
    let mut cmd = Command::new(ours);
    cmd.arg("render").arg(&p.ours).args(["--quiet", "--nthreads", &o.nthreads.to_string()]);
    cmd.arg("--outfile").arg(p.dir.join("ours.exr")).args(&o.ours_args);
    cmd.arg("--mse-reference-image").arg(&p.reference_file).arg("--mse-reference-out").arg(&csv);
    match budget {
        // Far more iterations than needed; the time limit ends the run.
        Some(t) => cmd.args(["--spp", &(64 * top).to_string(), "--time-limit", &format!("{t:.3}")]),
        None => cmd.args(["--spp", &top.to_string()]),
    };
    let t = Instant::now();
    let done = output(&mut cmd)?;
    let wall = t.elapsed().as_secs_f64();
    if !done.status.success() {
        return Err(format!("pbrt-sppm on {}: {}", p.ours.display(), error_line(&done.stderr)));
    }
    let rows = read_errors(&csv)?;
    // Loading and writing, which ERRORS.csv leaves out, are added to every row.
    let overhead = wall - rows.last().map_or(0.0, |r| r.1);
    Ok(rows.into_iter().map(|(i, s, e)| (i, s + overhead, e)).collect())
}

fn read_errors(path: &Path) -> Res<Vec<(u32, f64, f64)>> {
    let rows = read_columns(path, &["iteration", "seconds", "relmse"])?;
    Ok(rows.into_iter().map(|r| (r[0] as u32, r[1], r[2])).collect())
}

/// The scene text with `numiterations` set on every `Integrator` and, for `half`, the
/// `Film`'s resolution halved. Token-exact: comments, layout and everything else stay.
fn rewrite(src: &str, iterations: Option<u32>, half: bool) -> Res<String> {
    let tokens = tokens(src)?;
    let text = |t: &Token| &src[t.start as usize..t.end as usize];
    let is_directive = |t: &Token| t.kind == TokenKind::Word && text(t).starts_with(|c: char| c.is_ascii_uppercase());
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    let (mut integrators, mut films) = (0, 0);
    for (i, t) in tokens.iter().enumerate() {
        let name = match (text(t), iterations) {
            ("Integrator", Some(_)) | ("Film", _) if is_directive(t) => text(t),
            _ => continue,
        };
        if name == "Film" && !half {
            continue;
        }
        let Some(kind) = tokens.get(i + 1).filter(|t| t.kind == TokenKind::Str) else {
            return Err(format!("{name} without a type"));
        };
        let end = tokens[i + 1..].iter().position(is_directive).map_or(tokens.len(), |k| i + 1 + k);
        let params = params(src, &tokens[i + 2..end]);
        if let ("Integrator", Some(n)) = (name, iterations) {
            integrators += 1;
            match params.iter().find(|p| p.0 == "numiterations") {
                Some(p) => edits.push((p.1, p.2, format!("[ {n} ]"))),
                None => {
                    edits.push((kind.end as usize, kind.end as usize, format!(" \"integer numiterations\" [ {n} ]")))
                }
            }
        } else {
            films += 1;
            for axis in ["xresolution", "yresolution"] {
                let p = params.iter().find(|p| p.0 == axis).ok_or_else(|| format!("Film has no {axis} to halve"))?;
                let v: u32 = p.3.parse().map_err(|_| format!("Film {axis} '{}' is not an integer", p.3))?;
                edits.push((p.1, p.2, format!("[ {} ]", (v / 2).max(1))));
            }
        }
    }
    if iterations.is_some() && integrators == 0 {
        return Err("no Integrator directive in the main file".into());
    }
    if half && films == 0 {
        return Err("no Film directive in the main file".into());
    }
    edits.sort_by_key(|e| e.0);
    let mut out = String::with_capacity(src.len() + 64);
    let mut at = 0;
    for (start, end, new) in edits {
        out.push_str(&src[at..start]);
        out.push_str(&new);
        at = end;
    }
    out.push_str(&src[at..]);
    Ok(out)
}

/// `file` with its Integrator replaced by `method` at `max_depth` and, given `spp`, its
/// Sampler by a Halton sampler of that many samples (pbrt-v3 has no `--spp`); written
/// beside it, named after the method and count.
fn method_input(file: &Path, method: Method, max_depth: u32, spp: Option<u32>) -> Res<PathBuf> {
    let src = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    // pbrt's `path` ignores media; its `volpath` is the same integrator with them.
    let name = match method {
        Method::Bdpt => "bdpt",
        _ if src.contains("MakeNamedMedium") => "volpath",
        _ => "path",
    };
    let mut text =
        replace_directive(&src, "Integrator", &format!("Integrator \"{name}\" \"integer maxdepth\" [ {max_depth} ]"))?;
    if let Some(n) = spp {
        let sampler = format!("Sampler \"halton\" \"integer pixelsamples\" [ {n} ]");
        text = match replace_directive(&text, "Sampler", &sampler) {
            Ok(t) => t,
            Err(_) => text.replacen("Integrator", &format!("{sampler}\nIntegrator"), 1),
        };
    }
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let out = file.with_file_name(format!("{stem}.{name}{}.pbrt", spp.map_or(String::new(), |n| format!(".{n}"))));
    write_text(&out, &text).map_err(|e| e.to_string())?;
    Ok(out)
}

/// `src` with the first `directive` statement (name, type and parameters) replaced by
/// `with`; an error when there is none.
fn replace_directive(src: &str, directive: &str, with: &str) -> Res<String> {
    let tokens = tokens(src)?;
    let text = |t: &Token| &src[t.start as usize..t.end as usize];
    let is_directive = |t: &Token| t.kind == TokenKind::Word && text(t).starts_with(|c: char| c.is_ascii_uppercase());
    let i = tokens.iter().position(|t| is_directive(t) && text(t) == directive).ok_or(format!("no {directive}"))?;
    let end = tokens[i + 1..].iter().position(is_directive).map_or(tokens.len(), |k| i + 1 + k);
    let (a, b) = (tokens[i].start as usize, tokens[end - 1].end as usize);
    Ok(format!("{}{with}{}", &src[..a], &src[b..]))
}

fn tokens(src: &str) -> Res<Vec<Token>> {
    let mut lexer = Lexer::new(src.as_bytes());
    let mut v = Vec::new();
    while let Some(t) = lexer.next_significant().map_err(|e| format!("byte {}: {}", e.offset, e.message))? {
        v.push(t);
    }
    Ok(v)
}

/// A directive's parameters: (name, value start, value end, first value's text).
fn params(src: &str, tokens: &[Token]) -> Vec<(String, usize, usize, String)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let t = tokens[i];
        i += 1;
        if t.kind != TokenKind::Str {
            continue;
        }
        let decl = decode_string(&src.as_bytes()[t.start as usize..t.end as usize]);
        let Some(name) = decl.split_whitespace().nth(1).map(str::to_string) else { continue };
        let Some(first) = tokens.get(i) else { break };
        let (last, value) = if first.kind == TokenKind::LBracket {
            let close =
                tokens[i..].iter().position(|t| t.kind == TokenKind::RBracket).map_or(tokens.len() - 1, |k| i + k);
            (close, tokens.get(i + 1).filter(|_| close > i + 1).copied())
        } else {
            (i, Some(*first))
        };
        let text = value.map_or(String::new(), |v| src[v.start as usize..v.end as usize].to_string());
        out.push((name, first.start as usize, tokens[last].end as usize, text));
        i = last + 1;
    }
    out
}
