//! How glibc's allocator hands memory back, set for the two phases of a run.
//!
//! glibc starts by mapping each block of 128 KiB or more on its own, and raises that
//! bound to the size of any such block freed (up to 32 MiB), and the free room it keeps
//! at a heap's top to twice the bound. That suits a renderer's passes, which free and
//! make the same buffers again, but not the load: a build's records of 32 MB, freed
//! on a worker thread, stayed resident at the top of that thread's heap, which
//! `malloc_trim` does not shrink. A million instances peaked 62 MB higher for it.
//!
//! - [`for_loading`]: blocks of 128 KiB or more mapped on their own, and a heap's free
//!   top above 4 MiB given back, for the whole load.
//! - [`for_rendering`]: the bounds glibc's own rule ends at (32 MiB, 64 MiB), so that
//!   the passes reuse their buffers' pages instead of mapping fresh ones.
//!
//! Elsewhere (another C library, another system) both do nothing.

/// Sets the allocator for reading a scene and building its BVHs.
pub fn for_loading() {
    set(128 << 10, 4 << 20);
}

/// Sets the allocator for the passes of a render, once its scene is built.
pub fn for_rendering() {
    set(32 << 20, 64 << 20);
}

/// `mallopt` of the bound over which blocks are mapped alone, and of the free room
/// kept at a heap's top. Either turns glibc's own raising of both off.
fn set(mmap_threshold: i32, trim_threshold: i32) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes the allocator's thresholds; it takes its lock.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, mmap_threshold);
        libc::mallopt(libc::M_TRIM_THRESHOLD, trim_threshold);
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = (mmap_threshold, trim_threshold);
}
