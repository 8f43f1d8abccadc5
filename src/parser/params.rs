//! Parameter lists: `"type name" value` or `"type name" [ values ... ]`.
//!
//! ```text
//! Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 1 1 0] "integer indices" [0 1 2]
//! Material "matte" "rgb Kd" [.5 .5 .5] "bool twosided" "true"    # v3 bool
//! LightSource "point" "blackbody I" [5500 125]                    # v3 pair
//! ```
//! Accepts the union of pbrt-v3 and pbrt-v4 types: `integer float point2 vector2 point3
//! vector3 normal bool string texture rgb spectrum blackbody`, the v3 aliases `point`,
//! `vector`, `color` and `xyz`, and `normal3`. Bools in both spellings (`"true"` and
//! `true`). Values are parsed while reading the list, straight into typed vectors.
//! Every parameter keeps its span and a "looked up" flag, so unused ones are warned
//! about at their own location.

use super::Syntax;
use super::error::Diagnostic;
use super::source::Span;
use std::cell::Cell;

/// A parameter type after alias resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamType {
    Integer,
    Float,
    Point2,
    Vector2,
    Point3,
    Vector3,
    Normal3,
    Rgb,
    Xyz,
    Blackbody,
    Spectrum,
    Bool,
    String,
    Texture,
}

impl ParamType {
    /// The type for a declaration keyword, and the syntax version the keyword proves.
    pub fn from_keyword(k: &str) -> Option<(ParamType, Option<Syntax>)> {
        use ParamType::*;
        Some(match k {
            "integer" => (Integer, None),
            "float" => (Float, None),
            "point2" => (Point2, None),
            "vector2" => (Vector2, None),
            "point3" => (Point3, None),
            "vector3" => (Vector3, None),
            "normal" => (Normal3, None),
            "bool" => (Bool, None),
            "string" => (String, None),
            "texture" => (Texture, None),
            "rgb" => (Rgb, None),
            "spectrum" => (Spectrum, None),
            "blackbody" => (Blackbody, None),
            "point" => (Point3, Some(Syntax::V3)),
            "vector" => (Vector3, Some(Syntax::V3)),
            "color" => (Rgb, Some(Syntax::V3)),
            "xyz" => (Xyz, Some(Syntax::V3)),
            "normal3" => (Normal3, Some(Syntax::V4)),
            _ => return None,
        })
    }

    /// The canonical keyword.
    pub fn keyword(self) -> &'static str {
        use ParamType::*;
        match self {
            Integer => "integer",
            Float => "float",
            Point2 => "point2",
            Vector2 => "vector2",
            Point3 => "point3",
            Vector3 => "vector3",
            Normal3 => "normal",
            Rgb => "rgb",
            Xyz => "xyz",
            Blackbody => "blackbody",
            Spectrum => "spectrum",
            Bool => "bool",
            String => "string",
            Texture => "texture",
        }
    }

    /// Numbers per item (0 for non-numeric types).
    pub fn arity(self) -> usize {
        use ParamType::*;
        match self {
            Integer | Float => 1,
            Point2 | Vector2 => 2,
            Point3 | Vector3 | Normal3 | Rgb | Xyz => 3,
            Blackbody | Spectrum => 1,
            Bool | String | Texture => 0,
        }
    }
}

/// The parsed values of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    Ints(Vec<i32>),
    Floats(Vec<f32>),
    Strings(Vec<String>),
    Bools(Vec<bool>),
}

