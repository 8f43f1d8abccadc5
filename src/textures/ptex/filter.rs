//! The Ptex library's separable B-spline filter on quad meshes (`PtexFilter` with
//! `f_bspline`, which pbrt-v3 and pbrt-v4 ask for): a 4-texel-wide cubic kernel at the
//! resolution that the footprint picks, split where it crosses a face edge and carried
//! into the neighbouring faces (rotated to their frame, resized to their resolution),
//! around corners of any valence, and merged back at mesh borders.
//!
//! The kernel is Ptex's: its weights, its choice of resolution, its treatment of
//! subfaces and corners, so that a lookup gives the library's value.

use super::file::{BorderMode, FaceData, FaceInfo, MeshType, PtexFile, Res, pixel, res_from_width};

/// Ptex's `kmax` is 10; doubling a kernel (`upres`) may need twice that.
const KMAX: usize = 20;
/// Deepest re-splitting into subfaces; a well-formed file needs 2.
// DEVIATION(pbrt): robustness. The library recurses as far as a damaged file's
// neighbour links lead; here the walk stops.
const MAX_DEPTH: u32 = 8;

/// One axis of a kernel: weights `k[..w]` over texels `at..at + w`.
#[derive(Clone, Copy, Debug)]
struct Axis {
    at: i32,
    w: i32,
    k: [f32; KMAX],
}

impl Axis {
    fn sum(&self) -> f32 {
        self.k[..self.w as usize].iter().sum()
    }

    /// Drops `n` leading weights.
    fn drop_front(&mut self, n: i32) {
        let n = n.clamp(0, self.w);
        self.k.copy_within(n as usize..self.w as usize, 0);
        self.w -= n;
    }

    /// Weights from `from` for `w` texels starting at texel `at`.
    fn part(&self, at: i32, from: i32, w: i32) -> Axis {
        let mut k = [0.0; KMAX];
        k[..w as usize].copy_from_slice(&self.k[from as usize..(from + w) as usize]);
        Axis { at, w, k }
    }

    /// Splits off the texels below 0, placed at the far end of a neighbour of `size`
    /// texels; all of it where none is inside.
    fn split_low(&mut self, size: i32) -> Axis {
        let w = -self.at;
        if w < self.w {
            let part = self.part(size - w, 0, w);
            self.drop_front(w);
            self.at = 0;
            part
        } else {
            let part = Axis { at: self.at + size, ..*self };
            (self.at, self.w) = (0, 0);
            part
        }
    }

    /// Splits off the texels past `size`, placed at the start of the neighbour.
    fn split_high(&mut self, size: i32) -> Axis {
        let w = self.at + self.w - size;
        if w < self.w {
            let part = self.part(0, self.w - w, w);
            self.w -= w;
            part
        } else {
            let part = Axis { at: self.at - size, ..*self };
            (self.at, self.w) = (0, 0);
            part
        }
    }

    fn flip(&mut self, size: i32) {
        self.at = size - self.at - self.w;
        self.k[..self.w as usize].reverse();
    }

    /// Texel pairs merged, for half the resolution (Ptex's `downresU`).
    fn halve(&mut self) {
        let (mut src, mut dst) = (0usize, 0usize);
        let mut w = self.w;
        if self.at & 1 != 0 {
            src += 1;
            dst += 1;
            w -= 1;
        }
        for _ in 0..w / 2 {
            self.k[dst] = self.k[src] + self.k[src + 1];
            dst += 1;
            src += 2;
        }
        if w & 1 != 0 {
            self.k[dst] = self.k[src];
            dst += 1;
        }
        self.at = self.at.div_euclid(2);
        self.w = dst as i32;
    }

    /// Each texel split in two, for twice the resolution (Ptex's `upresU`).
    fn double(&mut self) {
        let w = (self.w as usize).min(KMAX / 2);
        for i in (0..w).rev() {
            let half = self.k[i] / 2.0;
            self.k[2 * i] = half;
            self.k[2 * i + 1] = half;
        }
        self.w = 2 * w as i32;
        self.at *= 2;
    }

