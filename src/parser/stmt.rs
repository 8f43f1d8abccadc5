//! Statements: every directive of pbrt-v3 and pbrt-v4, read from a token stream with a
//! file stack.
//!
//! ```text
//! LookAt 0 5 -10  0 0 0  0 1 0          Camera "perspective" "float fov" 45
//! WorldBegin
//! AttributeBegin
//!   Translate 0 1 0   Material "matte"   Shape "sphere" "float radius" 1
//! AttributeEnd
//! Include "geometry.pbrt"  # token level: a parameter list may run on past its end
//! Import "lights.pbrt"     # v4: a copy of the graphics state; nothing flows back
//! ```
//! `Include` pushes the file's tokens onto the stream, so the last statement of an
//! included file can take parameters from the including file (pbrt-v3-scenes
//! cloud/f15-4a relies on this). Paths are relative to the top-level file's directory.
//! Files ending in `.gz` (or starting with the gzip magic) are decompressed.

use super::Syntax;
use super::error::Diagnostic;
use super::lexer::{Lexer, TokenKind, decode_string};
use super::numbers::{parallel_numbers, parse_f32, parse_f64, parse_int};
use super::params::{Param, ParamList, ParamType, Values};
use super::quick;
use super::source::{FileId, SourceMap, Span};
use crate::limits::{FileBytes, Files, Limits};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A directive and its arguments. The large arguments of rare directives (a 4 × 4
/// matrix, `LookAt`, a texture's class) are boxed: a statement is moved from the reader
/// to the builder several times, and a file of a million instances has four million
/// of them (at 152 bytes a statement, those copies were a tenth of reading it).
#[derive(Debug)]
pub enum StmtKind {
    Identity,
    Translate([f64; 3]),
    Scale([f64; 3]),
    Rotate([f64; 4]),
    LookAt(Box<[f64; 9]>),
    CoordinateSystem(String),
    CoordSysTransform(String),
    Transform(Box<[f64; 16]>),
    ConcatTransform(Box<[f64; 16]>),
    TransformTimes([f64; 2]),
    ActiveTransform(ActiveTransform),
    ReverseOrientation,
    Option {
        name: String,
        value: String,
    },
    ColorSpace(String),
    Camera(Entity),
    Sampler(Entity),
    Film(Entity),
    PixelFilter(Entity),
    Integrator(Entity),
    Accelerator(Entity),
    MakeNamedMedium(Entity),
    MediumInterface {
        inside: String,
        outside: String,
    },
    WorldBegin,
    WorldEnd,
    AttributeBegin,
    AttributeEnd,
    TransformBegin,
    TransformEnd,
    Attribute(Entity),
    Shape(Entity),
    ObjectBegin(String),
    ObjectEnd,
    ObjectInstance(String),
    LightSource(Entity),
    AreaLightSource(Entity),
    Material(Entity),
    MakeNamedMaterial(Entity),
    NamedMaterial(String),
    Texture {
        name: String,
        ty: String,
        class: Box<Entity>,
    },
    /// `Import "file"`: the statements that follow, up to the matching `ImportEnd`,
    /// come from the imported file.
    ImportBegin(String),
    ImportEnd,
}

impl StmtKind {
    /// The parameter list of a statement that has one.
    pub fn params_mut(&mut self) -> Option<&mut ParamList> {
        use StmtKind as K;
        match self {
            K::Camera(e)
            | K::Sampler(e)
            | K::Film(e)
            | K::PixelFilter(e)
            | K::Integrator(e)
            | K::Accelerator(e)
            | K::MakeNamedMedium(e)
            | K::Attribute(e)
            | K::Shape(e)
            | K::LightSource(e)
            | K::AreaLightSource(e)
            | K::Material(e)
            | K::MakeNamedMaterial(e) => Some(&mut e.params),
            K::Texture { class, .. } => Some(&mut class.params),
            _ => None,
        }
    }
}

/// `ActiveTransform` argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActiveTransform {
    StartTime,
    EndTime,
    All,
}

/// A quoted type or name followed by a parameter list (`Shape "sphere" ...`).
#[derive(Debug)]
pub struct Entity {
    pub name: String,
    pub name_span: Span,
    pub params: ParamList,
}

impl Entity {
    /// An entity with no parameters and no location (defaults for missing statements).
    pub fn default_named(name: &str) -> Entity {
        Entity { name: name.to_string(), name_span: Span::default(), params: ParamList::default() }
    }
}

/// One statement with the span of its directive keyword.
#[derive(Debug)]
pub struct Stmt {
    pub kind: StmtKind,
    pub span: Span,
}

