//! Transparent huge pages for the large arrays rays walk: BVH nodes, leaf blocks and
//! mesh vertices and indices. Incoherent rays on a large scene touch a new 4 KiB page at nearly
//! every step, and each TLB miss is a page walk (a two-dimensional one under a
//! hypervisor); 2 MiB pages cut most of those walks away. Embree does the same.

/// Asks Linux to back the 2 MiB-aligned middle of `data` with huge pages now
/// (`MADV_HUGEPAGE`, then `MADV_COLLAPSE` to fold in pages already written). Slices
/// under 4 MiB are left alone; a kernel that declines changes nothing.
pub fn advise<T>(data: &[T]) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        const HUGE: usize = 2 << 20;
        let (start, bytes) = (data.as_ptr() as usize, std::mem::size_of_val(data));
        let (first, end) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
        if bytes >= 2 * HUGE && end > first {
            let (ptr, len) = (first as *mut libc::c_void, end - first);
            // SAFETY: the range lies inside `data`'s allocation, which outlives the call;
            // these advices change how the kernel backs the pages, never their contents.
            unsafe {
                libc::madvise(ptr, len, libc::MADV_HUGEPAGE);
                libc::madvise(ptr, len, libc::MADV_COLLAPSE);
            }
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = data;
}

#[cfg(test)]
mod tests {
    /// The advice must change how pages are backed, never what they hold (a
    /// `MADV_DONTNEED` or `MADV_FREE` here would zero them).
    #[test]
    fn advising_keeps_every_value() {
        let value = |i: usize| (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let v: Vec<u64> = (0..3_000_000).map(value).collect();
        super::advise(&v);
        super::advise(&v[1..5]);
        super::advise::<u8>(&[]);
        assert!(v.iter().enumerate().all(|(i, &x)| x == value(i)));
    }
}
