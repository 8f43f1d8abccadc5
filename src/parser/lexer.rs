//! The pbrt tokenizer (identical in pbrt-v3 and pbrt-v4), written with nom 8.
//!
//! ```text
//! Shape"sphere" "float radius" [1]   # a comment runs to the end of the line
//! ```
//! gives `Shape`, `"sphere"`, `"float radius"`, `[`, `1`, `]`, `# a comment ...`.
//! Whitespace is space, tab, CR and LF. `[` and `]` are tokens even when glued to other
//! text. `#` starts a comment only where a token starts. Quoted strings keep their quotes
//! in the token and accept the escapes `\b \f \n \r \t \\ \' \"`; a raw line break inside
//! one is "unterminated string", end of file inside one is "premature EOF".

use nom::branch::alt;
use nom::bytes::complete::{tag, take_till, take_while, take_while1};
use nom::combinator::{recognize, value};
use nom::error::{ErrorKind, ParseError};
use nom::{IResult, Parser};

/// What a token is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TokenKind {
    /// A bare word: directive keyword, number, `true`/`false`, `ActiveTransform` argument.
    Word,
    /// A quoted string; the token's bytes include the quotes.
    Str,
    LBracket,
    RBracket,
    /// `#` to the end of the line.
    Comment,
}

/// A token: its kind and byte range in its file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Token {
    pub kind: TokenKind,
    pub start: u32,
    pub end: u32,
}

/// A tokenizer error at a byte offset.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LexError {
    pub offset: usize,
    pub message: &'static str,
}

/// nom error type: remaining input length (so the offset can be recovered) and a message.
#[derive(Debug)]
struct Failure {
    remaining: usize,
    message: &'static str,
}

impl ParseError<&[u8]> for Failure {
    fn from_error_kind(input: &[u8], _: ErrorKind) -> Self {
        Failure { remaining: input.len(), message: "unexpected character" }
    }
    fn append(_: &[u8], _: ErrorKind, other: Self) -> Self {
        other
    }
}

type LexResult<'a, O> = IResult<&'a [u8], O, Failure>;

/// pbrt's whitespace: space, tab, CR and LF (not form feed or vertical tab).
pub(crate) fn is_space(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\r' | b'\n')
}

fn is_word_byte(c: u8) -> bool {
    !is_space(c) && c != b'"' && c != b'[' && c != b']'
}

fn whitespace(i: &[u8]) -> LexResult<'_, &[u8]> {
    take_while(is_space).parse(i)
}

fn comment(i: &[u8]) -> LexResult<'_, TokenKind> {
    value(TokenKind::Comment, recognize((tag("#"), take_till(|c| c == b'\n' || c == b'\r')))).parse(i)
}

fn bracket(i: &[u8]) -> LexResult<'_, TokenKind> {
    alt((value(TokenKind::LBracket, tag("[")), value(TokenKind::RBracket, tag("]")))).parse(i)
}

fn word(i: &[u8]) -> LexResult<'_, TokenKind> {
    value(TokenKind::Word, take_while1(is_word_byte)).parse(i)
}

/// A quoted string. Once the opening quote matched, any problem is a hard failure.
fn quoted(i: &[u8]) -> LexResult<'_, TokenKind> {
    let (mut rest, _) = tag("\"").parse(i)?;
    loop {
        let fail = |r: &[u8], message| Err(nom::Err::Failure(Failure { remaining: r.len(), message }));
        match rest.iter().position(|&c| matches!(c, b'"' | b'\\' | b'\n' | b'\r' | 0)) {
            None => return fail(&rest[rest.len()..], "premature EOF inside a quoted string"),
            Some(p) => match rest[p] {
                b'"' => return Ok((&rest[p + 1..], TokenKind::Str)),
                b'\\' => match rest.get(p + 1) {
                    None => return fail(&rest[p + 1..], "premature EOF inside a quoted string"),
                    Some(b'b' | b'f' | b'n' | b'r' | b't' | b'\\' | b'\'' | b'"') => rest = &rest[p + 2..],
                    Some(_) => return fail(&rest[p..], "unexpected escaped character"),
                },
                // DEVIATION(pbrt): robustness. pbrt takes a NUL into the string, and
                // then reports the name as unknown, printed cut short at the NUL.
                0 => return fail(&rest[p..], "NUL byte inside a quoted string"),
                _ => return fail(&rest[p..], "unterminated string (line break inside quotes)"),
            },
        }
    }
}

