//! Limits on what a scene may ask for, checked before anything is allocated.
//!
//! ```text
//! pbrt-sppm scene.pbrt --limit pixels=1e9 --limit file-bytes=8e9
//! ```
//! A scene that goes past a limit gets a located error naming the limit and the flag
//! that raises it, never an out-of-memory abort. Files are read only when they are
//! regular files (so `/dev/zero`, FIFOs and folders are refused) of at most
//! `file-bytes`, and gzip streams are decompressed to at most `file-bytes` too.
//!
//! A load reads every input file through [`Files`], which also notes its name and a
//! hash of its bytes ([`Files::list`]): what a checkpoint's scene fingerprint is made of
//! (commands that make no fingerprint skip the hashes: [`Files::without_hashes`]).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A file a scene was made from: its path made absolute and a 64-bit XXH3 of its bytes
/// as stored (0 when the load was told not to hash: [`Files::without_hashes`]).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct InputFile {
    pub path: PathBuf,
    pub hash: u64,
}

/// What one load may read (its [`Limits`]) and what it has read. Every loader (Include,
/// PLY, OBJ, SPD, images) reaches the disk through [`Files::read`], so the list of files
/// a scene came from is complete; clones share the list.
#[derive(Clone, Debug, Default)]
pub struct Files {
    pub limits: Limits,
    read: Arc<Mutex<Vec<InputFile>>>,
    /// Hashes of mapped files under way on threads of their own ([`Files::list`] waits).
    hashing: Arc<Mutex<Vec<std::thread::JoinHandle<()>>>>,
    skip_hashes: bool,
}

impl Files {
    pub fn new(limits: Limits) -> Files {
        Files { limits, ..Default::default() }
    }

    /// As [`Files::new`], for a load whose file hashes nobody reads (`check`, `trace`,
    /// `export`: they write no checkpoint or part). Hashing a 50 MB file took 8 ms of
    /// a core that its parse wanted.
    pub fn without_hashes(limits: Limits) -> Files {
        Files { limits, skip_hashes: true, ..Default::default() }
    }

    /// Reads a whole input file within the limits (a regular file of at most
    /// `file-bytes`, gunzipped to at most as many) and notes it.
    pub fn read(&self, path: &Path) -> Result<FileBytes, String> {
        read_file(path, &self.limits, |raw| match raw {
            FileBytes::Mapped(map) if map.len() >= HASH_THREAD_BYTES && !self.skip_hashes => {
                self.note_later(path, Arc::clone(map))
            }
            bytes => self.note(path, bytes),
        })
    }

    /// [`Files::note`] on a thread of its own: hashing a large file (2 ms for 50 MB)
    /// then overlaps reading it, where it held up the parse. Smaller files (the PLY
    /// files read on the thread pool, mostly) are hashed where they are read: a thread
    /// costs about as much as hashing a megabyte.
    fn note_later(&self, path: &Path, map: Arc<memmap2::Mmap>) {
        let (files, path_buf, bytes) = (self.clone(), path.to_path_buf(), Arc::clone(&map));
        match std::thread::Builder::new().spawn(move || files.note(&path_buf, &bytes)) {
            Ok(handle) => match self.hashing.lock() {
                Ok(mut pending) => pending.push(handle),
                Err(_) => _ = handle.join(),
            },
            // No thread to be had: hashed here.
            Err(_) => self.note(path, &map),
        }
    }

    /// Notes a file read otherwise (a scene given as bytes, such as standard input).
    pub fn note(&self, path: &Path, bytes: &[u8]) {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        let hash = if self.skip_hashes { 0 } else { xxhash_rust::xxh3::xxh3_64(bytes) };
        if let Ok(mut log) = self.read.lock() {
            log.push(InputFile { path, hash });
        }
    }

    /// The files read so far, sorted by path, each path once.
    pub fn list(&self) -> Vec<InputFile> {
        let pending = self.hashing.lock().map(|mut p| std::mem::take(&mut *p)).unwrap_or_default();
        for handle in pending {
            _ = handle.join();
        }
        let mut v = self.read.lock().map(|l| l.clone()).unwrap_or_default();
        v.sort();
        v.dedup_by(|a, b| a.path == b.path);
        v
    }
}

/// The limits in force for one run; `--limit NAME=N` changes one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Film pixels (the crop window's).
    pub pixels: u64,
    /// Photons per SPPM iteration.
    pub photons: u64,
    /// SPPM iterations.
    pub iterations: u64,
    /// `maxdepth`.
    pub max_depth: u64,
    /// Bytes of any one file read (scene, Include, Import, PLY, OBJ, image), and of what
    /// a gzip file decompresses to.
    pub file_bytes: u64,
    /// Pixels of one texture or environment image.
    pub texture_pixels: u64,
    /// Nested `Include`/`Import` files.
    pub include_depth: u64,
    /// Triangles one `loopsubdiv` shape refines into.
    pub triangles: u64,
    /// Bytes the scene may need at its peak ([`crate::memory`]); 0: the memory the
    /// system has free when the load starts.
    pub memory: u64,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            pixels: 1 << 28,
            photons: 1 << 28,
            iterations: 1 << 24,
            max_depth: 1 << 16,
            file_bytes: (1 << 32) - 1,
            texture_pixels: 1 << 28,
            include_depth: 64,
            triangles: 1 << 28,
            memory: 0,
        }
    }
}

