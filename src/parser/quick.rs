//! Reading the plain statements that large instancing and transform files repeat
//! straight from the bytes ([`super::stmt`] matches the keyword):
//!
//! ```text
//! AttributeBegin Translate 0.25 0 0 ObjectInstance "o1" AttributeEnd
//! ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  3 4 5 1]
//! ```
//!
//! A million-instance file took about 400 ns a line through the general reader (a token
//! at a time, each result handed back through memory). This reads the same tokens with
//! the same number and string readers, so it gives the same values and spans; anything
//! it does not expect (a comment, a string with escapes, the end of a file, a malformed
//! number) gives `None`, and the general reader then reads the statement from its
//! start, with its errors and warnings.

use super::lexer::{decode_string, is_space};
use super::numbers::parse_f64;

/// A reading position in a file's bytes.
pub struct Bytes<'a> {
    text: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    pub fn new(text: &'a [u8], at: usize) -> Bytes<'a> {
        Bytes { text, at }
    }

    /// Where reading has got to.
    pub fn at(&self) -> usize {
        self.at
    }

    pub fn text(&self, (start, end): (usize, usize)) -> &'a [u8] {
        &self.text[start..end]
    }

    fn skip_space(&mut self) {
        while self.text.get(self.at).is_some_and(|&c| is_space(c)) {
            self.at += 1;
        }
    }

    /// The next token's range when it is a bare word (not a comment).
    pub fn word(&mut self) -> Option<(usize, usize)> {
        self.skip_space();
        let start = self.at;
        if matches!(self.text.get(start), None | Some(b'#')) {
            return None;
        }
        let len = self.text[start..].iter().position(|&c| is_space(c) || matches!(c, b'"' | b'[' | b']'));
        self.at = start + len.unwrap_or(self.text.len() - start);
        (self.at > start).then_some((start, self.at))
    }

    /// `N` numbers, each a word of its own.
    pub fn numbers<const N: usize>(&mut self) -> Option<[f64; N]> {
        let mut out = [0.0; N];
        for v in &mut out {
            let (s, e) = self.word()?;
            *v = parse_f64(&self.text[s..e])?;
        }
        Some(out)
    }

    /// `[` and `N` numbers and `]`.
    pub fn bracketed<const N: usize>(&mut self) -> Option<[f64; N]> {
        self.byte(b'[')?;
        let values = self.numbers()?;
        self.byte(b']')?;
        Some(values)
    }

    fn byte(&mut self, b: u8) -> Option<()> {
        self.skip_space();
        self.byte_here(b)
    }

    fn byte_here(&mut self, b: u8) -> Option<()> {
        (self.text.get(self.at) == Some(&b)).then(|| self.at += 1)
    }

    /// A quoted string without escapes, line breaks or NULs (those the general
    /// reader decodes or reports).
    pub fn string(&mut self) -> Option<String> {
        self.byte(b'"')?;
        let start = self.at - 1;
        let len = self.text[self.at..].iter().position(|&c| matches!(c, b'"' | b'\\' | b'\n' | b'\r' | 0))?;
        self.at += len;
        self.byte_here(b'"')?;
        Some(decode_string(&self.text[start..self.at]))
    }
}
