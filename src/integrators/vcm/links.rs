//! Connections to light vertices chosen from the whole pass (`--connections cached`):
//! probabilistic connections (Popov, Ramamoorthi, Durand and Drettakis 2015) over a
//! light vertex cache (Davidovič, Georgiev and Slusallek 2014), with the choice learnt.
//!
//! ```text
//! pbrt-sppm render room.pbrt --integrator vcm --connections cached
//! ```
//! By default a camera subpath connects to every vertex of one light subpath, its pair.
//! Here each camera vertex draws [`Links::draws`] vertices from all the pass's stored
//! light vertices instead. The scene's box is cut into cells ([`Cells`]); the pilot's
//! passes ([`super::balance`]) learn, for each cell a camera vertex stands in, how much
//! its connections got from light vertices in each other cell, visibility included
//! ([`Learning`]). A draw picks a cell by that share (or, with probability
//! [`UNIFORM`], any vertex of the pass) and then one of the cell's vertices.
//!
//! A connection is divided by N_L·M·q(y | x), for N_L light subpaths, M draws and q
//! the chance of drawing y. In the weights the technique that connects an edge (y, x)
//! then counts as N_L·M·q samples where a pair counts one ([`Links::count`]). The
//! weights take q from the learnt table with each cell's expected vertex count, known
//! before the pass, so that both subpaths give every edge the same count as they grow
//! (`mis`); the estimate takes the q it drew with. Weights that sum to 1 for every
//! path and an estimate divided by its own density keep the image unbiased.
//!
//! Learning is deterministic: the pilot's samples are summed in pixel order, and a
//! shard or a resumed render plays the pilot again (`Vcm::rehearse`).
//!
//! `auto`, the default, learns the table too, and draws by it only where most of the
//! pilot's connections were occluded ([`AUTO_CLEAR_BELOW`]) and drawing by the table
//! would unblock many of them ([`AUTO_GAIN`], [`Unblocking`]); elsewhere each camera
//! vertex keeps its pair.

use glam::Vec3;

/// The chance a draw ignores the table and takes any vertex of the pass: every light
/// vertex can be drawn, whatever the pilot saw. On `doorway` (32 passes, seeds 1–3)
/// 0.1 left 5.28e-4, 0.25 5.39e-4 and 0.5 5.75e-4 (`docs/vcm.md`).
pub const UNIFORM: f64 = 0.1;

/// Draws per camera vertex for each vertex a light subpath stores: with its pair, a
/// camera vertex connects once per stored vertex. On `doorway` twice as many draws
/// (four) left 0.77 of the error for about 1.15 times the time, and eight 0.8 of
/// four's error for 1.3 times its time (`docs/vcm.md`).
pub const DRAWS_PER_VERTEX: f64 = 2.0;

/// The most draws a camera vertex makes.
pub const MAX_DRAWS: usize = 16;

/// `auto` considers the cache only when fewer than this share of the pilot's
/// connections carried light (their shadow ray clear). Measured shares (paired,
/// `--stats`): `doorway` 0.34, `quadric-gallery` 0.33, buddha-fractal 0.25;
/// `cornell-glass` 0.81, `window` 0.86, `keyhole` and `pool` 0.95 and more,
/// `sppm-bench` 0.99, where cached connections gained little or lost (`docs/vcm.md`).
pub const AUTO_CLEAR_BELOW: f64 = 0.5;

/// ... and draws from it only where the table would take that share up this many
/// times (predicted from the pilot's share per pair of cells, which flatters the
/// table: it learnt from the same connections). Occlusion the cells cannot tell apart
/// is not unblocked: buddha-fractal's fractal shadows itself at every scale
/// (predicted 1.6 times, measured 0.25 → 0.30 over 32 passes, error × time 1.12 of
/// paired's); `doorway`'s wall stands between cells (predicted 2.5 times, measured
/// 0.34 → 0.77, error × time 0.66–0.73); `quadric-gallery` 2.4 times, 1.03.
pub const AUTO_GAIN: f64 = 2.0;

/// About this many cells over the scene's box. On `doorway` 128 cells left 1.05 of
/// the error of 512, and 2,048 (a table of 4 million entries, sparsely learnt) 1.3.
const CELLS: f64 = 512.0;

/// A uniform grid of cells over a box.
#[derive(Clone, Debug)]
pub struct Cells {
    min: Vec3,
    per: Vec3,
    dims: [u32; 3],
}

