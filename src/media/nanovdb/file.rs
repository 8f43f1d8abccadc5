//! NanoVDB files (`.nvdb`, format version 32): the float grids pbrt-v4's `nanovdb`
//! medium reads, decoded into a typed tree.
//!
//! A file is a run of segments. Each starts with a 16-byte header (magic `NanoVDB0`,
//! version, grid count, codec), then one record per grid (sizes, name hash, type,
//! class, bounds, name) and then the grids' bytes, stored raw or zlib-compressed
//! (`ZIP`, with its compressed size in front). A grid's bytes are NanoVDB's memory
//! image: the grid header (672 bytes: its map between index and world space, world
//! bounds, type and class), the tree header (64 bytes: where each level's nodes
//! begin, and how many), then the root (a table of 32-byte tiles keyed by origin),
//! the upper nodes (32³ children or values), the lower nodes (16³) and the leaves
//! (8³ values). Child links are byte offsets from their parent. Every offset, count
//! and size is checked against the bytes before use, so a damaged file is an error,
//! never a wild read.

use glam::{DVec3, Vec3};

/// "NanoVDB" and a digit: `0` in files of every version 32, `1` and `2` (grids and
/// files) in those of NanoVDB 32.6 on.
const MAGIC: u64 = 0x0042_4456_6f6e_614e;
const MAGIC_MASK: u64 = 0x00ff_ffff_ffff_ffff;

fn magic(word: u64) -> bool {
    word & MAGIC_MASK == MAGIC && (b'0'..=b'2').contains(&((word >> 56) as u8))
}
const MAJOR: u32 = 32;
const HEADER: usize = 16;
const META: usize = 176;
const GRID: usize = 672;
const ROOT: usize = 64;
const ROOT_TILE: usize = 32;
const UPPER: Node = Node { log2: 5, child_log2: 7, table_at: 8256 };
const LOWER: Node = Node { log2: 4, child_log2: 3, table_at: 1088 };
const LEAF_VALUES_AT: usize = 96;
const LEAF_SIZE: usize = LEAF_VALUES_AT + 512 * 4;
/// A root tile spans 2^12 voxels a side.
const ROOT_LOG2: u32 = 12;
const GRID_TYPE_FLOAT: u32 = 1;
/// Grid classes pbrt-v4 accepts: unknown and fog volume.
const CLASSES: [u32; 2] = [0, 2];

/// Why a file cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NvdbError {
    #[error("not a NanoVDB file (no \"NanoVDB0\" magic at byte {0})")]
    Magic(usize),
    #[error("NanoVDB format version {0}; version 32 files are read")]
    Version(u32),
    #[error("the file ends at byte {at}, inside {what}")]
    Truncated { at: usize, what: &'static str },
    #[error("grid \"{name}\" is compressed with {codec}, which is not read (only uncompressed and ZIP grids)")]
    Codec { name: String, codec: &'static str },
    #[error("grid \"{0}\": its ZIP data does not decompress to its stated size")]
    Zip(String),
    #[error("grid \"{name}\" holds {ty} values; pbrt-v4 reads float grids")]
    Type { name: String, ty: String },
    #[error("grid \"{0}\" is not a fog volume (pbrt-v4 reads fog volumes)")]
    Class(String),
    #[error("grid \"{name}\": {what}")]
    Damaged { name: String, what: String },
    #[error("grid \"{0}\" is too large ({1} bytes)")]
    TooLarge(String, u64),
}

/// One float grid: its map and its tree.
#[derive(Debug)]
pub struct FloatGrid {
    /// World (the medium's space) to index space: `inverse · (p − offset)`.
    inverse: [f32; 9],
    offset: Vec3,
    /// The world box of the active values (NanoVDB's `worldBBox`).
    pub world_min: DVec3,
    pub world_max: DVec3,
    /// The index box of the active values, both ends inclusive.
    pub index_min: [i32; 3],
    pub index_max: [i32; 3],
    background: f32,
    /// Root tiles sorted by origin.
    roots: Vec<([i32; 3], Slot)>,
    uppers: Vec<Vec<Slot>>,
    lowers: Vec<Vec<Slot>>,
    leaves: Vec<[f32; 512]>,
    /// Each node's largest value: leaves, lower nodes, upper nodes.
    maxima: [Vec<f32>; 3],
}

/// A table entry: a constant value or a child node (its index in the level below).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    Value(f32),
    Child(u32),
}

