//! The memory a scene needs at its peak, estimated while it loads, and the memory the
//! machine has for it: what `--limit memory=N` bounds. (Also the cache prefetch
//! helpers the accelerator, the photon grid, SPPM and vcm share.)
//!
//! ```text
//! pbrt-sppm render city.pbrt --limit memory=16e9
//! pbrt-sppm check city.pbrt        # memory: the estimate, and the limit
//! ```
//!
//! The loader adds each mesh and each `ObjectInstance` as it reads it and stops, with
//! an error at that statement, as soon as the estimate passes the limit: before the
//! rest of the file is read, before the BVH is built and before any pixel is rendered.
//! The film's pixels are added once the film is known. By default the limit is the
//! memory the system had free when the load started (`MemAvailable`, or what the
//! process's cgroup still allows, whichever is less).
//!
//! The costs are peaks measured on `pbrt-bench load` and the bundled scenes
//! (docs/benchmarks.md, "Memory estimate"): a mesh's triangle costs its indices, the
//! BVH build's record and box, its reordered copy and its share of leaf blocks and
//! nodes; an instance its record, the top-level build's record and tree. Images are
//! not counted: each is bounded by `texture-pixels`.

/// Bytes per triangle at the peak (indices, BVH build, reordered copy, leaf blocks).
pub const TRIANGLE_BYTES: u64 = 80;
/// Bytes per mesh vertex (positions and normals, in the file's order and reordered).
pub const VERTEX_BYTES: u64 = 32;
/// Bytes per `ObjectInstance`: its record and the accelerator's (112 bytes each), the
/// top-level BVH's nodes (about 66) and its build records (32), with a margin.
pub const INSTANCE_BYTES: u64 = 384;
/// Bytes per film pixel (SPPM's pixel state and visible point, the photon grid's
/// entry, the film; vcm's pixels take a little less).
pub const PIXEL_BYTES: u64 = 360;
/// About the most photon deposits SPPM holds before it sums them.
pub const DEPOSITS_HELD: usize = 1 << 22;
/// What rendering holds whatever the film's size, once there is one: the deposits
/// waiting to be summed, 16 bytes each and as many again while grouped by pixel.
pub const RENDER_BYTES: u64 = DEPOSITS_HELD as u64 * 32;
/// The process before any scene: code, thread stacks, the pool.
pub const BASE_BYTES: u64 = 16 << 20;

/// The estimate so far and the limit it is held to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    pub need: MemoryNeed,
    /// In bytes; `u64::MAX` where no limit was given and the free memory is unknown.
    pub limit: u64,
    /// Whether the limit is the default: the memory free when the load started.
    pub free_memory: bool,
}

impl MemoryBudget {
    pub fn new(limit: u64, free_memory: bool) -> MemoryBudget {
        MemoryBudget { need: MemoryNeed::default(), limit, free_memory }
    }

    /// "about 1.7 GiB at the peak, estimated (21.9 GiB free)", as `check` prints it.
    pub fn summary(&self) -> String {
        let limit = match (self.limit, self.free_memory) {
            (u64::MAX, _) => "no limit".to_string(),
            (l, true) => format!("{} free", size(l)),
            (l, false) => format!("limit {}", size(l)),
        };
        format!("about {} at the peak, estimated ({limit})", size(self.need.bytes()))
    }

    /// Adds to the estimate; `Err` with the message once it is over the limit.
    pub fn add(&mut self, f: impl FnOnce(&mut MemoryNeed)) -> Result<(), String> {
        f(&mut self.need);
        self.need.check(self.limit, self.free_memory)
    }
}

/// What a scene holds that its peak memory grows with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryNeed {
    /// Mesh triangles (a bilinear patch counts as two), instanced objects' once.
    pub triangles: u64,
    pub vertices: u64,
    pub instances: u64,
    pub pixels: u64,
}

impl MemoryNeed {
    /// The estimated peak, in bytes.
    pub fn bytes(&self) -> u64 {
        [
            (self.triangles, TRIANGLE_BYTES),
            (self.vertices, VERTEX_BYTES),
            (self.instances, INSTANCE_BYTES),
            (self.pixels, PIXEL_BYTES),
            ((self.pixels > 0) as u64, RENDER_BYTES),
        ]
        .iter()
        .fold(BASE_BYTES, |sum, &(n, b)| sum.saturating_add(n.saturating_mul(b)))
    }

    /// `Err` with a message when the estimate is over `limit` bytes (`by_default`: the
    /// limit is the memory that was free).
    pub fn check(&self, limit: u64, by_default: bool) -> Result<(), String> {
        if self.bytes() <= limit {
            return Ok(());
        }
        let what = format!("the memory the scene needs by here, about {} ({}),", size(self.bytes()), self.parts());
        let free = match by_default {
            true => format!(", the memory free when loading started ({})", size(limit)),
            false => String::new(),
        };
        Err(format!("{what} is over the limit of {limit} bytes{free} (raise it with --limit memory=N)"))
    }

