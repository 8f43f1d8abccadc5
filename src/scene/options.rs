//! Camera, film and integrator settings, resolved after the whole file is read (the
//! syntax version decides some defaults).
//!
//! ```text
//! Camera "perspective" "float fov" 45 "float lensradius" 0 "float focaldistance" 1e6
//!        "float frameaspectratio" 1.5 "float screenwindow" [-1 1 -1 1]
//! Film "image" "integer xresolution" 1280 "integer yresolution" 720
//!      "string filename" "pbrt.exr" "float cropwindow" [0 1 0 1] "float scale" 1    # v3
//! Film "rgb" ... "integer pixelbounds" [0 1280 0 720] "float iso" 100              # v4
//! Integrator "sppm" "integer numiterations" 64 "integer maxdepth" 5                # v3
//!            "integer photonsperiteration" -1 "float radius" 1
//! Sampler "halton" "integer pixelsamples" 16     # v4: SPPM iterations = pixelsamples
//! ```

use crate::approx::Approx;
use crate::camera::clamp::SampleClamp;
pub use crate::camera::desc::{Camera, CameraKind, Film, SphericalMapping};
use crate::camera::realistic::{LensDesc, Weighting};
use crate::filters::PixelFilter;
use crate::limits::Limits;
use crate::parser::Syntax;
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::parser::stmt::Entity;
use crate::spectrum::buckets::Buckets;
use crate::spectrum::colorspace::{ColorSpaceName, Matrix3};
use crate::spectrum::sensor::CameraSensor;
use crate::values::{self, Range};
use glam::DMat4;

#[derive(Clone, Debug, PartialEq)]
pub struct Integrator {
    /// The integrator the file asked for (see `integrators::Algorithm::for_file`).
    pub requested: String,
    /// No Integrator line: `requested` is the file's pbrt's default (`path` in v3,
    /// `volpath` in v4).
    pub implied: bool,
    pub iterations: u32,
    pub max_depth: u32,
    pub photons_per_iteration: u64,
    pub radius: f32,
    /// Whether the file gave `radius` (VCM otherwise picks one by the scene's size).
    pub radius_given: bool,
    /// Whether media in the scene emit light: only SPPM sends light from them (vcm and
    /// bdpt find it by camera paths alone).
    pub emitting_media: bool,
    pub seed: u64,
    /// Camera rays' differentials are scaled by max(this, 1/√iterations): pbrt-v3
    /// scales them by 1/√iterations, pbrt-v4 by at least 1/8.
    pub differential_floor: f32,
}

/// The option-block statements as read (last one of each kind wins).
#[derive(Default)]
pub struct RenderOptions {
    pub camera: Option<(Entity, DMat4)>,
    /// The camera's end transform and the transform times, when it moves.
    pub camera_end: Option<(DMat4, [f64; 2])>,
    /// A realistic camera's lens file, read where the `Camera` statement names it.
    pub lens_data: Option<Vec<f64>>,
    /// pbrt-v4's `aperture` of a realistic camera: a built-in shape or an image.
    pub lens_aperture: Option<crate::camera::realistic::Aperture>,
    /// The frame motion is interpolated in (pbrt-v4's rendering space; identity for v3).
    pub world_from_render: DMat4,
    pub film: Option<Entity>,
    pub sampler: Option<Entity>,
    pub integrator: Option<Entity>,
    pub filter: Option<Entity>,
    pub accelerator: Option<Entity>,
    /// `Option "seed"`, when given.
    pub seed_option: Option<u64>,
    /// Whether the scene has media that emit light (known once the file is read).
    pub emitting_media: bool,
    /// The first `ColorSpace` (pbrt-v4), which the whole scene and its film use.
    pub color_space: Option<crate::spectrum::colorspace::ColorSpaceName>,
    /// Whether paths carry wavelengths (a named camera's curves need them).
    pub spectral: bool,
}

/// The smallest photon radius: its square is a normal f32 (the gather compares squared
/// distances; below it no photon is ever found).
pub const MIN_RADIUS: f32 = 1e-18;

/// Results and warnings of resolving the options.
pub struct Resolved {
    pub camera: Camera,
    pub film: Film,
    pub integrator: Integrator,
}

type Res<T> = Result<T, Diagnostic>;

/// Approximations found while resolving: where, what, how.
pub type Notes = Vec<(Span, String, Approx)>;

