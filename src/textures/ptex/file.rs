//! Ptex files (`.ptx`, Ptex format version 1): per-face textures, decoded whole into
//! texel arrays, with the mip levels the file stores and the ones the reader makes.
//!
//! A file is a 64-byte header (data type, channels, face count and the sizes of the
//! blocks that follow), an extended header (border and edge-filter modes, where edits
//! begin), the face infos (zlib: per face its resolution as two log2s, flags, its four
//! neighbours and the edges it meets them by), the constant data (zlib: one pixel per
//! face), the level infos and the levels. Level 0 holds every face's full-resolution
//! data; level i > 0 the faces whose smaller side is at least 2^(i+2), halved i times
//! in both directions and ordered by decreasing smaller side. A level is a zlib block
//! of 4-byte face headers (size and encoding: constant, zlib, zlib of byte differences,
//! or tiled) and then the faces' data. Tiled faces hold a tile size, the tiles' own
//! headers and then the tiles. Edits appended by Ptex's incremental writer replace
//! faces of level 0. Every size and offset is checked before use, so a damaged file
//! is an error, never a wild read.
//!
//! Texels are kept as the file's numbers in f32 (0–255 for 8-bit data), as the Ptex
//! library filters them; a reduction rounds as the library does for the data type.

use std::collections::HashMap;
use std::io::Read;
use std::sync::{Arc, Mutex};

const MAGIC: u32 = u32::from_le_bytes(*b"Ptex");
const HEADER: usize = 64;
const EXT_HEADER: usize = 40;
const FACE_INFO: usize = 20;
const LEVEL_INFO: usize = 16;
/// The largest face side read, as log2 (2^15 texels; Ptex's own writer makes no more).
const MAX_RES_LOG2: i8 = 15;

/// Why a file cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PtexError {
    #[error("not a Ptex file (no \"Ptex\" magic)")]
    Magic,
    #[error("Ptex format version {0}; version 1 files are read")]
    Version(u32),
    #[error("mesh type {0} is neither triangles (0) nor quads (1)")]
    MeshType(u32),
    #[error("data type {0} is none of uint8, uint16, half and float (0 to 3)")]
    DataType(u32),
    #[error("the file ends at byte {at}, inside {what}")]
    Truncated { at: usize, what: &'static str },
    #[error("{0} does not decompress to its stated size")]
    Zip(&'static str),
    #[error("face {face}: {what}")]
    Face { face: usize, what: String },
    #[error("its texels take {0} bytes, more than the file-size limit")]
    TooLarge(u64),
    #[error("{0}")]
    Damaged(String),
}

type Result<T> = std::result::Result<T, PtexError>;

/// Ptex's `MeshType`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshType {
    Triangle,
    Quad,
}

/// Ptex's `DataType`: how texels are stored, and so how reductions round.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataType {
    U8,
    U16,
    Half,
    F32,
}

impl DataType {
    fn size(self) -> usize {
        match self {
            DataType::U8 => 1,
            DataType::U16 | DataType::Half => 2,
            DataType::F32 => 4,
        }
    }

    /// The stored number for 1.0 (Ptex's `OneValue`).
    pub fn one(self) -> f32 {
        match self {
            DataType::U8 => 255.0,
            DataType::U16 => 65535.0,
            _ => 1.0,
        }
    }

    /// `x` as a number of this type holds it (Ptex's `T(x)`: integers truncate).
    pub fn store(self, x: f32) -> f32 {
        match self {
            DataType::U8 => (x as u8) as f32,
            DataType::U16 => (x as u16) as f32,
            DataType::Half => half::f16::from_bits(ptex_half(x)).to_f32(),
            DataType::F32 => x,
        }
    }

    /// Ptex's `halve(a + b)`: integers shift, the others scale in float.
    fn halve(self, a: f32, b: f32) -> f32 {
        match self {
            DataType::U8 | DataType::U16 => ((a as u32 + b as u32) >> 1) as f32,
            _ => self.store(0.5 * (a + b)),
        }
    }

    /// Ptex's `quarter(a + b + c + d)`.
    fn quarter(self, [a, b, c, d]: [f32; 4]) -> f32 {
        match self {
            DataType::U8 | DataType::U16 => ((a as u32 + b as u32 + c as u32 + d as u32) >> 2) as f32,
            _ => self.store(0.25 * (a + b + c + d)),
        }
    }

    /// The texel numbers in `raw` (little-endian values of this type).
    fn decode(self, raw: &[u8]) -> Vec<f32> {
        match self {
            DataType::U8 => raw.iter().map(|&b| b as f32).collect(),
            DataType::U16 => raw.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]]) as f32).collect(),
            DataType::Half => raw.chunks_exact(2).map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32()).collect(),
            DataType::F32 => raw.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect(),
        }
    }
}

