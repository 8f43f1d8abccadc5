//! The SPPM photon lookup grid (and VCM's, of light vertices): sites binned into a
//! uniform grid, its cells hashed into buckets, each site once in the cell of its
//! centre or in every cell its radius reaches ([`Binning`]). Built in parallel and
//! deterministically: every bucket lists its entries (cell, site, pixel) in pixel order
//! whatever the thread count, so lookups find their sites in the same order and the
//! image is bit-identical.
//!
//! The build is a two-level stable counting sort. Pixels are cut into fixed chunks;
//! each chunk lists its entries grouped by the top bits of the bucket ("super
//! buckets"). Then each super bucket, in parallel, gathers its entries chunk by chunk
//! and sorts them by bucket into its own slice of the table.

use glam::Vec3;
use rayon::prelude::*;

/// Pixels per build chunk.
const CHUNK: usize = 8192;
/// Super buckets (a power of two): the parallel grain of the second sort level.
const SUPER: usize = 256;

/// A visible point as the grid sees it: where, and how far photons reach it from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Site {
    pub p: Vec3,
    pub radius: f32,
}

impl Site {
    /// Whether `p` lies within the radius.
    #[inline(always)]
    pub fn reaches(&self, p: Vec3) -> bool {
        (self.p - p).length_squared() <= self.radius * self.radius
    }
}

/// Items in groups, each group keeping the items' order (a stable counting sort).
pub struct Grouped<T> {
    items: Vec<T>,
    /// Group g holds `items[starts[g]..starts[g + 1]]`.
    starts: Vec<u32>,
}

impl<T: Copy + Default> Grouped<T> {
    pub fn new(items: Vec<T>, groups: usize, group: impl Fn(&T) -> usize) -> Grouped<T> {
        let mut starts = vec![0u32; groups + 1];
        for it in &items {
            starts[group(it) + 1] += 1;
        }
        for g in 0..groups {
            starts[g + 1] += starts[g];
        }
        let mut next = starts.clone();
        let mut sorted = vec![T::default(); items.len()];
        for it in items {
            let g = group(&it);
            sorted[next[g] as usize] = it;
            next[g] += 1;
        }
        Grouped { items: sorted, starts }
    }

    pub fn group(&self, g: usize) -> &[T] {
        &self.items[self.starts[g] as usize..self.starts[g + 1] as usize]
    }
}

impl Grouped<(u32, Vec3)> {
    /// Lists of (pixel, value) (photon deposits, light-tracing splats) each grouped, in
    /// parallel, by ranges of `span` pixels; returns them and the span. Range r then
    /// reads, list by list and in each list's order, the items of pixels r·span up to
    /// (r+1)·span: a reduction in a fixed order whatever the thread count.
    pub fn by_pixel_range(lists: Vec<Vec<(u32, Vec3)>>, pixels: usize, ranges: usize) -> (Vec<Self>, usize) {
        let span = pixels.div_ceil(ranges).max(1);
        (lists.into_par_iter().map(|l| Grouped::new(l, ranges, |d| d.0 as usize / span)).collect(), span)
    }
}

/// How a grid bins its sites.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binning {
    /// In every cell its ball's box overlaps (at most 8, cells being twice the
    /// largest radius): a point looks in its own cell only. Beams walk the cells along
    /// a segment, which needs this.
    Overlap,
    /// In the cell holding its centre only: a point looks in every cell its box of
    /// the largest radius overlaps (8, cells being twice that radius). One entry a
    /// site, so the build is cheap: SPPM's visible points and VCM's light vertices (on
    /// f16-9a overlap binning made 6.9 entries a site, and the build took 2.5 times as
    /// long).
    Centre,
}

/// Sites binned into a uniform grid: entries grouped by a hash of the cell (pixel
/// order within a bucket, so deterministic).
pub struct Grid {
    lo: Vec3,
    inv_cell: Vec3,
    res: [u64; 3],
    binning: Binning,
    /// The largest radius, a little enlarged: how far a centre-binned lookup looks.
    reach: f32,
    /// Bucket b holds `entries[offsets[b]..offsets[b + 1]]`.
    offsets: Vec<u32>,
    entries: Vec<Entry>,
}

