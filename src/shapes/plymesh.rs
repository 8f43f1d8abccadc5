//! `Shape "plymesh" "string filename" "mesh.ply"` (also `.ply.gz`).
//!
//! Reads ASCII and both binary byte orders. Vertex properties `x y z` (required),
//! `nx ny nz`, and texture coordinates from the first pair present of `u v`, `s t`,
//! `texture_u texture_v`, `texture_s texture_t`; faces from `vertex_indices` (or
//! `vertex_index`) lists of 3 or 4 entries; optional `face_indices`. A quad (a,b,c,d) is
//! split as pbrt-v3 splits it, (a,b,c) and (d,a,c), or for pbrt-v4 files kept as the
//! bilinear patch with corners p00 = a, p10 = b, p01 = d, p11 = c, as pbrt-v4 keeps it.
//!
//! The header is read here, and every count in it checked against the bytes that
//! follow, before anything is allocated; ASCII payloads then go through ply-rs and
//! binary payloads are decoded straight from the bytes.
//!
//! Errors name the element: `face 12 has 5 vertices (pbrt reads triangles and quads)`.

use super::{Built, ShapeContext};
use crate::parser::error::Diagnostic;
use crate::parser::params::ParamList;
use crate::parser::source::Span;
use crate::shapes::{PatchMesh, TriangleMesh};
use crate::values::Res;
use ply_rs::parser::Parser;
use ply_rs::ply::{
    Addable, ElementDef, Encoding, Header, Property, PropertyAccess, PropertyDef, PropertyType, ScalarType,
};
use std::io::BufRead;

/// Per-vertex slots: x y z nx ny nz, then the four texture coordinate pairs.
const VERTEX_NAMES: [&str; 14] =
    ["x", "y", "z", "nx", "ny", "nz", "u", "v", "s", "t", "texture_u", "texture_v", "texture_s", "texture_t"];

fn vertex_slot(name: &str) -> Option<usize> {
    VERTEX_NAMES.iter().position(|n| *n == name)
}

/// What the reader collects before building the mesh.
#[derive(Default)]
struct Collected {
    /// Each vertex's position (slots 0 to 2 of [`VERTEX_NAMES`]), kept by the mesh.
    p: Vec<[f32; 3]>,
    /// Each vertex's other slots (normal and texture coordinates), only when the file
    /// has any: a 14-slot record per vertex was 56 bytes of pages to fault in, clear
    /// and free for every 12 the mesh keeps.
    attributes: Vec<[f32; 11]>,
    /// Triangulated vertex indices (checked against the vertex count at the end).
    tris: Indices,
    /// `face_indices` per triangle, when the file has them.
    tri_ids: Vec<i32>,
    /// Quads kept whole: four vertex indices each, in patch order (p00 p10 p01 p11).
    quads: Indices,
    quad_ids: Vec<i32>,
    /// Whether quads are split into triangles (pbrt-v3) or kept (pbrt-v4).
    split_quads: bool,
    faces: usize,
}

/// Vertex indices as the mesh keeps them (`u32`; they were `i64` until the end, 24 MB
/// for a million triangles). One outside `u32`'s range, or `u32::MAX` itself, is kept
/// as `u32::MAX`, past any vertex count a file within the size limit can have, and
/// the first such is remembered as written, for the message.
#[derive(Default)]
struct Indices {
    values: Vec<u32>,
    first_wide: Option<(usize, i64)>,
}

impl Indices {
    fn push(&mut self, i: i64) {
        let narrow = u32::try_from(i).ok().filter(|&v| v != u32::MAX);
        if narrow.is_none() && self.first_wide.is_none() {
            self.first_wide = Some((self.values.len(), i));
        }
        self.values.push(narrow.unwrap_or(u32::MAX));
    }

    /// The indices, or the first that is no vertex's: its place and its value.
    fn checked(self, n_v: usize) -> Result<Vec<u32>, (usize, i64)> {
        match self.values.iter().position(|&i| i as usize >= n_v) {
            None => Ok(self.values),
            Some(k) => match self.first_wide {
                Some((wide, value)) if wide == k => Err((k, value)),
                _ => Err((k, self.values[k] as i64)),
            },
        }
    }
}