/// `x` as a half's bits, rounded as Ptex's `PtexHalf::fromFloat` rounds: ties away
/// from zero (not to even), denormals to nearest.
fn ptex_half(x: f32) -> u16 {
    if x == 0.0 {
        return 0;
    }
    let bits = x.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let e = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    match e {
        1..=30 => sign | (((e as u32) << 10) + (((bits & 0x7f_ffff) + 0x1000) >> 13)) as u16,
        ..=0 => sign | (x.abs() * 16_777_216.0 + 0.5) as u16,
        _ if x.is_nan() => sign | 0x7c00 | ((bits & 0x7f_ffff) >> 13) as u16,
        _ => sign | 0x7c00,
    }
}

/// Ptex's `BorderMode`: what a filter does past a mesh border.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BorderMode {
    Clamp,
    Black,
    Periodic,
}

/// A face's resolution as log2 of its sides (Ptex's `Res`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Res {
    pub u: i8,
    pub v: i8,
}

impl Res {
    pub fn new(u: i8, v: i8) -> Res {
        Res { u, v }
    }

    pub fn su(self) -> i32 {
        1 << self.u
    }

    pub fn sv(self) -> i32 {
        1 << self.v
    }

    pub fn size(self) -> usize {
        (self.su() * self.sv()) as usize
    }
}

/// A face's resolution, neighbours and flags (Ptex's `FaceInfo`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct FaceInfo {
    pub res: Res,
    adj_edges: u8,
    flags: u8,
    pub adj_faces: [i32; 4],
}

impl FaceInfo {
    const CONSTANT: u8 = 1;
    const HAS_EDITS: u8 = 2;
    const NB_CONSTANT: u8 = 4;
    const SUBFACE: u8 = 8;

    /// The edge of neighbour `adj_faces[e]` that edge `e` meets.
    pub fn adj_edge(&self, e: i32) -> i32 {
        ((self.adj_edges >> (2 * (e & 3))) & 3) as i32
    }

    pub fn adj_face(&self, e: i32) -> i32 {
        self.adj_faces[(e & 3) as usize]
    }

    pub fn is_constant(&self) -> bool {
        self.flags & Self::CONSTANT != 0
    }

    pub fn has_edits(&self) -> bool {
        self.flags & Self::HAS_EDITS != 0
    }

    pub fn is_neighborhood_constant(&self) -> bool {
        self.flags & Self::NB_CONSTANT != 0
    }

    pub fn is_subface(&self) -> bool {
        self.flags & Self::SUBFACE != 0
    }

    fn parse(b: &[u8]) -> FaceInfo {
        let i = |k: usize| i32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
        FaceInfo {
            res: Res::new(b[0] as i8, b[1] as i8),
            adj_edges: b[2],
            flags: b[3],
            adj_faces: [i(4), i(8), i(12), i(16)],
        }
    }
}

/// One face's texels at one resolution: a single pixel, or `res.size()` pixels of
/// `channels` numbers each, row by row from v = 0.
#[derive(Clone, Debug, PartialEq)]
pub enum FaceData {
    Constant(Box<[f32]>),
    Texels { res: Res, texels: Box<[f32]> },
}

/// A Ptex texture, read whole.
#[derive(Debug)]
pub struct PtexFile {
    pub mesh: MeshType,
    pub data_type: DataType,
    pub channels: usize,
    pub u_border: BorderMode,
    pub v_border: BorderMode,
    /// Values are tangent-space vectors, turned with the kernel across edges.
    pub tanvec: bool,
    pub faces: Vec<FaceInfo>,
    /// Level 0 by face id (constant faces hold their constant); level i by the face's
    /// reduction order.
    levels: Vec<Vec<Arc<FaceData>>>,
    constant: Vec<Arc<FaceData>>,
    reduction_order: Vec<u32>,
    /// Reductions made on demand, by face and resolution.
    made: Mutex<HashMap<(u32, Res), Arc<FaceData>>>,
}

