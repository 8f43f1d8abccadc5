//! The Ptex library's filter on triangle meshes (`PtexTriangleFilter`, which every
//! filter type but `point` becomes there): a Gaussian over the footprint's ellipse in
//! the triangle's barycentric (u, v, w), 3.5 filter widths wide, split at the edges it
//! crosses and carried into the neighbours.
//!
//! A triangle face of 2^n texels a side stores two triangles of texels in its square:
//! "even" ones in the lower left, "odd" ones flipped into the upper right.

use super::file::{FaceData, FaceInfo, PtexFile, Res};

/// Kernel width in filter widths (Ptex's `PtexTriangleKernelWidth`).
const WIDTH: f32 = 3.5;
/// Deepest walk across edges.
// DEVIATION(pbrt): robustness. The library follows a damaged file's neighbour links
// without end; here the walk stops.
const MAX_DEPTH: u32 = 8;
const THIRD: f32 = (1.0f64 / 3.0) as f32;

/// Ptex's `PtexTriangleKernel`: the ellipse A u² + B u v + C v² < 1 about (u, v), and
/// its (u, v, w) bounds.
#[derive(Clone, Copy, Debug)]
struct Kernel {
    res: i8,
    u: f32,
    v: f32,
    lo: [f32; 3],
    hi: [f32; 3],
    abc: [f32; 3],
}

impl Kernel {
    /// Places the kernel in the neighbour across edge `eid` (met by its edge `aeid`).
    fn reorient(&mut self, eid: i32, aeid: i32) {
        let (u, v) = (self.u, self.v);
        let w = 1.0 - u - v;
        let ([u1, v1, w1], [u2, v2, w2]) = (self.lo, self.hi);
        let [a, b, c] = self.abc;
        let rot1 = [c, 2.0 * c - b, a + c - b];
        let rot2 = [a + c - b, 2.0 * a - b, a];
        let (centre, lo, hi, abc) = match (eid, aeid) {
            (0, 0) => ([1.0 - u, -v], [1.0 - u2, -v2, 1.0 - w2], [1.0 - u1, -v1, 1.0 - w1], self.abc),
            (0, 1) => ([1.0 - w, 1.0 - u], [1.0 - w2, 1.0 - u2, -v2], [1.0 - w1, 1.0 - u1, -v1], rot1),
            (0, 2) => ([-v, 1.0 - w], [-v2, 1.0 - w2, 1.0 - u2], [-v1, 1.0 - w1, 1.0 - u1], rot2),
            (1, 0) => ([1.0 - v, -w], [1.0 - v2, -w2, 1.0 - u2], [1.0 - v1, -w1, 1.0 - u1], rot2),
            (1, 1) => ([1.0 - u, 1.0 - v], [1.0 - u2, 1.0 - v2, -w2], [1.0 - u1, 1.0 - v1, -w1], self.abc),
            (1, 2) => ([-w, 1.0 - u], [-w2, 1.0 - u2, 1.0 - v2], [-w1, 1.0 - u1, 1.0 - v1], rot1),
            (2, 0) => ([1.0 - w, -u], [1.0 - w2, -u2, 1.0 - v2], [1.0 - w1, -u1, 1.0 - v1], rot1),
            (2, 1) => ([1.0 - v, 1.0 - w], [1.0 - v2, 1.0 - w2, -u2], [1.0 - v1, 1.0 - w1, -u1], rot2),
            (2, 2) => ([-u, 1.0 - v], [-u2, 1.0 - v2, 1.0 - w2], [-u1, 1.0 - v1, 1.0 - w1], self.abc),
            _ => return,
        };
        *self = Kernel { u: centre[0], v: centre[1], lo, hi, abc, ..*self };
    }

    /// Ptex's `clampExtent`.
    fn clamp_extent(&mut self) {
        let [u1, v1, w1] = self.lo.map(|x| x.max(0.0));
        self.lo = [u1, v1, w1];
        self.hi = [self.hi[0].min(1.0 - (v1 + w1)), self.hi[1].min(1.0 - (w1 + u1)), self.hi[2].min(1.0 - (u1 + v1))];
    }