/// A film's crop window (as fractions) and pixel bounds, from `cropwindow` and
/// `pixelbounds` over the resolution `res`.
fn film_window(
    e: &Entity,
    [xres, yres]: [u32; 2],
    syntax: Syntax,
    warn: &mut Vec<Diagnostic>,
) -> Res<([f32; 4], [u32; 4])> {
    let p = &e.params;
    // pbrt-v4 renders the whole film past a miscounted crop window or pixel bounds;
    // pbrt-v3 leaves its crop window unset there and renders nothing: an error.
    let v4 = syntax == Syntax::V4;
    let crop = match v4 && ignored_if_not_four(p, "cropwindow", ParamType::Float, "pbrt-v4", warn) {
        true => None,
        false => p.fixed::<4>("cropwindow", &[ParamType::Float])?,
    };
    if let Some(c) = crop
        && let Some(x) = c.iter().find(|x| !x.is_finite())
    {
        let at = p.named("cropwindow").map_or(e.name_span, |c| c.value_span);
        return Err(Diagnostic::error(at, format!("\"cropwindow\" must be finite, not {x}")));
    }
    let crop_window = crop.map_or([0.0, 1.0, 0.0, 1.0], |c| {
        let [a, b, c0, d] = c.map(|v| v.clamp(0.0, 1.0));
        [a.min(b), a.max(b), c0.min(d), c0.max(d)]
    });
    let pixel_bounds = match v4 && ignored_if_not_four(p, "pixelbounds", ParamType::Integer, "pbrt-v4", warn) {
        true => None,
        false => p.find("pixelbounds", &[ParamType::Integer]),
    };
    let bounds = match pixel_bounds {
        Some(pb) => match pb.ints() {
            &[x0, x1, y0, y1] => {
                let c = |v: i32, hi: u32| v.clamp(0, hi as i32) as u32;
                [c(x0.min(x1), xres), c(x0.max(x1), xres), c(y0.min(y1), yres), c(y0.max(y1), yres)]
            }
            _ => return Err(Diagnostic::error(pb.span, "\"pixelbounds\" needs 4 integers")),
        },
        None => {
            let c = |f: f32, n: u32| (n as f32 * f).ceil() as u32;
            [c(crop_window[0], xres), c(crop_window[1], xres), c(crop_window[2], yres), c(crop_window[3], yres)]
        }
    };
    Ok((crop_window, bounds))
}

/// Whether `name` is of type `ty` with other than four values, which `ignorer` (the
/// pbrt that reports it and renders on) ignores: then it is marked used, with a warning.
fn ignored_if_not_four(p: &ParamList, name: &str, ty: ParamType, ignorer: &str, warn: &mut Vec<Diagnostic>) -> bool {
    let Some(q) = p.named(name).filter(|q| q.ty == ty && q.values.len() != 4) else { return false };
    q.mark_used();
    let msg = format!("\"{name}\" needs 4 values, found {}; ignored, as {ignorer} ignores it", q.values.len());
    warn.push(Diagnostic::warning(q.value_span, msg));
    true
}

impl RenderOptions {
    pub fn resolve(
        &self,
        syntax: Syntax,
        limits: &Limits,
        warn: &mut Vec<Diagnostic>,
        notes: &mut Notes,
    ) -> Res<Resolved> {
        let (film, exposure_scale) = self.film(syntax, limits, warn, notes)?;
        let camera = self.camera(&film, syntax, warn)?;
        let mut film = film;
        if syntax == Syntax::V4 {
            self.check_shutter_opens()?;
            film.scale *= exposure_scale * (camera.shutter_close - camera.shutter_open);
        }
        let integrator = self.integrator(syntax, &film, limits, warn)?;
        for e in [&self.sampler, &self.filter, &self.accelerator].into_iter().flatten() {
            e.params.mark_all_used(); // irrelevant to SPPM except pixelsamples (read below)
        }
        // (a v4 filter's parameters have been read by then, with their errors)
        Ok(Resolved { camera, film, integrator })
    }

