//! Tables read from files that materials share for the process's life: one per file
//! contents (keyed by a hash of the bytes, so a file that changes on disk is read
//! again), referred to by `Copy` lobes and compared by address. The `fourier` and
//! `measured` materials keep theirs here.

use crate::spectrum::Rgb;
use glam::Vec3;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// A shared table, compared by address.
#[derive(Debug)]
pub struct Shared<T: 'static>(pub &'static T);

impl<T> Clone for Shared<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Shared<T> {}

impl<T> PartialEq for Shared<T> {
    fn eq(&self, o: &Self) -> bool {
        std::ptr::eq(self.0, o.0)
    }
}

/// The tables of one kind already read, by their bytes' hash.
pub struct Loaded<T: 'static>(OnceLock<Mutex<HashMap<u64, &'static T>>>);

impl<T: Sync> Default for Loaded<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Sync> Loaded<T> {
    pub const fn new() -> Self {
        Loaded(OnceLock::new())
    }

    /// The table in `bytes`, read by `read` the first time these bytes are seen.
    pub fn get(
        &'static self,
        bytes: &[u8],
        read: impl FnOnce(&[u8]) -> Result<T, String>,
    ) -> Result<Shared<T>, String> {
        let map = self.0.get_or_init(Mutex::default);
        let key = xxhash_rust::xxh3::xxh3_64(bytes);
        if let Some(t) = map.lock().ok().and_then(|m| m.get(&key).copied()) {
            return Ok(Shared(t));
        }
        let t: &'static T = Box::leak(Box::new(read(bytes)?));
        if let Ok(mut m) = map.lock() {
            m.insert(key, t);
        }
        Ok(Shared(t))
    }
}

/// A direction sampled from a table: (ωi, f, density). (Not the lobes' `LobeSample`:
/// the lobes refer to the tables, so the tables do not refer to the lobes.)
pub struct Sampled {
    pub wi: Vec3,
    pub f: Rgb,
    pub pdf: f32,
}
