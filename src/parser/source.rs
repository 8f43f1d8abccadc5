//! Source files and byte spans.
//!
//! Every token and parameter carries a [`Span`] (file id + byte range). Line and column
//! are computed only when a message is printed, from a line-start table built lazily
//! per file (binary search), so parsing a 50 MB mesh never counts lines.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use crate::limits::FileBytes;

/// Index of a file in a [`SourceMap`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
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
    line_starts: OnceLock<Vec<u32>>,
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
        self.files.push(SourceFile {
            path: path.to_path_buf(),
            name,
            text: Arc::new(text),
            line_starts: OnceLock::new(),
        });
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
        let starts = f.line_starts.get_or_init(|| line_starts(&f.text));
        let offset = (span.start as usize).min(f.text.len());
        let line = starts.partition_point(|&s| s as usize <= offset).max(1);
        let line_start = starts[line - 1] as usize;
        let column = String::from_utf8_lossy(&f.text[line_start..offset]).chars().count() + 1;
        Location { file: f.name.clone(), line: line as u32, column: column as u32 }
    }

    /// The full source line holding the span's start, without its line break.
    pub fn line_text(&self, span: Span) -> String {
        let f = self.file(span.file);
        let starts = f.line_starts.get_or_init(|| line_starts(&f.text));
        let offset = (span.start as usize).min(f.text.len());
        let line = starts.partition_point(|&s| s as usize <= offset).max(1);
        let start = starts[line - 1] as usize;
        let end = f.text[start..].iter().position(|&c| c == b'\n' || c == b'\r').map_or(f.text.len(), |e| start + e);
        String::from_utf8_lossy(&f.text[start..end]).into_owned()
    }
}

fn line_starts(text: &[u8]) -> Vec<u32> {
    let mut starts = vec![0u32];
    for i in memchr::memchr2_iter(b'\n', b'\r', text) {
        // CR alone, LF alone and CR LF each end one line.
        if text[i] == b'\n' || text.get(i + 1) != Some(&b'\n') {
            starts.push(i as u32 + 1);
        }
    }
    starts
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
}