/// A site binned in a cell. The site comes along, so that [`Grid::gather_within`]
/// tests distances on the bucket's own memory and its caller reads a pixel's large
/// record only for sites in reach: a photon on f16-9a looked at 29 sites for 4 in
/// reach, each a random read.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Entry {
    /// The cell's key in two halves: 28 bytes an entry rather than 32.
    key: [u32; 2],
    site: Site,
    pixel: u32,
}

impl Entry {
    fn new(key: u64, site: Site, pixel: u32) -> Entry {
        Entry { key: [key as u32, (key >> 32) as u32], site, pixel }
    }

    fn key(&self) -> u64 {
        self.key[0] as u64 | (self.key[1] as u64) << 32
    }
}

impl Grid {
    /// (cell, pixel) pairs stored: at most 8 per site, whatever the radii.
    pub fn entries(&self) -> usize {
        self.entries.len()
    }

    /// `sites[i]` is pixel i's visible point, if photons should reach it. `None` when
    /// there is none.
    pub fn build(sites: &[Option<Site>], binning: Binning) -> Option<Grid> {
        let (lo, hi, max_r) = bounds(sites)?;
        let diag = hi - lo;
        let max_diag = diag.max_element().max(f32::MIN_POSITIVE);
        // Cells twice the largest radius: each r-box overlaps at most 2 cells per axis.
        let base = (max_diag / (2.0 * max_r)).clamp(1.0, (1u32 << 20) as f32);
        let res = [0, 1, 2].map(|a| ((base * diag[a] / max_diag) as u64).clamp(1, 1 << 20));
        let inv_cell =
            Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32) / diag.max(Vec3::splat(f32::MIN_POSITIVE));
        // A margin over the largest radius, for a distance test rounded in f32.
        let reach = max_r * (1.0 + 1e-4);
        let mut grid = Grid { lo, inv_cell, res, binning, reach, offsets: Vec::new(), entries: Vec::new() };
        let total: usize =
            sites.par_chunks(CHUNK).map(|c| c.iter().flatten().map(|s| grid.overlap_count(s)).sum::<usize>()).sum();
        let buckets = total.next_power_of_two().max(SUPER);
        let shift = buckets.trailing_zeros() - SUPER.trailing_zeros();
        let chunks: Vec<Grouped<Entry>> = sites
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                // One entry a site when centre-binned: room for all at once.
                let mut out = Vec::with_capacity(if binning == Binning::Centre { chunk.len() } else { 0 });
                for (k, s) in chunk.iter().enumerate() {
                    if let Some(s) = s {
                        grid.overlapped_cells(s, |key| out.push(Entry::new(key, *s, (c * CHUNK + k) as u32)));
                    }
                }
                Grouped::new(out, SUPER, |e| bucket(e.key(), buckets) >> shift)
            })
            .collect();
        (grid.offsets, grid.entries) = sort_by_bucket(&chunks, total, buckets);
        Some(grid)
    }

    fn cell(&self, p: Vec3) -> [u64; 3] {
        let c = (p - self.lo) * self.inv_cell;
        // Through u32, which holds every resolution (at most 2^20): a float's
        // conversion to u64 takes a dozen instructions on x86-64, to u32 one.
        [0, 1, 2].map(|a| (c[a].max(0.0) as u32).min(self.res[a] as u32 - 1) as u64)
    }

    fn key(&self, c: [u64; 3]) -> u64 {
        c[0] + self.res[0] * (c[1] + self.res[1] * c[2])
    }

    /// How many cells a site is binned in.
    fn overlap_count(&self, s: &Site) -> usize {
        if self.binning == Binning::Centre {
            return 1;
        }
        let (a, b) = (self.cell(s.p - s.radius), self.cell(s.p + s.radius));
        (0..3).map(|k| (b[k] - a[k] + 1) as usize).product()
    }

    /// Calls `f` with the key of every cell a site is binned in.
    fn overlapped_cells(&self, s: &Site, mut f: impl FnMut(u64)) {
        if self.binning == Binning::Centre {
            return f(self.key(self.cell(s.p)));
        }
        self.box_cells(s.p - s.radius, s.p + s.radius, f)
    }

    /// Calls `f` with the key of every cell the box from `lo` to `hi` overlaps.
    fn box_cells(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(u64)) {
        let (a, b) = (self.cell(lo), self.cell(hi));
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    f(self.key([x, y, z]));
                }
            }
        }
    }

    /// Calls `f(pixel, site)` for every pixel whose site's ball may hold `p`: those
    /// binned in the cell containing `p` (overlap binning; none outside the grid), or
    /// in the cells the box of the largest radius about `p` overlaps (centre binning),
    /// cell by cell, in pixel order within a cell. Whether there was any.
    pub fn gather_sites(&self, p: Vec3, mut f: impl FnMut(u32, &Site)) -> bool {
        let mut f = |e: &Entry| f(e.pixel, &e.site);
        let c = (p - self.lo) * self.inv_cell;
        if self.binning == Binning::Centre {
            let margin = self.reach * self.inv_cell;
            if (0..3).any(|a| c[a] < -margin[a] || c[a] >= self.res[a] as f32 + margin[a]) {
                return false;
            }
            // The cells' keys are listed first and the cache asked for their buckets,
            // so that the buckets' misses overlap; then the cells are read in the same
            // order. (Cells twice the reach give 8; rounding may give a few more.)
            let (mut keys, mut n) = ([0u64; 27], 0);
            let (lo, hi) = (p - self.reach, p + self.reach);
            self.box_cells(lo, hi, |key| {
                if let Some(k) = keys.get_mut(n) {
                    crate::memory::prefetch(&self.offsets[bucket(key, self.offsets.len() - 1)]);
                    *k = key;
                }
                n += 1;
            });
            let mut any = false;
            match keys.get(..n) {
                Some(keys) => keys.iter().for_each(|&key| any |= self.cell_entries(key, &mut f)),
                None => self.box_cells(lo, hi, |key| any |= self.cell_entries(key, &mut f)),
            }
            return any;
        }
        if (0..3).any(|a| c[a] < 0.0 || c[a] >= self.res[a] as f32) {
            return false;
        }
        self.cell_entries(self.key(self.cell(p)), &mut f)
    }

    /// Calls `f` for every entry binned in the cell with this key; whether there was any.
    fn cell_entries(&self, key: u64, mut f: impl FnMut(&Entry)) -> bool {
        let b = bucket(key, self.offsets.len() - 1);
        let range = self.offsets[b] as usize..self.offsets[b + 1] as usize;
        let mut any = false;
        for e in self.entries[range].iter().filter(|e| e.key() == key) {
            f(e);
            any = true;
        }
        any
    }

    /// [`Grid::gather_sites`] for the pixels whose site's ball holds `p` (its boundary
    /// included); whether the cells looked in held any pixel, in reach or not.
    pub fn gather_within(&self, p: Vec3, mut f: impl FnMut(u32)) -> bool {
        self.gather_sites(p, |pixel, site| {
            if site.reaches(p) {
                f(pixel)
            }
        })
    }

    /// [`Grid::gather_within`] in two steps: the pixels in reach are listed, each
    /// handed to `prefetch` (which asks the cache for what `f` will read of it), then
    /// handed to `f` in the same order. Their cache misses overlap rather than follow
    /// each other.
    pub fn gather_within_prefetched(&self, p: Vec3, prefetch: impl Fn(u32), f: impl FnMut(u32)) -> bool {
        let near = |pixel, site: &Site| {
            let near = site.reaches(p);
            if near {
                prefetch(pixel);
            }
            near
        };
        self.gather_picked(p, near, f)
    }

    /// [`Grid::gather_sites`] in two steps: `pick` sees every entry and keeps some
    /// (asking the cache for what `f` will read of them); then `f` gets the kept ones,
    /// in the same order. Whether the cells looked in held any entry.
    pub fn gather_picked(&self, p: Vec3, mut pick: impl FnMut(u32, &Site) -> bool, mut f: impl FnMut(u32)) -> bool {
        const LISTED: usize = 32;
        let (mut listed, mut count, mut more) = ([0u32; LISTED], 0, Vec::new());
        let any = self.gather_sites(p, |pixel, site| {
            if !pick(pixel, site) {
                return;
            }
            match listed.get_mut(count) {
                Some(slot) => (*slot, count) = (pixel, count + 1),
                None => more.push(pixel),
            }
        });
        listed[..count].iter().chain(&more).for_each(|&pixel| f(pixel));
        any
    }
}

