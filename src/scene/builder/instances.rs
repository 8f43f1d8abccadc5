//! The `ObjectInstance` statements of a scene, kept as its instance records from the
//! start:
//!
//! ```text
//! AttributeBegin Translate 0.25 0 0 ObjectInstance "o1" AttributeEnd
//! ```
//!
//! An object is found by name at the end of the world (pbrt-v4 files may define it
//! after its instances), so until then a record's `object` holds its name's index;
//! the names are resolved in place. A million instances are common: a record per
//! statement then, no second list and no copy (that copy's fresh pages were a tenth of
//! a million-instance file's load).

use super::super::Instances;
use crate::math::animated::AnimatedTransform;
use crate::parser::error::Diagnostic;
use crate::parser::source::Span;
use glam::DMat4;
use std::collections::HashMap;

/// Room is counted ahead only once this many records are full.
const ROOM_COUNTED_FROM: usize = 4096;
/// The most records one count reserves room for (416 MiB of address space; doubling
/// goes on past it).
const MOST_RESERVED: usize = 1 << 22;

#[derive(Default)]
pub(super) struct InstanceUses {
    records: Instances,
    /// Per name index: the name, and its first use's position and statement.
    names: Vec<(String, usize, Span)>,
    ids: HashMap<String, u32>,
    /// The moving ones: their position and end transform.
    ends: Vec<(usize, DMat4)>,
}

impl InstanceUses {
    /// Records an instance of the object called `name` placed by `ctm` (start, end).
    pub fn push(&mut self, name: String, span: Span, [start, end]: [DMat4; 2]) {
        let at = self.records.len();
        let next = self.names.len() as u32;
        let id = match self.ids.get(name.as_str()) {
            Some(&id) => id,
            None => {
                self.names.push((name.clone(), at, span));
                self.ids.insert(name, next);
                next
            }
        };
        if end != start {
            self.ends.push((at, end));
        }
        self.records.push(id, start, None);
    }

    /// Whether the records are full and many: then room for the statements ahead is
    /// worth counting ([`InstanceUses::reserve`]).
    pub fn wants_room(&self) -> bool {
        self.records.is_full() && self.records.len() >= ROOM_COUNTED_FROM
    }

    /// Makes room for `n` more records at once, up to [`MOST_RESERVED`], and at least
    /// for as many again as there are (so that instances spread over many small files,
    /// each counted alone, still grow the list by doubling). Grown by doubling alone, a
    /// million records were copied about once over, into fresh pages: 40% of reading a
    /// million-instance file.
    pub fn reserve(&mut self, n: usize) {
        self.records.reserve(n.min(MOST_RESERVED).max(self.records.len()));
    }

    /// The instances recorded so far.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// The names instances use, each once, in order of first use.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.names.iter().map(|(n, _, _)| n.as_str())
    }

    /// The error for the first instance, in file order, whose name `found` lacks.
    pub fn first_undefined(&self, found: &[Option<u32>]) -> Option<Diagnostic> {
        let (name, _, span) = self.undefined(found).min_by_key(|(_, at, _)| *at)?;
        Some(Diagnostic::error(*span, format!("object \"{name}\" is not defined")))
    }

    /// Per name that `found` lacks: its index, the name and its first use.
    pub fn undefined<'a>(&'a self, found: &'a [Option<u32>]) -> impl Iterator<Item = &'a (String, usize, Span)> {
        self.names.iter().zip(found).filter(|(_, f)| f.is_none()).map(|(n, _)| n)
    }

    /// The records with their objects resolved: name index `i` stands for object
    /// `remap[object_of_name[i]]`. A moving instance interpolates between its
    /// transforms in rendering space (`frame`), as pbrt-v4 does.
    pub fn resolve(self, object_of_name: &[u32], remap: &[u32], frame: DMat4, times: [f64; 2]) -> Instances {
        let mut records = self.records;
        records.remap_objects(|name| remap[object_of_name[name as usize] as usize]);
        let inner = frame.inverse();
        for (at, end) in self.ends {
            let start = records.get(at).world_from_instance();
            records.set_motion(at, AnimatedTransform::framed(start, end, times, frame, inner));
        }
        records
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// However few instances a count finds ahead, room grows at least by doubling.
    #[test]
    fn room_grows_at_least_by_doubling() {
        let mut uses = InstanceUses::default();
        while !uses.wants_room() {
            uses.push("o".into(), Span::default(), [DMat4::IDENTITY; 2]);
        }
        let full = uses.len();
        uses.reserve(1);
        assert!(uses.records.capacity() >= 2 * full, "room for {} after {full}", uses.records.capacity());
        uses.reserve(3 * full);
        assert!(uses.records.capacity() >= 4 * full);
    }
}
