//! `pbrt-bench stress mesh`: rays that escape closed triangle meshes.
//!
//! ```text
//! pbrt-bench stress mesh [--meshes 20] [--rays 5000]
//! ```
//! Each mesh is a closed UV sphere (24 × 16, shared poles and seam, every vertex at a
//! random radius in [1, 1.5]) loaded from scene text, either as a world shape under
//! `ConcatTransform` or as an `ObjectInstance` under it, so both the loader's world-space
//! vertices and the instance path are exercised. The transforms are the sweep's (scales
//! 1e-6…1e6, distances 0, 1e6 and 1e7, three kinds). Rays start inside, within 0.3 of the
//! centre in object units, and go a third each in a random direction, exactly at a
//! vertex (a fan of up to 24 triangles at the poles), and at a point on an edge. A ray
//! from inside a closed surface must hit it: a miss is an escape. Meshes below f32's
//! resolution at their distance are not judged and are counted apart.

use super::{DISTANCES, KINDS, cases, dir, per_1e7, resolvable, transform};
use glam::{DMat4, DVec3, Vec3};
use pbrt_sppm::accel::Geometry;
use pbrt_sppm::math::{Point3, Ray, Vector3};
use pbrt_sppm::sampling::{Rng, hash};
use pbrt_sppm::scene::{LoadOptions, load_scene_from_bytes};
use rayon::prelude::*;
use std::fmt::Write;
use std::path::Path;

const RINGS: usize = 16;
const SEGMENTS: usize = 24;

/// Object-space vertices and triangles of a closed UV sphere with random radii.
fn sphere(rng: &mut Rng) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = vec![DVec3::Z * (1.0 + 0.5 * rng.uniform() as f64)];
    for t in 1..RINGS {
        let theta = std::f64::consts::PI * t as f64 / RINGS as f64;
        for k in 0..SEGMENTS {
            let phi = std::f64::consts::TAU * k as f64 / SEGMENTS as f64;
            let r = 1.0 + 0.5 * rng.uniform() as f64;
            p.push(r * DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
        }
    }
    p.push(-DVec3::Z * (1.0 + 0.5 * rng.uniform() as f64));
    let ring = |t: usize, k: usize| (1 + (t - 1) * SEGMENTS + k % SEGMENTS) as u32;
    let south = (p.len() - 1) as u32;
    let mut tris = Vec::new();
    for k in 0..SEGMENTS {
        tris.push([0, ring(1, k), ring(1, k + 1)]);
        tris.push([south, ring(RINGS - 1, k + 1), ring(RINGS - 1, k)]);
        for t in 1..RINGS - 1 {
            tris.push([ring(t, k), ring(t + 1, k), ring(t + 1, k + 1)]);
            tris.push([ring(t, k), ring(t + 1, k + 1), ring(t, k + 1)]);
        }
    }
    (p, tris)
}

/// Scene text placing the mesh under `m`, as a world shape or an instance.
fn scene_text(p: &[DVec3], tris: &[[u32; 3]], m: DMat4, instanced: bool) -> String {
    let mut shape = String::from("Shape \"trianglemesh\" \"integer indices\" [");
    for t in tris {
        let _ = write!(shape, " {} {} {}", t[0], t[1], t[2]);
    }
    shape.push_str(" ] \"point3 P\" [");
    for v in p {
        let _ = write!(shape, " {} {} {}", v.x, v.y, v.z);
    }
    shape.push_str(" ]\n");
    let concat = m.to_cols_array().iter().map(|x| format!("{x:e}")).collect::<Vec<_>>().join(" ");
    if instanced {
        format!("WorldBegin\nObjectBegin \"m\"\n{shape}ObjectEnd\nConcatTransform [ {concat} ]\nObjectInstance \"m\"\n")
    } else {
        format!("WorldBegin\nConcatTransform [ {concat} ]\n{shape}")
    }
}

/// Rays traced from inside one mesh and the escapes, or None where f32 cannot
/// resolve the mesh.
fn one_mesh(kind: usize, scale: f64, distance: f64, instanced: bool, rays: usize, seed: u64) -> Option<(u64, u64)> {
    let mut rng = Rng::new(seed);
    let (m, smallest) = transform(kind, scale, distance, &mut rng);
    if !resolvable(smallest, distance) {
        return None;
    }
    let (p, tris) = sphere(&mut rng);
    let text = scene_text(&p, &tris, m, instanced);
    let scene = match load_scene_from_bytes(Path::new("stress-mesh.pbrt"), text.into_bytes(), &LoadOptions::default()) {
        Ok(s) => s,
        Err(e) => panic!("the generated mesh scene did not load: {e}"),
    };
    // The loader's own world-space vertices, so that "at a vertex" is exact.
    let world: Vec<Vec3> = match scene.meshes.first() {
        Some(mesh) if !instanced => mesh.p.iter().map(|v| Vec3::from(*v)).collect(),
        _ => p.iter().map(|v| m.transform_point3(*v).as_vec3()).collect(),
    };
    let g = Geometry::new(&scene);
    let mut escapes = 0;
    for i in 0..rays {
        let o = m.transform_point3(dir(&mut rng) * 0.3 * rng.uniform() as f64).as_vec3();
        let target = match i % 3 {
            0 => o + dir(&mut rng).as_vec3(),
            1 => world[rng.next_u32() as usize % world.len()],
            _ => {
                let [a, b, _] = tris[rng.next_u32() as usize % tris.len()];
                world[a as usize].lerp(world[b as usize], rng.uniform())
            }
        };
        escapes += g.intersect(&Ray::new(Point3(o), Vector3(target - o))).is_none() as u64;
    }
    Some((rays as u64, escapes))
}

/// Prints a line per case and a summary; the summary follows the line naming "escapes
/// per 10^7".
pub fn run(meshes: usize, rays: usize) {
    println!("\nrays from inside closed meshes: {meshes} meshes a case, {rays} rays each");
    println!("{:<9} {:<14} {:>9} {:>7} {:>11} {:>8}", "placed", "transform", "distance", "scale", "rays", "escapes");
    let (mut total, mut escapes, mut skipped) = (0u64, 0u64, 0u64);
    let mut failing = Vec::new();
    for (placed, instanced) in [("world", false), ("instance", true)] {
        for (k, kind) in KINDS.iter().enumerate() {
            for &d in &DISTANCES {
                for e in -6..=6 {
                    let s = 10f64.powi(e);
                    let seed = |i: usize| hash(&[i as u64, k as u64, s.to_bits(), d.to_bits(), instanced as u64]);
                    let res: Vec<Option<(u64, u64)>> =
                        (0..meshes).into_par_iter().map(|i| one_mesh(k, s, d, instanced, rays, seed(i))).collect();
                    skipped += res.iter().filter(|r| r.is_none()).count() as u64;
                    let (n, x) = res.iter().flatten().fold((0, 0), |a, r| (a.0 + r.0, a.1 + r.1));
                    if n == 0 {
                        continue;
                    }
                    (total, escapes) = (total + n, escapes + x);
                    if x > 0 {
                        failing.push(format!("{placed}/{kind}/{s:.0e}@{d:.0e}"));
                    }
                    println!("{placed:<9} {kind:<14} {d:>9.0e} {s:>7.0e} {n:>11} {x:>8}");
                }
            }
        }
    }
    println!(
        "\n{:>11} {:>8} {:>16} {:>15}   cases with escapes",
        "rays", "escapes", "escapes per 10^7", "meshes skipped"
    );
    let cases = cases(&failing);
    println!("{total:>11} {escapes:>8} {:>16.2} {skipped:>15}   {cases}", per_1e7(escapes, total));
}