impl Cells {
    /// About [`CELLS`] cubic cells over the box from `min` to `max`.
    pub fn new(min: Vec3, max: Vec3) -> Cells {
        let extent = (max - min).max(Vec3::splat(1e-6));
        let side = ((extent.x as f64 * extent.y as f64 * extent.z as f64) / CELLS).cbrt().max(1e-9) as f32;
        let dims = extent.to_array().map(|e| ((e / side).round() as u32).clamp(1, 64));
        let per = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) / extent;
        Cells { min, per, dims }
    }

    pub fn len(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The cell holding `p` (points outside fall in the nearest).
    #[inline]
    pub fn of(&self, p: Vec3) -> u32 {
        let c = ((p - self.min) * self.per).to_array();
        let i = |k: usize| (c[k].max(0.0) as u32).min(self.dims[k] - 1);
        (i(2) * self.dims[1] + i(1)) * self.dims[0] + i(0)
    }
}

/// One connection the pilot made: the camera vertex's cell, the light vertex's, and
/// what it carried (luminance, unweighted, after visibility).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub camera: u32,
    pub light: u32,
    pub value: f32,
}

/// What the pilot's passes teach, summed as they end.
#[derive(Clone, Debug)]
pub struct Learning {
    cells: Cells,
    /// Row-major: camera cell × light cell.
    got: Vec<f64>,
    /// Row-major as `got`: the connections tried, and those that carried light.
    tried: Vec<u32>,
    carried: Vec<u32>,
    /// Light vertices stored per cell over the pilot.
    vertices: Vec<u64>,
    subpaths: u64,
    /// Whether the table is used whatever the pilot saw (`cached`) or only where it
    /// would unblock many connections (`auto`).
    mode: Connections,
}

/// What `auto` weighs (shares of connections that carried light): the pilot's, and
/// the one drawing by the table would give, predicted from the pilot's.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Unblocking {
    pub paired: f64,
    pub predicted: f64,
}

impl Unblocking {
    /// Whether `auto` draws from the cache (never where nothing would be unblocked:
    /// a pilot whose connections all failed predicts 0 either way).
    pub fn draws(&self) -> bool {
        self.paired < AUTO_CLEAR_BELOW && self.predicted >= AUTO_GAIN * self.paired && self.predicted > self.paired
    }
}

impl Learning {
    pub fn new(cells: Cells, mode: Connections) -> Learning {
        let n = cells.len();
        let (got, tried, carried) = (vec![0.0; n * n], vec![0; n * n], vec![0; n * n]);
        Learning { cells, got, tried, carried, vertices: vec![0; n], subpaths: 0, mode }
    }

    pub fn cells(&self) -> &Cells {
        &self.cells
    }

    /// The table's sums, for a pilot pass to add its connections to.
    pub fn tally(&self) -> Tally {
        Tally { n: self.cells.len(), got: self.got.clone(), tried: self.tried.clone(), carried: self.carried.clone() }
    }

    /// A pilot pass: the table's sums with its connections added ([`Tally`]), where
    /// its stored light vertices stand and how many light subpaths it traced.
    pub fn add_pass(&mut self, tally: Tally, vertices: impl Iterator<Item = Vec3>, subpaths: u64) {
        (self.got, self.tried, self.carried) = (tally.got, tally.tried, tally.carried);
        for p in vertices {
            self.vertices[self.cells.of(p) as usize] += 1;
        }
        self.subpaths += subpaths;
    }

    /// What the passes after the pilot do: draw by the table (`cached`, or `auto`
    /// where it would unblock many connections), or keep their pairs.
    pub fn finish(self) -> State {
        let links = self.table();
        let unblocking = self.unblocking(&links);
        match self.mode {
            Connections::Auto if !unblocking.draws() => State::Paired(unblocking),
            Connections::Auto => State::Learnt(std::sync::Arc::new(Links { auto: Some(unblocking), ..links })),
            _ => State::Learnt(std::sync::Arc::new(links)),
        }
    }