    fn film(&self, syntax: Syntax, limits: &Limits, warn: &mut Vec<Diagnostic>, notes: &mut Notes) -> Res<(Film, f32)> {
        let empty = Entity::default_named(if syntax == Syntax::V3 { "image" } else { "rgb" });
        let e = self.film.as_ref().unwrap_or(&empty);
        let p = &e.params;
        let res = |name: &str, default: i32| -> Res<u32> {
            match p.int(name)? {
                None => Ok(default as u32),
                Some(v) if v >= 1 => Ok(v as u32),
                Some(v) => Err(err_at(
                    p.find(name, &[ParamType::Integer]),
                    e,
                    format!("\"{name}\" must be at least 1, not {v}"),
                )),
            }
        };
        let (xres, yres) = (res("xresolution", 1280)?, res("yresolution", 720)?);
        let filename = p.string("filename")?.filter(|f| !f.is_empty()).unwrap_or_else(|| "pbrt.exr".into());
        let (crop_window, bounds) = film_window(e, [xres, yres], syntax, warn)?;
        if bounds[0] >= bounds[1] || bounds[2] >= bounds[3] {
            return Err(Diagnostic::error(e.name_span, format!("the crop window selects no pixels ({bounds:?})")));
        }
        let pixels = (bounds[1] - bounds[0]) as u64 * (bounds[3] - bounds[2]) as u64;
        if pixels > limits.pixels {
            let what = format!("the film's {}x{} = {pixels} pixels", bounds[1] - bounds[0], bounds[3] - bounds[2]);
            return Err(Diagnostic::error(e.name_span, Limits::over(what, "pixels", limits.pixels)));
        }
        let scale = values::float(p, "scale", 1.0, Range::NonNegative)?;
        let iso = values::float(p, "iso", 100.0, Range::Positive)?;
        // Output format and spectral-film details: nothing in the pixel values changes.
        let diagonal_mm = values::float(p, "diagonal", 35.0, Range::Positive)?;
        values::no_effect(p, &["savefp16", "coordinatesystem"]);
        let clamp = sample_clamp(p, syntax)?;
        let space = self.color_space.unwrap_or(ColorSpaceName::Srgb);
        let (white_balance, sensor) = if syntax == Syntax::V4 { self.sensor(e, space, notes)? } else { (None, None) };
        let buckets = self.film_type(e, notes, (pixels, limits.pixels))?;
        let film = Film {
            ty: e.name.clone(),
            x_resolution: xres,
            y_resolution: yres,
            filename,
            filename_location: None,
            location: None,
            crop_window,
            pixel_bounds: bounds,
            scale,
            diagonal_mm,
            white_balance,
            sensor,
            filter: if syntax == Syntax::V4 { self.pixel_filter()? } else { None },
            buckets,
            clamp,
        };
        Ok((film, iso / 100.0))
    }

    /// Checks the film's type; a `spectral` film's buckets when they are written.
    /// `gbuffer` is written as `rgb`.
    /// A spectral film's sums (`pixels` × buckets) count against the pixel limit.
    fn film_type(&self, e: &Entity, notes: &mut Notes, (pixels, limit): (u64, u64)) -> Res<Option<Buckets>> {
        let layout = match e.name.as_str() {
            "image" | "rgb" => return Ok(None),
            "spectral" => spectral_buckets(e, (pixels, limit))?,
            // pbrt-v4's SPPM writes its own image of R, G and B for this film, as we
            // do: only the other integrators' files lose the extra channels.
            "gbuffer" if self.asks_for_sppm() => return Ok(None),
            "gbuffer" => Buckets::DEFAULT,
            other => return Err(Diagnostic::error(e.name_span, format!("unknown film type \"{other}\""))),
        };
        // DEVIATION(pbrt): robustness. pbrt-v4's SPPM stops on a spectral film
        // ("ToOutputRGB() is unimplemented"); we write its R, G and B.
        if e.name == "gbuffer" || self.asks_for_sppm() || !self.spectral {
            notes.push((e.name_span, format!("Film \"{}\"", e.name), Approx::FilmType));
            return Ok(None);
        }
        Ok(Some(layout))
    }

    /// Whether the file asks for SPPM (pbrt-v4's default is `volpath`).
    fn asks_for_sppm(&self) -> bool {
        self.integrator.as_ref().is_some_and(|e| e.name == "sppm")
    }

    /// pbrt-v4's pixel filter: the file's, or its default Gaussian.
    fn pixel_filter(&self) -> Res<Option<PixelFilter>> {
        match &self.filter {
            Some(e) => PixelFilter::new(&e.name, &e.params),
            None => PixelFilter::new("gaussian", &crate::parser::params::ParamList::default()),
        }
    }