const _: () = assert!(std::mem::size_of::<Stmt>() <= 88, "a statement stays small: box large arguments");

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TokKind {
    Word,
    Str,
    LBracket,
    RBracket,
    /// The end of an `Import`ed file: ends any parameter list, like a directive would.
    ImportEnd,
}

#[derive(Clone, Copy, Debug)]
struct Tok {
    kind: TokKind,
    span: Span,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum FrameKind {
    Top,
    Include,
    Import,
}

struct Frame {
    file: FileId,
    text: Arc<FileBytes>,
    pos: usize,
    kind: FrameKind,
}

/// Reads statements from a top-level file and everything it includes.
pub struct StatementReader {
    pub sources: SourceMap,
    base_dir: PathBuf,
    stack: Vec<Frame>,
    peeked: Option<Tok>,
    /// Warnings found while reading (non-integer integers, v3 bools that are not
    /// "true"/"false", ...).
    pub warnings: Vec<Diagnostic>,
    /// The first version-specific construct seen, if any.
    pub evidence: Option<(Syntax, Span, String)>,
    /// What the load may read, and the list of what it has read.
    pub files: Files,
    /// Included files served from memory by name (see `LoadOptions::in_memory`).
    pub in_memory: std::collections::HashMap<String, Arc<[u8]>>,
    /// Whether plain statements are read by [`quick`] (tests compare with `false`).
    quick: bool,
}

/// Reads a scene file's bytes within the limits, decompressing gzip and rejecting UTF-16.
pub fn read_scene_bytes(path: &Path, files: &Files) -> Result<FileBytes, String> {
    let bytes = files.read(path)?;
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(format!("\"{}\" is UTF-16; pbrt scene files must be ASCII or UTF-8", path.display()));
    }
    if bytes.starts_with(&[0xef, 0xbb, 0xbf]) {
        let mut bytes = bytes.into_vec();
        bytes[..3].fill(b' '); // a UTF-8 byte-order mark: keep offsets, drop the mark
        return Ok(bytes.into());
    }
    Ok(bytes)
}

/// The statement of keyword `kw` when [`quick`] can read its arguments from `r`. None
/// of these is version-specific, so none notes evidence.
#[inline(always)]
fn quick_kind(kw: &[u8], r: &mut quick::Bytes) -> Option<StmtKind> {
    use StmtKind as K;
    Some(match kw {
        b"AttributeBegin" => K::AttributeBegin,
        b"AttributeEnd" => K::AttributeEnd,
        b"Identity" => K::Identity,
        b"ReverseOrientation" => K::ReverseOrientation,
        b"Translate" => K::Translate(r.numbers()?),
        b"Scale" => K::Scale(r.numbers()?),
        b"Rotate" => K::Rotate(r.numbers()?),
        b"LookAt" => K::LookAt(Box::new(r.numbers()?)),
        b"Transform" => K::Transform(Box::new(r.bracketed()?)),
        b"ConcatTransform" => K::ConcatTransform(Box::new(r.bracketed()?)),
        b"ObjectInstance" => K::ObjectInstance(r.string()?),
        b"NamedMaterial" => K::NamedMaterial(r.string()?),
        b"CoordSysTransform" => K::CoordSysTransform(r.string()?),
        _ => return None,
    })
}

/// Directives that only pbrt-v3 has, and only pbrt-v4: reading one decides the syntax.
const V3_ONLY: [&str; 3] = ["WorldEnd", "TransformBegin", "TransformEnd"];
const V4_ONLY: [&str; 4] = ["Option", "ColorSpace", "Attribute", "Import"];

impl StatementReader {
    /// Starts reading `text` as the top-level file `path` (the base for relative paths).
    pub fn new(path: &Path, text: FileBytes, files: Files) -> Result<StatementReader, String> {
        let mut sources = SourceMap::default();
        let file = sources.add(path, path.display().to_string(), text)?;
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let text = sources.file(file).text.clone();
        Ok(StatementReader {
            sources,
            base_dir,
            stack: vec![Frame { file, text, pos: 0, kind: FrameKind::Top }],
            peeked: None,
            warnings: Vec::new(),
            evidence: None,
            files,
            in_memory: Default::default(),
            quick: true,
        })
    }

    /// How often `ObjectInstance` occurs in the rest of the file being read (comments
    /// and strings too): room to reserve, at least the instances that follow there.
    pub fn instance_words_ahead(&self) -> usize {
        let Some(frame) = self.stack.last() else { return 0 };
        let rest = frame.text.get(frame.pos..).unwrap_or_default();
        memchr::memmem::find_iter(rest, b"ObjectInstance").count()
    }