    /// The pilot's share of connections that carried light, and the share drawing by
    /// `links` would give: each camera cell's connections, as many as the pilot's,
    /// drawn over the light cells by the table, each pair of cells clear as often as
    /// in the pilot (as often as the camera cell's connections overall where the
    /// pilot tried none). No connections: nothing to unblock (1 and 1).
    fn unblocking(&self, links: &Links) -> Unblocking {
        let n = self.cells.len();
        let (mut tried, mut carried, mut predicted) = (0u64, 0u64, 0.0);
        for c in 0..n {
            let row = c * n..(c + 1) * n;
            let (t, k) = (&self.tried[row.clone()], &self.carried[row]);
            let total = |v: &[u32]| v.iter().map(|&x| x as u64).sum::<u64>();
            let (row_tried, row_carried) = (total(t), total(k));
            if row_tried == 0 {
                continue;
            }
            let prior = row_carried as f64 / row_tried as f64;
            let drawn: f64 = (0..n)
                .map(|l| {
                    let rate = if t[l] > 0 { k[l] as f64 / t[l] as f64 } else { prior };
                    links.cell_chance(c as u32, l as u32) * rate
                })
                .sum();
            (tried, carried, predicted) =
                (tried + row_tried, carried + row_carried, predicted + row_tried as f64 * drawn);
        }
        match tried {
            0 => Unblocking { paired: 1.0, predicted: 1.0 },
            t => Unblocking { paired: carried as f64 / t as f64, predicted: predicted / t as f64 },
        }
    }

    /// The table the passes after the pilot draw from.
    fn table(&self) -> Links {
        let n = self.cells.len();
        let per_path = |v: u64| v as f64 / self.subpaths.max(1) as f64;
        let stored = per_path(self.vertices.iter().sum());
        let nu: Vec<f64> = self.vertices.iter().map(|&v| per_path(v)).collect();
        let rows = (0..n)
            .map(|c| {
                let row = &self.got[c * n..(c + 1) * n];
                let mut cdf = Vec::with_capacity(n);
                let mut sum = 0.0;
                for (&g, &v) in row.iter().zip(&nu) {
                    // A cell without stored vertices can give nothing to draw.
                    sum += if v > 0.0 { g } else { 0.0 };
                    cdf.push(sum);
                }
                (sum > 0.0).then(|| cdf.iter().map(|c| c / sum).collect::<Vec<f64>>())
            })
            .collect();
        // At least one: a fraction of a draw (one more with the chance of the fraction)
        // took `keyhole`'s error × time from 0.90 of paired's to 1.04 (`docs/vcm.md`).
        let draws = (DRAWS_PER_VERTEX * stored).round().clamp(1.0, MAX_DRAWS as f64) as u32;
        Links { cells: self.cells.clone(), rows, nu, stored: stored.max(1e-9), draws, auto: None }
    }
}

/// The table's sums while a pilot pass adds to them: a copy of [`Learning`]'s, so that
/// the pass adds its connections a band of pixels at a time, in pixel order, and never
/// holds all of them, while the render's state stays read-only.
#[derive(Debug)]
pub struct Tally {
    n: usize,
    got: Vec<f64>,
    tried: Vec<u32>,
    carried: Vec<u32>,
}

impl Tally {
    /// Connections of the pass, the next in pixel order.
    pub fn add(&mut self, samples: &[Sample]) {
        for s in samples {
            let k = s.camera as usize * self.n + s.light as usize;
            self.tried[k] = self.tried[k].saturating_add(1);
            if s.value.is_finite() && s.value > 0.0 {
                self.got[k] += s.value as f64;
                self.carried[k] = self.carried[k].saturating_add(1);
            }
        }
    }
}

/// The learnt choice of light vertices (see the module's docs).
#[derive(Clone, Debug)]
pub struct Links {
    cells: Cells,
    /// Per camera cell, the cumulative share of each light cell; `None` where the
    /// pilot saw nothing (draws there are uniform).
    rows: Vec<Option<Vec<f64>>>,
    /// Stored light vertices per light subpath, per cell and in all.
    nu: Vec<f64>,
    stored: f64,
    /// Draws per camera vertex: [`DRAWS_PER_VERTEX`] times the pilot's stored vertices
    /// per light subpath (twice the connections its pair gave), at least one.
    pub draws: u32,
    /// With `auto`: what chose the table.
    pub auto: Option<Unblocking>,
}

impl Links {
    pub fn cells(&self) -> &Cells {
        &self.cells
    }

    /// The share of light cell `l` in camera cell `c`'s row.
    fn share(&self, c: u32, l: u32) -> f64 {
        match &self.rows[c as usize] {
            None => 0.0,
            Some(cdf) => cdf[l as usize] - if l == 0 { 0.0 } else { cdf[l as usize - 1] },
        }
    }

    /// The chance a draw for camera cell `c` lands in light cell `l`.
    fn cell_chance(&self, c: u32, l: u32) -> f64 {
        let u = self.uniform_share(c);
        u * self.nu[l as usize] / self.stored + (1.0 - u) * self.share(c, l)
    }

    fn uniform_share(&self, c: u32) -> f64 {
        if self.rows[c as usize].is_some() { UNIFORM } else { 1.0 }
    }