impl Grid {
    /// The key of the cell holding `p` (points outside count in the nearest cell).
    pub fn key_of(&self, p: Vec3) -> u64 {
        self.key(self.cell(p))
    }

    /// Calls `f(cell key, site)` for every site binned in every cell the segment
    /// `o + t·d`, t in `t0..t1`, crosses (a 3D DDA, cells in order along the ray).
    /// Only overlap binning puts every site in each cell its ball reaches.
    pub fn along(&self, o: Vec3, d: Vec3, (t0, t1): (f32, f32), mut f: impl FnMut(u64, u32)) {
        let (co, cd) = ((o - self.lo) * self.inv_cell, d * self.inv_cell);
        let res = [0, 1, 2].map(|a| self.res[a] as f32);
        let (mut ta, mut tb) = (t0, t1);
        for a in 0..3 {
            if cd[a] == 0.0 {
                if co[a] < 0.0 || co[a] >= res[a] {
                    return;
                }
                continue;
            }
            let (n, far) = ((0.0 - co[a]) / cd[a], (res[a] - co[a]) / cd[a]);
            (ta, tb) = (ta.max(n.min(far)), tb.min(n.max(far)));
        }
        if ta.partial_cmp(&tb).is_none_or(|o| o.is_gt()) || !tb.is_finite() {
            return;
        }
        let p = co + cd * ta;
        let (mut cell, mut next, mut delta, mut step) = ([0i64; 3], [f32::INFINITY; 3], [0f32; 3], [0i64; 3]);
        for a in 0..3 {
            cell[a] = (p[a].floor() as i64).clamp(0, self.res[a] as i64 - 1);
            if cd[a] > 0.0 {
                (step[a], delta[a]) = (1, 1.0 / cd[a]);
                next[a] = ta + (cell[a] as f32 + 1.0 - p[a]) / cd[a];
            } else if cd[a] < 0.0 {
                (step[a], delta[a]) = (-1, -1.0 / cd[a]);
                next[a] = ta + (cell[a] as f32 - p[a]) / cd[a];
            }
        }
        loop {
            let key = self.key(cell.map(|c| c as u64));
            self.cell_entries(key, |e| f(key, e.pixel));
            let a = (0..3).fold(0, |m, a| if next[a] < next[m] { a } else { m });
            if next[a] >= tb {
                return;
            }
            cell[a] += step[a];
            if !(0..self.res[a] as i64).contains(&cell[a]) {
                return;
            }
            next[a] += delta[a];
        }
    }
}