/// Little-endian reads with the bounds checked.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn slice(&self, at: u64, len: u64, what: &'static str) -> Result<&[u8]> {
        let end = at.checked_add(len).filter(|&e| e <= self.0.len() as u64);
        end.map(|e| &self.0[at as usize..e as usize]).ok_or(PtexError::Truncated { at: self.0.len(), what })
    }

    fn u16(&self, at: u64, what: &'static str) -> Result<u16> {
        self.slice(at, 2, what).map(|b| u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32(&self, at: u64, what: &'static str) -> Result<u32> {
        self.slice(at, 4, what).map(|b| u32::from_le_bytes(b.try_into().unwrap()))
    }

    fn u64(&self, at: u64, what: &'static str) -> Result<u64> {
        self.slice(at, 8, what).map(|b| u64::from_le_bytes(b.try_into().unwrap()))
    }

    /// The zlib block of `zip_size` bytes at `at`, which must inflate to `size` bytes.
    fn unzip(&self, at: u64, zip_size: u64, size: usize, what: &'static str) -> Result<Vec<u8>> {
        let stored = self.slice(at, zip_size, what)?;
        // A damaged size cannot make a large allocation: zlib inflates at most ~1000:1.
        let mut out = Vec::with_capacity(size.min(zip_size as usize * 8));
        let mut z = flate2::read::ZlibDecoder::new(stored).take(size as u64 + 1);
        z.read_to_end(&mut out).map_err(|_| PtexError::Zip(what))?;
        if out.len() != size {
            return Err(PtexError::Zip(what));
        }
        Ok(out)
    }
}

/// The header fields the reader uses.
struct Header {
    mesh: MeshType,
    data_type: DataType,
    alpha: Option<usize>,
    channels: usize,
    levels: usize,
    faces: usize,
    ext_size: u64,
    face_info_size: u64,
    const_size: u64,
    level_info_size: u64,
    level_data_size: u64,
    meta_zip_size: u64,
}

fn header(b: &Bytes) -> Result<Header> {
    const W: &str = "the header";
    if b.u32(0, W)? != MAGIC {
        return Err(PtexError::Magic);
    }
    b.slice(0, HEADER as u64, W)?;
    let version = b.u32(4, W)?;
    if version != 1 {
        return Err(PtexError::Version(version));
    }
    let mesh = match b.u32(8, W)? {
        0 => MeshType::Triangle,
        1 => MeshType::Quad,
        m => return Err(PtexError::MeshType(m)),
    };
    let data_type = match b.u32(12, W)? {
        0 => DataType::U8,
        1 => DataType::U16,
        2 => DataType::Half,
        3 => DataType::F32,
        d => return Err(PtexError::DataType(d)),
    };
    let channels = b.u16(20, W)? as usize;
    let alpha = b.u32(16, W)? as i32;
    let alpha = (alpha >= 0 && (alpha as usize) < channels).then_some(alpha as usize);
    if channels == 0 {
        return Err(PtexError::Damaged("the file has no channels".into()));
    }
    let u32_at = |at| b.u32(at, W).map(u64::from);
    Ok(Header {
        mesh,
        data_type,
        alpha,
        channels,
        levels: b.u16(22, W)? as usize,
        faces: b.u32(24, W)? as usize,
        ext_size: u32_at(28)?,
        face_info_size: u32_at(32)?,
        const_size: u32_at(36)?,
        level_info_size: u32_at(40)?,
        level_data_size: b.u64(48, W)?,
        meta_zip_size: u32_at(56)?,
    })
}

/// The extended header's fields; absent ones (older files) are zero.
struct ExtHeader {
    u_border: u16,
    v_border: u16,
    edge_filter: u16,
    lmd_zip_size: u64,
    lmd_data_size: u64,
    edit_data_size: u64,
    edit_data_at: u64,
}

fn ext_header(b: &Bytes, size: u64) -> Result<ExtHeader> {
    let mut e = [0u8; EXT_HEADER];
    let n = size.min(EXT_HEADER as u64) as usize;
    e[..n].copy_from_slice(b.slice(HEADER as u64, n as u64, "the extended header")?);
    let e = Bytes(&e);
    const W: &str = "the extended header";
    Ok(ExtHeader {
        u_border: e.u16(0, W)?,
        v_border: e.u16(4, W)?,
        edge_filter: e.u16(6, W)?,
        lmd_zip_size: e.u32(8, W)? as u64,
        lmd_data_size: e.u64(16, W)?,
        edit_data_size: e.u64(24, W)?,
        edit_data_at: e.u64(32, W)?,
    })
}

fn border(mode: u16) -> Result<BorderMode> {
    Ok(match mode {
        0 => BorderMode::Clamp,
        1 => BorderMode::Black,
        2 => BorderMode::Periodic,
        m => return Err(PtexError::Damaged(format!("border mode {m} is none of clamp, black, periodic"))),
    })
}

/// Where a face's data sits and how it is stored (Ptex's `FaceDataHeader`).
#[derive(Clone, Copy)]
struct DataHeader {
    size: u64,
    encoding: u32,
}

impl DataHeader {
    fn parse(b: &[u8]) -> DataHeader {
        let w = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        DataHeader { size: (w & 0x3fff_ffff) as u64, encoding: w >> 30 }
    }
}

const ENC_CONSTANT: u32 = 0;
const ENC_ZIPPED: u32 = 1;
const ENC_DIFF_ZIPPED: u32 = 2;
const ENC_TILED: u32 = 3;

/// Decodes face data stored at `at` with header `h`, of resolution `res`.
struct Decoder<'a> {
    b: Bytes<'a>,
    data_type: DataType,
    channels: usize,
    /// Premultiply by this alpha channel (level 0 only, as Ptex's cache does).
    alpha: Option<usize>,
}