    /// How many samples connecting the edge from light-side point `y` to camera-side
    /// point `x` counts as in the weights, where a pair counts 1: N_L·M·q(y | x) with
    /// each cell's expected vertex count.
    pub fn count(&self, y: Vec3, x: Vec3) -> f64 {
        let (c, l) = (self.cells.of(x), self.cells.of(y));
        let u = self.uniform_share(c);
        let table = match self.nu[l as usize] {
            nu if nu > 0.0 => (1.0 - u) * self.share(c, l) / nu,
            _ => 0.0,
        };
        self.draws as f64 * (u / self.stored + table)
    }
}

/// A pass's stored light vertices sorted by cell.
#[derive(Debug, Default)]
pub struct Pool {
    /// Cell c holds `order[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    order: Vec<u32>,
    /// Each vertex's cell.
    keys: Vec<u32>,
}

impl Pool {
    /// The pool of vertices at `points` (in the pass's order).
    pub fn new(cells: &Cells, points: impl ExactSizeIterator<Item = Vec3>) -> Pool {
        let keys: Vec<u32> = points.map(|p| cells.of(p)).collect();
        let mut starts = vec![0u32; cells.len() + 1];
        for &k in &keys {
            starts[k as usize + 1] += 1;
        }
        for c in 0..cells.len() {
            starts[c + 1] += starts[c];
        }
        let mut next = starts.clone();
        let mut order = vec![0u32; keys.len()];
        for (i, &k) in keys.iter().enumerate() {
            order[next[k as usize] as usize] = i as u32;
            next[k as usize] += 1;
        }
        Pool { starts, order, keys }
    }

    fn in_cell(&self, c: u32) -> &[u32] {
        &self.order[self.starts[c as usize] as usize..self.starts[c as usize + 1] as usize]
    }

    /// One draw for a camera vertex at `x` from `u`: the vertex's number and the chance
    /// q of drawing it; `None` where the drawn cell is empty.
    pub fn draw(&self, links: &Links, x: Vec3, u: [f32; 2]) -> Option<(u32, f64)> {
        let total = self.order.len();
        if total == 0 {
            return None;
        }
        let c = links.cells.of(x);
        let share = links.uniform_share(c);
        let (u0, u1) = (u[0] as f64, u[1] as f64);
        // The drawn vertex's cell and how many the cell holds: read from the table's
        // side they are at hand, where a look-up by vertex would miss the cache.
        let (i, l, n) = if u0 < share {
            let k = ((u0 / share * total as f64) as usize).min(total - 1);
            let i = self.order[k];
            let l = self.keys[i as usize];
            (i, l, self.in_cell(l).len())
        } else {
            let cdf = links.rows[c as usize].as_ref()?;
            let l = cdf.partition_point(|&v| v <= u1).min(cdf.len() - 1) as u32;
            let here = self.in_cell(l);
            let k = ((u0 - share) / (1.0 - share) * here.len() as f64) as usize;
            (*here.get(k.min(here.len().checked_sub(1)?))?, l, here.len())
        };
        // The chance of drawing vertex i: by the uniform share, or by its cell's.
        let q = share / total as f64 + (1.0 - share) * links.share(c, l) / n.max(1) as f64;
        Some((i, q))
    }
}

/// What a camera vertex connects to (`--connections`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Connections {
    /// `cached` where the pilot found most connections occluded and the table would
    /// unblock many of them, else `paired`.
    #[default]
    Auto,
    /// Every vertex of its pair, one light subpath (Georgiev et al.'s).
    Paired,
    /// Vertices drawn from the whole pass by a table the pilot learns (the module).
    Cached,
}

impl Connections {
    /// The option's value that asks for it.
    pub fn name(self) -> &'static str {
        match self {
            Connections::Auto => "auto",
            Connections::Paired => "paired",
            Connections::Cached => "cached",
        }
    }
}

impl std::str::FromStr for Connections {
    type Err = String;
    fn from_str(s: &str) -> Result<Connections, String> {
        [Connections::Auto, Connections::Paired, Connections::Cached]
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| format!("expected auto, paired or cached, not \"{s}\""))
    }
}

/// The table under way: learning over the pilot, learnt, or to be learnt again
/// before the first pass past the pilot (a render that did not start at pass 0).
#[derive(Debug)]
pub enum State {
    Learning(Box<Learning>),
    Learnt(std::sync::Arc<Links>),
    /// `auto` keeps the pairs: the table would not unblock enough connections.
    Paired(Unblocking),
    Unknown,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// χ² of `counts` against `expected` stays below its 99.9th percentile (the
    /// degrees of freedom plus 3.1 of its standard deviations).
    fn assert_chi2(counts: &[u32], expected: &[f64]) {
        let chi2: f64 = counts.iter().zip(expected).map(|(&c, &e)| (c as f64 - e).powi(2) / e).sum();
        let dof = (counts.len() - 1) as f64;
        assert!(chi2 < dof + 3.1 * (2.0 * dof).sqrt(), "χ² {chi2} over {dof} degrees of freedom");
    }