    /// Folds the weights past texel 0 onto it (Ptex's `mergeL`).
    fn merge_low(&mut self, mode: BorderMode) {
        let n = (-self.at).min(self.w - 1).max(0);
        if mode != BorderMode::Black {
            let s: f32 = self.k[..n as usize].iter().sum();
            self.k[n as usize] += s;
        }
        self.drop_front(n);
        self.at = 0;
    }

    /// Folds the weights past the last texel onto it (Ptex's `mergeR`).
    fn merge_high(&mut self, mode: BorderMode, size: i32) {
        let n = (self.w + self.at - size).min(self.w - 1).max(0);
        let keep = (self.w - n) as usize;
        if mode != BorderMode::Black {
            let s: f32 = self.k[keep..self.w as usize].iter().sum();
            self.k[keep - 1] += s;
        }
        self.w -= n;
    }
}

/// Ptex's `PtexSeparableKernel`.
#[derive(Clone, Copy, Debug)]
struct Kernel {
    res: Res,
    u: Axis,
    v: Axis,
    rot: i32,
}

/// Ptex's edge ids.
const BOTTOM: i32 = 0;
const RIGHT: i32 = 1;
const TOP: i32 = 2;
const LEFT: i32 = 3;

impl Kernel {
    fn weight(&self) -> f32 {
        self.u.sum() * self.v.sum()
    }

    fn strip_zeros(&mut self) {
        for a in [&mut self.u, &mut self.v] {
            while a.w > 1 && a.k[0] == 0.0 {
                a.drop_front(1);
                a.at += 1;
            }
            while a.w > 1 && a.k[a.w as usize - 1] == 0.0 {
                a.w -= 1;
            }
        }
    }

    /// Splits off the part past one edge (Ptex's `splitL`, `splitR`, `splitB`,
    /// `splitT`): along u or v, below texel 0 (`low`) or past the last, placed in the
    /// neighbour's frame before rotation.
    fn split(&mut self, along_u: bool, low: bool) -> Kernel {
        let size = if along_u { self.res.su() } else { self.res.sv() };
        let a = if along_u { &mut self.u } else { &mut self.v };
        let whole = if low { -a.at >= a.w } else { a.at + a.w - size >= a.w };
        let part = if low { a.split_low(size) } else { a.split_high(size) };
        // A piece keeps the kernel's turns only where it is the whole kernel.
        let rot = if whole { self.rot } else { 0 };
        if along_u { Kernel { u: part, rot, ..*self } } else { Kernel { v: part, rot, ..*self } }
    }

    fn split_left(&mut self) -> Kernel {
        self.split(true, true)
    }

    fn split_right(&mut self) -> Kernel {
        self.split(true, false)
    }

    fn split_bottom(&mut self) -> Kernel {
        self.split(false, true)
    }

    fn split_top(&mut self) -> Kernel {
        self.split(false, false)
    }

    fn swap_uv(&mut self) {
        self.res = Res::new(self.res.v, self.res.u);
        std::mem::swap(&mut self.u, &mut self.v);
    }

    /// Turns the kernel `r` quarter turns counter-clockwise.
    fn rotate(&mut self, r: i32) {
        let (su, sv) = (self.res.su(), self.res.sv());
        match r & 3 {
            1 => {
                self.u.flip(su);
                self.swap_uv();
            }
            2 => {
                self.u.flip(su);
                self.v.flip(sv);
            }
            3 => {
                self.v.flip(sv);
                self.swap_uv();
            }
            _ => return,
        }
        self.rot = (self.rot + r) & 3;
    }

    fn halve_u(&mut self) {
        self.u.halve();
        self.res.u -= 1;
    }

    fn halve_v(&mut self) {
        self.v.halve();
        self.res.v -= 1;
    }

    fn double_u(&mut self) {
        self.u.double();
        self.res.u += 1;
    }

    fn double_v(&mut self) {
        self.v.double();
        self.res.v += 1;
    }