/// One token; the first byte decides which rule applies (cheaper than trying each).
fn token(i: &[u8]) -> LexResult<'_, TokenKind> {
    match i.first() {
        Some(b'#') => comment(i),
        Some(b'"') => quoted(i),
        Some(b'[' | b']') => bracket(i),
        _ => word(i),
    }
}

/// Pulls tokens from one file's bytes.
pub struct Lexer<'a> {
    src: &'a [u8],
    pos: usize,
}

impl<'a> Lexer<'a> {
    pub fn new(src: &'a [u8]) -> Lexer<'a> {
        Lexer { src, pos: 0 }
    }

    /// Starts at a byte offset (used to resume a file after an `Include`).
    pub fn at(src: &'a [u8], pos: usize) -> Lexer<'a> {
        Lexer { src, pos }
    }

    pub fn position(&self) -> usize {
        self.pos
    }

    /// The next token including comments; `Ok(None)` at end of input.
    pub fn next_token(&mut self) -> Result<Option<Token>, LexError> {
        let rest = &self.src[self.pos..];
        let rest = whitespace(rest).map_or(rest, |(r, _)| r);
        if rest.is_empty() {
            self.pos = self.src.len();
            return Ok(None);
        }
        let start = self.src.len() - rest.len();
        match token(rest) {
            Ok((after, kind)) => {
                self.pos = self.src.len() - after.len();
                Ok(Some(Token { kind, start: start as u32, end: self.pos as u32 }))
            }
            Err(nom::Err::Failure(f) | nom::Err::Error(f)) => {
                Err(LexError { offset: self.src.len() - f.remaining, message: f.message })
            }
            Err(nom::Err::Incomplete(_)) => Err(LexError { offset: start, message: "premature end of input" }),
        }
    }

    /// The next token that is not a comment.
    pub fn next_significant(&mut self) -> Result<Option<Token>, LexError> {
        loop {
            match self.next_token()? {
                Some(t) if t.kind == TokenKind::Comment => continue,
                other => return Ok(other),
            }
        }
    }
}

/// The text of a quoted-string token with quotes removed and escapes decoded.
pub fn decode_string(raw: &[u8]) -> String {
    let inner = raw.get(1..raw.len().saturating_sub(1)).unwrap_or(&[]);
    if !inner.contains(&b'\\') {
        return String::from_utf8_lossy(inner).into_owned();
    }
    let mut out = Vec::with_capacity(inner.len());
    let mut bytes = inner.iter();
    while let Some(&c) = bytes.next() {
        if c != b'\\' {
            out.push(c);
            continue;
        }
        out.push(match bytes.next() {
            Some(b'b') => 0x08,
            Some(b'f') => 0x0c,
            Some(b'n') => b'\n',
            Some(b'r') => b'\r',
            Some(b't') => b'\t',
            Some(&other) => other,
            None => break,
        });
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Tokenizes a whole buffer into token texts, comments included (for tests and tools).
pub fn tokenize_all(src: &[u8]) -> Result<Vec<String>, LexError> {
    let mut lexer = Lexer::new(src);
    let mut out = Vec::new();
    while let Some(t) = lexer.next_token()? {
        out.push(String::from_utf8_lossy(&src[t.start as usize..t.end as usize]).into_owned());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn word_stops_at_quote_and_brackets() {
        let want: Vec<String> = ["a", "\"b\"", "[", "c", "]", "d"].map(String::from).to_vec();
        assert_eq!(tokenize_all(b"a\"b\"[c]d"), Ok(want));
    }

    #[test]
    fn decodes_escapes() {
        assert_eq!(decode_string(br#""a\"b\\c\n""#), "a\"b\\c\n");
    }
}