impl Values {
    pub fn len(&self) -> usize {
        match self {
            Values::Ints(v) => v.len(),
            Values::Floats(v) => v.len(),
            Values::Strings(v) => v.len(),
            Values::Bools(v) => v.len(),
        }
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One `"type name" value(s)` item.
#[derive(Clone, Debug)]
pub struct Param {
    pub ty: ParamType,
    /// The type keyword as written (`color`, `point`, ...).
    pub type_name: String,
    pub name: String,
    pub values: Values,
    /// The declaration string.
    pub span: Span,
    /// From the first value to the last (or the closing bracket).
    pub value_span: Span,
    used: Cell<bool>,
    /// Set when a lookup found the name with another type.
    wanted: Cell<Option<ParamType>>,
}

impl Param {
    pub fn new(ty: ParamType, type_name: String, name: String, values: Values, span: Span, value_span: Span) -> Param {
        Param { ty, type_name, name, values, span, value_span, used: Cell::new(false), wanted: Cell::new(None) }
    }

    pub fn mark_used(&self) {
        self.used.set(true);
    }
    pub fn is_used(&self) -> bool {
        self.used.get()
    }

    pub fn floats(&self) -> &[f32] {
        match &self.values {
            Values::Floats(v) => v,
            _ => &[],
        }
    }
    pub fn ints(&self) -> &[i32] {
        match &self.values {
            Values::Ints(v) => v,
            _ => &[],
        }
    }
    pub fn strings(&self) -> &[String] {
        match &self.values {
            Values::Strings(v) => v,
            _ => &[],
        }
    }
}

/// A spectrum-valued parameter in any of its spellings.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumValue {
    Rgb([f32; 3]),
    Xyz([f32; 3]),
    /// Temperature in kelvin; v3 files add a scale (`[T scale]`), v4 files do not.
    Blackbody {
        kelvin: f32,
        scale: Option<f32>,
    },
    /// `(lambda, value)` pairs.
    Sampled(Vec<(f32, f32)>),
    /// A named spectrum (`metal-Au-eta`) or an SPD file name.
    Named(String),
    /// A reference to a spectrum texture.
    Texture(String),
}

/// A float-valued parameter that may also name a float texture.
#[derive(Clone, Debug, PartialEq)]
pub enum FloatValue {
    Const(f32),
    Texture(String),
}

/// The parameter list of one statement.
#[derive(Clone, Debug, Default)]
pub struct ParamList {
    pub params: Vec<Param>,
}

type Lookup<T> = Result<Option<T>, Diagnostic>;

impl ParamList {
    /// The last parameter of this name (pbrt-v4: the last occurrence wins), if its type
    /// is one of `types`; marks it used. A name with another type is left unused and
    /// remembered for the unused-parameter warning.
    pub fn find(&self, name: &str, types: &[ParamType]) -> Option<&Param> {
        let p = self.params.iter().rev().find(|p| p.name == name)?;
        if types.contains(&p.ty) {
            p.mark_used();
            Some(p)
        } else {
            p.wanted.set(types.first().copied());
            None
        }
    }

    fn one<T: Copy>(&self, name: &str, ty: ParamType, get: impl Fn(&Param) -> &[T]) -> Lookup<T> {
        let Some(p) = self.find(name, &[ty]) else { return Ok(None) };
        match get(p) {
            [v] => Ok(Some(*v)),
            vs => Err(Diagnostic::error(
                p.span,
                format!("\"{} {}\" needs exactly one value, found {}", p.type_name, name, vs.len()),
            )),
        }
    }

    pub fn float(&self, name: &str) -> Lookup<f32> {
        self.one(name, ParamType::Float, Param::floats)
    }
    pub fn int(&self, name: &str) -> Lookup<i32> {
        self.one(name, ParamType::Integer, Param::ints)
    }
    pub fn bool(&self, name: &str) -> Lookup<bool> {
        let Some(p) = self.find(name, &[ParamType::Bool]) else { return Ok(None) };
        match &p.values {
            Values::Bools(v) if v.len() == 1 => Ok(Some(v[0])),
            _ => Err(Diagnostic::error(p.span, format!("\"bool {name}\" needs exactly one value"))),
        }
    }
    pub fn string(&self, name: &str) -> Lookup<String> {
        let Some(p) = self.find(name, &[ParamType::String]) else { return Ok(None) };
        match p.strings() {
            [s] => Ok(Some(s.clone())),
            vs => {
                Err(Diagnostic::error(p.span, format!("\"string {name}\" needs exactly one value, found {}", vs.len())))
            }
        }
    }

    /// `n` floats of a fixed-size type (`point3`, `float[4]` screen windows, ...).
    pub fn fixed<const N: usize>(&self, name: &str, types: &[ParamType]) -> Lookup<[f32; N]> {
        let Some(p) = self.find(name, types) else { return Ok(None) };
        <[f32; N]>::try_from(p.floats()).map(Some).map_err(|_| {
            Diagnostic::error(p.span, format!("\"{} {name}\" needs {N} values, found {}", p.type_name, p.values.len()))
        })
    }

    pub fn point3(&self, name: &str) -> Lookup<[f32; 3]> {
        self.fixed(name, &[ParamType::Point3])
    }

    /// A variable-length array whose length must be a multiple of the type's arity.
    pub fn array(&self, name: &str, ty: ParamType) -> Result<Option<&Param>, Diagnostic> {
        let Some(p) = self.find(name, &[ty]) else { return Ok(None) };
        let n = ty.arity().max(1);
        if p.values.len() % n != 0 {
            return Err(Diagnostic::error(
                p.span,
                format!("\"{} {name}\" needs a multiple of {n} values, found {}", p.type_name, p.values.len()),
            ));
        }
        Ok(Some(p))
    }