impl Collected {
    fn push_vertex(&mut self, v: &[f32; 14], with_attributes: bool) {
        let [x, y, z, rest @ ..] = *v;
        self.p.push([x, y, z]);
        if with_attributes {
            self.attributes.push(rest);
        }
    }
}

/// Whether any of these vertex property slots is past the position's.
fn has_attributes(slots: &[Option<usize>]) -> bool {
    slots.iter().any(|s| s.is_some_and(|k| k >= 3))
}

/// What a PLY file holds: its triangles, and its quads when they are kept as patches.
/// Both index the file's vertex list (a file of quads only leaves the triangle mesh
/// empty, vertices and all).
#[derive(Clone, Debug, Default)]
pub struct PlyMesh {
    pub triangles: TriangleMesh,
    pub patches: Option<PatchMesh>,
}

/// How a file's quads are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quads {
    /// Two triangles each (pbrt-v3).
    Split,
    /// One bilinear patch each (pbrt-v4).
    Patches,
}

/// Loads a PLY file. Errors are plain messages; the caller adds the location.
pub fn load(path: &std::path::Path, quads: Quads, files: &crate::limits::Files) -> Result<PlyMesh, String> {
    parse(&files.read(path)?, quads)
}

/// Parses a PLY file's bytes (already decompressed).
pub fn parse(bytes: &[u8], quads: Quads) -> Result<PlyMesh, String> {
    let (header, body) = read_header(bytes)?;
    check_header(&header)?;
    check_counts(&header, body.len())?;
    let mut reader = body;
    let mut got = Collected { split_quads: quads == Quads::Split, ..Collected::default() };
    match header.encoding {
        Encoding::Ascii => read_ascii(&mut reader, &header, &mut got)?,
        Encoding::BinaryLittleEndian => read_binary::<false>(reader, &header, &mut got)?,
        Encoding::BinaryBigEndian => read_binary::<true>(reader, &header, &mut got)?,
    }
    build(&header, got)
}

/// Parses the header (up to and including `end_header`'s line break); returns it and
/// the payload bytes.
fn read_header(bytes: &[u8]) -> Result<(Header, &[u8]), String> {
    const MAX_HEADER: usize = 1 << 20;
    let mut header = Header::new();
    let mut format = None;
    let mut pos = 0;
    for n in 1.. {
        let end = bytes[pos..].iter().position(|&c| c == b'\n').map(|e| pos + e + 1);
        let Some(end) = end.filter(|&e| e <= MAX_HEADER) else {
            return Err("bad PLY header: no end_header line".into());
        };
        let line =
            std::str::from_utf8(&bytes[pos..end]).map_err(|_| format!("bad PLY header: line {n} is not text"))?;
        pos = end;
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = |why: &str| Err(format!("bad PLY header, line {n} (\"{}\"): {why}", line.trim_end()));
        match words.as_slice() {
            ["ply"] if n == 1 => {}
            _ if n == 1 => return bad("a PLY file starts with \"ply\""),
            ["format", enc, version] => {
                let e = match *enc {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => Encoding::BinaryBigEndian,
                    _ => return bad("unknown format"),
                };
                if *version != "1.0" {
                    return bad("only PLY version 1.0 is read");
                }
                format = Some(e);
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let Ok(count) = count.parse::<usize>() else { return bad("the count is not a whole number that fits") };
                let mut e = ElementDef::new(name.to_string());
                e.count = count;
                header.elements.add(e);
            }
            ["property", rest @ ..] => {
                let (ty, name) = match rest {
                    ["list", count, item, name] => match (scalar_type(count), scalar_type(item)) {
                        (Some(c), Some(i)) => (PropertyType::List(c, i), name),
                        _ => return bad("unknown list types"),
                    },
                    [ty, name] => match scalar_type(ty) {
                        Some(t) => (PropertyType::Scalar(t), name),
                        None => return bad("unknown property type"),
                    },
                    _ => return bad("expected \"property TYPE NAME\" or \"property list COUNT ITEM NAME\""),
                };
                let Some((_, mut e)) = header.elements.pop_back() else { return bad("a property before any element") };
                e.properties.add(PropertyDef::new(name.to_string(), ty));
                header.elements.add(e);
            }
            ["end_header"] => break,
            _ => return bad("unknown header line"),
        }
    }
    header.encoding = format.ok_or("bad PLY header: no format line")?;
    Ok((header, &bytes[pos..]))
}