/// An internal node's shape: its table is 2^(3·log2) entries at `table_at`.
#[derive(Clone, Copy)]
struct Node {
    log2: u32,
    child_log2: u32,
    table_at: usize,
}

impl Node {
    fn entries(self) -> usize {
        1 << (3 * self.log2)
    }

    fn size(self) -> usize {
        self.table_at + 8 * self.entries()
    }

    fn child_mask_at(self) -> usize {
        32 + self.entries() / 8
    }

    /// The entry of index point `p` in a node of this shape.
    fn offset(self, p: [i32; 3]) -> usize {
        let mask = (1i32 << (self.log2 + self.child_log2)) - 1;
        let k = |c: i32| ((c & mask) >> self.child_log2) as usize;
        (k(p[0]) << (2 * self.log2)) | (k(p[1]) << self.log2) | k(p[2])
    }
}

/// Little-endian reads with the bounds checked.
struct Bytes<'a> {
    b: &'a [u8],
}

impl<'a> Bytes<'a> {
    fn get<const N: usize>(&self, at: usize, what: &'static str) -> Result<[u8; N], NvdbError> {
        let end = at.checked_add(N).filter(|&e| e <= self.b.len());
        end.map(|e| self.b[at..e].try_into().unwrap()).ok_or(NvdbError::Truncated { at: self.b.len(), what })
    }
}

/// `Bytes::u16` and the like: the little-endian number at a byte offset.
macro_rules! readers {
    ($($t:ident),*) => {
        impl Bytes<'_> {
            $(fn $t(&self, at: usize, what: &'static str) -> Result<$t, NvdbError> {
                self.get(at, what).map($t::from_le_bytes)
            })*
        }
    };
}
readers!(u16, u32, i32, u64, i64, f32, f64);

/// One grid's record in a segment.
struct Meta {
    grid_size: u64,
    file_size: u64,
    grid_type: u32,
    name: String,
}

/// The grid named `name` in the file's bytes, `Ok(None)` where no grid has that name;
/// `max_bytes` bounds a grid's decoded size.
pub fn read_grid(file: &[u8], name: &str, max_bytes: u64) -> Result<Option<FloatGrid>, NvdbError> {
    let b = Bytes { b: file };
    let mut at = 0;
    while at < file.len() {
        if !magic(b.u64(at, "a segment header")?) {
            return Err(NvdbError::Magic(at));
        }
        let version = b.u32(at + 8, "a segment header")?;
        if version >> 21 != MAJOR {
            return Err(NvdbError::Version(version >> 21));
        }
        let count = b.u16(at + 12, "a segment header")?;
        let codec = b.u16(at + 14, "a segment header")?;
        at += HEADER;
        let mut metas = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let (meta, next) = read_meta(&b, at)?;
            metas.push(meta);
            at = next;
        }
        for meta in metas {
            let end = usize::try_from(meta.file_size).ok().and_then(|s| at.checked_add(s)).filter(|&e| e <= file.len());
            let end = end.ok_or(NvdbError::Truncated { at: file.len(), what: "a grid's data" })?;
            if meta.name == name {
                return decode(&file[at..end], &meta, codec, max_bytes).map(Some);
            }
            at = end;
        }
    }
    Ok(None)
}

fn read_meta(b: &Bytes, at: usize) -> Result<(Meta, usize), NvdbError> {
    const WHAT: &str = "a grid's record";
    let name_size = b.u32(at + 136, WHAT)? as usize;
    let start = at + META;
    let end = start.checked_add(name_size).filter(|&e| e <= b.b.len());
    let end = end.ok_or(NvdbError::Truncated { at: b.b.len(), what: "a grid's name" })?;
    let raw = &b.b[start..end];
    let name = String::from_utf8_lossy(raw.split(|&c| c == 0).next().unwrap_or_default()).into_owned();
    let meta =
        Meta { grid_size: b.u64(at, WHAT)?, file_size: b.u64(at + 8, WHAT)?, grid_type: b.u32(at + 32, WHAT)?, name };
    Ok((meta, end))
}