/// Every limit: its name on the command line and what it bounds.
pub const NAMES: [(&str, &str); 9] = [
    ("pixels", "film pixels"),
    ("photons", "photons per iteration"),
    ("iterations", "SPPM iterations"),
    ("maxdepth", "maxdepth"),
    ("file-bytes", "bytes of one input file (after gzip decompression)"),
    ("texture-pixels", "pixels of one texture image"),
    ("include-depth", "nested Include/Import files"),
    ("triangles", "triangles of one subdivided (loopsubdiv) shape"),
    ("memory", "bytes the scene needs at its peak, estimated (0: what the system has free)"),
];

impl Limits {
    fn slot(&mut self, name: &str) -> Option<&mut u64> {
        Some(match name {
            "pixels" => &mut self.pixels,
            "photons" => &mut self.photons,
            "iterations" => &mut self.iterations,
            "maxdepth" => &mut self.max_depth,
            "file-bytes" => &mut self.file_bytes,
            "texture-pixels" => &mut self.texture_pixels,
            "include-depth" => &mut self.include_depth,
            "triangles" => &mut self.triangles,
            "memory" => &mut self.memory,
            _ => return None,
        })
    }

    /// Applies `NAME=N` (N may be written `1e9`).
    pub fn set(&mut self, spec: &str) -> Result<(), String> {
        let names = || NAMES.map(|n| n.0).join(", ");
        let (name, value) =
            spec.split_once('=').ok_or_else(|| format!("expected NAME=N, not \"{spec}\" (names: {})", names()))?;
        let n: f64 = value.trim().parse().map_err(|_| format!("limit {name}: \"{value}\" is not a number"))?;
        if !(n >= 0.0 && n.fract() == 0.0 && n < 1.8e19) {
            return Err(format!("limit {name}: {value} is not a whole number of at least 0"));
        }
        let slot = self.slot(name.trim()).ok_or_else(|| format!("unknown limit \"{name}\" (names: {})", names()))?;
        *slot = n as u64;
        Ok(())
    }

    /// An empty memory budget under this memory limit: the given one, or by default
    /// the memory free now (no limit where that cannot be read).
    pub fn memory_budget(&self) -> crate::memory::MemoryBudget {
        match self.memory {
            0 => crate::memory::MemoryBudget::new(crate::memory::available().unwrap_or(u64::MAX), true),
            n => crate::memory::MemoryBudget::new(n, false),
        }
    }

    /// `"{what} is over the limit of N (raise it with --limit NAME=N)"`.
    pub fn over(what: impl std::fmt::Display, name: &str, limit: u64) -> String {
        format!("{what} is over the limit of {limit} (raise it with --limit {name}=N)")
    }
}

/// How [`read_file`]'s message for a file that cannot be opened or read begins.
const CANNOT_READ: &str = "cannot read";

/// Whether a file reader's message says the file could not be opened or read (missing,
/// not a regular file, an I/O error), as opposed to a limit or its contents.
pub fn is_unreadable(message: &str) -> bool {
    message.starts_with(CANNOT_READ)
}

/// Reads a whole input file: a regular file of at most `limits.file_bytes`, gunzipped
/// (to at most as many bytes) when it starts with the gzip magic; `note` sees the bytes
/// as stored (before gunzip).
fn read_file(path: &Path, limits: &Limits, note: impl FnOnce(&FileBytes)) -> Result<FileBytes, String> {
    let shown = path.display();
    let meta = std::fs::metadata(path).map_err(|e| format!("{CANNOT_READ} \"{shown}\": {e}"))?;
    if !meta.is_file() {
        return Err(format!("{CANNOT_READ} \"{shown}\": not a regular file"));
    }
    if meta.len() > limits.file_bytes {
        let what = format!("\"{shown}\" has {} bytes, which", meta.len());
        return Err(Limits::over(what, "file-bytes", limits.file_bytes));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("{CANNOT_READ} \"{shown}\": {e}"))?;
    let raw = match FileBytes::map(&file, meta.len()) {
        Some(mapped) => mapped,
        None => FileBytes::Owned(read_all(file, meta.len(), path, limits)?),
    };
    note(&raw);
    if raw.starts_with(&[0x1f, 0x8b]) {
        gunzip(&raw, limits).map(FileBytes::Owned).map_err(|e| format!("\"{shown}\": {e}"))
    } else {
        Ok(raw)
    }
}

