//! Reporting while rendering: `ERRORS.csv` rows (a fixed contract), the progress bar,
//! and the counts of the iteration under way ([`Live`]) that keep it moving inside long
//! iterations.

use std::sync::atomic::{AtomicU64, Ordering};

/// One `ERRORS.csv` row.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorRow {
    pub iteration: u32,
    pub seconds: f64,
    pub photons: u64,
    pub mse: f64,
    pub rmse: f64,
    pub relmse: f64,
}

/// The header of `ERRORS.csv` (a fixed contract).
pub const ERRORS_HEADER: &str = "iteration,seconds,photons,mse,rmse,relmse";

/// `ERRORS.csv` text.
pub fn errors_csv(rows: &[ErrorRow]) -> String {
    let mut s = format!("{ERRORS_HEADER}\n");
    for r in rows {
        s.push_str(&format!(
            "{},{:.6},{},{:e},{:e},{:e}\n",
            r.iteration, r.seconds, r.photons, r.mse, r.rmse, r.relmse
        ));
    }
    s
}

/// The progress bar after an iteration, on one line of stderr.
pub fn progress_bar(at: Pace) {
    let (bar, eta) = at.bar();
    eprint!("\r{bar}, ETA {eta:.1} s   ");
}

/// Camera paths and photons (or light subpaths) of the iteration under way, counted a
/// work item at a time (one atomic add per item of up to a thousand paths).
#[derive(Debug, Default)]
pub struct Live {
    camera: AtomicU64,
    photons: AtomicU64,
}

impl Live {
    pub fn reset(&self) {
        self.camera.store(0, Ordering::Relaxed);
        self.photons.store(0, Ordering::Relaxed);
    }

    pub fn add_camera(&self, n: u64) {
        self.camera.fetch_add(n, Ordering::Relaxed);
    }

    pub fn add_photons(&self, n: u64) {
        self.photons.fetch_add(n, Ordering::Relaxed);
    }

    /// (camera paths, photons) so far.
    pub fn counts(&self) -> (u64, u64) {
        (self.camera.load(Ordering::Relaxed), self.photons.load(Ordering::Relaxed))
    }
}

/// The progress bar while iteration `done + 1` runs: how far its camera paths and
/// photons are (`photons` per iteration, `pixels` camera paths).
pub fn progress_inside(at: Pace, live: &Live, (pixels, photons): (u64, u64)) {
    let (bar, _) = at.bar();
    let (c, p) = live.counts();
    let pct = |a: u64, b: u64| (100 * a / b.max(1)).min(100);
    let n = at.done + 1;
    eprint!("\r{bar}; {} {n}: camera paths {}%, {} {}%   ", at.singular(), pct(c, pixels), at.light, pct(p, photons));
}

/// Where a render stands, for its progress lines.
#[derive(Clone, Copy, Debug)]
pub struct Pace {
    pub done: u32,
    pub total: u32,
    pub seconds: f64,
    /// `--time-limit`.
    pub limit: Option<f64>,
    /// What an iteration is called: "iterations" (SPPM) or "passes" (vcm, bdpt, and
    /// SPPM's independent passes), as the summary calls them.
    pub word: &'static str,
    /// "photons" or "light subpaths".
    pub light: &'static str,
}

impl Pace {
    /// The bar and what it counts, toward whichever ends the render first: `total`
    /// iterations (at the pace so far) or the time `limit`; and the seconds left.
    fn bar(&self) -> (String, f64) {
        let Pace { done, total, seconds, limit, word, .. } = *self;
        let width = 30;
        let left = seconds / done.max(1) as f64 * total.saturating_sub(done) as f64;
        let (filled, text, eta) = match limit {
            Some(l) if done == 0 || l - seconds < left => {
                let filled = ((seconds / l).clamp(0.0, 1.0) * width as f64) as usize;
                (filled, format!("{seconds:.1}/{l} s, {done} {word}"), (l - seconds).max(0.0))
            }
            _ => (
                (done as usize * width) / total.max(1) as usize,
                format!("{done}/{total} {word}, {seconds:.1} s"),
                left,
            ),
        };
        (format!("[{}{}] {text}", "#".repeat(filled), "-".repeat(width - filled)), eta)
    }

    fn singular(&self) -> &'static str {
        self.word.strip_suffix('s').unwrap_or(self.word)
    }
}
