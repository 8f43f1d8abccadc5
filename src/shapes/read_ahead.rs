//! PLY files read ahead. When the scene builder meets a world `plymesh` shape (once the
//! file's version is known) it names the file here; a pool thread reads and parses it
//! while the main thread goes on reading the scene's text, and the shape takes the
//! parsed mesh when it is built, at the end of the world. The meshes, errors and
//! warnings are those of reading each file in its turn.
//!
//! ```text
//! Shape "plymesh" "string filename" "meshes/part-017.ply"   # read on a pool thread
//! ```

use super::plymesh::{self, PlyMesh, Quads};
use crate::limits::Files;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::mpsc::{Receiver, sync_channel};
use std::sync::{Arc, Mutex};

/// A file's parsed mesh, or the plain message `plymesh::load` gives.
type Parsed = Result<PlyMesh, String>;

/// A file and how its quads are read.
type Key = (PathBuf, Quads);

/// Who reads a file: nobody yet, the pool, or the shape that wants it (when the pool
/// had not begun: the pool may be busy with other work, such as another render in the
/// same process, and the shape should not wait behind it).
const QUEUED: u8 = 0;
const POOL: u8 = 1;
const SHAPE: u8 = 2;

/// One read: who does it, and where the pool sends what it read.
struct Read {
    who: Arc<AtomicU8>,
    result: Receiver<Parsed>,
    path: PathBuf,
    files: Files,
}

/// The files being read ahead, oldest first; each read is taken once (a file named
/// twice is read twice, as it would be in turn).
#[derive(Default)]
pub struct ReadAhead {
    pending: Mutex<HashMap<Key, Vec<Read>>>,
}

impl ReadAhead {
    /// Starts reading `path` on the thread pool, within `files`' limits.
    pub fn start(&self, path: PathBuf, quads: Quads, files: &Files) {
        let (send, result) = sync_channel(1);
        let who = Arc::new(AtomicU8::new(QUEUED));
        let (job_who, job_path, job_files) = (who.clone(), path.clone(), files.clone());
        rayon::spawn(move || {
            if job_who.compare_exchange(QUEUED, POOL, Ordering::AcqRel, Ordering::Acquire).is_ok() {
                // The receiver may be gone (the load stopped at an error): nothing to do then.
                drop(send.send(plymesh::load(&job_path, quads, &job_files)));
            }
        });
        if let Ok(mut pending) = self.pending.lock() {
            let read = Read { who, result, path: path.clone(), files: files.clone() };
            pending.entry((path, quads)).or_default().push(read);
        }
    }

    /// The oldest read started for `path` with `quads`: waiting for it if the pool is
    /// reading it, read here if the pool has not begun; `None` when none was started
    /// (the caller reads the file itself).
    pub fn take(&self, path: &Path, quads: Quads) -> Option<Parsed> {
        let read = {
            let mut pending = self.pending.lock().ok()?;
            let reads = pending.get_mut(&(path.to_path_buf(), quads))?;
            (!reads.is_empty()).then(|| reads.remove(0))?
        };
        match read.who.compare_exchange(QUEUED, SHAPE, Ordering::AcqRel, Ordering::Acquire) {
            Ok(_) => Some(plymesh::load(&read.path, quads, &read.files)),
            Err(_) => read.result.recv().ok(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ply(triangles: u32) -> String {
        let mut s = format!(
            "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {triangles}\nproperty list uchar int vertex_indices\nend_header\n",
            triangles + 2
        );
        (0..triangles + 2).for_each(|i| s += &format!("{i} {} 0\n", i % 2));
        (0..triangles).for_each(|i| s += &format!("3 {i} {} {}\n", i + 1, i + 2));
        s
    }

    /// Each start is taken once, in order, and gives what reading in turn gives;
    /// a file never started, or started for the other quad reading, is not taken.
    #[test]
    fn reads_are_taken_once_each_as_read_in_turn() {
        let dir = std::env::temp_dir().join(format!("pbrt-sppm-read-ahead-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        let (a, b) = (dir.join("a.ply"), dir.join("b.ply"));
        std::fs::write(&a, ply(3)).expect("write a");
        std::fs::write(&b, "ply\nformat ascii 1.0\nelement vertex 1\n").expect("write b");
        let files = Files::default();
        let ahead = ReadAhead::default();
        ahead.start(a.clone(), Quads::Split, &files);
        ahead.start(a.clone(), Quads::Split, &files);
        ahead.start(b.clone(), Quads::Split, &files);
        let in_turn = |p: &Path| plymesh::load(p, Quads::Split, &files);
        let tris = |r: Parsed| r.map(|m| m.triangles.indices);
        for _ in 0..2 {
            let got = ahead.take(&a, Quads::Split).expect("started");
            assert_eq!(tris(got), tris(in_turn(&a)));
        }
        assert!(ahead.take(&a, Quads::Split).is_none(), "each read is taken once");
        assert!(ahead.take(&b, Quads::Patches).is_none(), "the quad reading is part of the key");
        let err = ahead.take(&b, Quads::Split).expect("started").map(|_| ()).expect_err("a truncated header");
        assert_eq!(Err(err), in_turn(&b).map(|_| ()));
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A shape whose file the pool has not begun (its threads busy with other work)
    /// reads it itself rather than wait: here the pool's one thread is the one asking.
    #[test]
    fn a_read_the_busy_pool_has_not_begun_is_done_by_the_shape() {
        let dir = std::env::temp_dir().join(format!("pbrt-sppm-read-ahead-busy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        let a = dir.join("a.ply");
        std::fs::write(&a, ply(5)).expect("write a");
        let files = Files::default();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
        let got = pool.install(|| {
            let ahead = ReadAhead::default();
            ahead.start(a.clone(), Quads::Split, &files);
            ahead.take(&a, Quads::Split).expect("started")
        });
        let in_turn = plymesh::load(&a, Quads::Split, &files);
        assert_eq!(got.map(|m| m.triangles.indices), in_turn.map(|m| m.triangles.indices));
        std::fs::remove_dir_all(&dir).ok();
    }
}