/// Reads `file` (`len` bytes when it was looked at) to its end. The size can change
/// between the check and the read (a growing file): it reads at most one byte past the
/// limit to notice.
fn read_all(file: std::fs::File, len: u64, path: &Path, limits: &Limits) -> Result<Vec<u8>, String> {
    let shown = path.display();
    // Room for the whole file at once: a growing buffer would copy it several times.
    let mut raw = Vec::with_capacity(len.min(limits.file_bytes).saturating_add(1) as usize);
    file.take(limits.file_bytes + 1).read_to_end(&mut raw).map_err(|e| format!("{CANNOT_READ} \"{shown}\": {e}"))?;
    if raw.len() as u64 > limits.file_bytes {
        return Err(Limits::over(format!("\"{shown}\" grew while being read and"), "file-bytes", limits.file_bytes));
    }
    Ok(raw)
}

/// Files at least this large are hashed on a thread of their own.
const HASH_THREAD_BYTES: usize = 8 << 20;

/// Files at least this large are mapped rather than read.
const MAP_BYTES: u64 = 1 << 20;

/// The bytes of an input file: read into memory, or mapped when large.
///
/// Reading copies the page cache into fresh pages (about 30 ms for 50 MB on the 2-core
/// test machine, as long as parsing its numbers on both cores); a read-only, pre-faulted mapping
/// shares the cached pages (about 1.5 ms; a writable private one would copy them all
/// when pre-faulted). Like any program that maps its input, a file cut short by
/// another process while it is mapped ends the process (SIGBUS).
pub enum FileBytes {
    Owned(Vec<u8>),
    Mapped(Arc<memmap2::Mmap>),
}

impl FileBytes {
    /// A read-only mapping of the first `len` bytes of `file`, or `None` when it is
    /// small or cannot be mapped (the caller reads it instead).
    fn map(file: &std::fs::File, len: u64) -> Option<FileBytes> {
        if len < MAP_BYTES || usize::try_from(len).is_err() {
            return None;
        }
        // SAFETY: the mapping is read-only; another process truncating the file while
        // it is mapped is the one hazard, documented above.
        let map = unsafe { memmap2::MmapOptions::new().len(len as usize).populate().map(file) };
        map.ok().map(|m| FileBytes::Mapped(Arc::new(m)))
    }

    /// The bytes as an owned vector (a copy only for a mapped file).
    pub fn into_vec(self) -> Vec<u8> {
        match self {
            FileBytes::Owned(v) => v,
            FileBytes::Mapped(m) => m.to_vec(),
        }
    }
}

impl From<Vec<u8>> for FileBytes {
    fn from(v: Vec<u8>) -> FileBytes {
        FileBytes::Owned(v)
    }
}

impl std::ops::Deref for FileBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            FileBytes::Owned(v) => v,
            FileBytes::Mapped(m) => m,
        }
    }
}

/// Decompresses a gzip stream (several members allowed) to at most `file_bytes`.
pub fn gunzip(raw: &[u8], limits: &Limits) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(raw)
        .take(limits.file_bytes + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot decompress (corrupt or truncated gzip data): {e}"))?;
    if out.len() as u64 > limits.file_bytes {
        return Err(Limits::over("the decompressed data", "file-bytes", limits.file_bytes));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mapped_files_are_listed_with_their_hash_unless_told_not_to() {
        let dir = std::env::temp_dir().join(format!("pbrt-sppm-files-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (big, small) = (dir.join("big.pbrt"), dir.join("small.pbrt"));
        let text: Vec<u8> = (0..HASH_THREAD_BYTES as u32 + 5).map(|i| b"0123456789 "[i as usize % 11]).collect();
        std::fs::write(&big, &text).unwrap();
        std::fs::write(&small, b"WorldBegin").unwrap();
        let listed = |files: Files| {
            assert!(matches!(files.read(&big), Ok(FileBytes::Mapped(_))), "a large file is mapped");
            assert!(matches!(files.read(&small), Ok(FileBytes::Owned(_))));
            files.clone().list()
        };
        let (hashed, unhashed) =
            (listed(Files::new(Limits::default())), listed(Files::without_hashes(Limits::default())));
        std::fs::remove_dir_all(&dir).unwrap();
        let hashes: Vec<u64> = hashed.iter().map(|f| f.hash).collect();
        assert_eq!(hashes, [xxhash_rust::xxh3::xxh3_64(&text), xxhash_rust::xxh3::xxh3_64(b"WorldBegin")]);
        // Without hashes, the same files are still listed.
        let names = |list: &[InputFile]| list.iter().map(|f| f.path.clone()).collect::<Vec<_>>();
        assert_eq!(names(&unhashed), names(&hashed));
        assert!(unhashed.iter().all(|f| f.hash == 0));
    }

    #[test]
    fn limits_are_set_by_name() {
        let mut l = Limits::default();
        assert_eq!(l.set("pixels=1e9"), Ok(()));
        assert_eq!(l.pixels, 1_000_000_000);
        assert!(l.set("pixles=3").unwrap_err().contains("unknown limit"));
        assert!(l.set("photons=-1").is_err());
        assert!(l.set("photons=1.5").is_err());
        assert!(l.set("photons").is_err());
    }
}
