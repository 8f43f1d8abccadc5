//! Shards of a render with independent passes, and their merge.
//!
//! ```text
//! pbrt-sppm render scene.pbrt --spp 64 --pass-range 0..16 --partial a.part.exr
//! pbrt-sppm render scene.pbrt --spp 64 --pass-range 16..64 --partial b.part.exr
//! pbrt-sppm merge a.part.exr b.part.exr --outfile scene.exr
//! ```
//! A part is an EXR whose `R`, `G`, `B` hold the per-pixel *sum* of its passes'
//! estimates as 32-bit floats, and `lo.R`, `lo.G`, `lo.B` what f32 rounding left of
//! that f64 sum, so a merge adds the sums as the single-machine render does (to
//! about 1e-14). Its header names what it belongs to:
//!
//! - `pbrtSppmPart`: the format's version (1);
//! - `fingerprint`: JSON of the scene's input files with their hashes and every
//!   setting that changes the image (the checkpoint's [`Fingerprint`]);
//! - `sceneFingerprint`: a hash of the input files' contents and those settings;
//! - `seed`, `passes` (such as `0..16` or `0..4,8..12`), `photons` (paths traced);
//! - the usual `samplesPerPixel` (passes), `photonsPerIteration`,
//!   `renderTimeSeconds`, `worldToCamera`, `software`;
//! - for a spectral film, `spectralBuckets` (`count lambdamin lambdamax`), its bucket
//!   sums in channels `S0.<λ>nm` and `lo.S0.<λ>nm` as R, G, B hold theirs.
//!
//! [`merge`] refuses parts of other scenes or settings, reports passes missing from
//! `0..N` (an error unless gaps are allowed) and passes given twice (always an error,
//! except the same passes in identical files, which count once), and averages.

use super::buckets::BucketTotals;
use super::checkpoint::Fingerprint;
use super::passes::PassSet;
use crate::imageio::{ImageError, ImageMeta, RgbImage, atomically};
use crate::spectrum::buckets::Buckets;
use exr::prelude::*;
use std::path::{Path, PathBuf};

type Res<T> = std::result::Result<T, PartError>;

/// Why a part cannot be written or read, or parts cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    #[error("the sum of the passes at pixel ({}, {}) is beyond the range of 32-bit floats", pixel.0, pixel.1)]
    NotFinite { pixel: (i32, i32) },
    #[error("only independent passes make parts")]
    NotIndependent,
    #[error(transparent)]
    File(#[from] ImageError),
    /// A file that is not a part this version reads; `why` says what is wrong with it.
    #[error("\"{}\": {why}", path.display())]
    Unreadable { path: PathBuf, why: String },
    #[error("the part does not say how many passes the render has")]
    NoPassCount,
    #[error("\"{}\" is not a part of the same render as \"{}\": {why}", path.display(), first.display())]
    OtherRender { path: PathBuf, first: PathBuf, why: String },
    #[error("\"{}\" and \"{}\" both hold passes {passes}; a pass must be merged once (remove one of them)", a.display(), b.display())]
    Overlap { a: PathBuf, b: PathBuf, passes: PassSet },
    #[error("passes {missing} of 0..{planned} are in no part (re-run those shards, or merge with --allow-gaps)")]
    Missing { missing: PassSet, planned: u32 },
    #[error("no parts to merge")]
    NoParts,
}

const VERSION: &str = "1";
/// The header's text naming a spectral film's buckets: `count lambdamin lambdamax`.
const BUCKETS: &str = "spectralBuckets";
/// Channel names, in the order EXR stores them (sorted).
const CHANNELS: [&str; 6] = ["B", "G", "R", "lo.B", "lo.G", "lo.R"];

/// The passes of one shard, summed.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub fingerprint: Fingerprint,
    pub passes: PassSet,
    pub seed: u64,
    /// Photon paths traced over these passes.
    pub photons: u64,
    pub photons_per_pass: u64,
    pub seconds: f64,
    pub width: usize,
    pub height: usize,
    /// The data window's corner in the display window, and the display window's size.
    pub origin: (i32, i32),
    pub full: (usize, usize),
    pub world_to_camera: Option<[f32; 16]>,
    /// Per pixel, the sum of the passes' estimates.
    pub sums: Vec<[f64; 3]>,
    /// A spectral film's bucket sums.
    pub buckets: Option<BucketTotals>,
}

impl Part {
    /// The passes the whole render plans (the fingerprint's `iterations`).
    pub fn planned(&self) -> Res<u32> {
        let s = self.fingerprint.settings.iter().find(|(k, _)| k == "iterations");
        s.and_then(|(_, v)| v.parse().ok()).ok_or(PartError::NoPassCount)
    }