    /// What the estimate is made of, in words: "12.6M triangles, 1.0M instances".
    pub fn parts(&self) -> String {
        let parts = [(self.triangles, "triangles"), (self.instances, "instances"), (self.pixels, "pixels")];
        let said: Vec<String> =
            parts.iter().filter(|p| p.0 > 0).map(|&(n, what)| format!("{} {what}", count(n))).collect();
        if said.is_empty() { "the renderer alone".into() } else { said.join(", ") }
    }
}

/// A byte count for people: "812 MiB", "3.2 GiB".
pub fn size(bytes: u64) -> String {
    const MIB: f64 = (1u64 << 20) as f64;
    match bytes as f64 / MIB {
        m if m < 1024.0 => format!("{m:.0} MiB"),
        m => format!("{:.1} GiB", m / 1024.0),
    }
}

fn count(n: u64) -> String {
    match n {
        0..10_000 => n.to_string(),
        10_000..1_000_000 => format!("{:.0}k", n as f64 / 1e3),
        _ => format!("{:.1}M", n as f64 / 1e6),
    }
}

/// Asks the cache for the 64-byte lines the addresses `range` touches, for a read that
/// follows soon.
#[inline(always)]
pub fn prefetch_lines(range: std::ops::Range<usize>) {
    #[cfg(target_arch = "x86_64")]
    for line in (range.start & !63..range.end).step_by(64) {
        // SAFETY: a prefetch reads nothing the program sees and cannot fault; it is
        // `unsafe` only for its `sse` target feature, which every x86_64 has.
        unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(line as *const i8) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = range;
}

/// Asks the cache for the lines `value` spans, for a read that follows soon.
#[inline(always)]
pub fn prefetch<T>(value: &T) {
    let start = value as *const T as usize;
    prefetch_lines(start..start + std::mem::size_of::<T>());
}

/// The memory the process may still take: the system's `MemAvailable`, or what its
/// cgroup (v2) allows beyond what it uses, whichever is less; `None` where neither can
/// be read.
pub fn available() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    let system = meminfo.as_deref().and_then(mem_available);
    let cgroup = cgroup_headroom();
    match (system, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// `MemAvailable` of a `/proc/meminfo` text, in bytes.
fn mem_available(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// `memory.max − memory.current` of the process's cgroup (v2), if it has a maximum.
fn cgroup_headroom() -> Option<u64> {
    let own = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = own.lines().find_map(|l| l.strip_prefix("0::"))?;
    let dir = std::path::Path::new("/sys/fs/cgroup").join(path.trim_start_matches('/'));
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).ok();
    let max: u64 = read("memory.max")?.trim().parse().ok()?;
    let current: u64 = read("memory.current")?.trim().parse().ok()?;
    Some(max.saturating_sub(current))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_adds_each_part_at_its_cost() {
        let need = MemoryNeed { triangles: 1_000_000, vertices: 500_000, instances: 1000, pixels: 4096 };
        let want = BASE_BYTES + 80_000_000 + 16_000_000 + 384_000 + 4096 * PIXEL_BYTES + RENDER_BYTES;
        assert_eq!(need.bytes(), want);
        assert_eq!(MemoryNeed { triangles: u64::MAX, ..need }.bytes(), u64::MAX);
        assert!(need.check(want, false).is_ok());
        let e = need.check(want - 1, false).unwrap_err();
        assert!(e.contains("1.0M triangles, 1000 instances, 4096 pixels") && e.contains("--limit memory=N"), "{e}");
    }

    #[test]
    fn a_budget_refuses_the_addition_that_passes_its_limit() {
        let mut budget = MemoryBudget::new(BASE_BYTES + 10 * INSTANCE_BYTES, false);
        for _ in 0..10 {
            assert!(budget.add(|n| n.instances += 1).is_ok());
        }
        let e = budget.add(|n| n.instances += 1).unwrap_err();
        assert!(e.contains("(11 instances)") && !e.contains("free when"), "{e}");
        assert_eq!(budget.summary(), format!("about 16 MiB at the peak, estimated (limit {})", size(budget.limit)));
        let free = MemoryBudget::new(1 << 30, true);
        assert!(free.summary().ends_with("(1.0 GiB free)"), "{}", free.summary());
        assert!(MemoryBudget::new(u64::MAX, true).summary().ends_with("(no limit)"));
        let e = MemoryBudget { need: MemoryNeed { pixels: 1 << 30, ..MemoryNeed::default() }, ..free }.add(|_| ());
        assert!(e.is_err_and(|e| e.contains("the memory free when loading started (1.0 GiB)")));
    }

    #[test]
    fn available_memory_is_read_from_meminfo() {
        let text = "MemTotal:       24000000 kB\nMemFree:  100 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(mem_available(text), Some(20_000_000 * 1024));
        assert_eq!(mem_available("MemTotal: 1 kB\n"), None);
        if cfg!(target_os = "linux") {
            assert!(available().is_some_and(|b| b > 0));
        }
    }
}