    /// Ptex's `getIterators`: the even and the odd texels' iterators.
    fn iterators(&self) -> [Iter; 2] {
        let n = 1i32 << self.res;
        let s = n as f32;
        let [a, b, c] = self.abc;
        let f_inv = 1.0 / (s * s * (a * c - 0.25 * b * b));
        let (ak, bk, ck) = (a * f_inv, b * f_inv, c * f_inv);
        let at = |x: f32| (x * s - THIRD).ceil() as i32;
        let ([u1, v1, w1], [u2, v2, w2]) = (self.lo, self.hi);
        let even = Iter {
            row: n,
            wscale: 1.0 / (s * s),
            u: self.u * s - THIRD,
            v: self.v * s - THIRD,
            lo: [at(u1), at(v1), at(w1)],
            hi: [at(u2), at(v2), at(w2)],
            abc: [ak, bk, ck],
        };
        let odd = Iter {
            u: (1.0 - self.v) * s - THIRD,
            v: (1.0 - self.u) * s - THIRD,
            lo: [at(1.0 - v2), at(1.0 - u2), at(-w2)],
            hi: [at(1.0 - v1), at(1.0 - u1), at(-w1)],
            abc: [ck, bk, ak],
            ..even
        };
        [even, odd]
    }
}

/// Ptex's `PtexTriangleKernelIter`, in texel units.
#[derive(Clone, Copy, Debug)]
struct Iter {
    row: i32,
    wscale: f32,
    u: f32,
    v: f32,
    lo: [i32; 3],
    hi: [i32; 3],
    abc: [f32; 3],
}

impl Iter {
    fn valid(&self) -> bool {
        (0..3).all(|i| self.hi[i] > self.lo[i])
    }

    /// Calls `f(x, y, weight)` for each texel inside the ellipse (the library's finite
    /// differences of the ellipse's quadratic, Heckbert 1989); returns the weights' sum.
    fn each(&self, mut f: impl FnMut(i32, i32, f32)) -> f32 {
        let [a, b, c] = self.abc;
        let ddq = 2.0 * a;
        let mut total = 0.0;
        for vi in self.lo[1]..self.hi[1] {
            let xw = self.row - vi;
            let (x1, x2) = (self.lo[0].max(xw - self.hi[2]), self.hi[0].min(xw - self.lo[2]));
            let (u, v) = (x1 as f32 - self.u, vi as f32 - self.v);
            let mut dq = a * (2.0 * u + 1.0) + b * v;
            let mut q = a * u * u + (b * u + c * v) * v;
            for x in x1..x2 {
                if q < 1.0 {
                    let w = (-0.5 * WIDTH * WIDTH * q).exp() * self.wscale;
                    total += w;
                    f(x, vi, w);
                }
                q += dq;
                dq += ddq;
            }
        }
        total
    }
}