    /// pbrt-v4's `sensor` and `whitebalance`: the white balance as a matrix on the
    /// output space's linear RGB, or a named camera, whose fitted matrix balances.
    /// Paths that carry RGB see a named camera as the CIE observer (noted).
    fn sensor(
        &self,
        e: &Entity,
        space: ColorSpaceName,
        notes: &mut Notes,
    ) -> Res<(Option<Matrix3>, Option<CameraSensor>)> {
        use crate::spectrum::sensor::{balance_temperature, named_sensors, white_balance_rgb};
        let p = &e.params;
        let sensor = p.string("sensor")?.unwrap_or_else(|| "cie1931".into());
        let at = p.named("sensor").map_or(e.name_span, |x| x.value_span);
        if sensor != "cie1931" && !named_sensors().any(|n| n == sensor) {
            let known: Vec<&str> = std::iter::once("cie1931").chain(named_sensors()).collect();
            return Err(Diagnostic::error(at, super::names::unknown("sensor", &sensor, &known)));
        }
        let kelvin = balance_temperature(&sensor, values::float(p, "whitebalance", 0.0, Range::NonNegative)?);
        if kelvin == 0.0 {
            return Ok((None, None));
        }
        let m = white_balance_rgb(kelvin as f64, space);
        if !m.iter().flatten().all(|v| v.is_finite()) {
            // DEVIATION(pbrt): robustness. Below about 30 K a blackbody's visible light
            // underflows; pbrt-v4 then balances by a white of 0/0 and writes NaN pixels.
            let at = p.named("whitebalance").map_or(e.name_span, |x| x.value_span);
            let why = format!("\"whitebalance\" {kelvin} K: light that cold has no visible colour to balance");
            return Err(Diagnostic::error(at, why));
        }
        if sensor == "cie1931" {
            return Ok((Some(m), None));
        }
        if !self.spectral {
            notes.push((at, format!("sensor \"{sensor}\""), Approx::Sensor));
            return Ok((Some(m), None));
        }
        Ok((None, CameraSensor::named(&sensor, kelvin as f64, space)))
    }

    /// pbrt-v4 stops when `shutterclose` is not after `shutteropen` (the film's exposure
    /// would be zero or negative: a black image); pbrt-v3 swaps a reversed pair.
    fn check_shutter_opens(&self) -> Res<()> {
        let Some((e, _)) = &self.camera else { return Ok(()) };
        let open = values::float(&e.params, "shutteropen", 0.0, Range::Any)?;
        let close = values::float(&e.params, "shutterclose", 1.0, Range::Any)?;
        if close - open > 0.0 {
            return Ok(());
        }
        let at = e.params.named("shutterclose").or(e.params.named("shutteropen")).map_or(e.name_span, |p| p.value_span);
        let msg = format!(
            "the shutter does not open (shutterclose {close} is not after shutteropen {open}): the image would be black"
        );
        Err(Diagnostic::error(at, msg))
    }

    /// A realistic camera's lens: the file's interfaces, the stop's diameter, the focus
    /// distance and the weighting (a located error where the lens cannot focus).
    fn lens(&self, kind: CameraKind, e: &Entity, film: &Film, syntax: Syntax) -> Res<Option<std::sync::Arc<LensDesc>>> {
        let (CameraKind::Realistic, Some(data)) = (kind, &self.lens_data) else { return Ok(None) };
        let p = &e.params;
        let aperture_diameter = values::float(p, "aperturediameter", 1.0, Range::Positive)? as f64;
        let focus_distance = values::float(p, "focusdistance", 10.0, Range::Positive)? as f64;
        let simple = syntax == Syntax::V3 && p.bool("simpleweighting")?.unwrap_or(true);
        let shutter = (values::float(p, "shutterclose", 1.0, Range::Any)?
            - values::float(p, "shutteropen", 0.0, Range::Any)?)
        .abs();
        let weighting = match (simple, syntax) {
            (true, _) => Weighting::Simple,
            (false, Syntax::V3) => Weighting::Physical(shutter as f64),
            (false, _) => Weighting::Physical(1.0),
        };
        let aperture = self.lens_aperture.clone();
        let desc = LensDesc { data: data.clone(), aperture_diameter, focus_distance, weighting, aperture };
        crate::camera::realistic::check_focus(&desc, film.diagonal_mm as f64)
            .map_err(|why| Diagnostic::error(p.named("focusdistance").map_or(e.name_span, |f| f.value_span), why))?;
        Ok(Some(std::sync::Arc::new(desc)))
    }