    /// Resolves a file name from the scene against the top-level file's directory
    /// (pbrt-v4 falls back to the name as written when the joined path does not exist).
    /// The top-level file's directory: the base of relative file names.
    pub fn base_dir(&self) -> &Path {
        &self.base_dir
    }

    pub fn resolve_path(&self, name: &str) -> PathBuf {
        resolve_relative(&self.base_dir, name)
    }

    /// Records the first piece of version-specific syntax.
    pub fn note_evidence(&mut self, syntax: Syntax, span: Span, what: impl Into<String>) {
        if self.evidence.is_none() {
            self.evidence = Some((syntax, span, what.into()));
        }
    }

    pub fn text(&self, span: Span) -> &[u8] {
        &self.sources.file(span.file).text[span.start as usize..span.end as usize]
    }

    fn word(&self, t: Tok) -> String {
        String::from_utf8_lossy(self.text(t.span)).into_owned()
    }

    fn lex(&mut self) -> Result<Option<Tok>, Diagnostic> {
        while let Some(frame) = self.stack.last_mut() {
            let mut lexer = Lexer::at(&frame.text, frame.pos);
            let next = lexer.next_significant();
            frame.pos = lexer.position();
            let file = frame.file;
            match next {
                Err(e) => return Err(Diagnostic::error(Span::new(file, e.offset, e.offset + 1), e.message)),
                Ok(Some(t)) => {
                    let kind = match t.kind {
                        TokenKind::Word | TokenKind::Comment => TokKind::Word,
                        TokenKind::Str => TokKind::Str,
                        TokenKind::LBracket => TokKind::LBracket,
                        TokenKind::RBracket => TokKind::RBracket,
                    };
                    let span = Span { file, start: t.start, end: t.end };
                    return Ok(Some(Tok { kind, span }));
                }
                Ok(None) => {
                    let ended = self.stack.pop().map(|f| (f.kind, f.file, f.text.len()));
                    if let Some((FrameKind::Import, file, len)) = ended {
                        let span = Span::new(file, len, len);
                        return Ok(Some(Tok { kind: TokKind::ImportEnd, span }));
                    }
                }
            }
        }
        Ok(None)
    }

    fn peek(&mut self) -> Result<Option<Tok>, Diagnostic> {
        if self.peeked.is_none() {
            self.peeked = self.lex()?;
        }
        Ok(self.peeked)
    }