    /// Ptex's `adjustMainToSubface`: whether the target is the primary subface.
    fn main_to_subface(&mut self, eid: i32) -> bool {
        if self.res.u == 0 {
            self.double_u();
        }
        if self.res.v == 0 {
            self.double_v();
        }
        self.res.u = (self.res.u - 1).max(0);
        self.res.v = (self.res.v - 1).max(0);
        let (su, sv) = (self.res.su(), self.res.sv());
        let (u, v) = (&mut self.u.at, &mut self.v.at);
        match eid & 3 {
            BOTTOM => {
                let primary = *u < su;
                *v -= sv;
                if !primary {
                    *u -= su;
                }
                primary
            }
            RIGHT => {
                let primary = *v < sv;
                if !primary {
                    *v -= sv;
                }
                primary
            }
            TOP => {
                let primary = *u >= su;
                if primary {
                    *u -= su;
                }
                primary
            }
            _ => {
                let primary = *v >= sv;
                *u -= su;
                if primary {
                    *v -= sv;
                }
                primary
            }
        }
    }

    /// Ptex's `adjustSubfaceToMain`.
    fn subface_to_main(&mut self, eid: i32) {
        let (su, sv) = (self.res.su(), self.res.sv());
        match eid & 3 {
            BOTTOM => self.v.at += sv,
            RIGHT => {}
            TOP => self.u.at += su,
            _ => {
                self.u.at += su;
                self.v.at += sv;
            }
        }
        self.res.u += 1;
        self.res.v += 1;
    }

    /// Ptex's `makeSymmetric`, for corners of valence 5 and more: returns the new weight.
    fn make_symmetric(&mut self, initial: f32) -> f32 {
        while self.res.u > self.res.v {
            self.halve_u();
        }
        while self.res.v > self.res.u {
            self.halve_v();
        }
        let w = self.u.w.min(self.v.w);
        (self.u.w, self.v.w) = (w, w);
        let mut new = 0.0;
        for i in 0..w as usize {
            let s = self.u.k[i] + self.v.k[i];
            (self.u.k[i], self.v.k[i]) = (s, s);
            new += s;
        }
        new *= new;
        let scale = if new == 0.0 { 1.0 } else { initial / new };
        if scale < 1.0 {
            let by = if scale < -1.0 { -1.0 } else { scale };
            for k in &mut self.u.k[..w as usize] {
                *k *= by;
            }
            new = if scale < -1.0 { -new } else { initial };
        }
        new
    }
}

/// The B-spline (Ptex's bicubic kernel with sharpness 0: B = 1, C = 0).
fn bspline(x: f32) -> f32 {
    const B: f32 = 1.0;
    let c = [
        1.5 - B,
        1.5 * B - 2.5,
        1.0 - (1.0f64 / 3.0) as f32 * B,
        (1.0f64 / 3.0) as f32 * B - 0.5,
        2.5 - 1.5 * B,
        2.0 * B - 4.0,
        2.0 - (2.0f64 / 3.0) as f32 * B,
    ];
    let x = x.abs();
    if x < 1.0 {
        (c[0] * x + c[1]) * x * x + c[2]
    } else if x < 2.0 {
        ((c[3] * x + c[4]) * x + c[5]) * x + c[6]
    } else {
        0.0
    }
}

/// Ptex's 2-unit Hermite blur, for footprints of half a face and more.
fn blur(x: f32) -> f32 {
    let x = x.abs();
    if x < 1.0 { (2.0 * x - 3.0) * x * x + 1.0 } else { 0.0 }
}

