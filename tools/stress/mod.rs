//! `pbrt-bench stress`: numerical stress sweeps, each printing a table and a summary.
//!
//! ```text
//! pbrt-bench stress [spawn|mesh|grazing|furnace] [--shapes N] [--rays N] [--meshes N] [--iterations N]
//! ```
//! - `spawn` (`spawn.rs`): spawned rays that hit their own surface again, per family;
//! - `mesh` (`mesh.rs`): rays from inside closed meshes that escape them;
//! - `grazing` (`grazing.rs`): rays tangent to the quadrics, through their rims and
//!   poles, checked against an f64 reference;
//! - `furnace` (`furnace.rs`): a long progressive run against its analytic value.
//!
//! Without a part, all four run in that order. Every sweep places its shapes at scales
//! 1e-6…1e6 and distances from the origin up to 1e7, under the [`KINDS`] of transform.

mod furnace;
mod grazing;
mod mesh;
mod spawn;

use glam::{DMat4, DVec3};
use pbrt_sppm::math::{Point3, Ray, Vector3};
use pbrt_sppm::sampling::{Rng, uniform_sphere};
use std::process::ExitCode;

/// `pbrt-bench stress --help`.
pub const HELP: &str = "\
Usage: pbrt-bench stress [spawn|mesh|grazing|furnace] [OPTIONS]

Numerical stress sweeps, each printing a table and a summary; without a part, all four
in that order. Shapes are placed at scales 1e-6..1e6 and up to 1e7 from the origin.
  spawn     spawned rays that hit their own surface again, per shape family
  mesh      rays from inside closed meshes that escape them
  grazing   rays tangent to the quadrics, through rims and poles, against f64
  furnace   a long progressive SPPM run against its analytic value
  --shapes N       shapes per case (spawn: default 500; grazing: 100)
  --rays N         rays per shape or mesh (spawn 500, mesh 5000, grazing 400)
  --meshes N       closed meshes (mesh: default 20)
  --iterations N   SPPM iterations (furnace: default 100000)
";

const FAMILIES: [&str; 8] = ["sphere", "cylinder", "disk", "cone", "paraboloid", "hyperboloid", "triangle", "curve"];
const KINDS: [&str; 3] = ["plain", "mirror+shear", "near-singular"];
const DISTANCES: [f64; 3] = [0.0, 1e6, 1e7];

/// A random unit direction.
fn dir(rng: &mut Rng) -> DVec3 {
    uniform_sphere(rng.uniform2()).as_dvec3().normalize()
}

/// Translate(distance · a random direction) · Rotate(random) · X · Scale(scale), X the
/// kind of transform; and the smallest size it leaves a unit shape with.
fn transform(kind: usize, scale: f64, distance: f64, rng: &mut Rng) -> (DMat4, f64) {
    let t = DMat4::from_translation(distance * dir(rng));
    let r = DMat4::from_axis_angle(dir(rng), std::f64::consts::TAU * rng.uniform() as f64);
    let (x, smallest) = match kind {
        0 => (DMat4::IDENTITY, 1.0),
        1 => (
            DMat4::from_cols_array(&[-1.0, 0.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.3, 0.2, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
            0.5,
        ),
        _ => (DMat4::from_scale(DVec3::new(1.0, 1.0, 1e-4)), 1e-4),
    };
    (t * r * x * DMat4::from_scale(DVec3::splat(scale)), smallest * scale)
}

/// Whether f32 resolves a shape whose smallest size is `size` at `distance` from the
/// origin: at least 10^4 of f32's spacings there.
fn resolvable(size: f64, distance: f64) -> bool {
    size >= 1e4 * ulp32(distance + size)
}

/// f32's spacing at magnitude `x`.
fn ulp32(x: f64) -> f64 {
    let x = x.abs() as f32;
    (x.next_up() - x) as f64
}

fn to_ray(o: DVec3, d: DVec3) -> Ray {
    Ray::new(Point3(o.as_vec3()), Vector3(d.as_vec3()))
}

/// The failing cases for a summary line: "none", or the first eight and how many more.
fn cases(failing: &[String]) -> String {
    match failing.len() {
        0 => "none".into(),
        n if n <= 8 => failing.join(" "),
        n => format!("{} (and {} more)", failing[..8].join(" "), n - 8),
    }
}

/// Rays per 10^7, for the summaries.
fn per_1e7(count: u64, rays: u64) -> f64 {
    count as f64 * 1e7 / rays.max(1) as f64
}

pub fn main(args: &[String]) -> ExitCode {
    let flag = |name: &str, default: usize| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let part = args.first().filter(|a| !a.starts_with("--")).map(String::as_str);
    let all = part.is_none();
    if !matches!(part, None | Some("spawn" | "mesh" | "grazing" | "furnace")) {
        eprint!("{HELP}");
        return ExitCode::FAILURE;
    }
    if all || part == Some("spawn") {
        spawn::run(flag("--shapes", 500), flag("--rays", 500));
    }
    if all || part == Some("mesh") {
        mesh::run(flag("--meshes", 20), flag("--rays", 5000));
    }
    if all || part == Some("grazing") {
        grazing::run(flag("--shapes", 100), flag("--rays", 400));
    }
    if all || part == Some("furnace") {
        furnace::run(flag("--iterations", 100_000) as u32);
    }
    ExitCode::SUCCESS
}