    /// The average of the passes: the image the part stands for.
    pub fn image(&self) -> RgbImage {
        let k = self.passes.count().max(1) as f64;
        RgbImage {
            width: self.width,
            height: self.height,
            pixels: self.sums.iter().map(|s| s.map(|c| (c / k) as f32)).collect(),
            bands: self.buckets.as_ref().map(|b| b.bands(self.passes.ranges().iter().flat_map(|r| r.clone()))),
            origin: self.origin,
            full: self.full,
            meta: ImageMeta {
                render_time_seconds: Some(self.seconds as f32),
                samples_per_pixel: Some(self.passes.count().min(i32::MAX as u64) as i32),
                photons_per_iteration: Some(self.photons_per_pass as i64),
                world_to_camera: self.world_to_camera,
                software: Some(format!("pbrt-sppm {}", env!("CARGO_PKG_VERSION"))),
            },
        }
    }

    /// A short hash of the input files' contents and the settings: equal for every
    /// part of one render, wherever its files were.
    pub fn scene_fingerprint(&self) -> String {
        let mut inputs: Vec<u64> = self.fingerprint.inputs.iter().map(|i| i.1).collect();
        inputs.sort_unstable();
        let text = format!("{inputs:?}{:?}", self.fingerprint.settings);
        format!("{:016x}", xxhash_rust::xxh3::xxh3_64(text.as_bytes()))
    }

    pub fn write(&self, path: &Path) -> Res<()> {
        if let Some(i) = self.sums.iter().position(|s| !s.iter().all(|c| (*c as f32).is_finite())) {
            let (x, y) =
                (self.origin.0 + (i % self.width.max(1)) as i32, self.origin.1 + (i / self.width.max(1)) as i32);
            return Err(PartError::NotFinite { pixel: (x, y) });
        }
        let fail = |e: exr::error::Error| ImageError::write(path, e);
        let json = serde_json::to_string(&self.fingerprint).map_err(|e| ImageError::write(path, e))?;
        let mut attrs = LayerAttributes::named("");
        attrs.layer_position = Vec2(self.origin.0, self.origin.1);
        attrs.software_name = Some(Text::from(format!("pbrt-sppm {}", env!("CARGO_PKG_VERSION")).as_str()));
        attrs.world_to_camera = self.world_to_camera;
        let text = |s: &str| AttributeValue::Text(Text::from_slice_unchecked(s.as_bytes()));
        let entries = [
            ("pbrtSppmPart", text(VERSION)),
            ("fingerprint", text(&json)),
            ("sceneFingerprint", text(&self.scene_fingerprint())),
            ("seed", text(&self.seed.to_string())),
            ("passes", text(&self.passes.to_string())),
            ("photons", text(&self.photons.to_string())),
            ("photonsPerIteration", text(&self.photons_per_pass.to_string())),
            ("renderTimeSeconds", AttributeValue::F32(self.seconds as f32)),
            ("renderTimeSecondsF64", text(&format!("{:?}", self.seconds))),
            ("samplesPerPixel", AttributeValue::I32(self.passes.count().min(i32::MAX as u64) as i32)),
        ];
        for (k, v) in entries {
            attrs.other.insert(Text::from(k), v);
        }
        if let Some(b) = &self.buckets {
            let l = b.layout;
            attrs
                .other
                .insert(Text::from(BUCKETS), text(&format!("{} {:?} {:?}", l.count, l.lambda_min, l.lambda_max)));
        }
        let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> =
            CHANNELS.iter().map(|name| AnyChannel::new(*name, FlatSamples::F32(self.channel(name)))).collect();
        channels.extend(self.bucket_channels());
        let layer = Layer::new((self.width, self.height), attrs, Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels));
        let mut image = Image::from_layer(layer);
        image.attributes.display_window = IntegerBounds::new((0, 0), self.full);
        Ok(atomically(path, |tmp| image.write().to_file(tmp).map_err(fail))?)
    }

    /// One channel's samples: the f32 nearest each sum (`R`) or what it leaves (`lo.R`).
    fn channel(&self, name: &str) -> Vec<f32> {
        let c = match name.trim_start_matches("lo.") {
            "R" => 0,
            "G" => 1,
            _ => 2,
        };
        let lo = name.starts_with("lo.");
        self.sums.iter().map(|s| if lo { (s[c] - s[c] as f32 as f64) as f32 } else { s[c] as f32 }).collect()
    }

    /// Each bucket's channel (its sums' nearest f32) and `lo.` channel (what is left).
    fn bucket_channels(&self) -> Vec<AnyChannel<FlatSamples>> {
        let Some(b) = &self.buckets else { return Vec::new() };
        let n = b.layout.count;
        let column = |k: usize| b.sums.iter().skip(k).step_by(n);
        (0..n)
            .flat_map(|k| {
                let name = b.layout.channel(k);
                let hi = column(k).map(|&s| s as f32).collect();
                let lo = column(k).map(|&s| (s - s as f32 as f64) as f32).collect();
                [
                    AnyChannel::new(name.as_str(), FlatSamples::F32(hi)),
                    AnyChannel::new(format!("lo.{name}").as_str(), FlatSamples::F32(lo)),
                ]
            })
            .collect()
    }

    pub fn read(path: &Path) -> Res<Part> {
        let bytes =
            std::fs::read(path).map_err(|e| ImageError::Read { path: path.to_path_buf(), why: e.to_string() })?;
        decode(&bytes).map_err(|why| PartError::Unreadable { path: path.to_path_buf(), why })
    }
}

