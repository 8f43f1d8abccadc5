//! Source files and byte spans.
//!
//! Every token and parameter carries a [`Span`] (file id + byte range). Line and column
//! are computed only when a message is printed, from a line-start table built lazily
//! per file, only as far into it as the messages reach (binary search), so parsing a
//! 50 MB mesh never counts lines.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::limits::FileBytes;

/// Index of a file in a [`SourceMap`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct FileId(pub u32);

/// A byte range `[start, end)` in one source file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Span {
    pub file: FileId,
    pub start: u32,
    pub end: u32,
}

impl Span {
    pub fn new(file: FileId, start: usize, end: usize) -> Span {
        Span { file, start: start as u32, end: end as u32 }
    }

    /// The smallest span covering both (same file assumed; otherwise `self`).
    pub fn to(self, other: Span) -> Span {
        if self.file != other.file {
            return self;
        }
        Span { file: self.file, start: self.start.min(other.start), end: self.end.max(other.end) }
    }
}

/// One loaded source file (decompressed when it was gzip).
pub struct SourceFile {
    pub path: PathBuf,
    /// The name used in messages: the path as the user or the scene wrote it.
    pub name: String,
    /// Shared with the reader's frame (adding a file does not copy it).
    pub text: Arc<FileBytes>,
    lines: Mutex<LineStarts>,
}

/// Where a file's lines start, found as far as messages have needed: a warning near
/// the top of a 71 MB file of instances made the whole table (50 ms on one thread).
#[derive(Default)]
struct LineStarts {
    starts: Vec<u32>,
    /// Line breaks before this offset are in `starts`.
    scanned: usize,
    /// The last column found, (offset, column), where the byte before the offset is
    /// ASCII (or the offset starts its line): a later offset on that line counts its
    /// characters from there. Counting from the line's start each time took over a
    /// minute for the warnings of a one-line statement with 100,000 unused parameters.
    column_at: Option<(usize, usize)>,
}

impl LineStarts {
    /// The start of the line holding `offset` (at most the text's length): its
    /// 1-based number and its offset.
    fn line_of(&mut self, text: &[u8], offset: usize) -> (usize, usize) {
        if self.starts.is_empty() {
            self.starts.push(0);
        }
        if offset > self.scanned {
            let breaks = memchr::memchr2_iter(b'\n', b'\r', &text[self.scanned..offset]).map(|i| self.scanned + i);
            // CR alone, LF alone and CR LF each end one line.
            let ends = |&i: &usize| text[i] == b'\n' || text.get(i + 1) != Some(&b'\n');
            let found: Vec<u32> = breaks.filter(ends).map(|i| i as u32 + 1).collect();
            self.starts.extend(found);
            self.scanned = offset;
        }
        let line = self.starts.partition_point(|&s| s as usize <= offset).max(1);
        (line, self.starts[line - 1] as usize)
    }
}

/// A resolved location, for printing.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Location {
    pub file: String,
    pub line: u32,
    pub column: u32,
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}

/// All files read while loading one scene.
#[derive(Default)]
pub struct SourceMap {
    files: Vec<SourceFile>,
}

impl SourceMap {
    /// Adds a file's bytes. Files larger than 4 GiB cannot be addressed by a span.
    pub fn add(&mut self, path: &Path, name: String, text: FileBytes) -> Result<FileId, String> {
        if text.len() >= u32::MAX as usize {
            return Err(format!("{name}: file is larger than 4 GiB"));
        }
        let id = FileId(self.files.len() as u32);
        self.files.push(SourceFile { path: path.to_path_buf(), name, text: Arc::new(text), lines: Mutex::default() });
        Ok(id)
    }

    pub fn file(&self, id: FileId) -> &SourceFile {
        &self.files[id.0 as usize]
    }

    /// The text a span covers (lossy UTF-8).
    pub fn snippet(&self, span: Span) -> String {
        let f = self.file(span.file);
        let end = (span.end as usize).min(f.text.len());
        let start = (span.start as usize).min(end);
        String::from_utf8_lossy(&f.text[start..end]).into_owned()
    }

    /// 1-based line and column (in characters) of the span's start.
    pub fn location(&self, span: Span) -> Location {
        let f = self.file(span.file);
        let offset = (span.start as usize).min(f.text.len());
        let (line, column) = f.line_and_column(offset);
        Location { file: f.name.clone(), line: line as u32, column: column as u32 }
    }

    /// The full source line holding the span's start, without its line break.
    pub fn line_text(&self, span: Span) -> String {
        let f = self.file(span.file);
        let (_, start) = f.line_of((span.start as usize).min(f.text.len()));
        let end = f.text[start..].iter().position(|&c| c == b'\n' || c == b'\r').map_or(f.text.len(), |e| start + e);
        String::from_utf8_lossy(&f.text[start..end]).into_owned()
    }
}