impl Decoder<'_> {
    fn pixel_size(&self) -> usize {
        self.data_type.size() * self.channels
    }

    fn face(&self, at: u64, h: DataHeader, res: Res, tiles_allowed: bool) -> Result<FaceData> {
        match h.encoding {
            ENC_CONSTANT => {
                let raw = self.b.slice(at, self.pixel_size() as u64, "a constant face")?;
                Ok(FaceData::Constant(self.premultiplied(self.data_type.decode(raw)).into()))
            }
            ENC_ZIPPED | ENC_DIFF_ZIPPED => self.packed(at, h, res),
            ENC_TILED if tiles_allowed => self.tiled(at, res),
            _ => Err(PtexError::Damaged("a tile is itself tiled".into())),
        }
    }

    /// Zipped planes of channels, each row by row, as differences for integer data.
    fn packed(&self, at: u64, h: DataHeader, res: Res) -> Result<FaceData> {
        let n = res.size();
        let mut raw = self.b.unzip(at, h.size, n * self.pixel_size(), "a face's texels")?;
        if h.encoding == ENC_DIFF_ZIPPED {
            undo_differences(&mut raw, self.data_type);
        }
        let planes = self.data_type.decode(&raw);
        let mut texels = vec![0.0; n * self.channels];
        for (c, plane) in planes.chunks_exact(n.max(1)).enumerate().take(self.channels) {
            for (i, &x) in plane.iter().enumerate() {
                texels[i * self.channels + c] = x;
            }
        }
        Ok(FaceData::Texels { res, texels: self.premultiplied(texels).into() })
    }

    /// A tiled face, assembled into one array.
    fn tiled(&self, at: u64, res: Res) -> Result<FaceData> {
        const W: &str = "a tiled face";
        let tr = self.b.slice(at, 2, W)?;
        let tile = Res::new(tr[0] as i8, tr[1] as i8);
        if !(0..=res.u).contains(&tile.u) || !(0..=res.v).contains(&tile.v) {
            return Err(PtexError::Damaged(format!(
                "tiles of 2^{}×2^{} in a face of 2^{}×2^{}",
                tile.u, tile.v, res.u, res.v
            )));
        }
        let header_size = self.b.u32(at + 2, W)? as u64;
        let (nu, nv) = (res.su() / tile.su(), res.sv() / tile.sv());
        let n_tiles = (nu * nv) as usize;
        let headers = self.b.unzip(at + 6, header_size, 4 * n_tiles, "a tiled face's tile headers")?;
        let mut pos = at + 6 + header_size;
        let mut texels = vec![0.0; res.size() * self.channels];
        for (k, h) in headers.chunks_exact(4).map(DataHeader::parse).enumerate() {
            let data = self.face(pos, h, tile, false)?;
            pos += h.size;
            let (tu, tv) = ((k as i32 % nu) * tile.su(), (k as i32 / nu) * tile.sv());
            for y in 0..tile.sv() {
                for x in 0..tile.su() {
                    let src = pixel(&data, tile, x, y, self.channels);
                    let at = (((tv + y) * res.su() + tu + x) as usize) * self.channels;
                    texels[at..at + self.channels].copy_from_slice(src);
                }
            }
        }
        Ok(FaceData::Texels { res, texels: texels.into() })
    }

    /// Ptex's `multalpha`: the colour channels times alpha, in the data type.
    fn premultiplied(&self, mut px: Vec<f32>) -> Vec<f32> {
        let Some(a) = self.alpha else { return px };
        let (n, scale) = (self.channels, 1.0 / self.data_type.one());
        let colour: Vec<usize> = if a == 0 { (1..n).collect() } else { (0..a).collect() };
        for p in px.chunks_exact_mut(n) {
            let alpha = scale * p[a];
            for &c in &colour {
                p[c] = self.data_type.store(p[c] * alpha);
            }
        }
        px
    }
}

/// Ptex's `calcResFromWidth`: log2 of 1 / w, read from the float's exponent.
pub fn res_from_width(w: f32) -> i8 {
    (127 - ((w.to_bits() >> 23) & 0xff) as i32) as i8
}

/// Pixel (x, y) of face data at resolution `res`.
pub fn pixel(d: &FaceData, res: Res, x: i32, y: i32, channels: usize) -> &[f32] {
    match d {
        FaceData::Constant(c) => c,
        FaceData::Texels { texels, .. } => {
            let at = ((y * res.su() + x) as usize) * channels;
            &texels[at..at + channels]
        }
    }
}

/// Ptex's `decodeDifference`: running sums, wrapping, of 8- and 16-bit numbers.
fn undo_differences(raw: &mut [u8], t: DataType) {
    match t {
        DataType::U8 => {
            let mut prev = 0u8;
            for b in raw.iter_mut() {
                *b = b.wrapping_add(prev);
                prev = *b;
            }
        }
        DataType::U16 => {
            let mut prev = 0u16;
            for c in raw.chunks_exact_mut(2) {
                let v = u16::from_le_bytes([c[0], c[1]]).wrapping_add(prev);
                c.copy_from_slice(&v.to_le_bytes());
                prev = v;
            }
        }
        _ => {}
    }
}