    fn camera(&self, film: &Film, syntax: Syntax, warn: &mut Vec<Diagnostic>) -> Res<Camera> {
        let default = (Entity::default_named("perspective"), DMat4::IDENTITY);
        let (e, camera_from_world) = self.camera.as_ref().unwrap_or(&default);
        let p = &e.params;
        let kind = match e.name.as_str() {
            "perspective" => CameraKind::Perspective,
            "orthographic" => CameraKind::Orthographic,
            "environment" => CameraKind::Environment,
            "spherical" => CameraKind::Spherical(match p.string("mapping")?.as_deref() {
                None | Some("equalarea") => SphericalMapping::EqualArea,
                Some("equirectangular") => SphericalMapping::Equirectangular,
                Some(m) => {
                    let at = p.named("mapping").map_or(e.name_span, |q| q.value_span);
                    let msg = format!(
                        "spherical camera: unknown mapping \"{m}\" (expected \"equalarea\" or \"equirectangular\")"
                    );
                    return Err(Diagnostic::error(at, msg));
                }
            }),
            "realistic" => CameraKind::Realistic,
            // The builder stops at names neither pbrt knows (`scene::names`).
            other => return Err(Diagnostic::error(e.name_span, super::names::Family::Camera.unknown(other))),
        };
        let frame = match values::float(p, "frameaspectratio", -1.0, Range::Any)? {
            f if f > 0.0 => f,
            _ => film.x_resolution as f32 / film.y_resolution as f32,
        };
        let default_window =
            if frame > 1.0 { [-frame, frame, -1.0, 1.0] } else { [-1.0, 1.0, -1.0 / frame, 1.0 / frame] };
        // Both pbrts report a miscounted window and render with the default one.
        let screen_window = match ignored_if_not_four(p, "screenwindow", ParamType::Float, "pbrt", warn) {
            true => None,
            false => p.fixed::<4>("screenwindow", &[ParamType::Float])?,
        };
        let screen_window = screen_window.unwrap_or(default_window);
        if let Some(x) = screen_window.iter().find(|x| !x.is_finite()) {
            let at = p.named("screenwindow").map_or(e.name_span, |c| c.value_span);
            return Err(Diagnostic::error(at, format!("\"screenwindow\" must be finite, not {x}")));
        }
        let mut fov = values::float(p, "fov", 90.0, Range::Any)?;
        let half = values::float(p, "halffov", -1.0, Range::Any)?;
        if half > 0.0 {
            fov = 2.0 * half;
        }
        let open = values::float(p, "shutteropen", 0.0, Range::Any)?;
        let close = values::float(p, "shutterclose", 1.0, Range::Any)?;
        let (mut open, mut close) = (open, close);
        if close < open {
            std::mem::swap(&mut open, &mut close);
        }
        if kind == CameraKind::Perspective && !(fov > 0.0 && fov < 180.0) {
            return Err(Diagnostic::error(
                p.named("fov").map_or(e.name_span, |f| f.value_span),
                format!("\"fov\" must be between 0 and 180 degrees, not {fov}"),
            ));
        }
        Ok(Camera {
            kind,
            fov,
            lens_radius: values::float(p, "lensradius", 0.0, Range::NonNegative)?,
            focal_distance: values::float(p, "focaldistance", 1e6, Range::Positive)?,
            frame_aspect_ratio: frame,
            screen_window,
            shutter_open: open,
            shutter_close: close,
            camera_from_world: *camera_from_world,
            camera_from_world_end: self.camera_end,
            world_from_render: self.world_from_render,
            lens: self.lens(kind, e, film, syntax)?,
        })
    }