    /// `auto` draws from the cache where the pilot's connections were mostly blocked
    /// and the table picks the cells they were clear to; it keeps the pairs where the
    /// blocking is spread over every pair of cells alike, where most were clear, and
    /// where every connection was blocked (nothing to unblock).
    #[test]
    fn auto_draws_where_the_table_unblocks_connections() {
        let cells = Cells::new(Vec3::ZERO, Vec3::ONE);
        let (x, near, far) = (Vec3::splat(0.1), Vec3::splat(0.2), Vec3::splat(0.9));
        let decide = |clear_near: f32, clear_far: f32| {
            let mut learning = Learning::new(cells.clone(), Connections::Auto);
            let cells = &cells;
            let mut tally = learning.tally();
            // Ten connections to a near light vertex and thirty to a far one, the
            // share `clear_near` or `clear_far` of them carrying light.
            let lit = |i: usize, n: usize, share: f32| if (i as f32) < n as f32 * share { 1.0 } else { 0.0 };
            let to = |p: Vec3, n: usize, share: f32| {
                (0..n).map(move |i| Sample { camera: cells.of(x), light: cells.of(p), value: lit(i, n, share) })
            };
            let samples: Vec<Sample> = to(near, 10, clear_near).chain(to(far, 30, clear_far)).collect();
            tally.add(&samples);
            learning.add_pass(tally, [near, far].into_iter(), 1);
            match learning.finish() {
                State::Learnt(l) => (true, l.auto.expect("auto's figures")),
                State::Paired(u) => (false, u),
                _ => panic!("neither"),
            }
        };
        let (drawn, u) = decide(0.6, 0.0);
        assert!(drawn && (u.paired - 0.15).abs() < 1e-9 && (u.predicted - 0.57).abs() < 1e-9, "{u:?}");
        let (drawn, u) = decide(0.3, 0.3);
        assert!(!drawn && (u.predicted - u.paired).abs() < 1e-9, "{u:?}");
        let (drawn, u) = decide(1.0, 0.6);
        assert!(!drawn && (u.paired - 0.7).abs() < 1e-9, "{u:?}");
        let (drawn, u) = decide(0.0, 0.0);
        assert!(!drawn && u.paired == 0.0 && u.predicted == 0.0, "{u:?}");
    }

    /// The chance a draw reports for a vertex is how often draws take it: the estimate
    /// divides each connection by it.
    #[test]
    fn a_draw_reports_the_chance_it_had() {
        let cells = Cells::new(Vec3::ZERO, Vec3::ONE);
        let mut rng = Rng::new(9);
        let mut point = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        let points: Vec<Vec3> = (0..400).map(|_| point()).collect();
        // Connections from around one camera point, to a third of the cells.
        let x = Vec3::splat(0.3);
        let samples: Vec<Sample> = points
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 3 == 0)
            .map(|(i, &p)| Sample { camera: cells.of(x), light: cells.of(p), value: 1.0 + (i % 5) as f32 })
            .collect();
        let mut learning = Learning::new(cells.clone(), Connections::Cached);
        let mut tally = learning.tally();
        tally.add(&samples);
        learning.add_pass(tally, points.iter().copied(), 200);
        let links = learning.table();
        let pool = Pool::new(&cells, points.iter().copied());
        let (mut counts, mut chance, draws) = (vec![0u32; points.len()], vec![0.0; points.len()], 2_000_000);
        let mut rng = Rng::new(13);
        let mut missed = 0;
        for _ in 0..draws {
            match pool.draw(&links, x, [rng.uniform(), rng.uniform()]) {
                Some((i, q)) => {
                    counts[i as usize] += 1;
                    assert!(chance[i as usize] == 0.0 || chance[i as usize] == q, "vertex {i}: two chances");
                    chance[i as usize] = q;
                }
                None => missed += 1,
            }
        }
        assert_eq!(missed, 0, "every drawn cell holds vertices");
        let total: f64 = chance.iter().sum();
        assert!((total - 1.0).abs() < 1e-9, "the chances sum to {total}");
        let expected: Vec<f64> = chance.iter().map(|q| q * draws as f64).collect();
        assert_chi2(&counts, &expected);
    }
}
