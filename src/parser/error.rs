//! Errors and warnings with source locations.
//!
//! Messages read `file:line:col: error: message` (gcc and pbrt style); on a terminal the
//! source line and a caret follow. A [`Diagnostic`] holds a [`Span`] until it is
//! printed or resolved into a [`Located`] entry for `check --json`.

use super::source::{Location, SourceMap, Span};
use std::fmt::Write as _;

/// How bad a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    Warning,
    Error,
}

/// A message tied to a place in a source file (or to no place, for whole-file problems).
#[derive(Clone, Debug)]
pub struct Diagnostic {
    pub severity: Severity,
    pub span: Option<Span>,
    pub message: String,
}

impl Diagnostic {
    pub fn error(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Error, span: Some(span), message: message.into() }
    }
    pub fn warning(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Warning, span: Some(span), message: message.into() }
    }
}

/// A fatal problem while loading a scene: the first error, resolved for printing.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.one_line())]
pub struct LoadError {
    /// `None` when the problem is not inside a file (e.g. the top-level file is missing).
    pub location: Option<Location>,
    /// The file name used when there is no location.
    pub file: String,
    pub message: String,
    /// The offending source line and caret column, for terminals.
    pub source_line: Option<(String, u32)>,
}

impl LoadError {
    /// A whole-file problem (no line and column).
    pub fn in_file(file: impl Into<String>, message: impl Into<String>) -> LoadError {
        LoadError { location: None, file: file.into(), message: message.into(), source_line: None }
    }

    /// A problem with a whole file, reported at its first line and column.
    pub fn at_start(file: impl Into<String>, message: impl Into<String>) -> LoadError {
        let file = file.into();
        let location = Location { file: file.clone(), line: 1, column: 1 };
        LoadError { location: Some(location), file, message: message.into(), source_line: None }
    }

    /// Resolves a diagnostic's span now that it is about to be printed.
    pub fn from_diagnostic(sources: &SourceMap, d: &Diagnostic) -> LoadError {
        match d.span {
            Some(span) => {
                let location = sources.location(span);
                let line = sources.line_text(span);
                LoadError {
                    file: location.file.clone(),
                    source_line: Some((line, location.column)),
                    location: Some(location),
                    message: d.message.clone(),
                }
            }
            None => LoadError::in_file("<scene>", d.message.clone()),
        }
    }

    /// `file:line:col: error: message`.
    pub fn one_line(&self) -> String {
        match &self.location {
            Some(l) => format!("{l}: error: {}", self.message),
            None => format!("{}: error: {}", self.file, self.message),
        }
    }

    /// The one-line form plus the source line and a caret under the column.
    pub fn with_source(&self) -> String {
        let mut s = self.one_line();
        if let Some((line, col)) = &self.source_line {
            let pad: String =
                line.chars().take(*col as usize - 1).map(|c| if c == '\t' { '\t' } else { ' ' }).collect();
            let _ = write!(s, "\n  {line}\n  {pad}^");
        }
        s
    }
}

/// A warning resolved to its location, as listed by `check --json`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Located {
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub message: String,
}

impl Located {
    pub fn resolve(sources: &SourceMap, span: Option<Span>, message: &str) -> Located {
        match span {
            Some(span) => {
                let l = sources.location(span);
                Located { file: l.file, line: l.line, column: l.column, message: message.to_string() }
            }
            None => Located { file: String::new(), line: 0, column: 0, message: message.to_string() },
        }
    }
}

impl std::fmt::Display for Located {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line == 0 {
            write!(f, "warning: {}", self.message)
        } else {
            write!(f, "{}:{}:{}: warning: {}", self.file, self.line, self.column, self.message)
        }
    }
}