/// The order in which faces are stored in reduction levels: by decreasing smaller
/// side, constant faces counting as 2 texels a side, ties by face id (Ptex's
/// `genRfaceids`). Returns each face's position in that order.
fn reduction_order(faces: &[FaceInfo]) -> Vec<u32> {
    let min = |f: &FaceInfo| if f.is_constant() { 1 } else { f.res.u.min(f.res.v) };
    let mut ids: Vec<u32> = (0..faces.len() as u32).collect();
    ids.sort_by_key(|&i| std::cmp::Reverse(min(&faces[i as usize])));
    let mut order = vec![0; faces.len()];
    for (r, &i) in ids.iter().enumerate() {
        order[i as usize] = r as u32;
    }
    order
}

impl PtexFile {
    /// Reads a whole file; `max_bytes` bounds the texels' stored size.
    pub fn read(file: &[u8], max_bytes: u64) -> Result<PtexFile> {
        let b = Bytes(file);
        let h = header(&b)?;
        let e = ext_header(&b, h.ext_size)?;
        let face_info_at = HEADER as u64 + h.ext_size;
        let const_at = face_info_at + h.face_info_size;
        let level_info_at = const_at + h.const_size;
        let level_data_at = level_info_at + h.level_info_size;
        let edits_from = (level_data_at.saturating_add(h.level_data_size))
            .saturating_add(h.meta_zip_size)
            .saturating_add(8)
            .saturating_add(e.lmd_zip_size)
            .saturating_add(e.lmd_data_size);
        let faces = read_face_infos(&b, face_info_at, h.face_info_size, h.faces)?;
        let stored: u64 =
            faces.iter().map(|f| f.res.size() as u64).sum::<u64>() * (h.channels * h.data_type.size()) as u64;
        if stored > max_bytes {
            return Err(PtexError::TooLarge(stored));
        }
        let d = Decoder { b: Bytes(file), data_type: h.data_type, channels: h.channels, alpha: h.alpha };
        let raw_const = b.unzip(const_at, h.const_size, h.faces * d.pixel_size(), "the constant data")?;
        let mut constant: Vec<Vec<f32>> =
            raw_const.chunks_exact(d.pixel_size()).map(|p| d.premultiplied(d.data_type.decode(p))).collect();
        let mut faces = faces;
        let order = reduction_order(&faces);
        let edits = read_edits(
            &d,
            (e.edit_data_at.max(edits_from), e.edit_data_size, e.edit_data_at),
            &mut faces,
            &mut constant,
        )?;
        let constant: Vec<Arc<FaceData>> =
            constant.into_iter().map(|c| Arc::new(FaceData::Constant(c.into()))).collect();
        let level_info = b.slice(level_info_at, (LEVEL_INFO * h.levels) as u64, "the level infos")?;
        let mut levels = Vec::with_capacity(h.levels);
        let mut at = level_data_at;
        for (i, li) in level_info.chunks_exact(LEVEL_INFO).enumerate() {
            let size = u64::from_le_bytes(li[0..8].try_into().unwrap());
            let header_size = u32::from_le_bytes(li[8..12].try_into().unwrap()) as u64;
            let n = u32::from_le_bytes(li[12..16].try_into().unwrap()) as usize;
            let level = LevelSpec { at, header_size, n, index: i };
            levels.push(read_level(&d, &level, &faces, &order, &constant, &edits)?);
            at = at.saturating_add(size);
        }
        if levels.is_empty() && faces.iter().any(|f| !f.is_constant()) {
            return Err(PtexError::Damaged("the file has no levels".into()));
        }
        Ok(PtexFile {
            mesh: h.mesh,
            data_type: h.data_type,
            channels: h.channels,
            u_border: border(e.u_border)?,
            v_border: border(e.v_border)?,
            tanvec: e.edge_filter == 1,
            faces,
            levels,
            constant,
            reduction_order: order,
            made: Mutex::default(),
        })
    }

    /// Face `face`'s data at resolution `res` (Ptex's `getData`): its constant where it
    /// is constant or `res` is one texel, the stored level where there is one, else a
    /// reduction made here (halving u or v in turn, as the library does).
    pub fn data(&self, face: usize, res: Res) -> Arc<FaceData> {
        let f = &self.faces[face];
        if f.is_constant() || res == Res::default() {
            return self.constant[face].clone();
        }
        let (ru, rv) = (f.res.u - res.u, f.res.v - res.v);
        if ru == 0 && rv == 0 {
            return self.levels[0][face].clone();
        }
        if ru == rv && !f.has_edits() {
            let r = self.reduction_order[face] as usize;
            if let Some(d) = self.levels.get(ru as usize).and_then(|l| l.get(r)) {
                return d.clone();
            }
        }
        if let Some(d) = self.made.lock().ok().and_then(|m| m.get(&(face as u32, res)).cloned()) {
            return d;
        }
        let made = Arc::new(self.reduce(face, f, res));
        if let Ok(mut m) = self.made.lock() {
            m.insert((face as u32, res), made.clone());
        }
        made
    }

