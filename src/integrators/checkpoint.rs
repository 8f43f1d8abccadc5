//! Checkpoints: the whole progressive state of a render between two iterations, saved
//! atomically and resumed bit-for-bit.
//!
//! ```text
//! pbrt-sppm render scene.pbrt --checkpoint scene.ckpt --checkpoint-every 5m
//! pbrt-sppm render scene.pbrt --resume scene.ckpt      # after a crash or Ctrl-C
//! ```
//! What is saved: per pixel the radius, N, τ and the summed direct light (f64, as held)
//! and a spectral film's bucket sums;
//! the iterations done, the seconds spent, the statistics and `ERRORS.csv` rows so far;
//! the adaptive photon chains. Camera and photon numbers are functions of (seed, pixel
//! or photon, iteration), so no sampler state is needed beyond the chains'.
//!
//! A checkpoint names what made it ([`Fingerprint`]): every input file with a hash of
//! its bytes, and every setting that changes the image. `--resume` refuses one that
//! does not match, saying what differs.
//!
//! The file: a text line `pbrt-sppm checkpoint 1`, a little-endian u64 length and a
//! JSON header of that length, the pixels (8 little-endian f64 each: radius, N, Ld,
//! τ), a spectral film's bucket sums (f64, as many as the header's `bucket_sums`), and
//! the 64-bit XXH3 of everything before it, so that a torn or damaged file is
//! refused rather than resumed.

use super::adaptive::Chain;
use super::report::ErrorRow;
use super::sppm::{PixelState, Stats};
use crate::imageio::ImageError;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

const MAGIC: &[u8] = b"pbrt-sppm checkpoint 1\n";
/// Bytes of one pixel's state.
const PIXEL_BYTES: usize = 64;

/// Why a checkpoint cannot be written, read or continued.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot encode the checkpoint: {0}")]
    Encode(serde_json::Error),
    #[error("not a pbrt-sppm checkpoint (or one of another version)")]
    NotACheckpoint,
    #[error("the checkpoint is damaged or incomplete (its checksum does not match)")]
    Damaged,
    #[error("the checkpoint's header is unreadable: {0}")]
    Header(serde_json::Error),
    #[error(transparent)]
    File(#[from] ImageError),
}

/// How a render's fingerprint differs from the one it would continue: one sentence per
/// difference.
#[derive(Debug, PartialEq, thiserror::Error)]
#[error("{}", .0.join("; "))]
pub struct Mismatch(pub Vec<String>);

/// What a render was made from: compared on `--resume`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// The scene file as named on the command line, made absolute.
    pub scene: String,
    /// Every file read (scene, includes, meshes, images): absolute path and XXH3.
    pub inputs: Vec<(String, u64)>,
    /// Every setting that changes the image, by name.
    pub settings: Vec<(String, String)>,
}

impl Fingerprint {
    /// `Ok` when a render made from `self` may be continued as `now`; otherwise every
    /// difference found, one per line.
    pub fn check(&self, now: &Fingerprint) -> Result<(), Mismatch> {
        let mut diffs = Vec::new();
        for (name, old) in &self.settings {
            match now.settings.iter().find(|(n, _)| n == name) {
                Some((_, new)) if new != old => {
                    diffs.push(format!("it was made with {name} {old}, this run has {new}"))
                }
                None => diffs.push(format!("it was made with {name} {old}, which this run does not set")),
                _ => {}
            }
        }
        diffs.extend(self.input_differences(now));
        if diffs.is_empty() { Ok(()) } else { Err(Mismatch(diffs)) }
    }

