//! `pbrt-rgb2spec`: fits the sigmoid-polynomial tables pbrt-sppm upsamples RGB with.
//!
//! ```sh
//! cargo run --release --bin pbrt-rgb2spec -- src/spectrum/tables
//! ```
//! writes `srgb.bin`, `rec2020.bin`, `aces2065-1.bin` and `dci-p3.bin` (64³ cells per
//! max component each; the method is in `src/spectrum/fit.rs`). Their output is
//! committed: neither the build nor the tests run this.

use pbrt_sppm::spectrum::colorspace::ColorSpaceName;
use pbrt_sppm::spectrum::fit::Fitter;
use std::path::PathBuf;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--version") {
        println!("pbrt-rgb2spec {}", env!("CARGO_PKG_VERSION"));
        return;
    }
    let [dir] = args.as_slice() else {
        eprintln!("usage: pbrt-rgb2spec OUTPUT_FOLDER [--version]");
        std::process::exit(1);
    };
    let dir = PathBuf::from(dir);
    for space in ColorSpaceName::ALL {
        let start = std::time::Instant::now();
        let table = Fitter::new(space).table(64);
        let path = dir.join(format!("{}.bin", space.name()));
        let tmp = path.with_extension("bin.tmp");
        let written = std::fs::write(&tmp, table.to_bytes()).and_then(|()| std::fs::rename(&tmp, &path));
        if let Err(e) = written {
            eprintln!("error: cannot write {}: {e}", path.display());
            std::process::exit(1);
        }
        eprintln!("{}: {:.1} s", path.display(), start.elapsed().as_secs_f64());
    }
}