    fn reduce(&self, face: usize, f: &FaceInfo, res: Res) -> FaceData {
        let (ru, rv) = (f.res.u - res.u, f.res.v - res.v);
        if res.u < 0 || res.v < 0 || ru < 0 || rv < 0 || (self.mesh == MeshType::Triangle && ru != rv) {
            // Ptex's error data: black.
            return FaceData::Constant(vec![0.0; self.channels].into());
        }
        if self.mesh == MeshType::Triangle {
            let src = self.data(face, Res::new(res.u + 1, res.v + 1));
            return self.halve(&src, res, Halve::Triangle);
        }
        let along_u = if ru == rv { res.u & 1 != 0 } else { ru > rv };
        if along_u {
            self.halve(&self.data(face, Res::new(res.u + 1, res.v)), res, Halve::U)
        } else {
            self.halve(&self.data(face, Res::new(res.u, res.v + 1)), res, Halve::V)
        }
    }

    /// `src` halved to `res` (Ptex's `reduceu`, `reducev` and `reduceTri`).
    fn halve(&self, src: &FaceData, res: Res, how: Halve) -> FaceData {
        let FaceData::Texels { res: sr, texels } = src else { return src.clone() };
        let (n, t) = (self.channels, self.data_type);
        let at = |x: i32, y: i32, c: usize| texels[((y * sr.su() + x) as usize) * n + c];
        let w = sr.su();
        let mut out = Vec::with_capacity(res.size() * n);
        for y in 0..res.sv() {
            for x in 0..res.su() {
                for c in 0..n {
                    out.push(match how {
                        Halve::U => t.halve(at(2 * x, y, c), at(2 * x + 1, y, c)),
                        Halve::V => t.halve(at(x, 2 * y, c), at(x, 2 * y + 1, c)),
                        Halve::Triangle => t.quarter([
                            at(2 * x, 2 * y, c),
                            at(2 * x + 1, 2 * y, c),
                            at(2 * x, 2 * y + 1, c),
                            at(w - 1 - 2 * y, w - 1 - 2 * x, c),
                        ]),
                    });
                }
            }
        }
        FaceData::Texels { res, texels: out.into() }
    }
}

#[derive(Clone, Copy)]
enum Halve {
    U,
    V,
    Triangle,
}

fn read_face_infos(b: &Bytes, at: u64, zip_size: u64, n: usize) -> Result<Vec<FaceInfo>> {
    let size = n.checked_mul(FACE_INFO).ok_or(PtexError::Damaged(format!("{n} faces")))?;
    b.slice(at, zip_size, "the face infos")?;
    let raw = b.unzip(at, zip_size, size, "the face infos")?;
    let faces: Vec<FaceInfo> = raw.chunks_exact(FACE_INFO).map(FaceInfo::parse).collect();
    for (i, f) in faces.iter().enumerate() {
        check_face(i, f, n)?;
    }
    Ok(faces)
}

fn check_face(i: usize, f: &FaceInfo, n: usize) -> Result<()> {
    let bad = |what: String| Err(PtexError::Face { face: i, what });
    if !(0..=MAX_RES_LOG2).contains(&f.res.u) || !(0..=MAX_RES_LOG2).contains(&f.res.v) {
        return bad(format!("resolution 2^{} × 2^{} (sides of 1 to 2^{MAX_RES_LOG2} are read)", f.res.u, f.res.v));
    }
    match f.adj_faces.iter().find(|&&a| a < -1 || a >= n as i32) {
        Some(a) => bad(format!("neighbour {a} is not a face of the {n}")),
        None => Ok(()),
    }
}

/// Where a level is and which it is.
struct LevelSpec {
    at: u64,
    header_size: u64,
    n: usize,
    index: usize,
}

/// Level 0's data moved by edits: face id → (where, header).
type Edits = HashMap<usize, (u64, DataHeader)>;