    fn next(&mut self) -> Result<Option<Tok>, Diagnostic> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.lex(),
        }
    }

    /// The span just past the last token, for "premature end of file" messages.
    fn end_span(&self, after: Span) -> Span {
        Span { file: after.file, start: after.end, end: after.end }
    }

    /// The next token, or "premature end of file: expected {what}" (`what` is formatted
    /// only then: this runs for every number and string of a scene).
    fn require(&mut self, after: Span, what: impl std::fmt::Display) -> Result<Tok, Diagnostic> {
        self.next()?
            .ok_or_else(|| Diagnostic::error(self.end_span(after), format!("premature end of file: expected {what}")))
    }

    fn number(&mut self, after: Span, directive: &str) -> Result<(f64, Span), Diagnostic> {
        let t = self.require(after, format_args!("a number for {directive}"))?;
        let text = self.text(t.span);
        match (t.kind, parse_f64(text)) {
            (TokKind::Word, Some(v)) => Ok((v, t.span)),
            _ => Err(Diagnostic::error(t.span, format!("{directive}: expected a number, found '{}'", self.word(t)))),
        }
    }

    fn numbers<const N: usize>(&mut self, kw: Span, directive: &str) -> Result<[f64; N], Diagnostic> {
        let mut out = [0.0; N];
        let mut last = kw;
        for v in &mut out {
            (*v, last) = self.number(last, directive)?;
        }
        Ok(out)
    }

    fn bracketed<const N: usize>(&mut self, kw: Span, directive: &str) -> Result<[f64; N], Diagnostic> {
        let open = self.require(kw, "'['")?;
        if open.kind != TokKind::LBracket {
            return Err(Diagnostic::error(open.span, format!("{directive}: expected '[' and {N} numbers")));
        }
        let values = self.numbers::<N>(open.span, directive)?;
        let close = self.require(open.span, "']'")?;
        if close.kind != TokKind::RBracket {
            return Err(Diagnostic::error(
                close.span,
                format!("{directive}: expected ']' after {N} numbers, found '{}'", self.word(close)),
            ));
        }
        Ok(values)
    }

    fn string(&mut self, after: Span, directive: &str) -> Result<(String, Span), Diagnostic> {
        let t = self.require(after, format_args!("a quoted string for {directive}"))?;
        if t.kind != TokKind::Str {
            return Err(Diagnostic::error(
                t.span,
                format!("{directive}: expected a quoted string, found '{}'", self.word(t)),
            ));
        }
        Ok((decode_string(self.text(t.span)), t.span))
    }

    fn entity(&mut self, kw: Span, directive: &str) -> Result<Entity, Diagnostic> {
        let (name, name_span) = self.string(kw, directive)?;
        let params = self.params()?;
        Ok(Entity { name, name_span, params })
    }

    /// Reads the next statement; `Ok(None)` at the end of the top-level file.
    pub fn next_stmt(&mut self) -> Result<Option<Stmt>, Diagnostic> {
        if let Some(stmt) = self.quick_stmt() {
            return Ok(Some(stmt));
        }
        loop {
            let Some(t) = self.next()? else { return Ok(None) };
            let kind = match t.kind {
                TokKind::ImportEnd => StmtKind::ImportEnd,
                TokKind::Word => match self.directive(t)? {
                    Some(kind) => kind,
                    None => continue, // Include: its statements follow
                },
                _ => {
                    return Err(Diagnostic::error(t.span, format!("expected a directive, found '{}'", self.word(t))));
                }
            };
            return Ok(Some(Stmt { kind, span: t.span }));
        }
    }

    /// The next statement when it is one of the plain ones [`quick`] reads (from the
    /// keyword already peeked, if any); otherwise nothing is consumed.
    #[inline(always)]
    fn quick_stmt(&mut self) -> Option<Stmt> {
        if !self.quick {
            return None;
        }
        let frame = self.stack.last_mut()?;
        let mut r = quick::Bytes::new(&frame.text, frame.pos);
        let kw = match self.peeked {
            None => r.word()?,
            Some(t) if t.kind == TokKind::Word && t.span.file == frame.file && t.span.end as usize == frame.pos => {
                (t.span.start as usize, t.span.end as usize)
            }
            Some(_) => return None,
        };
        let kind = quick_kind(r.text(kw), &mut r)?;
        (frame.pos, self.peeked) = (r.at(), None);
        Some(Stmt { kind, span: Span::new(frame.file, kw.0, kw.1) })
    }

    fn directive(&mut self, t: Tok) -> Result<Option<StmtKind>, Diagnostic> {
        use StmtKind as K;
        let kw = t.span;
        // The keyword is copied out (the statement's reading moves the reader on): no
        // directive is longer than the buffer or anything but ASCII; a longer word is
        // read as "" and reported as unknown below.
        let mut buf = [0u8; 24];
        let text = self.text(kw);
        let word = match buf.get_mut(..text.len()) {
            Some(b) => {
                b.copy_from_slice(text);
                std::str::from_utf8(b).unwrap_or_default()
            }
            None => "",
        };
        if self.evidence.is_none() && V3_ONLY.contains(&word) {
            self.note_evidence(Syntax::V3, kw, format!("{word} (v3 only)"));
        } else if self.evidence.is_none() && V4_ONLY.contains(&word) {
            self.note_evidence(Syntax::V4, kw, format!("{word} (v4 only)"));
        }
        Ok(Some(match word {
            "Identity" => K::Identity,
            "Translate" => K::Translate(self.numbers(kw, "Translate")?),
            "Scale" => K::Scale(self.numbers(kw, "Scale")?),
            "Rotate" => K::Rotate(self.numbers(kw, "Rotate")?),
            "LookAt" => K::LookAt(Box::new(self.numbers(kw, "LookAt")?)),
            "CoordinateSystem" => K::CoordinateSystem(self.string(kw, "CoordinateSystem")?.0),
            "CoordSysTransform" => K::CoordSysTransform(self.string(kw, "CoordSysTransform")?.0),
            "Transform" => K::Transform(Box::new(self.bracketed(kw, "Transform")?)),
            "ConcatTransform" => K::ConcatTransform(Box::new(self.bracketed(kw, "ConcatTransform")?)),
            "TransformTimes" => K::TransformTimes(self.numbers(kw, "TransformTimes")?),
            "ActiveTransform" => K::ActiveTransform(self.active_transform(kw)?),
            "ReverseOrientation" => K::ReverseOrientation,
            "Option" => self.option(kw)?,
            "ColorSpace" => K::ColorSpace(self.string(kw, "ColorSpace")?.0),
            "Camera" => K::Camera(self.entity(kw, "Camera")?),
            "Sampler" => K::Sampler(self.entity(kw, "Sampler")?),
            "Film" => K::Film(self.entity(kw, "Film")?),
            "PixelFilter" => K::PixelFilter(self.entity(kw, "PixelFilter")?),
            "Integrator" => K::Integrator(self.entity(kw, "Integrator")?),
            "Accelerator" => K::Accelerator(self.entity(kw, "Accelerator")?),
            "MakeNamedMedium" => K::MakeNamedMedium(self.entity(kw, "MakeNamedMedium")?),
            "MediumInterface" => self.medium_interface(kw)?,
            "WorldBegin" => K::WorldBegin,
            "WorldEnd" => K::WorldEnd,
            "AttributeBegin" => K::AttributeBegin,
            "AttributeEnd" => K::AttributeEnd,
            "TransformBegin" => K::TransformBegin,
            "TransformEnd" => K::TransformEnd,
            "Attribute" => K::Attribute(self.entity(kw, "Attribute")?),
            "Shape" => K::Shape(self.entity(kw, "Shape")?),
            "ObjectBegin" => K::ObjectBegin(self.string(kw, "ObjectBegin")?.0),
            "ObjectEnd" => K::ObjectEnd,
            "ObjectInstance" => K::ObjectInstance(self.string(kw, "ObjectInstance")?.0),
            "LightSource" => K::LightSource(self.entity(kw, "LightSource")?),
            "AreaLightSource" => K::AreaLightSource(self.entity(kw, "AreaLightSource")?),
            "Material" => K::Material(self.entity(kw, "Material")?),
            "MakeNamedMaterial" => K::MakeNamedMaterial(self.entity(kw, "MakeNamedMaterial")?),
            "NamedMaterial" => K::NamedMaterial(self.string(kw, "NamedMaterial")?.0),
            "Texture" => self.texture(kw)?,
            "Include" => return self.include(kw, FrameKind::Include).map(|_| None),
            "Import" => K::ImportBegin(self.include(kw, FrameKind::Import)?),
            _ => return Err(Diagnostic::error(kw, format!("unknown directive '{}'", self.word(t)))),
        }))
    }

    /// `Texture "name" "type" "class" params...`
    fn texture(&mut self, kw: Span) -> Result<StmtKind, Diagnostic> {
        let (name, _) = self.string(kw, "Texture")?;
        let (ty, ty_span) = self.string(kw, "Texture")?;
        let class = self.entity(ty_span, "Texture")?;
        Ok(StmtKind::Texture { name, ty, class: Box::new(class) })
    }

    /// `Include "file"` or `Import "file"`: reading goes on in that file; its name.
    fn include(&mut self, kw: Span, kind: FrameKind) -> Result<String, Diagnostic> {
        let what = if kind == FrameKind::Include { "Include" } else { "Import" };
        let (name, span) = self.string(kw, what)?;
        match self.push_file(&name, span, kind) {
            // pbrt-v3 reports an Include it cannot open and reads on (pbrt-v4 stops):
            // so does a file already known as v3.
            Err(e)
                if crate::limits::is_unreadable(&e.message)
                    && self.evidence.as_ref().is_some_and(|e| e.0 == Syntax::V3) =>
            {
                let msg = format!("{}; the Include is skipped, as pbrt-v3 skips it", e.message);
                self.warnings.push(Diagnostic::warning(span, msg));
            }
            done => done?,
        }
        Ok(name)
    }

    fn active_transform(&mut self, kw: Span) -> Result<ActiveTransform, Diagnostic> {
        let t = self.require(kw, "StartTime, EndTime or All")?;
        match (t.kind, self.text(t.span)) {
            (TokKind::Word, b"StartTime") => Ok(ActiveTransform::StartTime),
            (TokKind::Word, b"EndTime") => Ok(ActiveTransform::EndTime),
            (TokKind::Word, b"All") => Ok(ActiveTransform::All),
            _ => Err(Diagnostic::error(
                t.span,
                format!("ActiveTransform: expected StartTime, EndTime or All, found '{}'", self.word(t)),
            )),
        }
    }

    /// `Option "name" value` (v4); `Option "bool name" value` is accepted too.
    fn option(&mut self, kw: Span) -> Result<StmtKind, Diagnostic> {
        let (name, name_span) = self.string(kw, "Option")?;
        let name = name.split_whitespace().last().unwrap_or_default().to_string();
        let t = self.require(name_span, "a value for Option")?;
        let value = match t.kind {
            TokKind::Str => decode_string(self.text(t.span)),
            TokKind::Word => self.word(t),
            _ => return Err(Diagnostic::error(t.span, "Option: expected one value")),
        };
        Ok(StmtKind::Option { name, value })
    }

    fn medium_interface(&mut self, kw: Span) -> Result<StmtKind, Diagnostic> {
        let (inside, _) = self.string(kw, "MediumInterface")?;
        let outside = match self.peek()? {
            Some(t) if t.kind == TokKind::Str => {
                self.next()?;
                decode_string(self.text(t.span))
            }
            _ => inside.clone(),
        };
        Ok(StmtKind::MediumInterface { inside, outside })
    }

    fn push_file(&mut self, name: &str, span: Span, kind: FrameKind) -> Result<(), Diagnostic> {
        let depth = self.files.limits.include_depth;
        if self.stack.len() as u64 > depth {
            let what = format!("Include/Import nesting ({} files deep; an Include cycle?)", self.stack.len());
            return Err(Diagnostic::error(span, Limits::over(what, "include-depth", depth)));
        }
        let path = self.resolve_path(name);
        let bytes = match self.in_memory.get(name) {
            Some(b) => b.to_vec().into(),
            None => read_scene_bytes(&path, &self.files).map_err(|e| Diagnostic::error(span, e))?,
        };
        let file =
            self.sources.add(&path, path.display().to_string(), bytes).map_err(|e| Diagnostic::error(span, e))?;
        let text = self.sources.file(file).text.clone();
        // A peeked token belongs to the including file; reading continues after it.
        debug_assert!(self.peeked.is_none());
        self.stack.push(Frame { file, text, pos: 0, kind });
        Ok(())
    }

    fn params(&mut self) -> Result<ParamList, Diagnostic> {
        let mut list = ParamList::default();
        while let Some(t) = self.peek()? {
            if t.kind != TokKind::Str {
                break;
            }
            self.next()?;
            list.params.push(self.param(t)?);
        }
        Ok(list)
    }

    fn param(&mut self, decl: Tok) -> Result<Param, Diagnostic> {
        let text = decode_string(self.text(decl.span));
        let mut words = text.split_ascii_whitespace();
        let (Some(type_name), Some(name), None) = (words.next(), words.next(), words.next()) else {
            return Err(Diagnostic::error(
                decl.span,
                format!(
                    "parameter declaration \"{text}\" must be a type and a name, like \"float radius\" (or a directive keyword is missing)"
                ),
            ));
        };
        let Some((ty, evidence)) = ParamType::from_keyword(type_name) else {
            return Err(Diagnostic::error(decl.span, format!("unknown parameter type \"{type_name}\"")));
        };
        if let Some(s) = evidence {
            self.note_evidence(s, decl.span, format!("parameter type \"{type_name}\""));
        }
        let first = self.require(decl.span, format_args!("a value for \"{text}\""))?;
        let mut sink = ValueSink::new(ty);
        let value_span = match first.kind {
            TokKind::LBracket => loop {
                if let Some(close) = self.fast_numbers(&mut sink) {
                    break first.span.to(close);
                }
                let t = self
                    .next()?
                    .ok_or_else(|| Diagnostic::error(first.span, "premature end of file: '[' is never closed"))?;
                match t.kind {
                    TokKind::RBracket => break first.span.to(t.span),
                    TokKind::Word | TokKind::Str => self.push_value(&mut sink, t, &text)?,
                    _ => return Err(Diagnostic::error(t.span, "'[' is never closed before this")),
                }
            },
            TokKind::Word | TokKind::Str => {
                self.push_value(&mut sink, first, &text)?;
                first.span
            }
            _ => {
                return Err(Diagnostic::error(first.span, format!("expected a value for \"{text}\"")));
            }
        };
        if ty == ParamType::Blackbody {
            let n = sink.len();
            let s = if n == 2 { Syntax::V3 } else { Syntax::V4 };
            self.note_evidence(s, value_span, format!("blackbody with {n} value(s)"));
        }
        let values = sink.finish();
        Ok(Param::new(ty, type_name.to_string(), name.to_string(), values, decl.span, value_span))
    }

    /// The hot loop for big meshes: reads plain numbers of a bracketed list straight
    /// from the current file. Returns the closing bracket's span, or `None` after
    /// stopping (unconsumed) at anything else (a string, a bad number, a file end),
    /// which the general path then handles with its messages.
    fn fast_numbers(&mut self, sink: &mut ValueSink) -> Option<Span> {
        if self.peeked.is_some() || !matches!(sink.values, Values::Floats(_) | Values::Ints(_)) {
            return None;
        }
        let frame = self.stack.last_mut()?;
        if let Some(close) = parallel_numbers(&frame.text[frame.pos..], &mut sink.values) {
            let close = frame.pos + close;
            frame.pos = close + 1;
            return Some(Span { file: frame.file, start: close as u32, end: close as u32 + 1 });
        }
        let mut lexer = Lexer::at(&frame.text, frame.pos);
        loop {
            let before = lexer.position();
            let Ok(Some(t)) = lexer.next_significant() else {
                frame.pos = before;
                return None;
            };
            let bytes = &frame.text[t.start as usize..t.end as usize];
            let pushed = match (t.kind, &mut sink.values) {
                (TokenKind::RBracket, _) => {
                    frame.pos = lexer.position();
                    return Some(Span { file: frame.file, start: t.start, end: t.end });
                }
                (TokenKind::Word, Values::Floats(v)) => parse_f32(bytes).map(|x| v.push(x)),
                (TokenKind::Word, Values::Ints(v)) => parse_int(bytes).map(|x| v.push(x)),
                _ => None,
            };
            if pushed.is_none() {
                frame.pos = before;
                return None;
            }
        }
    }

    fn push_value(&mut self, sink: &mut ValueSink, t: Tok, decl: &str) -> Result<(), Diagnostic> {
        let bytes = self.text(t.span);
        let is_str = t.kind == TokKind::Str;
        let mixed = || Diagnostic::error(t.span, format!("\"{decl}\": strings and numbers mixed in one list"));
        match (&mut sink.values, is_str) {
            (Values::Floats(v), false) => match parse_f32(bytes) {
                Some(x) => v.push(x),
                None => {
                    let msg = format!("\"{decl}\": expected a number, found '{}'", self.word(t));
                    return Err(Diagnostic::error(t.span, msg));
                }
            },
            (Values::Ints(v), false) => match parse_int(bytes) {
                Some(x) => v.push(x),
                // DEVIATION(pbrt): input leniency (no valid scene renders differently). pbrt-v4 rejects `5.0` for an
                // integer; we truncate with a warning, as pbrt-v3 does silently.
                None => match parse_f64(bytes).filter(|x| x.abs() < 2.147e9) {
                    Some(x) => {
                        v.push(x as i32);
                        if !sink.warned {
                            sink.warned = true;
                            let w = self.word(t);
                            let msg = format!("\"{decl}\": {w} is not an integer; truncated to {}", x as i32);
                            self.warnings.push(Diagnostic::warning(t.span, msg));
                        }
                    }
                    None => {
                        let msg = format!("\"{decl}\": expected an integer, found '{}'", self.word(t));
                        return Err(Diagnostic::error(t.span, msg));
                    }
                },
            },
            (Values::Bools(v), _) => {
                let raw = if is_str { decode_string(bytes) } else { self.word(t) };
                let b = match raw.as_str() {
                    "true" => true,
                    "false" => false,
                    _ if is_str => {
                        let msg = format!("\"{decl}\": value \"{raw}\" is neither \"true\" nor \"false\"; using false");
                        self.warnings.push(Diagnostic::warning(t.span, msg));
                        false
                    }
                    _ => {
                        let msg = format!("\"{decl}\": expected true or false, found '{raw}'");
                        return Err(Diagnostic::error(t.span, msg));
                    }
                };
                let syntax = if is_str { Syntax::V3 } else { Syntax::V4 };
                let what = if is_str { "quoted bool value" } else { "bare bool value" };
                self.note_evidence(syntax, t.span, what);
                v.push(b);
            }
            (Values::Strings(v), true) => v.push(decode_string(bytes)),
            (Values::Strings(v), false) if sink.ty == ParamType::Spectrum && v.is_empty() => {
                sink.values = Values::Floats(Vec::new());
                return self.push_value(sink, t, decl);
            }
            (Values::Floats(v), true) if sink.ty == ParamType::Spectrum && v.is_empty() => {
                sink.values = Values::Strings(vec![decode_string(bytes)]);
            }
            (Values::Strings(_), false) if matches!(sink.ty, ParamType::String | ParamType::Texture) => {
                let msg = format!("\"{decl}\": expected a quoted string, found '{}'", self.word(t));
                return Err(Diagnostic::error(t.span, msg));
            }
            _ => return Err(mixed()),
        }
        Ok(())
    }
}