/// One axis of Ptex's `PtexWidth4Filter::buildKernel` (without its `lerp` option,
/// which pbrt leaves off): the resolution and the weights for texture coordinate
/// `u` and filter width `uw` on a face of 2^`face_log2` texels.
fn kernel_axis(u: f32, uw: f32, face_log2: i8) -> (i8, Axis) {
    let uw = uw.max(f32::from_bits(((127 - face_log2 as i32) as u32) << 23));
    let mut a = Axis { at: 0, w: 0, k: [0.0; KMAX] };
    if uw >= 0.25 {
        if uw < 0.5 {
            let upix = u * 4.0 - 0.5;
            let u1 = ((upix - 2.0).ceil() as i32) & !1;
            let u2 = ((upix + 2.0).ceil() as i32 + 1) & !1;
            (a.at, a.w) = (u1, (u2 - u1).min(KMAX as i32));
            let x1 = u1 as f32 - upix;
            for i in (0..a.w as usize).step_by(2) {
                let xa = x1 + i as f32;
                a.k[i] = bspline(xa);
                a.k[i + 1] = bspline(xa + 1.0);
            }
            return (2, a);
        }
        if uw < 1.0 {
            let upix = u * 2.0 - 0.5;
            (a.at, a.w) = (((u - 0.5).floor() as i32) * 2, 4);
            let x1 = a.at as f32 - upix;
            let s = 1.0 / (uw * 1.5 + 0.5);
            for i in (0..4).step_by(2) {
                let xa = x1 + i as f32;
                a.k[i] = blur(xa * s);
                a.k[i + 1] = blur((xa + 1.0) * s);
            }
            return (1, a);
        }
        let upix = u - 0.5;
        let ui = upix.floor();
        (a.at, a.w) = (ui as i32, 2);
        a.k[0] = blur(upix - ui);
        a.k[1] = 1.0 - a.k[0];
        return (0, a);
    }
    let log2 = res_from_width(uw);
    let res = (1i32 << log2) as f32;
    let (upix, uwpix) = (u * res - 0.5, uw * res);
    let d = 2.0 * uwpix;
    let (u1, u2) = ((upix - d).ceil() as i32, (upix + d).ceil() as i32);
    (a.at, a.w) = (u1, (u2 - u1).clamp(0, KMAX as i32));
    let (x1, step) = ((u1 as f32 - upix) / uwpix, 1.0 / uwpix);
    for i in 0..a.w as usize {
        a.k[i] = bspline(x1 + i as f32 * step);
    }
    (log2, a)
}

fn build_kernel(u: f32, v: f32, uw: f32, vw: f32, face: Res) -> Kernel {
    let (ru, ku) = kernel_axis(u, uw, face.u);
    let (rv, kv) = kernel_axis(v, vw, face.v);
    Kernel { res: Res::new(ru, rv), u: ku, v: kv, rot: 0 }
}

/// A face a kernel is applied to, and how many subface splits led there.
#[derive(Clone, Copy)]
struct Face {
    id: i32,
    info: FaceInfo,
    depth: u32,
}

/// A face met walking around a corner, by the edge the walk left it through.
#[derive(Clone, Copy)]
struct Corner {
    face: i32,
    edge: i32,
    info: FaceInfo,
}

/// A lookup in progress: the running sum and weight.
struct Lookup<'a> {
    tx: &'a PtexFile,
    result: Vec<f32>,
    weight: f32,
}

impl PtexFile {
    /// The filtered value of face `face` at (u, v) with footprint (∂u/∂x, ∂v/∂x,
    /// ∂u/∂y, ∂v/∂y), normalised to 1.0 for the data type's largest number (Ptex's
    /// `PtexSeparableFilter::eval` with width 1 and no blur). Zero for a face that is
    /// not in the file.
    pub fn eval(&self, face: i32, u: f32, v: f32, duv: [f32; 4]) -> Vec<f32> {
        let n = self.channels;
        // DEVIATION(pbrt): robustness. The library leaves the result unwritten for a
        // face id outside the file, and pbrt reads whatever was on its stack.
        if face < 0 || face as usize >= self.faces.len() || !u.is_finite() || !v.is_finite() {
            return vec![0.0; n];
        }
        let f = &self.faces[face as usize];
        let one = self.data_type.one();
        if f.is_neighborhood_constant() {
            return pixel(&self.data(face as usize, Res::default()), Res::default(), 0, 0, n)
                .iter()
                .map(|x| x / one)
                .collect();
        }
        let duv = duv.map(|x| if x.is_finite() { x } else { 0.0 });
        if self.mesh == MeshType::Triangle {
            return super::triangle::eval(self, face as usize, u, v, duv);
        }
        let [uw1, vw1, uw2, vw2] = duv.map(f32::abs);
        let (uw, vw) = (uw1 + uw2, vw1 + vw2);
        let (Some(u), Some(v)) = (border(u, self.u_border), border(v, self.v_border)) else {
            return vec![0.0; n];
        };
        let mut k = if f.is_subface() {
            let r = Res::new(f.res.u + 1, f.res.v + 1);
            let mut k = build_kernel(u * 0.5, v * 0.5, uw * 0.5, vw * 0.5, r);
            if k.res.u == 0 {
                k.double_u();
            }
            if k.res.v == 0 {
                k.double_v();
            }
            k.res = Res::new(k.res.u - 1, k.res.v - 1);
            k
        } else {
            build_kernel(u, v, uw, vw, f.res)
        };
        k.strip_zeros();
        let mut l = Lookup { tx: self, result: vec![0.0; n], weight: k.weight() };
        l.split_and_apply(k, Face { id: face, info: *f, depth: 0 });
        let scale = 1.0 / (l.weight * one);
        l.result.iter().map(|x| x * scale).collect()
    }
}