    /// A moved scene folder is the same scene: files are compared by content first.
    fn input_differences(&self, now: &Fingerprint) -> Vec<String> {
        let contents = |f: &Fingerprint| {
            let mut h: Vec<u64> = f.inputs.iter().map(|i| i.1).collect();
            h.sort_unstable();
            h
        };
        if contents(self) == contents(now) {
            return Vec::new();
        }
        if self.scene != now.scene {
            return vec![format!("it was made from the scene \"{}\", not \"{}\"", self.scene, now.scene)];
        }
        let mut diffs = Vec::new();
        for (path, hash) in &self.inputs {
            match now.inputs.iter().find(|i| &i.0 == path) {
                Some(i) if i.1 != *hash => diffs.push(format!("\"{path}\" has changed since")),
                None => diffs.push(format!("the scene no longer reads \"{path}\"")),
                _ => {}
            }
        }
        for (path, _) in &now.inputs {
            if !self.inputs.iter().any(|i| &i.0 == path) {
                diffs.push(format!("the scene now reads \"{path}\", which it did not"));
            }
        }
        diffs
    }
}

/// When to save: every so many iterations or seconds (`--checkpoint-every 10`, `90s`,
/// `5m`, `2h`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Every {
    Iterations(u32),
    Seconds(f64),
}

impl Default for Every {
    fn default() -> Every {
        Every::Seconds(300.0)
    }
}

impl std::str::FromStr for Every {
    type Err = String;
    fn from_str(s: &str) -> Result<Every, String> {
        let bad = || format!("\"{s}\" is neither a number of iterations (10) nor a time (90s, 5m, 2h)");
        let (digits, unit) = match s.trim().char_indices().find(|c| c.1.is_ascii_alphabetic()) {
            Some((i, _)) => s.trim().split_at(i),
            None => (s.trim(), ""),
        };
        if unit.is_empty() {
            return match digits.parse::<u32>() {
                Ok(n) if n >= 1 => Ok(Every::Iterations(n)),
                _ => Err(bad()),
            };
        }
        let scale = match unit {
            "s" => 1.0,
            "m" => 60.0,
            "h" => 3600.0,
            _ => return Err(bad()),
        };
        match digits.parse::<f64>() {
            Ok(v) if v > 0.0 && v.is_finite() => Ok(Every::Seconds(v * scale)),
            _ => Err(bad()),
        }
    }
}

/// A render's state between two iterations. All but the pixels go into the JSON
/// header; the pixels follow it in binary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    pub fingerprint: Fingerprint,
    /// Iterations done.
    pub iteration: u32,
    /// Render seconds spent so far (over every run that continued it).
    pub seconds: f64,
    pub stats: Stats,
    pub errors: Vec<ErrorRow>,
    #[serde(skip)]
    pub pixels: Vec<PixelState>,
    pub chains: Option<Vec<Chain>>,
    /// A spectral film's bucket sums (vcm and bdpt), after the pixels in the file; the
    /// header's `bucket_sums` says how many (none in files written before them).
    #[serde(skip)]
    pub buckets: Vec<f64>,
    /// vcm's state that the passes so far decided and a resumed render would
    /// otherwise replay them for: the pilot's light subpaths per pass, the path guide
    /// and `--connections auto`'s choice to keep the pairs (none in files written
    /// before them; see [`super::vcm::Decided`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light_paths: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guide: Option<crate::guiding::Guide>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pairs_kept: Option<super::vcm::links::Unblocking>,
}

