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

pub fn progress_bar(done: u32, total: u32, seconds: f64) {
    let width = 30;
    let filled = (done as usize * width) / total.max(1) as usize;
    let eta = seconds / done.max(1) as f64 * (total - done) as f64;
    eprint!(
        "\r[{}{}] {done}/{total} iterations, {seconds:.1} s, ETA {eta:.1} s   ",
        "#".repeat(filled),
        "-".repeat(width - filled)
    );
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
pub fn progress_inside(done: u32, total: u32, seconds: f64, live: &Live, (pixels, photons): (u64, u64)) {
    let width = 30;
    let filled = (done as usize * width) / total.max(1) as usize;
    let (c, p) = live.counts();
    let pct = |a: u64, b: u64| (100 * a / b.max(1)).min(100);
    eprint!(
        "\r[{}{}] {done}/{total} iterations, {seconds:.1} s; iteration {}: camera paths {}%, photons {}%   ",
        "#".repeat(filled),
        "-".repeat(width - filled),
        done + 1,
        pct(c, pixels),
        pct(p, photons)
    );
}