fn bucket(key: u64, buckets: usize) -> usize {
    (key.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 32) as usize & (buckets - 1)
}

/// The box around every site's r-ball, and the largest radius; `None` without sites.
fn bounds(sites: &[Option<Site>]) -> Option<(Vec3, Vec3, f32)> {
    let empty = (Vec3::INFINITY, Vec3::NEG_INFINITY, 0f32);
    let join = |a: (Vec3, Vec3, f32), b: (Vec3, Vec3, f32)| (a.0.min(b.0), a.1.max(b.1), a.2.max(b.2));
    let (lo, hi, max_r) = sites
        .par_chunks(CHUNK)
        .map(|c| c.iter().flatten().fold(empty, |acc, s| join(acc, (s.p - s.radius, s.p + s.radius, s.radius))))
        .reduce(|| empty, join);
    (max_r > 0.0 && lo.x <= hi.x).then_some((lo, hi, max_r))
}

/// The second level: each super bucket gathers its pairs from the chunks in order and
/// sorts them by bucket into its own slice of the table. Returns (offsets, entries).
fn sort_by_bucket(chunks: &[Grouped<Entry>], total: usize, buckets: usize) -> (Vec<u32>, Vec<Entry>) {
    // Filled on all threads: `vec!` writes a struct's copies on one (and takes the
    // fresh pages' faults there), a fifth of a 700,000-site build.
    let mut entries = Vec::with_capacity(total);
    entries.par_extend(rayon::iter::repeat_n(Entry::default(), total));
    let mut offsets = vec![0u32; buckets + 1];
    offsets[buckets] = total as u32;
    let mut slices = Vec::with_capacity(SUPER);
    let (mut rest, mut start) = (entries.as_mut_slice(), 0usize);
    for s in 0..SUPER {
        let size: usize = chunks.iter().map(|c| c.group(s).len()).sum();
        let (mine, tail) = rest.split_at_mut(size);
        slices.push((s, start, mine));
        (rest, start) = (tail, start + size);
    }
    slices.into_par_iter().zip(offsets[..buckets].par_chunks_mut(buckets / SUPER)).for_each(
        |((s, start, out), offs)| {
            let mask = offs.len() - 1;
            let low = |key: u64| bucket(key, buckets) & mask;
            for e in chunks.iter().flat_map(|c| c.group(s)) {
                offs[low(e.key())] += 1;
            }
            let mut at = start as u32;
            for o in offs.iter_mut() {
                (*o, at) = (at, at + *o);
            }
            let mut next = offs.to_vec();
            for e in chunks.iter().flat_map(|c| c.group(s)) {
                let b = low(e.key());
                out[(next[b] - start as u32) as usize] = *e;
                next[b] += 1;
            }
        },
    );
    (offsets, entries)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn sites(n: usize, seed: u64) -> Vec<Option<Site>> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|_| {
                let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform() * 0.1) * 10.0;
                // Some pixels without a visible point, radii over two orders of magnitude.
                (rng.uniform() > 0.1).then(|| Site { p, radius: 0.01 + 0.3 * rng.uniform().powi(4) })
            })
            .collect()
    }

    /// Sites spread over 1e-3…1e4 with radii far too large or far too small: at most 8
    /// entries a site and no more than 2^20 cells an axis, so memory stays linear in the
    /// pixels whatever the radius; and gathering still finds the sites it should.
    #[test]
    fn the_grid_stays_linear_in_the_sites_for_any_radius() {
        let mut rng = Rng::new(4);
        let pts: Vec<Vec3> = (0..5000)
            .map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()).map(|c| 10f32.powf(7.0 * c - 3.0)))
            .collect();
        for (radius, binning) in [1e4, 1.0, 1e-9, f32::MIN_POSITIVE].into_iter().flat_map(|r| BINNINGS.map(|b| (r, b)))
        {
            let sites: Vec<Option<Site>> = pts.iter().map(|&p| Some(Site { p, radius })).collect();
            let Some(grid) = Grid::build(&sites, binning) else { panic!("no grid") };
            let most = if binning == Binning::Centre { 1 } else { 8 };
            assert!(grid.entries() <= most * sites.len(), "radius {radius}: {} entries", grid.entries());
            assert!(grid.res.iter().all(|&r| r <= 1 << 20), "radius {radius}: {:?}", grid.res);
            for (i, &p) in pts.iter().enumerate().step_by(97) {
                let mut found = false;
                grid.gather_sites(p, |j, _| found |= j == i as u32);
                assert!(found, "radius {radius}: site {i} at {p:?} not found at its own position");
            }
        }
    }

    const BINNINGS: [Binning; 2] = [Binning::Overlap, Binning::Centre];

    /// Each site once, and with overlap binning (one cell) in pixel order.
    #[test]
    fn gather_finds_every_site_whose_ball_holds_the_point_once() {
        let sites = sites(3 * CHUNK + 17, 5);
        for binning in BINNINGS {
            let Some(grid) = Grid::build(&sites, binning) else { panic!("no grid") };
            gathers_every_site_once(&grid, &sites, binning == Binning::Overlap);
        }
    }

    fn gathers_every_site_once(grid: &Grid, sites: &[Option<Site>], pixel_order: bool) {
        let mut rng = Rng::new(9);
        for _ in 0..2000 {
            let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform() * 0.1) * 10.0;
            let mut found = Vec::new();
            let any = grid.gather_sites(p, |i, _| found.push(i));
            let mut once = found.clone();
            once.sort_unstable();
            once.dedup();
            assert_eq!(once.len(), found.len(), "repeated: {found:?}");
            assert!(!pixel_order || found.windows(2).all(|w| w[0] < w[1]), "not in pixel order: {found:?}");
            // Within: those of the cell whose ball holds p, and the same answer.
            let mut within = Vec::new();
            assert_eq!(grid.gather_within(p, |i| within.push(i)), any);
            let holds = |i: &u32| sites[*i as usize].is_some_and(|s| (s.p - p).length_squared() <= s.radius * s.radius);
            assert_eq!(within, found.iter().copied().filter(holds).collect::<Vec<_>>());
            assert_eq!(prefetched(grid, p), (within.clone(), within), "the same pixels in the same order");
            for (i, s) in sites.iter().enumerate() {
                if let Some(s) = s
                    && (s.p - p).length() < s.radius
                {
                    assert!(found.contains(&(i as u32)), "site {i} at {:?} r {} missed for {p:?}", s.p, s.radius);
                }
            }
        }
    }

    /// What `gather_within_prefetched` announced and then gave, in order.
    fn prefetched(grid: &Grid, p: Vec3) -> (Vec<u32>, Vec<u32>) {
        let (announced, mut given) = (std::cell::RefCell::new(Vec::new()), Vec::new());
        grid.gather_within_prefetched(p, |i| announced.borrow_mut().push(i), |i| given.push(i));
        (announced.into_inner(), given)
    }

    #[test]
    fn prefetched_gathers_keep_the_order_past_their_list() {
        // 100 sites about one point, all in reach of it: past the 32 listed in place.
        let mut rng = Rng::new(2);
        let sites: Vec<Option<Site>> = (0..100)
            .map(|_| Some(Site { p: Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()), radius: 2.0 }))
            .collect();
        for binning in BINNINGS {
            let Some(grid) = Grid::build(&sites, binning) else { panic!("no grid") };
            let mut within = Vec::new();
            grid.gather_within(Vec3::splat(0.5), |i| within.push(i));
            assert_eq!(within.len(), 100);
            assert_eq!(prefetched(&grid, Vec3::splat(0.5)), (within.clone(), within));
            // Picked by another rule: every entry is seen, the kept ones come in order.
            let (mut seen, mut all, mut kept) = (0, Vec::new(), Vec::new());
            grid.gather_sites(Vec3::splat(0.5), |i, _| all.push(i));
            let pick = |i: u32, _: &Site| {
                seen += 1;
                i.is_multiple_of(3)
            };
            grid.gather_picked(Vec3::splat(0.5), pick, |i| kept.push(i));
            assert_eq!(seen, all.len());
            assert_eq!(kept, all.into_iter().filter(|i| i.is_multiple_of(3)).collect::<Vec<_>>());
        }
    }

    #[test]
    fn the_table_is_the_same_for_any_thread_count() {
        let sites = sites(5 * CHUNK, 3);
        for binning in BINNINGS {
            let build = |threads| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
                pool.install(|| Grid::build(&sites, binning)).ok_or("no grid".to_string())
            };
            let (Ok(a), Ok(b)) = (build(1), build(3)) else { panic!("no grid") };
            assert_eq!(a.offsets, b.offsets);
            assert_eq!(a.entries, b.entries);
            // Within a bucket, pairs are in pixel order.
            for w in a.offsets.windows(2) {
                let bucket = &a.entries[w[0] as usize..w[1] as usize];
                assert!(bucket.windows(2).all(|e| e[0].pixel <= e[1].pixel));
            }
        }
    }

    #[test]
    fn no_sites_no_grid() {
        assert!(Grid::build(&[None, None], Binning::Overlap).is_none());
        assert!(Grid::build(&[], Binning::Centre).is_none());
    }
}