/// The grid's bytes as stored, decompressed where they are, then decoded.
fn decode(stored: &[u8], meta: &Meta, codec: u16, max_bytes: u64) -> Result<FloatGrid, NvdbError> {
    let name = &meta.name;
    if meta.grid_type != GRID_TYPE_FLOAT {
        return Err(NvdbError::Type { name: name.clone(), ty: type_name(meta.grid_type).into() });
    }
    if meta.grid_size > max_bytes {
        return Err(NvdbError::TooLarge(name.clone(), meta.grid_size));
    }
    let bytes = match codec {
        0 => stored.to_vec(),
        1 => unzip(stored, meta)?,
        2 => return Err(NvdbError::Codec { name: name.clone(), codec: "BLOSC" }),
        _ => return Err(NvdbError::Codec { name: name.clone(), codec: "an unknown codec" }),
    };
    if bytes.len() as u64 != meta.grid_size {
        let what = format!("{} bytes stored where the record says {}", bytes.len(), meta.grid_size);
        return Err(NvdbError::Damaged { name: name.clone(), what });
    }
    FloatGrid::decode(&bytes, name)
}

fn unzip(stored: &[u8], meta: &Meta) -> Result<Vec<u8>, NvdbError> {
    use std::io::Read;
    let b = Bytes { b: stored };
    let size = b.u64(0, "a ZIP grid's size")?;
    let data = usize::try_from(size).ok().and_then(|s| stored.get(8..8usize.checked_add(s)?));
    let data = data.ok_or(NvdbError::Truncated { at: stored.len(), what: "a ZIP grid" })?;
    let mut out = Vec::new();
    let decoder = flate2::read::ZlibDecoder::new(data);
    let ok = decoder.take(meta.grid_size + 1).read_to_end(&mut out).is_ok();
    if !ok || out.len() as u64 != meta.grid_size {
        return Err(NvdbError::Zip(meta.name.clone()));
    }
    Ok(out)
}

fn type_name(t: u32) -> &'static str {
    const NAMES: [&str; 19] = [
        "unknown", "float", "double", "int16", "int32", "int64", "Vec3f", "Vec3d", "mask", "half", "uint32", "bool",
        "RGBA8", "Fp4", "Fp8", "Fp16", "FpN", "Vec4f", "Vec4d",
    ];
    NAMES.get(t as usize).copied().unwrap_or("unknown")
}

impl FloatGrid {
    /// Decodes a grid's memory image.
    fn decode(bytes: &[u8], name: &str) -> Result<FloatGrid, NvdbError> {
        let b = Bytes { b: bytes };
        const WHAT: &str = "the grid header";
        if !magic(b.u64(0, WHAT)?) {
            return Err(damaged(name, "its header has no \"NanoVDB0\" magic"));
        }
        if b.u32(636, WHAT)? != GRID_TYPE_FLOAT {
            return Err(NvdbError::Type { name: name.into(), ty: type_name(b.u32(636, WHAT)?).into() });
        }
        if !CLASSES.contains(&b.u32(632, WHAT)?) {
            return Err(NvdbError::Class(name.into()));
        }
        let f = |k: usize| b.f32(296 + 4 * k, WHAT);
        let d = |k: usize| b.f64(560 + 8 * k, WHAT);
        let inverse: [f32; 9] = std::array::from_fn(|k| f(9 + k).unwrap_or(f32::NAN));
        let offset = Vec3::new(f(18)?, f(19)?, f(20)?);
        let world_min = DVec3::new(d(0)?, d(1)?, d(2)?);
        let world_max = DVec3::new(d(3)?, d(4)?, d(5)?);
        let finite = inverse.iter().all(|v| v.is_finite()) && offset.is_finite();
        if !finite || !world_min.is_finite() || !world_max.is_finite() {
            return Err(damaged(name, "its map or world box is not finite"));
        }
        let mut grid = FloatGrid {
            inverse,
            offset,
            world_min,
            world_max,
            index_min: [0; 3],
            index_max: [-1; 3],
            background: 0.0,
            roots: Vec::new(),
            uppers: Vec::new(),
            lowers: Vec::new(),
            leaves: Vec::new(),
            maxima: Default::default(),
        };
        grid.read_tree(&b, name)?;
        grid.find_maxima();
        Ok(grid)
    }