    fn integrator(&self, syntax: Syntax, film: &Film, limits: &Limits, warn: &mut Vec<Diagnostic>) -> Res<Integrator> {
        // Without an Integrator line pbrt path-traces: `path` in pbrt-v3, `volpath` in
        // pbrt-v4 (the render says what renders it instead; no warning, as the file is
        // valid and silent).
        let default = Entity::default_named(if syntax == Syntax::V4 { "volpath" } else { "path" });
        let e = self.integrator.as_ref().unwrap_or(&default);
        let p = &e.params;
        if e.name != "sppm" && self.integrator.is_some() {
            warn.push(rendered_with(e, self.emitting_media));
        }
        let iterations = self.iterations(e, syntax, limits)?;
        let max_depth = match p.int("maxdepth")? {
            Some(d) if d < 0 => {
                return Err(err_at(p.named("maxdepth"), e, format!("\"maxdepth\" must be at least 0, not {d}")));
            }
            d => d.unwrap_or(5) as u32,
        };
        let photons = match p.int("photonsperiteration")? {
            Some(n) if n > 0 => n as u64,
            _ => film.pixel_count(),
        };
        let over = |name: &str, value: u64, limit: u64, what: &str| -> Res<()> {
            if value <= limit {
                return Ok(());
            }
            let at = p.named(name).map_or(e.name_span, |x| x.value_span);
            Err(Diagnostic::error(at, Limits::over(format!("{what} {value}"), name_of_limit(name), limit)))
        };
        over("maxdepth", max_depth as u64, limits.max_depth, "maxdepth")?;
        // The default (one photon per pixel) is bounded by the pixel limit already.
        if p.named("photonsperiteration").is_some() {
            over("photonsperiteration", photons, limits.photons, "photonsperiteration")?;
        }
        let radius = photon_radius(e)?;
        let seed = match p.int("seed")? {
            Some(s) => s as u64,
            None => self.seed_option.unwrap_or(0),
        };
        values::no_effect(p, &["imagewritefrequency"]);
        if e.name != "sppm" {
            p.mark_all_used();
        }
        Ok(Integrator {
            requested: e.name.clone(),
            implied: self.integrator.is_none(),
            iterations,
            max_depth,
            photons_per_iteration: photons,
            radius,
            radius_given: p.named("radius").is_some(),
            emitting_media: self.emitting_media,
            seed,
            differential_floor: if syntax == Syntax::V4 { 0.125 } else { 0.0 },
        })
    }

    /// SPPM's `iterations` (or `numiterations`), else one pass per pixel sample (SPPM's
    /// 64 in pbrt-v3), checked against the iteration limit.
    fn iterations(&self, e: &Entity, syntax: Syntax, limits: &Limits) -> Res<u32> {
        let p = &e.params;
        let positive = |name: &str, v: Option<i32>| -> Res<Option<u32>> {
            match v {
                Some(v) if v < 1 => Err(err_at(
                    p.find(name, &[ParamType::Integer]),
                    e,
                    format!("\"{name}\" must be at least 1, not {v}"),
                )),
                v => Ok(v.map(|v| v as u32)),
            }
        };
        let explicit = match p.int("iterations")? {
            Some(v) => positive("iterations", Some(v))?,
            None => positive("numiterations", p.int("numiterations")?)?,
        };
        let iterations = match (explicit, syntax) {
            (Some(n), _) => n,
            // Other integrators take one path per pixel sample, in either version.
            (None, _) if e.name != "sppm" => self.pixel_samples()?,
            (None, Syntax::V3) => 64,
            (None, Syntax::V4) => self.pixel_samples()?,
        };
        if iterations as u64 > limits.iterations {
            let sampler = self.sampler.as_ref().and_then(|s| s.params.named("pixelsamples"));
            let named = p.named("iterations").or(p.named("numiterations")).or(sampler);
            let at = named.map_or(e.name_span, |x| x.value_span);
            let what = format!("{iterations} SPPM iterations");
            return Err(Diagnostic::error(at, Limits::over(what, "iterations", limits.iterations)));
        }
        Ok(iterations)
    }

    /// The sampler's samples per pixel (pbrt-v4's SPPM iteration count), default 16.
    fn pixel_samples(&self) -> Res<u32> {
        let Some(s) = &self.sampler else { return Ok(16) };
        let p = &s.params;
        let n = match (p.int("pixelsamples")?, p.int("xsamples")?, p.int("ysamples")?) {
            (Some(n), _, _) => n,
            (None, Some(x), Some(y)) if s.name == "stratified" => x.saturating_mul(y),
            _ => 16,
        };
        if n < 1 {
            return Err(Diagnostic::error(s.name_span, format!("\"pixelsamples\" must be at least 1, not {n}")));
        }
        Ok(n as u32)
    }
}

