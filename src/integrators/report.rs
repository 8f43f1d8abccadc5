//! Reporting while rendering: `ERRORS.csv` rows (a fixed contract) and the progress bar.

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
