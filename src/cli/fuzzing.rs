//! Entry points the fuzz targets (`tools/fuzz`) and their regression test share: each
//! takes arbitrary bytes and must return, never panic.
//!
//! ```text
//! cargo +nightly fuzz run --fuzz-dir tools/fuzz builder
//! ```

use crate::limits::Limits;
use crate::parser::stmt::StatementReader;
use crate::scene::{LoadOptions, load_scene_from_bytes};
use std::path::Path;

/// Small limits, so that a fuzzer's inputs cannot ask for gigabytes.
pub fn limits() -> Limits {
    Limits {
        pixels: 1 << 16,
        photons: 1 << 16,
        iterations: 1 << 10,
        max_depth: 1 << 10,
        file_bytes: 1 << 20,
        texture_pixels: 1 << 16,
        include_depth: 16,
        triangles: 1 << 16,
        memory: 1 << 30,
    }
}

/// Tokenizer and statement reader: reads statements until the end or an error.
pub fn statements(data: &[u8]) {
    let Ok(mut reader) =
        StatementReader::new(Path::new("fuzz.pbrt"), data.to_vec().into(), crate::limits::Files::new(limits()))
    else {
        return;
    };
    while let Ok(Some(_)) = reader.next_stmt() {}
}

/// The whole builder, as `check` runs it. Bytes after the first NUL are the file
/// `Include "inc.pbrt"` (and `Import`) reads, from memory.
pub fn builder(data: &[u8]) {
    let (main, inc) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let mut opts = LoadOptions { limits: limits(), ..Default::default() };
    opts.in_memory.insert("inc.pbrt".into(), inc.into());
    if let Ok(scene) = load_scene_from_bytes(Path::new("/nonexistent/fuzz.pbrt"), main.to_vec(), &opts) {
        let _ = crate::cli::check::report(&scene, true);
    }
}

/// The PLY reader.
pub fn ply(data: &[u8]) {
    for quads in [crate::shapes::plymesh::Quads::Split, crate::shapes::plymesh::Quads::Patches] {
        let _ = crate::shapes::plymesh::parse(data, quads);
    }
}

/// The image readers: the first byte picks the format, below 128 PNG (odd) or EXR
/// (even) as before the other formats were read, from 128 on one of the others, its
/// lowest bit 8-bit values sRGB-decoded or raw.
pub fn image(data: &[u8]) {
    use crate::imageio::{EightBit, Format};
    let Some((&first, rest)) = data.split_first() else { return };
    let format = match first {
        0..128 => [Format::Exr, Format::Png][first as usize % 2],
        _ => {
            use Format::*;
            [Tga, Pfm, Hdr, Jpeg, Bmp, Gif, Pnm, Qoi][(first as usize / 2) % 8]
        }
    };
    let eight_bit = if first % 2 == 1 { EightBit::Srgb } else { EightBit::Raw };
    let _ = crate::imageio::decode_image(rest, format, eight_bit, limits().texture_pixels);
}

/// The Ptex reader and both of its filters, at each face's corners and centre, with
/// and without a footprint.
pub fn ptex(data: &[u8]) {
    use crate::textures::ptex::file::PtexFile;
    let Ok(tx) = PtexFile::read(data, limits().file_bytes) else { return };
    for face in 0..tx.faces.len().min(64) as i32 {
        for (u, v) in [(0.0, 0.0), (1.0, 1.0), (0.5, 0.5), (0.0, 1.0)] {
            let _ = tx.eval(face, u, v, [0.0; 4]);
            let _ = tx.eval(face, u, v, [0.3, 0.01, -0.02, 0.6]);
        }
    }
}

/// The Fourier BSDF reader, and the BSDF evaluated and sampled both ways.
pub fn fourier(data: &[u8]) {
    use crate::materials::TransportMode;
    use crate::materials::fourierbsdf::FourierTable;
    let Ok(t) = FourierTable::read(data) else { return };
    for o in [glam::Vec3::Z, glam::Vec3::new(0.6, 0.0, 0.8), glam::Vec3::new(0.0, -0.6, -0.8)] {
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            let _ = (t.f(o, -o, mode), t.pdf(o, -o), t.sample(o, [0.37, 0.71], mode));
        }
    }
}

/// The measured BSDF (tensor file) reader, and the BRDF evaluated and sampled in
/// spectral and RGB lanes.
pub fn measured(data: &[u8]) {
    use crate::materials::measuredbsdf::{Lanes, MeasuredTable};
    let Ok(t) = MeasuredTable::read(data) else { return };
    for o in [glam::Vec3::Z, glam::Vec3::new(0.6, 0.0, 0.8), glam::Vec3::new(0.0, -0.6, -0.8)] {
        for lanes in [Lanes::Wavelengths([380.0, 550.0, 900.0]), Lanes::Rgb] {
            let i = glam::Vec3::new(-o.x, 0.1, o.z).normalize();
            let _ = (t.f(o, i, lanes), t.pdf(o, i), t.sample(o, [0.37, 0.71], lanes));
        }
    }
}

/// The NanoVDB reader: the grids named `density` and `temperature`, and every lookup
/// the medium makes of them.
pub fn nanovdb(data: &[u8]) {
    use crate::media::nanovdb::file::read_grid;
    for name in ["density", "temperature"] {
        if let Ok(Some(grid)) = read_grid(data, name, limits().file_bytes) {
            let _ = (grid.max_value(), grid.max_over(grid.index_min, grid.index_max));
            let _ = grid.sample(grid.to_index(((grid.world_min + grid.world_max) * 0.5).as_vec3()));
        }
    }
}