/// A part from its file's bytes, or what is wrong with them.
fn decode(bytes: &[u8]) -> std::result::Result<Part, String> {
    // From the header alone: a part is never larger than a render may be.
    let image = crate::imageio::decode_all_channels(bytes, "part", crate::limits::Limits::default().pixels)?;
    let layer = &image.layer_data;
    let a = &layer.attributes;
    let text = |k: &str| match a.other.get(&Text::from(k)) {
        Some(AttributeValue::Text(t)) => Ok(String::from_utf8_lossy(t.bytes()).into_owned()),
        _ => Err(format!("the header has no text \"{k}\"")),
    };
    match text("pbrtSppmPart") {
        Ok(v) if v == VERSION => {}
        Ok(v) => return Err(format!("a part of format {v}, which this pbrt-sppm cannot read (it reads {VERSION})")),
        Err(_) => return Err("not a part of a render (made by render --partial)".into()),
    }
    let number = |k: &str| text(k).and_then(|t| t.parse::<u64>().map_err(|_| format!("\"{k}\" is not a number: {t}")));
    let fingerprint = serde_json::from_str(&text("fingerprint")?).map_err(|e| format!("bad \"fingerprint\": {e}"))?;
    let passes: PassSet = text("passes")?.parse()?;
    let seconds = text("renderTimeSecondsF64")?.parse().map_err(|_| "bad \"renderTimeSecondsF64\"".to_string())?;
    let (w, h) = (layer.size.width(), layer.size.height());
    let display = image.attributes.display_window;
    let part = Part {
        fingerprint,
        passes,
        seed: number("seed")?,
        photons: number("photons")?,
        photons_per_pass: number("photonsPerIteration")?,
        seconds,
        width: w,
        height: h,
        origin: (a.layer_position.x() - display.position.x(), a.layer_position.y() - display.position.y()),
        full: (display.size.width(), display.size.height()),
        world_to_camera: a.world_to_camera,
        sums: sums(&layer.channel_data.list, w * h)?,
        buckets: match text(BUCKETS) {
            Ok(layout) => Some(bucket_sums(&layer.channel_data.list, &layout, w * h)?),
            Err(_) => None,
        },
    };
    match text("sceneFingerprint")? {
        f if f == part.scene_fingerprint() => Ok(part),
        _ => Err("the header's \"sceneFingerprint\" does not match its \"fingerprint\" (an edited file?)".into()),
    }
}

/// A spectral film's bucket sums from the header's layout and their channels.
fn bucket_sums(list: &[AnyChannel<FlatSamples>], layout: &str, n: usize) -> std::result::Result<BucketTotals, String> {
    let bad = || format!("bad \"{BUCKETS}\": {layout}");
    let words: Vec<&str> = layout.split_whitespace().collect();
    let (count, lambda_min, lambda_max) = match words.as_slice() {
        [c, lo, hi] => (c.parse().map_err(|_| bad())?, lo.parse().map_err(|_| bad())?, hi.parse().map_err(|_| bad())?),
        _ => return Err(bad()),
    };
    let layout = Buckets { count, lambda_min, lambda_max };
    if count == 0 || count > list.len() {
        return Err(bad());
    }
    let mut sums = vec![0.0; n * count];
    for k in 0..count {
        let name = layout.channel(k);
        let (hi, lo) = (channel(list, &name, n)?, channel(list, &format!("lo.{name}"), n)?);
        for i in 0..n {
            sums[i * count + k] = hi[i] as f64 + lo[i] as f64;
        }
    }
    Ok(BucketTotals { layout, sums })
}

/// A channel of `n` 32-bit floats.
fn channel<'a>(list: &'a [AnyChannel<FlatSamples>], name: &str, n: usize) -> std::result::Result<&'a Vec<f32>, String> {
    match list.iter().find(|c| c.name == *name).map(|c| &c.sample_data) {
        Some(FlatSamples::F32(v)) if v.len() == n => Ok(v),
        Some(_) => Err(format!("channel \"{name}\" is not 32-bit float")),
        None => Err(format!("channel \"{name}\" is missing")),
    }
}