    /// The values of the last parameter of this name, moved out: the parameter keeps
    /// its name, type and spans and is left with no values of the same kind. For
    /// readers that keep a long array as it is (a mesh's points), which would otherwise
    /// copy it.
    pub fn take_values(&mut self, name: &str) -> Option<Values> {
        let p = self.params.iter_mut().rev().find(|p| p.name == name)?;
        let empty = match p.values {
            Values::Ints(_) => Values::Ints(Vec::new()),
            Values::Floats(_) => Values::Floats(Vec::new()),
            Values::Strings(_) => Values::Strings(Vec::new()),
            Values::Bools(_) => Values::Bools(Vec::new()),
        };
        Some(std::mem::replace(&mut p.values, empty))
    }

    /// The last parameter of this name, whatever its type, without marking it used.
    pub fn named(&self, name: &str) -> Option<&Param> {
        self.params.iter().rev().find(|p| p.name == name)
    }

    /// A float given directly or as a float texture name.
    pub fn float_or_texture(&self, name: &str) -> Lookup<FloatValue> {
        let Some(p) = self.find(name, &[ParamType::Float, ParamType::Texture]) else {
            return Ok(None);
        };
        match (&p.values, p.ty) {
            (Values::Floats(v), _) if v.len() == 1 => Ok(Some(FloatValue::Const(v[0]))),
            (Values::Strings(v), ParamType::Texture) if v.len() == 1 => Ok(Some(FloatValue::Texture(v[0].clone()))),
            _ => Err(Diagnostic::error(p.span, format!("\"{} {name}\" needs exactly one value", p.type_name))),
        }
    }

    /// A spectrum in any spelling (`rgb`, `color`, `xyz`, `blackbody`, `spectrum`) or a
    /// spectrum texture name.
    pub fn spectrum(&self, name: &str) -> Lookup<SpectrumValue> {
        use ParamType::*;
        let Some(p) = self.find(name, &[Rgb, Xyz, Blackbody, Spectrum, Texture]) else {
            return Ok(None);
        };
        let bad = |what: &str| Err(Diagnostic::error(p.span, format!("\"{} {name}\": {what}", p.type_name)));
        let f = p.floats();
        match p.ty {
            Rgb | Xyz => match <[f32; 3]>::try_from(f) {
                Ok(c) if p.ty == Rgb => Ok(Some(SpectrumValue::Rgb(c))),
                Ok(c) => Ok(Some(SpectrumValue::Xyz(c))),
                Err(_) => bad(&format!("needs 3 values, found {}", f.len())),
            },
            Blackbody => match f {
                [t] => Ok(Some(SpectrumValue::Blackbody { kelvin: *t, scale: None })),
                [t, s] => Ok(Some(SpectrumValue::Blackbody { kelvin: *t, scale: Some(*s) })),
                _ => bad(&format!("needs 1 value (v4) or 2 values (v3), found {}", f.len())),
            },
            Spectrum => match &p.values {
                Values::Strings(s) if s.len() == 1 => Ok(Some(SpectrumValue::Named(s[0].clone()))),
                Values::Floats(v) if !v.is_empty() && v.len() % 2 == 0 => {
                    Ok(Some(SpectrumValue::Sampled(v.chunks_exact(2).map(|c| (c[0], c[1])).collect())))
                }
                _ => bad("needs (wavelength, value) pairs or one name"),
            },
            _ => match p.strings() {
                [t] => Ok(Some(SpectrumValue::Texture(t.clone()))),
                _ => bad("needs exactly one texture name"),
            },
        }
    }

    /// Marks every parameter whose name is in `names` as used (any type).
    pub fn mark_known(&self, names: &[&str]) {
        for p in &self.params {
            if names.contains(&p.name.as_str()) {
                p.mark_used();
            }
        }
    }

    pub fn mark_all_used(&self) {
        self.params.iter().for_each(Param::mark_used);
    }

    /// The first parameter nobody found because a lookup wanted it with another type.
    pub fn wrong_type(&self) -> Option<Diagnostic> {
        let p = self.params.iter().find(|p| !p.is_used() && p.wanted.get().is_some())?;
        let want = p.wanted.get()?.keyword();
        Some(Diagnostic::error(
            p.span,
            format!("parameter \"{} {}\" has the wrong type: expected \"{want}\"", p.type_name, p.name),
        ))
    }

    /// One warning per parameter nobody looked up, at the parameter's own span.
    // DEVIATION(pbrt): input leniency (no valid scene renders differently). pbrt-v4 aborts on an unused parameter; we
    // warn, as pbrt-v3 does, so that v3 files (and v3 shape-level material overrides) still load.
    pub fn report_unused(&self, out: &mut Vec<Diagnostic>) {
        for p in self.params.iter().filter(|p| !p.is_used()) {
            let hint = match p.wanted.get() {
                Some(t) => format!(" (expected type \"{}\")", t.keyword()),
                None => String::new(),
            };
            out.push(Diagnostic::warning(
                p.span,
                format!("parameter \"{} {}\" is not used{hint}", p.type_name, p.name),
            ));
        }
    }
}