/// Collects the values of one parameter in the representation its type needs.
struct ValueSink {
    ty: ParamType,
    values: Values,
    warned: bool,
}

impl ValueSink {
    fn new(ty: ParamType) -> ValueSink {
        use ParamType::*;
        let values = match ty {
            Integer => Values::Ints(Vec::new()),
            Bool => Values::Bools(Vec::new()),
            String | Texture => Values::Strings(Vec::new()),
            // Spectra start numeric; the first value decides.
            _ => Values::Floats(Vec::new()),
        };
        ValueSink { ty, values, warned: false }
    }
    fn len(&self) -> usize {
        self.values.len()
    }
    fn finish(self) -> Values {
        self.values
    }
}

/// Joins a scene-relative name to the base directory; absolute names pass through, and
/// a name whose joined path does not exist falls back to itself (as pbrt-v4 does).
pub fn resolve_relative(base: &Path, name: &str) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let joined = base.join(p);
    if !joined.exists() && p.exists() { p.to_path_buf() } else { joined }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reader(main: &str, included: &str, quick: bool) -> StatementReader {
        let files = Files::new(Limits::default());
        let mut r = StatementReader::new(Path::new("main.pbrt"), main.as_bytes().to_vec().into(), files).unwrap();
        r.in_memory.insert("inc.pbrt".into(), Arc::from(included.as_bytes()));
        r.quick = quick;
        r
    }

    /// Every statement (kind and span) or the error that ends the reading, then the
    /// warnings and the version evidence.
    fn read_all(main: &str, included: &str, quick: bool) -> Vec<String> {
        let mut r = reader(main, included, quick);
        let mut out = Vec::new();
        loop {
            match r.next_stmt() {
                Ok(Some(s)) => out.push(format!("{:?} {:?}", s.kind, s.span)),
                Ok(None) => break,
                Err(e) => {
                    out.push(format!("error {e:?}"));
                    break;
                }
            }
        }
        out.extend(r.warnings.iter().map(|w| format!("{w:?}")));
        out.push(format!("{:?}", r.evidence));
        out
    }

    #[test]
    fn the_quick_reader_takes_the_plain_statements_of_an_instancing_file() {
        let mut r = reader("AttributeBegin Translate 0.25 0 0 ObjectInstance \"o1\" AttributeEnd\n", "", true);
        for _ in 0..4 {
            assert!(r.quick_stmt().is_some());
        }
        assert!(r.quick_stmt().is_none() && r.next_stmt().unwrap().is_none());
        let mut r =
            reader("Shape \"sphere\" \"float radius\" 1 ConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1]", "", true);
        assert!(r.quick_stmt().is_none());
        assert!(matches!(r.next_stmt().unwrap().unwrap().kind, StmtKind::Shape(_)));
        // The keyword the parameter list peeked at.
        assert!(r.peeked.is_some() && matches!(r.quick_stmt().unwrap().kind, StmtKind::ConcatTransform(_)));
    }

    /// Random texts of statements, in all the forms the lexer takes, with now and then
    /// a piece of one, a comment or a file that ends in mid-statement: the quick
    /// reader must give what the general one gives.
    #[test]
    fn plain_statements_read_quickly_are_those_the_general_reader_reads() {
        let statements = [
            "Translate 1 2 3\n",
            "Translate\t-1e3 +.5 3.\n",
            "Translate 1 # c\n 2 3\n",
            "Scale 1 -2 +.5 ",
            "Rotate 90 0 1 0 ",
            "LookAt 0 0 5 0 0 0 0 1 0\n",
            "Identity ",
            "ReverseOrientation\n",
            "AttributeBegin ",
            "AttributeEnd\n",
            "ConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1] ",
            "ConcatTransform[2 0 0 0 0 2 0 0 0 0 2 0 1 2 3 1]",
            "Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 ]\n",
            "ObjectInstance \"o1\"\n",
            "ObjectInstance\"o2\"",
            "ObjectInstance \"a\\\"b\" ",
            "ObjectInstance \"\" ",
            "NamedMaterial \"m\" ",
            "CoordSysTransform \"camera\" ",
            "Shape \"sphere\" \"float radius\" 1 ",
            "Shape \"sphere\" \"float radius\" [2] ",
            "# comment\n",
            "Include \"inc.pbrt\" ",
            "WorldBegin\n",
            "TransformBegin TransformEnd ",
            "Attribute \"shape\" \"float radius\" 2 ",
            "Translate 1e400 0 00000000000000000001 ",
            "Scale 1 1 1#x ",
            "Translate 0x1 2 3 ",
            "Scale 1 # c\r2 3 ",
            "# c\rAttributeEnd ",
            "Rotate 1 0 # c",
        ];
        let noise = [
            "1 ",
            "[",
            "]",
            "\"x",
            "\"x\ny\" ",
            "nan ",
            "- ",
            "1e ",
            "Translate 1 2",
            "\t",
            "\"o\u{0}\" ",
            "Rotate 1 2 3 4]",
        ];
        let mut state = 7u64;
        let mut rnd = |n: usize| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 33) as usize % n
        };
        let text = |n: usize, rnd: &mut dyn FnMut(usize) -> usize| -> String {
            (0..n)
                .map(|_| if rnd(8) == 0 { noise[rnd(noise.len())] } else { statements[rnd(statements.len())] })
                .collect()
        };
        for _ in 0..4000 {
            let (main, included) = (text(rnd(24), &mut rnd), text(rnd(6), &mut rnd));
            let (fast, general) = (read_all(&main, &included, true), read_all(&main, &included, false));
            assert_eq!(fast, general, "main {main:?} included {included:?}");
        }
    }
}