fn scalar_type(t: &str) -> Option<ScalarType> {
    Some(match t {
        "char" | "int8" => ScalarType::Char,
        "uchar" | "uint8" => ScalarType::UChar,
        "short" | "int16" => ScalarType::Short,
        "ushort" | "uint16" => ScalarType::UShort,
        "int" | "int32" => ScalarType::Int,
        "uint" | "uint32" => ScalarType::UInt,
        "float" | "float32" => ScalarType::Float,
        "double" | "float64" => ScalarType::Double,
        _ => return None,
    })
}

/// Every element count against the bytes present: a binary element takes at least its
/// scalars' bytes (a list at least its count), an ASCII one at least two bytes a value.
fn check_counts(header: &Header, payload: usize) -> Result<(), String> {
    let mut need: u128 = 0;
    for (name, def) in &header.elements {
        let per: u128 = def
            .properties
            .values()
            .map(|p| match (&header.encoding, &p.data_type) {
                (Encoding::Ascii, _) => 2,
                (_, PropertyType::Scalar(t)) => scalar_size(t) as u128,
                (_, PropertyType::List(c, _)) => scalar_size(c) as u128,
            })
            .sum();
        need += per * def.count as u128;
        if need > payload as u128 {
            return Err(format!(
                "the header declares {} \"{name}\" elements, more than the {payload} bytes after it can hold",
                def.count
            ));
        }
    }
    Ok(())
}

fn vertex_property_names(header: &Header) -> Vec<&str> {
    header.elements.get("vertex").map_or(vec![], |e| e.properties.keys().map(String::as_str).collect())
}

/// Rejects files without vertex positions before any payload is read.
fn check_header(header: &Header) -> Result<(), String> {
    let names = vertex_property_names(header);
    if ["x", "y", "z"].iter().all(|n| names.contains(n)) {
        Ok(())
    } else {
        Err("PLY file has no vertex element with x, y and z".into())
    }
}

fn build(header: &Header, got: Collected) -> Result<PlyMesh, String> {
    let names = vertex_property_names(header);
    let has = |n: &str| names.contains(&n);
    let p = got.p;
    let attributes = &got.attributes;
    let n = (has("nx") && has("ny") && has("nz")).then(|| attributes.iter().map(|v| [v[0], v[1], v[2]]).collect());
    let uv_pair = [(6, "u", "v"), (8, "s", "t"), (10, "texture_u", "texture_v"), (12, "texture_s", "texture_t")]
        .into_iter()
        .find(|(_, a, b)| has(a) && has(b));
    let uv: Option<Vec<[f32; 2]>> =
        uv_pair.map(|(slot, _, _)| attributes.iter().map(|v| [v[slot - 3], v[slot - 2]]).collect());
    let n_v = p.len();
    let check = |list: Indices, per: usize, what: &str| {
        list.checked(n_v)
            .map_err(|(k, value)| format!("{what} {} has vertex index {value}, but there are {n_v} vertices", k / per))
    };
    let indices = check(got.tris, 3, "triangle")?;
    let quads = check(got.quads, 4, "quad")?;
    // DEVIATION(pbrt): no image difference (nothing rendered reads face indices). pbrt-v4 hands the whole per-face list
    // to both the triangles and the patches of a mixed file, each indexing it by its own primitive number; here each
    // primitive keeps its own face's index.
    let ids = |ids: Vec<i32>, count: usize| (ids.len() == count && got.faces > 0).then_some(ids);
    let face_indices = ids(got.tri_ids, indices.len() / 3);
    let mut triangles = TriangleMesh { p, indices, n, uv, face_indices, ..Default::default() };
    if quads.is_empty() {
        return Ok(PlyMesh { triangles, patches: None });
    }
    // A file of quads only hands its vertices over; a mixed one shares copies.
    let (p, n, uv) = match triangles.indices.is_empty() {
        true => (std::mem::take(&mut triangles.p), triangles.n.take(), triangles.uv.take()),
        false => (triangles.p.clone(), triangles.n.clone(), triangles.uv.clone()),
    };
    let face_indices = ids(got.quad_ids, quads.len() / 4);
    Ok(PlyMesh { triangles, patches: Some(PatchMesh { p, indices: quads, n, uv, face_indices }) })
}