/// Ptex's border modes on a coordinate: `None` where `black` leaves nothing.
fn border(u: f32, mode: BorderMode) -> Option<f32> {
    match mode {
        BorderMode::Clamp => Some(u.clamp(0.0, 1.0)),
        BorderMode::Periodic => Some(u - u.floor()),
        BorderMode::Black => (u > -1.0 && u < 2.0).then_some(u),
    }
}

impl Lookup<'_> {
    fn info(&self, face: i32) -> FaceInfo {
        self.tx.faces[face as usize]
    }

    fn split_and_apply(&mut self, mut k: Kernel, at: Face) {
        if at.depth > MAX_DEPTH {
            return;
        }
        let f = &at.info;
        let split_r = k.u.at + k.u.w > k.res.su();
        let split_l = k.u.at < 0;
        let split_t = k.v.at + k.v.w > k.res.sv();
        let split_b = k.v.at < 0;
        let (um, vm) = (self.tx.u_border, self.tx.v_border);
        // A piece split off sideways first gives up its corners: (whether it reaches
        // past the top, the edge the corner walk starts from), the same for the bottom.
        let sides = [(RIGHT, [(split_t, TOP), (split_b, RIGHT)]), (LEFT, [(split_t, LEFT), (split_b, BOTTOM)])];
        for (eid, corners) in sides {
            if (eid == RIGHT && !split_r) || (eid == LEFT && !split_l) {
                continue;
            }
            if f.adj_face(eid) < 0 {
                match eid {
                    RIGHT => k.u.merge_high(um, k.res.su()),
                    _ => k.u.merge_low(um),
                }
                continue;
            }
            let mut ka = if eid == RIGHT { k.split_right() } else { k.split_left() };
            self.split_corners(&mut ka, at, corners);
            self.apply_across_edge(ka, at, eid);
        }
        if split_t {
            if f.adj_face(TOP) >= 0 {
                let ka = k.split_top();
                self.apply_across_edge(ka, at, TOP);
            } else {
                k.v.merge_high(vm, k.res.sv());
            }
        }
        if split_b {
            if f.adj_face(BOTTOM) >= 0 {
                let ka = k.split_bottom();
                self.apply_across_edge(ka, at, BOTTOM);
            } else {
                k.v.merge_low(vm);
            }
        }
        self.apply(k, at.id, f);
    }

    /// The corner pieces of a piece split off sideways: for the top, then the bottom,
    /// whether it reaches past it and which edge the corner walk starts from.
    fn split_corners(&mut self, ka: &mut Kernel, at: Face, [(top, top_eid), (bottom, bottom_eid)]: [(bool, i32); 2]) {
        let vm = self.tx.v_border;
        if top {
            if at.info.adj_face(TOP) >= 0 {
                let kc = ka.split_top();
                self.apply_to_corner(kc, at, top_eid);
            } else {
                ka.v.merge_high(vm, ka.res.sv());
            }
        }
        if bottom {
            if at.info.adj_face(BOTTOM) >= 0 {
                let kc = ka.split_bottom();
                self.apply_to_corner(kc, at, bottom_eid);
            } else {
                ka.v.merge_low(vm);
            }
        }
    }

    /// Ptex's `applyAcrossEdge`.
    fn apply_across_edge(&mut self, mut k: Kernel, at: Face, eid: i32) {
        let f = &at.info;
        let (mut afid, mut aeid) = (f.adj_face(eid), f.adj_edge(eid));
        let mut af = self.info(afid);
        let mut rot = eid - aeid + 2;
        if f.is_subface() != af.is_subface() {
            if af.is_subface() {
                if !k.main_to_subface(eid) {
                    let neid = (aeid + 3) % 4;
                    (afid, aeid) = (af.adj_face(neid), af.adj_edge(neid));
                    if afid < 0 {
                        return;
                    }
                    af = self.info(afid);
                    rot += neid - aeid + 2;
                }
            } else {
                let primary = af.adj_face(aeid) == at.id;
                k.subface_to_main(eid - primary as i32);
            }
        }
        k.rotate(rot);
        if af.is_subface() {
            self.split_and_apply(k, Face { id: afid, info: af, depth: at.depth + 1 });
        } else {
            self.apply(k, afid, &af);
        }
    }

    /// Ptex's `applyToCorner`: walks clockwise around the corner vertex.
    fn apply_to_corner(&mut self, mut k: Kernel, at: Face, eid: i32) {
        const MAX_VALENCE: usize = 10;
        let (mut afid, mut aeid, mut af) = (at.id, eid, at.info);
        let mut prev_sub = af.is_subface();
        let mut corner = [Corner { face: 0, edge: 0, info: FaceInfo::default() }; MAX_VALENCE];
        let mut n_corners = 0usize;
        for (i, slot) in corner.iter_mut().enumerate() {
            let prev = afid;
            afid = af.adj_face(aeid);
            aeid = (af.adj_edge(aeid) + 1) % 4;
            if afid < 0 || (afid == at.id && aeid == eid) {
                n_corners = i.saturating_sub(2);
                break;
            }
            af = self.info(afid);
            *slot = Corner { face: afid, edge: aeid, info: af };
            let sub = af.is_subface();
            if prev_sub && !sub && af.adj_face((aeid + 3) % 4) == prev {
                let primary = (i == 1) as i32;
                k.subface_to_main(eid + primary * 2);
                k.rotate(eid - aeid + 3 - primary);
                self.split_and_apply(k, Face { id: afid, info: af, depth: at.depth + 1 });
                return;
            }
            prev_sub = sub;
        }
        if n_corners == 1 {
            self.apply_to_corner_face(k, at, eid, corner[1]);
        } else if n_corners > 1 {
            k.rotate(eid + 2);
            let initial = k.weight();
            let new = k.make_symmetric(initial);
            for &c in &corner[1..=n_corners] {
                self.apply_to_corner_face(k, at, 2, c);
            }
            self.weight += new * n_corners as f32 - initial;
        } else {
            self.weight -= k.weight();
        }
    }

    /// Ptex's `applyToCornerFace`.
    fn apply_to_corner_face(&mut self, mut k: Kernel, at: Face, eid: i32, c: Corner) {
        if at.info.is_subface() != c.info.is_subface() {
            if c.info.is_subface() {
                k.main_to_subface(eid + 3);
            } else {
                k.subface_to_main(eid + 3);
            }
        }
        k.rotate(eid - c.edge + 2);
        if c.info.is_subface() {
            self.split_and_apply(k, Face { id: c.face, info: c.info, depth: at.depth + 1 });
        } else {
            self.apply(k, c.face, &c.info);
        }
    }

    /// Adds the kernel's sum over face `face`'s texels (Ptex's `apply`).
    fn apply(&mut self, mut k: Kernel, face: i32, f: &FaceInfo) {
        if k.u.w <= 0 || k.v.w <= 0 {
            return;
        }
        while k.res.u > f.res.u {
            k.halve_u();
        }
        while k.res.v > f.res.v {
            k.halve_v();
        }
        let n = self.tx.channels;
        let data = self.tx.data(face as usize, k.res);
        let mut add = vec![0.0f32; n];
        match &*data {
            FaceData::Constant(c) => {
                // Constants are added unturned, tangent vectors or not (as the library).
                let w = k.weight();
                self.result.iter_mut().zip(c.iter()).for_each(|(a, &c)| *a += c * w);
                return;
            }
            FaceData::Texels { res, texels } => {
                let inside = k.u.at >= 0 && k.v.at >= 0 && k.u.at + k.u.w <= res.su() && k.v.at + k.v.w <= res.sv();
                if *res != k.res || !inside {
                    return; // a damaged neighbour link: the library would read out of bounds
                }
                let mut row = vec![0.0f32; n];
                for j in 0..k.v.w {
                    let line = ((k.v.at + j) * res.su() + k.u.at) as usize * n;
                    row.iter_mut().enumerate().for_each(|(c, r)| *r = texels[line + c] * k.u.k[0]);
                    for i in 1..k.u.w as usize {
                        let at = line + i * n;
                        row.iter_mut().enumerate().for_each(|(c, r)| *r += texels[at + c] * k.u.k[i]);
                    }
                    add.iter_mut().zip(&row).for_each(|(a, r)| *a += r * k.v.k[j as usize]);
                }
            }
        }
        self.add_rotated(&add, k.rot);
    }

    /// Adds a face's share, turning tangent vectors (channels 0 and 1) with the kernel
    /// where the file says its values are such vectors.
    fn add_rotated(&mut self, add: &[f32], rot: i32) {
        let r = &mut self.result;
        if self.tx.tanvec && add.len() >= 2 && rot > 0 {
            let (a, b) = match rot {
                1 => (-add[1], add[0]),
                2 => (-add[0], -add[1]),
                _ => (add[1], -add[0]),
            };
            r[0] += a;
            r[1] += b;
            r.iter_mut().zip(add).skip(2).for_each(|(r, a)| *r += a);
        } else {
            r.iter_mut().zip(add).for_each(|(r, a)| *r += a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(name: &str) -> PtexFile {
        let dir = env!("CARGO_MANIFEST_DIR");
        let bytes = std::fs::read(format!("{dir}/pbrt-scenes/verify/textures/ptex-{name}.ptx")).unwrap();
        PtexFile::read(&bytes, 1 << 30).unwrap()
    }

    /// Every lookup in `tests/data/ptex/probes-NAME.txt` (the Ptex library's values,
    /// printed by tools/ptex_probe.cpp) gives the library's value.
    fn matches_the_library(name: &str) {
        let tx = load(name);
        let dir = env!("CARGO_MANIFEST_DIR");
        let probes = std::fs::read_to_string(format!("{dir}/tests/data/ptex/probes-{name}.txt")).unwrap();
        let mut worst = (0.0f32, String::new());
        for line in probes.lines() {
            let w: Vec<f32> = line.split_whitespace().map(|x| x.parse().unwrap()).collect();
            let got = tx.eval(w[0] as i32, w[1], w[2], [w[3], w[4], w[5], w[6]]);
            for (g, want) in got.iter().zip(&w[7..]) {
                let err = (g - want).abs() / want.abs().max(0.05);
                if err > worst.0 {
                    worst = (err, format!("{line}: got {got:?}"));
                }
            }
        }
        assert!(worst.0 < 1e-5, "{name}: worst relative error {} at {}", worst.0, worst.1);
    }

    #[test]
    fn grid_lookups_match_the_ptex_library() {
        matches_the_library("grid");
    }

    #[test]
    fn cube_lookups_match_the_ptex_library() {
        matches_the_library("cube");
    }

    #[test]
    fn fan_lookups_match_the_ptex_library() {
        matches_the_library("fan");
    }

    #[test]
    fn triangle_lookups_match_the_ptex_library() {
        matches_the_library("tri");
    }
}