/// The f64 sums from the six channels.
fn sums(list: &[AnyChannel<FlatSamples>], n: usize) -> std::result::Result<Vec<[f64; 3]>, String> {
    let get = |name: &str| channel(list, name, n);
    let [b, g, r, lb, lg, lr] = [
        get(CHANNELS[0])?,
        get(CHANNELS[1])?,
        get(CHANNELS[2])?,
        get(CHANNELS[3])?,
        get(CHANNELS[4])?,
        get(CHANNELS[5])?,
    ];
    Ok((0..n).map(|i| [r[i] as f64 + lr[i] as f64, g[i] as f64 + lg[i] as f64, b[i] as f64 + lb[i] as f64]).collect())
}

/// What a merge made, and what it noticed on the way.
pub struct Merged {
    /// All the parts' passes, summed (itself a part: merges can be merged).
    pub part: Part,
    /// Passes of `0..N` no part holds.
    pub missing: PassSet,
    /// Files skipped because an identical file with the same passes came first.
    pub duplicates: Vec<PathBuf>,
}

/// Adds up parts of one render, one file at a time (so a merge holds two parts in
/// memory, whatever their number). Parts of another scene or other settings, parts of
/// another size, and passes given twice are errors; missing passes are an error
/// unless `allow_gaps`.
pub fn merge(paths: &[PathBuf], allow_gaps: bool) -> Res<Merged> {
    let mut merger: Option<Merger> = None;
    for path in paths {
        let part = Part::read(path)?;
        match &mut merger {
            None => merger = Some(Merger::new(path.clone(), part)),
            Some(m) => m.add(path.clone(), part)?,
        }
    }
    merger.ok_or(PartError::NoParts)?.finish(allow_gaps)
}

/// The running sum of a merge.
struct Merger {
    /// The first part, its sums the running total.
    base: (PathBuf, Part),
    /// Every part kept: its file, passes and a hash of its sums (to tell a re-run
    /// shard's identical part from a different one).
    kept: Vec<(PathBuf, PassSet, u64)>,
    duplicates: Vec<PathBuf>,
}

fn sums_hash(p: &Part) -> u64 {
    let bytes: Vec<u8> = p.sums.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    xxhash_rust::xxh3::xxh3_64(&bytes)
}

impl Merger {
    fn new(path: PathBuf, part: Part) -> Merger {
        let kept = vec![(path.clone(), part.passes.clone(), sums_hash(&part))];
        Merger { base: (path, part), kept, duplicates: Vec::new() }
    }

    fn add(&mut self, path: PathBuf, part: Part) -> Res<()> {
        let (p0, base) = &self.base;
        belongs(base, &part).map_err(|why| PartError::OtherRender { path: path.clone(), first: p0.clone(), why })?;
        let hash = sums_hash(&part);
        match self.kept.iter().find(|k| k.1.intersection(&part.passes).count() > 0) {
            Some(k) if k.1 == part.passes && k.2 == hash => self.duplicates.push(path),
            Some((other, passes, _)) => {
                let passes = passes.intersection(&part.passes);
                return Err(PartError::Overlap { a: other.clone(), b: path, passes });
            }
            None => {
                let total = &mut self.base.1;
                total.sums.iter_mut().zip(&part.sums).for_each(|(s, v)| (0..3).for_each(|c| s[c] += v[c]));
                if let (Some(t), Some(b)) = (&mut total.buckets, &part.buckets) {
                    t.sums.iter_mut().zip(&b.sums).for_each(|(s, v)| *s += v);
                }
                total.passes = total.passes.union(&part.passes);
                total.photons += part.photons;
                total.seconds += part.seconds;
                self.kept.push((path, part.passes, hash));
            }
        }
        Ok(())
    }

    fn finish(self, allow_gaps: bool) -> Res<Merged> {
        let part = self.base.1;
        let planned = part.planned()?;
        let missing = part.passes.missing_from(planned);
        if !missing.ranges().is_empty() && !allow_gaps {
            return Err(PartError::Missing { missing, planned });
        }
        Ok(Merged { part, missing, duplicates: self.duplicates })
    }
}

/// Why `b` cannot be merged with `a`, if it cannot. The fingerprints hold every
/// setting (seed and photons among them); the windows are checked beside them.
fn belongs(a: &Part, b: &Part) -> std::result::Result<(), String> {
    a.fingerprint.check(&b.fingerprint).map_err(|e| e.to_string())?;
    b.fingerprint.check(&a.fingerprint).map_err(|e| e.to_string())?;
    if a.buckets.as_ref().map(|t| t.layout) != b.buckets.as_ref().map(|t| t.layout) {
        return Err("its spectral buckets differ".into());
    }
    if (a.width, a.height, a.origin, a.full) != (b.width, b.height, b.origin, b.full) {
        return Err(format!(
            "its image is {}x{} at {:?}, not {}x{} at {:?}",
            b.width, b.height, b.origin, a.width, a.height, a.origin
        ));
    }
    Ok(())
}