fn read_level(
    d: &Decoder,
    l: &LevelSpec,
    faces: &[FaceInfo],
    order: &[u32],
    constant: &[Arc<FaceData>],
    edits: &Edits,
) -> Result<Vec<Arc<FaceData>>> {
    if l.n > faces.len() || (l.index == 0 && l.n != faces.len()) {
        return Err(PtexError::Damaged(format!("level {} lists {} faces of {}", l.index, l.n, faces.len())));
    }
    let headers = d.b.unzip(l.at, l.header_size, 4 * l.n, "a level's face headers")?;
    let mut by_order = vec![0usize; faces.len()];
    for (f, &r) in order.iter().enumerate() {
        by_order[r as usize] = f;
    }
    let mut pos = l.at + l.header_size;
    let alpha = if l.index == 0 { d.alpha } else { None };
    let dec = Decoder { b: Bytes(d.b.0), alpha, ..*d };
    let mut out = Vec::with_capacity(l.n);
    for (k, h) in headers.chunks_exact(4).map(DataHeader::parse).enumerate() {
        let face = if l.index == 0 { k } else { by_order[k] };
        let f = &faces[face];
        let res = Res::new(f.res.u - l.index as i8, f.res.v - l.index as i8);
        let data = match edits.get(&face).filter(|_| l.index == 0) {
            _ if f.is_constant() || (l.index == 0 && res == Res::default()) => constant[face].clone(),
            Some(&(at, eh)) => Arc::new(dec.face(at, eh, res, true).map_err(|e| in_face(face, e))?),
            // Edited faces are reduced from their new data, never read from levels.
            None if res.u < 0 || res.v < 0 || (l.index > 0 && f.has_edits()) => constant[face].clone(),
            None => Arc::new(dec.face(pos, h, res, true).map_err(|e| in_face(face, e))?),
        };
        pos = pos.saturating_add(h.size);
        out.push(data);
    }
    Ok(out)
}

fn in_face(face: usize, e: PtexError) -> PtexError {
    PtexError::Face { face, what: e.to_string() }
}