impl Checkpoint {
    fn to_bytes(&self) -> Result<Vec<u8>, CheckpointError> {
        let mut header = serde_json::to_value(self).map_err(CheckpointError::Encode)?;
        header["bucket_sums"] = self.buckets.len().into();
        let json = serde_json::to_vec(&header).map_err(CheckpointError::Encode)?;
        let mut out = Vec::with_capacity(MAGIC.len() + 16 + json.len() + self.pixels.len() * PIXEL_BYTES);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&(json.len() as u64).to_le_bytes());
        out.extend_from_slice(&json);
        for p in &self.pixels {
            for v in [p.radius, p.n, p.ld[0], p.ld[1], p.ld[2], p.tau[0], p.tau[1], p.tau[2]] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        for v in &self.buckets {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let sum = xxhash_rust::xxh3::xxh3_64(&out);
        out.extend_from_slice(&sum.to_le_bytes());
        Ok(out)
    }

    fn from_bytes(bytes: &[u8]) -> Result<Checkpoint, CheckpointError> {
        use CheckpointError::Damaged;
        let body = bytes.strip_prefix(MAGIC).ok_or(CheckpointError::NotACheckpoint)?;
        let (body, sum) = body.split_at_checked(body.len().wrapping_sub(8)).ok_or(Damaged)?;
        let whole = &bytes[..bytes.len() - 8];
        if xxhash_rust::xxh3::xxh3_64(whole).to_le_bytes() != sum {
            return Err(Damaged);
        }
        let (len, rest) = body.split_at_checked(8).ok_or(Damaged)?;
        let len = usize::try_from(u64::from_le_bytes(len.try_into().map_err(|_| Damaged)?)).map_err(|_| Damaged)?;
        let (json, pixels) = rest.split_at_checked(len).ok_or(Damaged)?;
        let header: serde_json::Value = serde_json::from_slice(json).map_err(CheckpointError::Header)?;
        let bucket_sums = header.get("bucket_sums").and_then(|v| v.as_u64()).unwrap_or(0);
        let mut c: Checkpoint = serde_json::from_value(header).map_err(CheckpointError::Header)?;
        let cut = usize::try_from(bucket_sums)
            .ok()
            .and_then(|n| n.checked_mul(8))
            .and_then(|n| pixels.len().checked_sub(n))
            .ok_or(Damaged)?;
        let (pixels, buckets) = pixels.split_at(cut);
        if !pixels.len().is_multiple_of(PIXEL_BYTES) {
            return Err(Damaged);
        }
        let f = |c: &[u8], k: usize| f64::from_le_bytes(c[8 * k..8 * k + 8].try_into().unwrap_or([0; 8]));
        c.buckets = buckets.chunks_exact(8).map(|b| f(b, 0)).collect();
        c.pixels = pixels
            .chunks_exact(PIXEL_BYTES)
            .map(|c| {
                let v: [f64; 8] = std::array::from_fn(|k| f(c, k));
                PixelState { radius: v[0], n: v[1], ld: [v[2], v[3], v[4]], tau: [v[5], v[6], v[7]] }
            })
            .collect();
        Ok(c)
    }

    /// Writes the checkpoint beside `path`, flushes it to the disk and only then
    /// renames it over `path`: a crash at any moment leaves the previous checkpoint or
    /// this one, never a torn file.
    pub fn write(&self, path: &Path) -> Result<(), CheckpointError> {
        let bytes = self.to_bytes()?;
        let written = crate::imageio::atomically(path, |tmp| {
            let mut f = std::fs::File::create(tmp).map_err(|e| ImageError::write(path, e))?;
            f.write_all(&bytes).and_then(|()| f.sync_all()).map_err(|e| ImageError::write(path, e))
        });
        Ok(written?)
    }

    pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
        let cannot = |e: &dyn std::fmt::Display| ImageError::Read { path: path.to_path_buf(), why: e.to_string() };
        if !std::fs::metadata(path).map_err(|e| cannot(&e))?.is_file() {
            return Err(cannot(&"not a regular file").into());
        }
        let bytes = std::fs::read(path).map_err(|e| cannot(&e))?;
        Checkpoint::from_bytes(&bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        let fingerprint = Fingerprint {
            scene: "/s/a.pbrt".into(),
            inputs: vec![("/s/a.pbrt".into(), 1), ("/s/m.ply".into(), 2)],
            settings: vec![("photons".into(), "100".into()), ("seed".into(), "0".into())],
        };
        let px = |i: usize| PixelState {
            radius: 0.1 / (i + 1) as f64,
            n: i as f64,
            ld: [1e-300, 0.3, -0.0],
            tau: [f64::MAX, 2.5, 1.0 / 3.0],
        };
        Checkpoint {
            fingerprint,
            iteration: 7,
            seconds: 1.25,
            stats: Stats { iterations: 7, camera_rays: 99, ..Stats::default() },
            errors: vec![ErrorRow {
                iteration: 1,
                seconds: 0.1,
                photons: 100,
                mse: 0.1,
                rmse: 0.1f64.sqrt(),
                relmse: 1.0 / 3.0,
            }],
            pixels: (0..5).map(px).collect(),
            chains: Some(Chain::new_set(3)),
            buckets: vec![0.5, -1e-300, 7.0],
            light_paths: Some(12_345),
            guide: Some(trained_guide()),
            pairs_kept: Some(crate::integrators::vcm::links::Unblocking { paired: 0.1 + 0.2, predicted: 1.0 / 3.0 }),
        }
    }

    /// A guide after one round, its sums not short decimals.
    fn trained_guide() -> crate::guiding::Guide {
        use glam::Vec3;
        let mut g = crate::guiding::Guide::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0 / 7.0), true);
        let d = |k: u32| Vec3::new((k as f32).sin(), (k as f32).cos(), 0.3).normalize();
        let records: Vec<_> = (0..5000)
            .map(|k| crate::guiding::Record {
                p: Vec3::splat(k as f32 / 5000.0),
                d: d(k),
                energy: 1.0 / (1 + k) as f32,
            })
            .collect();
        // The importance tree learns the same points from the other way.
        let importance = records.iter().map(|r| crate::guiding::Record { d: -r.d, ..*r }).collect();
        g.add_pass(&crate::guiding::Records { radiance: records, importance });
        g
    }

    #[test]
    fn a_checkpoint_reads_back_bit_for_bit() {
        let c = sample();
        let back = Checkpoint::from_bytes(&c.to_bytes().unwrap()).unwrap();
        assert_eq!(back.pixels, c.pixels);
        assert_eq!(back.buckets, c.buckets);
        assert_eq!(back.errors, c.errors);
        assert_eq!((back.iteration, back.seconds, back.stats.camera_rays), (7, 1.25, 99));
        assert_eq!(back.fingerprint, c.fingerprint);
        assert_eq!(format!("{:?}", back.chains), format!("{:?}", c.chains));
        assert_eq!((back.light_paths, &back.guide), (Some(12_345), &c.guide));
        assert_eq!(back.pairs_kept, c.pairs_kept);
        assert!(c.guide.as_ref().is_some_and(|g| g.recorded() == 1 && g.importance().is_some()));
    }

    #[test]
    fn a_torn_or_altered_checkpoint_is_refused() {
        let bytes = sample().to_bytes().unwrap();
        for cut in [0, 5, MAGIC.len() + 3, bytes.len() / 2, bytes.len() - 1] {
            assert!(Checkpoint::from_bytes(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut flipped = bytes.clone();
        let at = bytes.len() - 20;
        flipped[at] ^= 1;
        assert!(matches!(Checkpoint::from_bytes(&flipped), Err(CheckpointError::Damaged)));
    }

    #[test]
    fn fingerprints_name_what_differs() {
        let a = sample().fingerprint;
        assert!(a.check(&a).is_ok());
        let mut b = a.clone();
        b.settings[0].1 = "200".into();
        assert_eq!(a.check(&b).unwrap_err().to_string(), "it was made with photons 100, this run has 200");
        let mut c = a.clone();
        c.inputs[1].1 = 3;
        assert_eq!(a.check(&c).unwrap_err().to_string(), "\"/s/m.ply\" has changed since");
        let mut moved = a.clone();
        moved.scene = "/t/a.pbrt".into();
        moved.inputs = vec![("/t/a.pbrt".into(), 1), ("/t/m.ply".into(), 2)];
        assert!(a.check(&moved).is_ok(), "a moved folder is the same scene");
        let mut other = c.clone();
        other.scene = "/t/b.pbrt".into();
        assert!(a.check(&other).unwrap_err().to_string().contains("made from the scene \"/s/a.pbrt\""));
    }

    #[test]
    fn intervals_parse_as_iterations_or_times() {
        assert_eq!("10".parse(), Ok(Every::Iterations(10)));
        assert_eq!("90s".parse(), Ok(Every::Seconds(90.0)));
        assert_eq!("1.5m".parse(), Ok(Every::Seconds(90.0)));
        assert_eq!("2h".parse(), Ok(Every::Seconds(7200.0)));
        for bad in ["0", "-1", "5x", "m", "", "0s", "nans", "1e400s"] {
            assert!(bad.parse::<Every>().is_err(), "{bad}");
        }
    }
}