    /// The tree header, the root and every node.
    fn read_tree(&mut self, b: &Bytes, name: &str) -> Result<(), NvdbError> {
        const WHAT: &str = "the tree header";
        let level = |k: usize| -> Result<usize, NvdbError> {
            let off = b.u64(GRID + 8 * k, WHAT)?;
            usize::try_from(off)
                .ok()
                .and_then(|o| o.checked_add(GRID))
                .ok_or_else(|| damaged(name, "a node offset overflows"))
        };
        let count = |k: usize| b.u32(GRID + 32 + 4 * k, WHAT).map(|c| c as usize);
        let levels =
            Levels { leaf: (level(0)?, count(0)?), lower: (level(1)?, count(1)?), upper: (level(2)?, count(2)?) };
        for (start, n, size) in
            [(levels.leaf.0, levels.leaf.1, LEAF_SIZE), (levels.lower.0, levels.lower.1, LOWER.size())]
                .into_iter()
                .chain([(levels.upper.0, levels.upper.1, UPPER.size())])
        {
            let end = n.checked_mul(size).and_then(|s| s.checked_add(start)).filter(|&e| e <= b.b.len());
            if n > 0 && end.is_none() {
                return Err(damaged(name, "its nodes run past its end"));
            }
        }
        let root = level(3)?;
        self.read_root(b, root, &levels, name)?;
        self.uppers = (0..levels.upper.1)
            .map(|k| read_internal(b, levels.upper.0 + k * UPPER.size(), UPPER, levels.lower, LOWER.size(), name))
            .collect::<Result<_, _>>()?;
        self.lowers = (0..levels.lower.1)
            .map(|k| read_internal(b, levels.lower.0 + k * LOWER.size(), LOWER, levels.leaf, LEAF_SIZE, name))
            .collect::<Result<_, _>>()?;
        self.leaves = (0..levels.leaf.1)
            .map(|k| {
                let at = levels.leaf.0 + k * LEAF_SIZE + LEAF_VALUES_AT;
                let mut v = [0f32; 512];
                for (i, x) in v.iter_mut().enumerate() {
                    *x = b.f32(at + 4 * i, "a leaf")?;
                }
                Ok(v)
            })
            .collect::<Result<_, NvdbError>>()?;
        Ok(())
    }