/// The Integrator's `radius`: positive, and at least [`MIN_RADIUS`].
fn photon_radius(e: &Entity) -> Res<f32> {
    let p = &e.params;
    let radius = values::float(p, "radius", 1.0, Range::Positive)?;
    if radius < MIN_RADIUS {
        let at = p.named("radius").map_or(e.name_span, |r| r.value_span);
        let message = format!("\"float radius\" must be at least {MIN_RADIUS:e}, not {radius:e}");
        return Err(Diagnostic::error(at, message));
    }
    Ok(radius)
}

/// The warning for a file asking for an integrator other than SPPM: what renders it.
fn rendered_with(e: &Entity, emitting_media: bool) -> Diagnostic {
    let (with, why) = match e.name.as_str() {
        "whitted" | "directlighting" => (
            "direct",
            "direct light and perfectly specular reflection and refraction only, as pbrt-v3's, without media",
        ),
        _ if emitting_media => ("sppm", "its photons start in the emitting media, which vcm's light paths do not"),
        "bdpt" => ("bdpt", "its bidirectional path tracing"),
        // Images of something other than light: not implemented.
        "ambientocclusion" | "aov" | "function" => {
            ("vcm", "vertex connection and merging: the scene's light, not this integrator's output")
        }
        _ => ("vcm", "vertex connection and merging, which converges to the same image"),
    };
    let message = format!("integrator \"{}\" is rendered with {with} ({why}); --integrator picks another", e.name);
    Diagnostic::warning(e.name_span, message)
}

/// The `--limit` name for an Integrator parameter.
fn name_of_limit(param: &str) -> &'static str {
    match param {
        "maxdepth" => "maxdepth",
        _ => "photons",
    }
}

fn err_at(p: Option<&crate::parser::params::Param>, e: &Entity, msg: String) -> Diagnostic {
    Diagnostic::error(p.map_or(e.name_span, |p| p.value_span), msg)
}

/// The film's bound on each sample: pbrt-v3's `maxsampleluminance`, pbrt-v4's
/// `maxcomponentvalue` (the other version's name stays unread, as in its pbrt).
// DEVIATION(pbrt): robustness. pbrt takes a negative bound, which negates every
// sample over it; we refuse it.
fn sample_clamp(p: &crate::parser::params::ParamList, syntax: Syntax) -> Res<Option<SampleClamp>> {
    let (name, rule): (_, fn(f64) -> SampleClamp) = match syntax {
        Syntax::V3 => ("maxsampleluminance", SampleClamp::Luminance),
        Syntax::V4 => ("maxcomponentvalue", SampleClamp::SensorComponent),
    };
    let max = values::float(p, name, f32::INFINITY, Range::NonNegative)?;
    Ok(max.is_finite().then(|| rule(max as f64)))
}

/// A `spectral` film's `nbuckets`, `lambdamin` and `lambdamax`, checked as pbrt-v4
/// checks them (its wavelengths lie within 360–830 nm).
fn spectral_buckets(e: &Entity, (pixels, limit): (u64, u64)) -> Res<Buckets> {
    let (p, d) = (&e.params, Buckets::DEFAULT);
    let param_error =
        |name: &str, why: String| Diagnostic::error(p.named(name).map_or(e.name_span, |x| x.value_span), why);
    let count = match p.int("nbuckets")? {
        None => d.count,
        Some(n) if n < 1 => return Err(param_error("nbuckets", format!("\"nbuckets\" must be at least 1, not {n}"))),
        // DEVIATION(pbrt): robustness. Its sums are film state like pixels: pbrt-v4
        // allocates them all and runs out of memory.
        Some(n) if pixels.saturating_mul(n as u64) > limit => {
            let what = format!("the spectral film's {pixels} pixels × {n} buckets");
            return Err(param_error("nbuckets", Limits::over(what, "pixels", limit)));
        }
        Some(n) => n as usize,
    };
    let lo = values::float(p, "lambdamin", d.lambda_min, Range::Any)?;
    let hi = values::float(p, "lambdamax", d.lambda_max, Range::Any)?;
    if lo < d.lambda_min || hi > d.lambda_max {
        let why = format!("wavelengths {lo}–{hi} nm reach beyond the 360–830 nm that pbrt-v4 renders");
        return Err(param_error(if lo < d.lambda_min { "lambdamin" } else { "lambdamax" }, why));
    }
    if lo.is_nan() || hi.is_nan() || lo >= hi {
        return Err(param_error("lambdamax", format!("\"lambdamax\" {hi} is not above \"lambdamin\" {lo}")));
    }
    Ok(Buckets { count, lambda_min: lo, lambda_max: hi })
}