/// Reads the edits appended by Ptex's incremental writer: new face infos and constant
/// values now, the new level-0 data's place for later. `(from, size, recorded)`:
/// where edits begin, their size and the position the extended header records
/// (zero in older files, whose edits run to the end).
fn read_edits(
    d: &Decoder,
    (from, size, recorded): (u64, u64, u64),
    faces: &mut [FaceInfo],
    constant: &mut [Vec<f32>],
) -> Result<Edits> {
    let end = if recorded > 0 { from.saturating_add(size) } else { d.b.0.len() as u64 };
    let mut edits = Edits::new();
    let mut pos = from;
    while pos < end {
        let (Ok(kind), Ok(len)) = (d.b.slice(pos, 1, "an edit"), d.b.u32(pos + 1, "an edit")) else { break };
        if len == 0 {
            break;
        }
        let body = pos + 5;
        pos = body + len as u64;
        if kind[0] != 0 {
            continue; // metadata edits: pbrt reads no metadata
        }
        const W: &str = "a face edit";
        let face = d.b.u32(body, W)? as usize;
        if face >= faces.len() {
            continue;
        }
        let info = FaceInfo::parse(d.b.slice(body + 4, FACE_INFO as u64, W)?);
        check_face(face, &info, faces.len())?;
        faces[face] = FaceInfo { flags: info.flags | FaceInfo::HAS_EDITS, ..info };
        let h = DataHeader::parse(d.b.slice(body + 24, 4, W)?);
        let px = d.b.slice(body + 28, d.pixel_size() as u64, W)?;
        constant[face] = d.premultiplied(d.data_type.decode(px));
        if !info.is_constant() {
            edits.insert(face, (body + 28 + d.pixel_size() as u64, h));
        }
    }
    Ok(edits)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn bytes(name: &str) -> Vec<u8> {
        let dir = env!("CARGO_MANIFEST_DIR");
        std::fs::read(format!("{dir}/pbrt-scenes/verify/textures/ptex-{name}.ptx")).unwrap()
    }

    fn zip(b: &[u8]) -> Vec<u8> {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(b).unwrap();
        z.finish().unwrap()
    }

    /// A file of constant 8-bit faces (no levels), neighbours in a row: face i's right
    /// edge meets face i + 1's left edge.
    pub(crate) fn constant_file(channels: u16, values: &[&[u8]], flags: u8) -> Vec<u8> {
        let n = values.len() as i32;
        let mut info = Vec::new();
        for i in 0..n {
            info.extend([2u8, 2, (3 << 2) | 1, flags]);
            let left = if i > 0 { i - 1 } else { -1 };
            let right = if i + 1 < n { i + 1 } else { -1 };
            for a in [-1, right, -1, left] {
                info.extend(a.to_le_bytes());
            }
        }
        let (zinfo, zconst) = (zip(&info), zip(&values.concat()));
        let mut f = Vec::new();
        let u32s = [u32::from_le_bytes(*b"Ptex"), 1, 1, 0, u32::MAX];
        u32s.iter().for_each(|x| f.extend(x.to_le_bytes()));
        f.extend(channels.to_le_bytes());
        f.extend(0u16.to_le_bytes());
        for x in [n as u32, 40, zinfo.len() as u32, zconst.len() as u32, 0, 4] {
            f.extend(x.to_le_bytes());
        }
        f.extend(0u64.to_le_bytes());
        f.extend([0u8; 8]);
        f.extend([0u8; 40]);
        f.extend(zinfo);
        f.extend(zconst);
        f
    }

    #[test]
    fn the_test_files_are_read_whole() {
        let grid = PtexFile::read(&bytes("grid"), 1 << 30).unwrap();
        assert_eq!((grid.mesh, grid.data_type, grid.channels, grid.faces.len()), (MeshType::Quad, DataType::U8, 3, 9));
        // The 256 × 256 face is stored in tiles; its reductions go down to 4 × 4.
        assert_eq!(grid.faces[6].res, Res::new(8, 8));
        let FaceData::Texels { texels, .. } = &*grid.data(6, Res::new(2, 2)) else { panic!("texels") };
        assert_eq!(texels.len(), 16 * 3);
        // The constant face.
        assert!(grid.faces[8].is_constant());
        assert_eq!(&*grid.data(8, Res::new(3, 3)), &FaceData::Constant(vec![200.0, 120.0, 40.0].into()));
        let cube = PtexFile::read(&bytes("cube"), 1 << 30).unwrap();
        // Face 2 was replaced by an edit at a smaller resolution.
        assert_eq!((cube.faces[2].res, cube.faces[2].has_edits()), (Res::new(3, 4), true));
        let tri = PtexFile::read(&bytes("tri"), 1 << 30).unwrap();
        assert_eq!((tri.mesh, tri.data_type), (MeshType::Triangle, DataType::U16));
        // A face larger than the limit allows is refused before it is decoded.
        assert!(matches!(PtexFile::read(&bytes("grid"), 100_000), Err(PtexError::TooLarge(_))));
    }

    #[test]
    fn reductions_halve_as_the_library_does() {
        let grid = PtexFile::read(&bytes("grid"), 1 << 30).unwrap();
        // Face 1 is 16 × 8: its 8 × 8 version halves u, the stored 8 × 4 level both.
        let full = grid.data(1, Res::new(4, 3));
        let half_u = grid.data(1, Res::new(3, 3));
        let (FaceData::Texels { texels: a, .. }, FaceData::Texels { texels: b, .. }) = (&*full, &*half_u) else {
            panic!("texels")
        };
        let (x, y, c) = (5, 6, 1);
        let want = ((a[(y * 16 + 2 * x) * 3 + c] as u32 + a[(y * 16 + 2 * x + 1) * 3 + c] as u32) >> 1) as f32;
        assert_eq!(b[(y * 8 + x) * 3 + c], want);
        // Half floats round ties away from zero, as Ptex's own conversion.
        assert_eq!(DataType::Half.store(1.0 + 1.0 / 2048.0), 1.0 + 1.0 / 1024.0);
        assert_eq!(DataType::U8.quarter([1.0, 1.0, 1.0, 0.0]), 0.0);
    }

    #[test]
    fn damaged_files_are_errors_never_panics() {
        for name in ["grid", "cube", "fan", "tri"] {
            let good = bytes(name);
            // Every cut before the barrier after the levels loses data the reader needs;
            // a cut inside edits drops them (as the library does) but never panics.
            let edits_at = u64::from_le_bytes(good[96..104].try_into().unwrap()) as usize;
            for end in (0..good.len()).step_by(good.len() / 400 + 1) {
                let r = std::panic::catch_unwind(|| PtexFile::read(&good[..end], 1 << 30).is_err());
                assert!(r.is_ok(), "{name} cut at {end} panicked");
                assert!(end + 8 > edits_at || r.unwrap(), "{name} cut at {end} is read");
            }
            let mut rng = crate::sampling::Rng::new(7);
            for _ in 0..150 {
                let mut b = good.clone();
                let at = (rng.uniform() * b.len() as f32) as usize % b.len();
                b[at] ^= 1 << ((rng.uniform() * 8.0) as u32 % 8);
                let r = std::panic::catch_unwind(|| {
                    if let Ok(t) = PtexFile::read(&b, 1 << 30) {
                        for f in 0..t.faces.len() as i32 {
                            t.eval(f, 0.1, 0.9, [0.2, 0.0, 0.0, 0.3]);
                            t.eval(f, 1.0, 0.0, [0.0; 4]);
                        }
                    }
                });
                assert!(r.is_ok(), "{name}: flipping a bit of byte {at} panicked");
            }
        }
    }

    #[test]
    fn a_constant_neighbourhood_is_its_constant() {
        // Two constant faces flagged "neighbourhood constant": the filter returns the
        // face's value without filtering; unflagged, it blends in the neighbour's.
        let file = |flags| PtexFile::read(&constant_file(1, &[&[51], &[255]], flags), 1 << 30).unwrap();
        assert_eq!(file(FaceInfo::CONSTANT | FaceInfo::NB_CONSTANT).eval(0, 1.0, 0.5, [0.0; 4]), vec![0.2]);
        let blended = file(FaceInfo::CONSTANT).eval(0, 1.0, 0.5, [0.0; 4])[0];
        assert!(blended > 0.25 && blended < 0.95, "{blended}");
        assert_eq!(file(FaceInfo::CONSTANT).eval(5, 0.5, 0.5, [0.0; 4]), vec![0.0], "a face not in the file");
    }
}