impl SourceFile {
    /// [`LineStarts::line_of`] for this file's text.
    fn line_of(&self, offset: usize) -> (usize, usize) {
        // Each scan's lines are added at once, so even a poisoned lock holds a whole
        // table.
        let mut lines = self.lines.lock().unwrap_or_else(|e| e.into_inner());
        lines.line_of(&self.text, offset)
    }

    /// The 1-based line and column (in characters of the lossy UTF-8 text) of `offset`.
    fn line_and_column(&self, offset: usize) -> (usize, usize) {
        let mut lines = self.lines.lock().unwrap_or_else(|e| e.into_inner());
        let (line, line_start) = lines.line_of(&self.text, offset);
        let (from, column) = match lines.column_at {
            Some((o, c)) if (line_start..=offset).contains(&o) => (o, c),
            _ => (line_start, 1),
        };
        let column = column + lossy_chars(&self.text[from..offset]);
        // An ASCII byte ends every chunk of the lossy text, valid or not, so counting
        // on from just after one counts what counting from the line's start would.
        if offset == line_start || self.text[offset - 1].is_ascii() {
            lines.column_at = Some((offset, column));
        }
        (line, column)
    }
}

/// How many characters `String::from_utf8_lossy(bytes)` has, without making it: each
/// run of invalid bytes is one replacement character.
fn lossy_chars(bytes: &[u8]) -> usize {
    bytes.utf8_chunks().map(|c| c.valid().chars().count() + usize::from(!c.invalid().is_empty())).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based_and_handle_crlf() {
        let mut map = SourceMap::default();
        let Ok(id) = map.add(Path::new("a.pbrt"), "a.pbrt".into(), b"ab\r\ncd\ref\n  g".to_vec().into()) else {
            panic!("small file rejected")
        };
        let at = |o: usize| {
            let l = map.location(Span::new(id, o, o));
            (l.line, l.column)
        };
        assert_eq!(at(0), (1, 1));
        assert_eq!(at(4), (2, 1));
        assert_eq!(at(7), (3, 1));
        assert_eq!(at(12), (4, 3));
        assert_eq!(map.line_text(Span::new(id, 12, 13)), "  g");
    }

    /// Columns counted on from an earlier message's are those counted from the line's
    /// start, over valid and invalid UTF-8 alike, in any order of offsets.
    #[test]
    fn columns_counted_on_are_those_of_the_lossy_line() {
        let mut rng = crate::sampling::Rng::new(9);
        let bytes = [b'a', b' ', b'\n', 0xc3, 0xa9, 0xe2, 0x82, 0xff, b'"'];
        let text: Vec<u8> = (0..4000).map(|_| bytes[(rng.uniform() * 9.0) as usize % 9]).collect();
        let mut map = SourceMap::default();
        let Ok(id) = map.add(Path::new("a.pbrt"), "a.pbrt".into(), text.clone().into()) else { panic!("rejected") };
        let mut offsets: Vec<usize> = (0..3000).map(|_| (rng.uniform() * 4001.0) as usize % 4001).collect();
        offsets[..1500].sort();
        for o in offsets {
            let start = text[..o].iter().rposition(|&c| c == b'\n').map_or(0, |i| i + 1);
            let column = String::from_utf8_lossy(&text[start..o]).chars().count() + 1;
            assert_eq!(map.location(Span::new(id, o, o)).column as usize, column, "offset {o}");
        }
    }

    /// Lines found as far as each message needs, asked for in any order, are those of
    /// one scan of the whole text (a CR at the end of one scan and its LF at the start
    /// of the next end one line, not two).
    #[test]
    fn lines_found_piece_by_piece_are_those_of_one_whole_scan() {
        let mut rng = crate::sampling::Rng::new(5);
        let text: Vec<u8> = (0..3000).map(|_| [b'a', b'\n', b'\r', b'b'][(rng.uniform() * 4.0) as usize % 4]).collect();
        let mut starts = vec![0];
        for (i, &c) in text.iter().enumerate() {
            if c == b'\n' || (c == b'\r' && text.get(i + 1) != Some(&b'\n')) {
                starts.push(i + 1);
            }
        }
        let whole = |o: usize| {
            let line = starts.iter().filter(|&&s| s <= o).count();
            (line as u32, (o - starts[line - 1] + 1) as u32)
        };
        let mut map = SourceMap::default();
        let Ok(id) = map.add(Path::new("a.pbrt"), "a.pbrt".into(), text.clone().into()) else { panic!("rejected") };
        for _ in 0..2000 {
            let o = (rng.uniform() * 3001.0) as usize % 3001;
            let l = map.location(Span::new(id, o, o));
            assert_eq!((l.line, l.column), whole(o), "offset {o}");
        }
    }
}