/// The Ptex library's `PtexTriangleFilter::buildKernel` (filter width 1, no blur).
fn build_kernel(u: f32, v: f32, [uw1, vw1, uw2, vw2]: [f32; 4], face_log2: i8) -> Kernel {
    let sqrt3 = 1.732_050_8_f32;
    let (scale_ac, scale_b) = (0.25f32, -0.5f32);
    let a = (vw1 * vw1 + vw2 * vw2) * scale_ac;
    let b = (uw1 * vw1 + uw2 * vw2) * scale_b;
    let c = (uw1 * uw1 + uw2 * uw2) * scale_ac;
    let (mut ac, bc, mut cc) = (0.75 * a, (sqrt3 / 2.0) * (b - a), 0.25 * a - 0.5 * b + c);
    let max_ecc = 15.0f32;
    let ecc_ratio = (max_ecc * max_ecc + 1.0) / (max_ecc * max_ecc - 1.0);
    let x = ((ac - cc) * (ac - cc) + bc * bc).sqrt();
    let b_e = 0.5 * (ecc_ratio * x - (ac + cc));
    let b_t = (0.5 / (1i32 << face_log2) as f32).powi(2);
    let blur = b_e.max(b_t).max(0.0);
    ac += blur;
    cc += blur;
    let m = (2.0 * (ac * cc - 0.25 * bc * bc) / (ac + cc + x)).sqrt();
    let res = super::file::res_from_width(2.0 * m).max(0);
    let a = (4.0f64 / 3.0) as f32 * ac;
    let b = (2.0 / sqrt3) * bc + a;
    let c = -0.25 * a + 0.5 * b + cc;
    let k = WIDTH * WIDTH;
    let (a, b, c) = (a * k, b * k, c * k);
    let (uw, vw, ww) = (c.sqrt().min(1.0), a.sqrt().min(1.0), (a - b + c).sqrt().min(1.0));
    let w = 1.0 - u - v;
    Kernel { res, u, v, lo: [u - uw, v - vw, w - ww], hi: [u + uw, v + vw, w + ww], abc: [a, b, c] }
}

/// A lookup in progress.
struct Lookup<'a> {
    tx: &'a PtexFile,
    result: Vec<f32>,
    weight: f32,
}

/// The filtered value of triangle face `face` at barycentric (u, v) with footprint
/// `duv`, before normalising by the data type.
pub fn eval(tx: &PtexFile, face: usize, u: f32, v: f32, duv: [f32; 4]) -> Vec<f32> {
    let f = &tx.faces[face];
    let k = build_kernel(u.clamp(0.0, 1.0), v.clamp(0.0, 1.0), duv, f.res.u);
    let mut l = Lookup { tx, result: vec![0.0; tx.channels], weight: 0.0 };
    l.split_and_apply(k, face, f, 0);
    let scale = 1.0 / (l.weight * tx.data_type.one());
    l.result.iter().map(|x| x * scale).collect()
}

impl Lookup<'_> {
    fn split_and_apply(&mut self, mut k: Kernel, face: usize, f: &FaceInfo, depth: u32) {
        if depth <= MAX_DEPTH {
            // (edge, bound): edge 2 is u = 0, edge 0 v = 0, edge 1 w = 0.
            for (eid, i) in [(2, 0), (0, 1), (1, 2)] {
                if k.lo[i] < 0.0 && f.adj_face(eid) >= 0 {
                    let mut ka = k;
                    k.lo[i] = 0.0;
                    ka.hi[i] = 0.0;
                    let afid = f.adj_face(eid) as usize;
                    ka.reorient(eid, f.adj_edge(eid));
                    let af = self.tx.faces[afid];
                    self.split_and_apply(ka, afid, &af, depth + 1);
                }
            }
        }
        self.apply(k, face, f);
    }

    fn apply(&mut self, mut k: Kernel, face: usize, f: &FaceInfo) {
        k.res = k.res.min(f.res.u);
        k.clamp_extent();
        let its = k.iterators();
        if !its.iter().any(Iter::valid) {
            return;
        }
        let data = self.tx.data(face, Res::new(k.res, k.res));
        let n = self.tx.channels;
        for it in its.iter().filter(|i| i.valid()) {
            match &*data {
                FaceData::Constant(c) => {
                    let w = it.each(|_, _, _| {});
                    self.result.iter_mut().zip(c.iter()).for_each(|(r, c)| *r += c * w);
                    self.weight += w;
                }
                FaceData::Texels { res, texels } => {
                    let size = res.su();
                    let result = &mut self.result;
                    self.weight += it.each(|x, y, w| {
                        if (0..size).contains(&x) && (0..size).contains(&y) {
                            let at = ((y * size + x) as usize) * n;
                            result.iter_mut().zip(&texels[at..at + n]).for_each(|(r, t)| *r += t * w);
                        }
                    });
                }
            }
        }
    }
}