    fn read_root(&mut self, b: &Bytes, root: usize, levels: &Levels, name: &str) -> Result<(), NvdbError> {
        const WHAT: &str = "the root";
        for k in 0..3 {
            self.index_min[k] = b.i32(root + 4 * k, WHAT)?;
            self.index_max[k] = b.i32(root + 12 + 4 * k, WHAT)?;
        }
        let tiles = b.u32(root + 24, WHAT)? as usize;
        self.background = b.f32(root + 28, WHAT)?;
        let end = tiles.checked_mul(ROOT_TILE).and_then(|s| s.checked_add(root + ROOT)).filter(|&e| e <= b.b.len());
        if end.is_none() {
            return Err(damaged(name, "its root table runs past its end"));
        }
        for k in 0..tiles {
            let at = root + ROOT + k * ROOT_TILE;
            let key = b.u64(at, WHAT)?;
            let field = |shift: u32| ((((key >> shift) & ((1 << 21) - 1)) as u32) << 12) as i32;
            let origin = [field(42), field(21), field(0)];
            let child = b.i64(at + 8, WHAT)?;
            let slot = if child == 0 {
                Slot::Value(b.f32(at + 20, WHAT)?)
            } else {
                Slot::Child(node_index(root, child, levels.upper, UPPER.size(), name)?)
            };
            self.roots.push((origin, slot));
        }
        self.roots.sort_by_key(|r| r.0);
        if self.roots.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err(damaged(name, "two root tiles share an origin"));
        }
        Ok(())
    }

    /// The value at index point `p` (the background outside every node).
    pub fn value(&self, p: [i32; 3]) -> f32 {
        let origin = p.map(|c| c & !4095);
        let Ok(k) = self.roots.binary_search_by_key(&origin, |r| r.0) else { return self.background };
        let upper = match self.roots[k].1 {
            Slot::Value(v) => return v,
            Slot::Child(i) => &self.uppers[i as usize],
        };
        let lower = match upper[UPPER.offset(p)] {
            Slot::Value(v) => return v,
            Slot::Child(i) => &self.lowers[i as usize],
        };
        match lower[LOWER.offset(p)] {
            Slot::Value(v) => v,
            Slot::Child(i) => self.leaves[i as usize][(((p[0] & 7) << 6) | ((p[1] & 7) << 3) | (p[2] & 7)) as usize],
        }
    }

    /// World (the medium's space) to index space, as NanoVDB's `worldToIndexF`.
    pub fn to_index(&self, p: Vec3) -> Vec3 {
        let q = p - self.offset;
        let m = &self.inverse;
        Vec3::new(
            q.x.mul_add(m[0], q.y.mul_add(m[1], q.z * m[2])),
            q.x.mul_add(m[3], q.y.mul_add(m[4], q.z * m[5])),
            q.x.mul_add(m[6], q.y.mul_add(m[7], q.z * m[8])),
        )
    }

    /// The trilinear interpolation of the voxel values at index point `x` (NanoVDB's
    /// first-order `SampleFromVoxels`: voxel centres at integer points).
    pub fn sample(&self, x: Vec3) -> f32 {
        let i = x.floor();
        let w = x - i;
        let (x, y, z) = (i.x as i32, i.y as i32, i.z as i32);
        let at =
            |dx: i32, dy: i32, dz: i32| self.value([x.saturating_add(dx), y.saturating_add(dy), z.saturating_add(dz)]);
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let x0 = lerp(lerp(at(0, 0, 0), at(0, 0, 1), w.z), lerp(at(0, 1, 0), at(0, 1, 1), w.z), w.y);
        let x1 = lerp(lerp(at(1, 0, 0), at(1, 0, 1), w.z), lerp(at(1, 1, 0), at(1, 1, 1), w.z), w.y);
        lerp(x0, x1, w.x)
    }

    /// An upper bound of the values over the voxels from `lo` to `hi` (inclusive): the
    /// largest of them, or the background where that is larger. Nodes wholly inside
    /// the range answer with their own largest value, so the cost follows the range's
    /// surface, not its volume (a damaged file's huge box cannot stall it).
    pub fn max_over(&self, lo: [i32; 3], hi: [i32; 3]) -> f32 {
        let range = Range { lo: lo.map(i64::from), hi: hi.map(i64::from) };
        let roots = self.roots.iter().filter(|r| range.meets(r.0, ROOT_LOG2));
        roots.fold(self.background, |m, &(origin, slot)| m.max(self.slot_max(slot, 2, origin, &range)))
    }

    /// The largest value of `slot`, a child at `level` (2 upper, 1 lower, 0 leaf) whose
    /// box starts at `origin`, over `range`.
    fn slot_max(&self, slot: Slot, level: usize, origin: [i32; 3], range: &Range) -> f32 {
        let i = match slot {
            Slot::Value(v) => return v,
            Slot::Child(i) => i as usize,
        };
        let extent = [3, LOWER.log2 + LOWER.child_log2, UPPER.log2 + UPPER.child_log2][level];
        if range.holds(origin, extent) {
            return self.maxima[level][i];
        }
        let (shape, log2_entry, table) = match level {
            0 => (3, 0, None),
            1 => (LOWER.log2, LOWER.child_log2, Some(&self.lowers[i])),
            _ => (UPPER.log2, UPPER.child_log2, Some(&self.uppers[i])),
        };
        let span = |a: usize| {
            let first = ((range.lo[a] - origin[a] as i64) >> log2_entry).max(0);
            let last = ((range.hi[a] - origin[a] as i64) >> log2_entry).min((1 << shape) - 1);
            first..=last
        };
        let mut m = f32::NEG_INFINITY;
        for x in span(0) {
            for y in span(1) {
                for z in span(2) {
                    let n = ((x << (2 * shape)) | (y << shape) | z) as usize;
                    m = m.max(match table {
                        None => self.leaves[i][n],
                        Some(t) => {
                            let o = [x, y, z].map(|k| (k << log2_entry) as i32);
                            let child = [origin[0] + o[0], origin[1] + o[1], origin[2] + o[2]];
                            self.slot_max(t[n], level - 1, child, range)
                        }
                    });
                }
            }
        }
        m
    }

    fn find_maxima(&mut self) {
        let leaves: Vec<f32> = self.leaves.iter().map(|l| l.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v))).collect();
        let fold = |tables: &[Vec<Slot>], below: &[f32]| -> Vec<f32> {
            let slot = |s: &Slot| match *s {
                Slot::Value(v) => v,
                Slot::Child(i) => below[i as usize],
            };
            tables.iter().map(|t| t.iter().map(slot).fold(f32::NEG_INFINITY, f32::max)).collect()
        };
        let lowers = fold(&self.lowers, &leaves);
        let uppers = fold(&self.uppers, &lowers);
        self.maxima = [leaves, lowers, uppers];
    }

    /// The largest value anywhere.
    pub fn max_value(&self) -> f32 {
        self.values().fold(f32::NEG_INFINITY, f32::max)
    }

    /// Every value the grid holds: the background, tiles and voxels.
    pub fn values(&self) -> impl Iterator<Item = f32> + '_ {
        let tiles = self.roots.iter().map(|r| r.1);
        let internal = self.uppers.iter().chain(&self.lowers).flat_map(|t| t.iter().copied());
        let values = tiles.chain(internal).filter_map(|s| if let Slot::Value(v) = s { Some(v) } else { None });
        let leaves = self.leaves.iter().flat_map(|l| l.iter().copied());
        std::iter::once(self.background).chain(values).chain(leaves)
    }
}