// ---- ASCII, through ply-rs -------------------------------------------------------

#[derive(Default)]
struct AsciiVertex([f32; 14]);

impl PropertyAccess for AsciiVertex {
    fn new() -> Self {
        AsciiVertex::default()
    }
    fn set_property(&mut self, name: String, p: Property) {
        if let (Some(slot), Some(v)) = (vertex_slot(&name), scalar(&p)) {
            self.0[slot] = v as f32;
        }
    }
}

struct AsciiFace {
    indices: Result<Vec<i64>, String>,
    id: Option<i64>,
}

impl PropertyAccess for AsciiFace {
    fn new() -> Self {
        AsciiFace { indices: Ok(Vec::new()), id: None }
    }
    fn set_property(&mut self, name: String, p: Property) {
        match name.as_str() {
            "vertex_indices" | "vertex_index" => self.indices = list(&p),
            "face_indices" => self.id = scalar(&p).map(|v| v as i64),
            _ => {}
        }
    }
}

struct Ignore;

impl PropertyAccess for Ignore {
    fn new() -> Self {
        Ignore
    }
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        _ => return None,
    })
}

/// A vertex index list; float lists must hold whole numbers.
fn list(p: &Property) -> Result<Vec<i64>, String> {
    let whole = |x: f64| {
        if x.fract() == 0.0 && x.abs() < 9e15 {
            Ok(x as i64)
        } else {
            Err(format!("vertex index {x} is not a whole number"))
        }
    };
    Ok(match p {
        Property::ListChar(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListUChar(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListShort(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListUShort(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListInt(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListUInt(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListFloat(v) => v.iter().map(|&x| whole(x as f64)).collect::<Result<_, _>>()?,
        Property::ListDouble(v) => v.iter().map(|&x| whole(x)).collect::<Result<_, _>>()?,
        _ => Vec::new(),
    })
}

fn read_ascii(reader: &mut impl BufRead, header: &Header, got: &mut Collected) -> Result<(), String> {
    for (name, def) in &header.elements {
        let err = |_| format!("bad ASCII data in the \"{name}\" elements (a value that is not a number, or too few)");
        match name.as_str() {
            "vertex" => {
                let v = Parser::<AsciiVertex>::new().read_payload_for_element(reader, def, header).map_err(err)?;
                let slots: Vec<Option<usize>> = def.properties.keys().map(|k| vertex_slot(k)).collect();
                let with_attributes = has_attributes(&slots);
                v.iter().for_each(|v| got.push_vertex(&v.0, with_attributes));
            }
            "face" => {
                let faces = Parser::<AsciiFace>::new().read_payload_for_element(reader, def, header).map_err(err)?;
                for f in faces {
                    let indices = f.indices.map_err(|e| format!("face {}: {e}", got.faces))?;
                    push_face(got, &indices, f.id)?;
                }
            }
            _ => {
                Parser::<Ignore>::new().read_payload_for_element(reader, def, header).map_err(err)?;
            }
        }
    }
    Ok(())
}

/// A triangle (a,b,c); a quad (a,b,c,d) as (a,b,c) and (d,a,c), or as the patch
/// (a,b,d,c).
fn push_face(got: &mut Collected, f: &[i64], id: Option<i64>) -> Result<(), String> {
    // (indices, ids, the face's corners in their order, primitives made)
    let (list, ids, order, prims): (_, _, &[usize], _) = match f.len() {
        3 => (&mut got.tris, &mut got.tri_ids, &[0, 1, 2], 1),
        4 if got.split_quads => (&mut got.tris, &mut got.tri_ids, &[0, 1, 2, 3, 0, 2], 2),
        4 => (&mut got.quads, &mut got.quad_ids, &[0, 1, 3, 2], 1),
        n => return Err(format!("face {} has {n} vertices (pbrt reads triangles and quads)", got.faces)),
    };
    got.faces += 1;
    order.iter().for_each(|&k| list.push(f[k]));
    if let Some(id) = id {
        // One per primitive: a split quad's two triangles share its id.
        ids.extend(std::iter::repeat_n(id as i32, prims));
    }
    Ok(())
}

// ---- binary, decoded from the byte slice ------------------------------------------

struct Bytes<'a, const BIG: bool> {
    data: &'a [u8],
    pos: usize,
}

impl<const BIG: bool> Bytes<'_, BIG> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let s = self.data.get(self.pos..self.pos + N).ok_or("PLY file ends early")?;
        self.pos += N;
        let mut a: [u8; N] = s.try_into().map_err(|_| "PLY file ends early")?;
        if BIG {
            a.reverse();
        }
        Ok(a)
    }

    fn scalar(&mut self, t: &ScalarType) -> Result<f64, String> {
        Ok(match t {
            ScalarType::Char => i8::from_le_bytes(self.take()?) as f64,
            ScalarType::UChar => u8::from_le_bytes(self.take()?) as f64,
            ScalarType::Short => i16::from_le_bytes(self.take()?) as f64,
            ScalarType::UShort => u16::from_le_bytes(self.take()?) as f64,
            ScalarType::Int => i32::from_le_bytes(self.take()?) as f64,
            ScalarType::UInt => u32::from_le_bytes(self.take()?) as f64,
            ScalarType::Float => f32::from_le_bytes(self.take()?) as f64,
            ScalarType::Double => f64::from_le_bytes(self.take()?),
        })
    }
}

fn scalar_size(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

fn read_binary<const BIG: bool>(data: &[u8], header: &Header, got: &mut Collected) -> Result<(), String> {
    let mut b = Bytes::<BIG> { data, pos: 0 };
    for (name, def) in &header.elements {
        let props: Vec<(&String, &PropertyType)> = def.properties.iter().map(|(k, p)| (k, &p.data_type)).collect();
        if props.is_empty() {
            continue; // holds no bytes, whatever its count says
        }
        // Never trust a header count for allocation beyond what the file can hold.
        let room = (data.len() - b.pos) / props.len().max(1);
        if !BIG && fast_path(name, &props, def.count, (data, &mut b.pos), got)? {
            continue;
        }
        match name.as_str() {
            "vertex" => {
                let slots: Vec<Option<usize>> = props.iter().map(|(k, _)| vertex_slot(k)).collect();
                let with_attributes = has_attributes(&slots);
                got.p.reserve(def.count.min(room));
                for _ in 0..def.count {
                    let mut v = [0f32; 14];
                    for ((_, ty), slot) in props.iter().zip(&slots) {
                        let x = read_value(&mut b, ty, &mut Vec::new())?;
                        if let Some(s) = slot {
                            v[*s] = x as f32;
                        }
                    }
                    got.push_vertex(&v, with_attributes);
                }
            }
            _ => {
                let is_face = name == "face";
                got.tris.values.reserve(if is_face { 3 * def.count.min(room) } else { 0 });
                let (mut indices, mut scratch) = (Vec::new(), Vec::new());
                for _ in 0..def.count {
                    let mut id = None;
                    indices.clear();
                    for (k, ty) in &props {
                        scratch.clear();
                        let x = read_value(&mut b, ty, &mut scratch)?;
                        match k.as_str() {
                            "vertex_indices" | "vertex_index" => std::mem::swap(&mut indices, &mut scratch),
                            "face_indices" => id = Some(x as i64),
                            _ => {}
                        }
                    }
                    if is_face {
                        push_face(got, &indices, id)?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Little-endian elements of the two layouts nearly every binary PLY file has, read
/// without going value by value: vertices of `float` properties alone, and faces of one
/// `list uchar int` (or `uint`) of vertex indices. Reads them into `got` and returns
/// true, or returns false for another layout. The same values and errors as the
/// general reader (`tests::fast_and_general_binary_reads_agree`); `check` of the 192
/// meshes of `pbrt-bench load` took 0.74 s with it against 0.99 s without.
fn fast_path(
    name: &str,
    props: &[(&String, &PropertyType)],
    count: usize,
    (data, pos): (&[u8], &mut usize),
    got: &mut Collected,
) -> Result<bool, String> {
    let floats = props.iter().all(|(_, t)| matches!(t, PropertyType::Scalar(ScalarType::Float)));
    if name == "vertex" && floats {
        let stride = 4 * props.len();
        let bytes = count.checked_mul(stride).filter(|&n| n <= data.len() - *pos).ok_or("PLY file ends early")?;
        let slots: Vec<Option<usize>> = props.iter().map(|(k, _)| vertex_slot(k)).collect();
        let with_attributes = has_attributes(&slots);
        got.p.reserve(count);
        got.attributes.reserve(if with_attributes { count } else { 0 });
        for c in data[*pos..*pos + bytes].chunks_exact(stride) {
            let mut v = [0f32; 14];
            for (k, slot) in slots.iter().enumerate() {
                if let Some(s) = slot {
                    v[*s] = f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]]);
                }
            }
            got.push_vertex(&v, with_attributes);
        }
        *pos += bytes;
        return Ok(true);
    }
    let signed = match props {
        [(k, PropertyType::List(ScalarType::UChar, item))]
            if matches!(k.as_str(), "vertex_indices" | "vertex_index") =>
        {
            match item {
                ScalarType::Int => true,
                ScalarType::UInt => false,
                _ => return Ok(false),
            }
        }
        _ => return Ok(false),
    };
    if name != "face" {
        return Ok(false);
    }
    let mut indices = Vec::with_capacity(4);
    // Triangles, most often; at most as many faces as the file has room for.
    got.tris.values.reserve(3 * count.min((data.len() - *pos) / 13));
    for _ in 0..count {
        let n = *data.get(*pos).ok_or("PLY file ends early")? as usize;
        let words = data.get(*pos + 1..*pos + 1 + 4 * n).ok_or("PLY file ends early")?;
        indices.clear();
        indices.extend(words.chunks_exact(4).map(|w| {
            let w = [w[0], w[1], w[2], w[3]];
            if signed { i32::from_le_bytes(w) as i64 } else { u32::from_le_bytes(w) as i64 }
        }));
        *pos += 1 + 4 * n;
        push_face(got, &indices, None)?;
    }
    Ok(true)
}

/// Reads one property; lists go to `list` (as integers) and return their length.
fn read_value<const BIG: bool>(b: &mut Bytes<'_, BIG>, ty: &PropertyType, list: &mut Vec<i64>) -> Result<f64, String> {
    match ty {
        PropertyType::Scalar(t) => b.scalar(t),
        PropertyType::List(count_ty, item_ty) => {
            let n = b.scalar(count_ty)?;
            if !(0.0..=1e9).contains(&n) {
                return Err(format!("bad PLY list length {n}"));
            }
            let n = n as usize;
            if b.pos + n * scalar_size(item_ty) > b.data.len() {
                return Err("PLY file ends early".into());
            }
            for _ in 0..n {
                let x = b.scalar(item_ty)?;
                if x.fract() != 0.0 || x.abs() >= 9e15 {
                    return Err(format!("vertex index {x} is not a whole number"));
                }
                list.push(x as i64);
            }
            Ok(n as f64)
        }
    }
}

pub const NAME: &str = "plymesh";

/// `Shape "plymesh" "string filename" "mesh.ply"`: the file's triangles, and its quads
/// as the file's version reads them (a file of both is two shapes, as in pbrt-v4).
/// With pbrt-v4's `"texture displacement"` its quads are split and the scene displaces
/// it ([`super::displace`]).
pub fn read(ctx: &mut ShapeContext, p: &ParamList, span: Span) -> Res<Built> {
    // pbrt-v3 has no displacement: there the parameter stays unused, as in pbrt-v3.
    let displaced = ctx.quads == Quads::Patches && super::displaces(p);
    if ctx.quads == Quads::Patches {
        // pbrt-v4 reads it with or without a displacement.
        p.mark_known(&["edgelength"]);
    }
    let (name, at, path) = super::mesh_file(ctx, NAME, p, span)?;
    let quads = if displaced { Quads::Split } else { ctx.quads };
    let m = match ctx.ahead.take(&path, quads).unwrap_or_else(|| load(&path, quads, ctx.files)) {
        Ok(m) => m,
        // pbrt-v3 reports a file it cannot open and goes on without the shape.
        // Read errors name the file already; format errors get its name first.
        Err(e) if crate::limits::is_unreadable(&e) => return ctx.left_out_by_v3(p, at, e),
        Err(e) => return Err(Diagnostic::error(at, format!("{name}: {e}"))),
    };
    if displaced {
        return super::displaced(m.triangles, NAME, name, p);
    }
    let has_triangles = !m.triangles.indices.is_empty();
    let tris = Built::Mesh { mesh: m.triangles, kind: NAME, filename: Some(name.clone()) };
    Ok(match m.patches {
        None => tris,
        Some(mesh) => {
            let patches = Built::Patches { mesh, kind: NAME, filename: Some(name) };
            if has_triangles { Built::Several(vec![tris, patches]) } else { patches }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_outside_u32_are_reported_as_written() {
        let list = |values: &[i64]| {
            let mut l = Indices::default();
            values.iter().for_each(|&i| l.push(i));
            l
        };
        assert_eq!(list(&[0, 2, 1]).checked(3), Ok(vec![0, 2, 1]));
        assert_eq!(list(&[0, 3, -1]).checked(3), Err((1, 3)));
        assert_eq!(list(&[0, 1, -1]).checked(3), Err((2, -1)));
        assert_eq!(list(&[0, 1 << 40, -1]).checked(3), Err((1, 1 << 40)));
        assert_eq!(list(&[0, 1, u32::MAX as i64]).checked(3), Err((2, u32::MAX as i64)));
        assert_eq!(list(&[7, -5, 1 << 40]).checked(3), Err((0, 7)), "the first bad one, wide or not");
    }

    /// A PLY file of `n` jittered vertices (position, normal, uv) and faces of three and
    /// four corners, little- or big-endian, face indices as `int` or `uint`.
    fn file(n: u32, big: bool, item: &str) -> Vec<u8> {
        let enc = if big { "binary_big_endian" } else { "binary_little_endian" };
        let faces = n - 3;
        let mut out = format!(
            "ply\nformat {enc} 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n\
             property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n\
             element face {faces}\nproperty list uchar {item} vertex_indices\nend_header\n"
        )
        .into_bytes();
        let f = |x: f32| if big { x.to_be_bytes() } else { x.to_le_bytes() };
        for k in 0..n {
            let t = k as f32 * 0.37;
            for x in [t.sin(), t.cos(), 0.1 * t, 0.0, 0.0, 1.0, t.fract(), (t * 1.3).fract()] {
                out.extend(f(x));
            }
        }
        for k in 0..faces {
            let corners: &[u32] = if k % 3 == 0 { &[k, k + 1, k + 2, k + 3] } else { &[k, k + 1, k + 2] };
            out.push(corners.len() as u8);
            for &c in corners {
                out.extend(if big { c.to_be_bytes() } else { c.to_le_bytes() });
            }
        }
        out
    }

    #[test]
    fn fast_and_general_binary_reads_agree() {
        // Big-endian files take the general reader, little-endian ones the fast path.
        for (item, quads) in [("int", Quads::Split), ("uint", Quads::Patches), ("int", Quads::Patches)] {
            let (le, be) = (file(200, false, item), file(200, true, item));
            let (a, b) = (parse(&le, quads).unwrap(), parse(&be, quads).unwrap());
            assert!(format!("{a:?}") == format!("{b:?}"), "{item} {quads:?}: the two reads differ");
            assert!(a.triangles.triangle_count() > 100, "{item} {quads:?}");
            // Cut anywhere in the payload (the vertices, a face's count, its indices):
            // the same error either way.
            let payload = |f: &[u8]| f.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
            for cut in [5, 200 * 16, 200 * 32 + 13, 200 * 32 + 14, 200 * 32 + 15, le.len() - payload(&le) - 3] {
                let x = parse(&le[..payload(&le) + cut], quads).map(|_| ());
                let y = parse(&be[..payload(&be) + cut], quads).map(|_| ());
                assert_eq!(x, y, "{item} {quads:?}, cut at {cut}");
                assert!(x.is_err(), "cut at {cut}");
            }
        }
    }
}
