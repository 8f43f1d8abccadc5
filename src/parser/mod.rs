//! From bytes to statements: [`source`] (files, spans), [`lexer`] (tokens),
//! [`params`] (typed parameter lists), [`numbers`] (floats, integers, long lists),
//! [`stmt`] (directives over a file stack),
//! [`error`] (located diagnostics).

pub mod error;
pub mod lexer;
pub mod numbers;
pub mod params;
mod quick;
pub mod source;
pub mod stmt;

/// Which pbrt file-format version a scene is written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Syntax {
    #[serde(rename = "v3")]
    V3,
    #[serde(rename = "v4")]
    V4,
}

impl Syntax {
    pub fn name(self) -> &'static str {
        match self {
            Syntax::V3 => "v3",
            Syntax::V4 => "v4",
        }
    }

    /// The renderer that reads this syntax: "pbrt-v3" or "pbrt-v4".
    pub fn pbrt(self) -> &'static str {
        match self {
            Syntax::V3 => "pbrt-v3",
            Syntax::V4 => "pbrt-v4",
        }
    }
}