/// A box of index points, both ends inclusive.
struct Range {
    lo: [i64; 3],
    hi: [i64; 3],
}

impl Range {
    /// Whether it meets the box of 2^log2 voxels a side at `origin`.
    fn meets(&self, origin: [i32; 3], log2: u32) -> bool {
        (0..3).all(|a| (origin[a] as i64) <= self.hi[a] && origin[a] as i64 + (1 << log2) > self.lo[a])
    }

    /// Whether it holds the whole box of 2^log2 voxels a side at `origin`.
    fn holds(&self, origin: [i32; 3], log2: u32) -> bool {
        (0..3).all(|a| (origin[a] as i64) >= self.lo[a] && origin[a] as i64 + (1 << log2) - 1 <= self.hi[a])
    }
}

/// Where each level's nodes begin (bytes from the grid's start) and how many there are.
struct Levels {
    leaf: (usize, usize),
    lower: (usize, usize),
    upper: (usize, usize),
}

fn damaged(name: &str, what: &str) -> NvdbError {
    NvdbError::Damaged { name: name.into(), what: what.into() }
}

/// The index among the nodes of the level `(start, count)` (each `size` bytes) of the
/// node `offset` bytes from `from`.
fn node_index(
    from: usize,
    offset: i64,
    (start, count): (usize, usize),
    size: usize,
    name: &str,
) -> Result<u32, NvdbError> {
    let at = i64::try_from(from).ok().and_then(|f| f.checked_add(offset)).and_then(|a| usize::try_from(a).ok());
    let k = at.and_then(|a| a.checked_sub(start)).filter(|d| d % size == 0).map(|d| d / size);
    match k {
        Some(k) if k < count => Ok(k as u32),
        _ => Err(damaged(name, "a child link points outside its level's nodes")),
    }
}

