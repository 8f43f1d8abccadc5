//! Transparent huge pages for the large arrays rays walk: BVH nodes, leaf blocks and
//! mesh vertices and indices (from the long number lists they are parsed from on);
//! and for a list that grows to hundreds of MB while a scene is read, the instance
//! records, where a fault per 4 KiB page was a tenth of reading a million instances.
//! Incoherent rays on a large scene touch a new 4 KiB page at nearly every step, and
//! each TLB miss is a page walk (a two-dimensional one under a hypervisor); 2 MiB
//! pages cut most of those walks away. Embree does the same.
//!
//! Arrays made once at their final size (leaf blocks, long number lists, a large
//! build's records and its BVH nodes, its subtrees appended there once written) are
//! marked before they are written, so their pages are huge from the first write. Folding pages
//! already written (`MADV_COLLAPSE`) makes the kernel copy them: 0.7 s for the 290 MB
//! of a 12.6M-triangle scene's nodes and blocks on our test machine, against 0.1–0.4
//! s for writing them to fresh huge pages.

const HUGE: usize = 2 << 20;

/// Asks Linux to back the 2 MiB-aligned middle of `data` with huge pages now
/// (`MADV_HUGEPAGE`, then `MADV_COLLAPSE` to fold in pages already written; cheap
/// where they are huge already). Slices under 4 MiB are left alone; a kernel that
/// declines changes nothing.
pub fn advise<T>(data: &[T]) {
    madvise(data.as_ptr(), std::mem::size_of_val(data), true);
}

/// An empty vector with room for `n` values, its pages marked to be huge ones when
/// first written (from 4 MiB).
pub fn with_capacity<T>(n: usize) -> Vec<T> {
    let v = Vec::with_capacity(n);
    madvise(v.as_ptr(), n * std::mem::size_of::<T>(), false);
    v
}

/// Pushes `value`, growing a full vector by doubling into room marked as with
/// [`with_capacity`]: a list that grows to hundreds of MB one value at a time (a
/// million instance records) takes its fresh pages 2 MiB at a time. The values are
/// copied at each growth, where `realloc` would have moved the pages.
pub fn push<T>(v: &mut Vec<T>, value: T) {
    if v.len() == v.capacity() {
        reserve(v, v.capacity().max(64) * 2 - v.len());
    }
    v.push(value);
}

/// Makes room for `additional` more values in one step, into room marked as with
/// [`with_capacity`] (the values are copied there).
pub fn reserve<T>(v: &mut Vec<T>, additional: usize) {
    if v.capacity() - v.len() < additional {
        let mut grown = with_capacity(v.len() + additional);
        grown.append(v);
        *v = grown;
    }
}

/// `MADV_HUGEPAGE` on the 2 MiB-aligned middle of the `bytes` bytes at `start` (an
/// allocation of the caller's), then `MADV_COLLAPSE` if `collapse`.
fn madvise<T>(start: *const T, bytes: usize, collapse: bool) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let start = start as usize;
        let (first, end) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
        if bytes >= 2 * HUGE && end > first {
            let (ptr, len) = (first as *mut libc::c_void, end - first);
            // SAFETY: the range lies inside the caller's allocation, which outlives the
            // call; these advices change how the kernel backs the pages, never their
            // contents.
            unsafe {
                libc::madvise(ptr, len, libc::MADV_HUGEPAGE);
                if collapse {
                    libc::madvise(ptr, len, libc::MADV_COLLAPSE);
                }
            }
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = (start, bytes, collapse);
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
        let mut w = super::with_capacity(v.len());
        w.extend_from_slice(&v);
        assert!(w == v && w.capacity() == v.len());
    }

    /// Growing by [`super::push`] keeps every value in order and doubles the room, so
    /// a long list is copied about once over, not once per value.
    #[test]
    fn pushing_keeps_values_and_doubles_the_room() {
        let mut v = Vec::new();
        let mut growths = 0;
        for i in 0..1_000_000u64 {
            let room = v.capacity();
            super::push(&mut v, i * 3);
            growths += usize::from(v.capacity() != room);
        }
        assert!(v.iter().enumerate().all(|(i, &x)| x == i as u64 * 3));
        assert!(growths <= 15 && v.capacity() < 2 * v.len() + 128, "{growths} growths, room {}", v.capacity());
    }
}