/// An internal node's table: values and links into the level below.
fn read_internal(
    b: &Bytes,
    at: usize,
    shape: Node,
    children: (usize, usize),
    child_size: usize,
    name: &str,
) -> Result<Vec<Slot>, NvdbError> {
    const WHAT: &str = "an internal node";
    let mask_at = at + shape.child_mask_at();
    (0..shape.entries())
        .map(|n| {
            let word = b.u64(mask_at + 8 * (n / 64), WHAT)?;
            let entry = at + shape.table_at + 8 * n;
            if word >> (n % 64) & 1 == 1 {
                Ok(Slot::Child(node_index(at, b.i64(entry, WHAT)?, children, child_size, name)?))
            } else {
                Ok(Slot::Value(b.f32(entry, WHAT)?))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const PUFF: &[u8] = include_bytes!("../../../tests/data/nanovdb/puff.nvdb");

    /// The generator's density (`tools/make_nanovdb_puff.py`), 0 outside the ball.
    fn density_at(i: i32, j: i32, k: i32) -> f32 {
        let r = ((i * i + k * k) as f64 + (j as f64 * 1.2).powi(2)).sqrt();
        if r >= 14.0 {
            return 0.0;
        }
        ((1.0 - r / 14.0).powf(1.5) * (1.0 + 0.5 * (0.7 * i as f64).sin() * (0.5 * k as f64).cos())) as f32
    }

    /// The same file with its grids stored uncompressed (segment by segment).
    fn uncompressed(zip: &[u8]) -> Vec<u8> {
        let b = Bytes { b: zip };
        let (mut at, mut out) = (0, Vec::new());
        while at < zip.len() {
            let count = b.u16(at + 12, "").unwrap() as usize;
            let mut head = zip[at..at + HEADER].to_vec();
            head[14..16].copy_from_slice(&0u16.to_le_bytes());
            at += HEADER;
            let mut metas = Vec::new();
            for _ in 0..count {
                let (meta, next) = read_meta(&b, at).unwrap();
                let mut m = zip[at..next].to_vec();
                m[8..16].copy_from_slice(&meta.grid_size.to_le_bytes());
                m[168..170].copy_from_slice(&0u16.to_le_bytes());
                head.extend(m);
                metas.push(meta);
                at = next;
            }
            for meta in metas {
                head.extend(unzip(&zip[at..], &meta).unwrap());
                at += meta.file_size as usize;
            }
            out.extend(head);
        }
        out
    }

    #[test]
    fn the_puff_reads_as_it_was_written_zipped_or_not() {
        for bytes in [PUFF.to_vec(), uncompressed(PUFF)] {
            let g = read_grid(&bytes, "density", u64::MAX).unwrap().expect("a density grid");
            for (i, j, k) in [(0, 0, 0), (3, -2, 5), (-13, 0, 0), (7, 7, 7), (-9, 4, -6), (14, 0, 0), (40, 40, 40)] {
                assert!((g.value([i, j, k]) - density_at(i, j, k)).abs() < 1e-6, "({i}, {j}, {k})");
            }
            // The slab: pruned into tiles of the lower nodes.
            assert_eq!(g.value([20, -20, 5]), 0.3);
            assert_eq!((g.index_min, g.index_max), ([-13, -24, -13], [31, 11, 15]));
            assert!((g.world_min - DVec3::new(-0.55, -0.3, -0.65)).abs().max_element() < 1e-9);
            assert!((g.to_index(Vec3::new(0.1, 0.9, 0.0))).abs().max_element() < 1e-5);
            assert!((g.to_index(Vec3::new(0.2, 0.85, 0.15)) - Vec3::new(2.0, -1.0, 3.0)).abs().max_element() < 1e-4);
            // Trilinear between voxel centres.
            let mid = g.sample(Vec3::new(0.5, 0.0, 0.0));
            assert!((mid - 0.5 * (density_at(0, 0, 0) + density_at(1, 0, 0))).abs() < 1e-6);
            assert_eq!(g.max_over([20, -20, 2], [21, -19, 3]), 0.3);
            assert!((g.max_value() - (-16..=16).map(|i| density_at(i, 0, 0)).fold(0.3, f32::max)).abs() < 0.2);
            let t = read_grid(&bytes, "temperature", u64::MAX).unwrap().expect("a temperature grid");
            assert!((t.value([0, 0, 0]) - 2900.0).abs() < 1e-3 && t.value([9, 0, 0]) == 0.0);
            assert!(read_grid(&bytes, "velocity", u64::MAX).unwrap().is_none());
        }
    }

    #[test]
    fn range_maxima_agree_with_every_voxel_in_the_range() {
        let g = read_grid(PUFF, "density", u64::MAX).unwrap().unwrap();
        let mut rng = crate::sampling::Rng::new(7);
        let mut next = |n: u32| (rng.next_u32() % n) as i32;
        for _ in 0..300 {
            let lo = [next(70) - 35, next(70) - 35, next(70) - 35];
            let hi = [lo[0] + next(24), lo[1] + next(24), lo[2] + next(24)];
            let mut m = g.background;
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        m = m.max(g.value([x, y, z]));
                    }
                }
            }
            assert_eq!(g.max_over(lo, hi), m, "{lo:?}..{hi:?}");
        }
        // The whole index space answers at once.
        assert_eq!(g.max_over([i32::MIN; 3], [i32::MAX; 3]), g.max_value());
    }

    /// The first grid record starts here, its grid's bytes at `grid` (uncompressed file).
    const RECORD: usize = HEADER;

    fn patched(bytes: &[u8], at: usize, with: &[u8]) -> Vec<u8> {
        let mut b = bytes.to_vec();
        b[at..at + with.len()].copy_from_slice(with);
        b
    }

    #[test]
    fn damaged_files_are_errors_that_say_what_is_wrong() {
        let raw = uncompressed(PUFF);
        let density = |b: &[u8]| read_grid(b, "density", u64::MAX).map(|g| g.is_some());
        assert_eq!(density(&raw[..14]), Err(NvdbError::Truncated { at: 14, what: "a segment header" }));
        assert_eq!(density(&patched(&raw, 0, b"NotVDB00")), Err(NvdbError::Magic(0)));
        assert_eq!(density(&patched(&raw, 8, &(31u32 << 21).to_le_bytes())), Err(NvdbError::Version(31)));
        let blosc = patched(PUFF, 14, &2u16.to_le_bytes());
        assert!(matches!(density(&blosc), Err(NvdbError::Codec { codec: "BLOSC", .. })));
        let double = patched(&raw, RECORD + 32, &2u32.to_le_bytes());
        assert!(matches!(density(&double), Err(NvdbError::Type { ref ty, .. }) if ty == "double"));
        // NanoVDB's tool writes one segment per grid: density's bytes follow its record.
        let meta_len = META + 8; // "density\0"
        let grid = HEADER + meta_len;
        let level_set = patched(&raw, grid + 632, &1u32.to_le_bytes());
        assert!(matches!(density(&level_set), Err(NvdbError::Class(_))));
        assert!(matches!(read_grid(&raw, "density", 1000), Err(NvdbError::TooLarge(..))));
        // The root's first tile links to an upper node half a node away.
        let root = grid + GRID + b_u64(&raw, grid + GRID + 24) as usize;
        let bad_link = patched(&raw, root + ROOT + 8, &(ROOT as i64 + 4).to_le_bytes());
        assert!(matches!(density(&bad_link), Err(NvdbError::Damaged { .. })), "{:?}", density(&bad_link).err());
        let zip_short = patched(PUFF, HEADER + meta_len + 8, &[0; 16]);
        assert!(matches!(density(&zip_short), Err(NvdbError::Zip(_))));
    }

    fn b_u64(b: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
    }

    #[test]
    fn truncated_and_scrambled_files_never_panic() {
        let raw = uncompressed(PUFF);
        for bytes in [PUFF, &raw[..]] {
            for len in (0..bytes.len()).step_by(bytes.len() / 97 + 1).chain([bytes.len() - 1]) {
                let r = read_grid(&bytes[..len], "temperature", u64::MAX);
                assert!(r.is_err() || len == 0, "{len} of {} bytes: {:?}", bytes.len(), r.map(|g| g.is_some()));
            }
        }
        // Flips in the headers and the first nodes, where the structure lives.
        let mut rng = crate::sampling::Rng::new(11);
        let mut next = || rng.next_u32();
        for _ in 0..48 {
            let mut b = raw.clone();
            let at = (next() % 12_000) as usize;
            b[at] ^= 1 << (next() % 8);
            if let Ok(Some(g)) = read_grid(&b, "density", u64::MAX) {
                let _ = (g.max_value(), g.sample(Vec3::splat(0.3)), g.max_over(g.index_min, g.index_max));
            }
        }
    }
}
