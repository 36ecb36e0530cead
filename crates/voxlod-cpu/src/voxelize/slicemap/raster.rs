//! Rasterization of [`SliceTriangle`]s as a GPU does it, and each fragment's depth.
//!
//! # Standard coverage (what the paper's hardware does)
//! A pixel produces a fragment when its **centre** `(x + ½, y + ½)` lies inside the snapped
//! triangle, decided in integer arithmetic on the `1/256`-pixel lattice. A centre exactly on an
//! edge counts by the **top-left rule** of Direct3D and Vulkan rasterizers (window y grows
//! downward): with the edge function `E = A·x + B·y + C` positive inside, a tie counts when
//! `A > 0` (a left edge) or `A = 0, B > 0` (a top edge), so two triangles sharing an edge never
//! both cover a centre on it, and a triangle of zero snapped area covers nothing — a triangle
//! seen exactly edge-on is missed (Eisemann and Décoret 2006, §2.5, Fig. 3 left).
//!
//! # Conservative coverage (the workaround of §2.5)
//! Every pixel whose **closed square** meets the closed snapped triangle produces a fragment
//! (overestimating conservative rasterization, as `VK_EXT_conservative_rasterization` defines
//! it), decided exactly by separating axes in integer arithmetic: the boxes overlap and no
//! edge line separates the square (for a zero-area triangle, its segment's line, both ways).
//! The fragment carries the **range** of depths the triangle takes over the square, so that a
//! steep triangle sets every slice it passes through in that column, not only the slice at the
//! centre (§2.5, Fig. 3 right). The range comes from the candidates for the extremes of the
//! affine `q` over triangle ∩ square: the triangle's vertices inside the square, the square's
//! corners inside the triangle, and the crossings of triangle edges with the square's sides;
//! which candidates exist is decided in integers, only their `q` values are rounded (`f32`),
//! and the range is clamped into the vertices' range (which it lies in exactly).
//!
//! # Depth of a fragment
//! Both rules give eye-space depth through `q` (module [`super::camera`]), evaluated in `f32`
//! exactly as the WGSL does: at a pixel centre `q = (q0 + ∂q/∂x·dx) + ∂q/∂y·dy` with
//! `(dx, dy)` the centre minus vertex 0 (exact in `f32`), then `z = q` or `1/q`, and the
//! fragment's depth below the near plane `d = z − near`.

use super::camera::{SUBPIXEL, SliceTriangle};

/// The per-map constants a fragment's depth needs (mirrors part of the WGSL `Params`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthParams {
    /// Whether `z = 1/q` (perspective) rather than `z = q`.
    pub perspective: bool,
    /// `near` rounded to `f32`.
    pub near: f32,
}

impl DepthParams {
    /// `d = z − near` of depth parameter `q`.
    #[inline]
    pub fn d_of_q(&self, q: f32) -> f32 {
        let z = if self.perspective { 1.0 / q } else { q };
        z - self.near
    }

    /// The interval of `d` for `q` in `[q_lo, q_hi]`.
    #[inline]
    pub fn d_range(&self, q_lo: f32, q_hi: f32) -> (f32, f32) {
        if self.perspective {
            (self.d_of_q(q_hi), self.d_of_q(q_lo))
        } else {
            (self.d_of_q(q_lo), self.d_of_q(q_hi))
        }
    }
}

/// `q` at pixel centre `(x + ½, y + ½)` by the triangle's plane, in `f32` as the WGSL does.
#[inline]
pub fn q_at_centre(t: &SliceTriangle, x: u32, y: u32) -> f32 {
    let dx = (x as f32 + 0.5) - t.x0 as f32 / SUBPIXEL as f32;
    let dy = (y as f32 + 0.5) - t.y0 as f32 / SUBPIXEL as f32;
    (t.q0 + t.dqdx * dx) + t.dqdy * dy
}

/// The range of pixel indices whose closed extent `[p, p + 1]` meets `[lo, hi]` (sub-pixel
/// units), clipped to `0..side`; `None` if empty.
#[inline]
fn pixel_span(lo: i64, hi: i64, side: u32) -> Option<(u32, u32)> {
    let a = ((lo - 1) >> super::camera::SUBPIXEL_BITS).max(0);
    let b = (hi >> super::camera::SUBPIXEL_BITS).min(side as i64 - 1);
    (a <= b).then_some((a as u32, b as u32))
}

/// An edge `E(p) = A·(x − xa) + B·(y − ya)`, positive inside, in sub-pixel units.
#[derive(Clone, Copy, Debug)]
struct Edge {
    a: i64,
    b: i64,
    xa: i64,
    ya: i64,
}

impl Edge {
    #[inline]
    fn new(from: (i64, i64), to: (i64, i64)) -> Self {
        Edge { a: -(to.1 - from.1), b: to.0 - from.0, xa: from.0, ya: from.1 }
    }

    #[inline]
    fn at(&self, x: i64, y: i64) -> i64 {
        self.a * (x - self.xa) + self.b * (y - self.ya)
    }

    /// Whether a centre with `E = 0` counts: the top-left rule.
    #[inline]
    fn top_left(&self) -> bool {
        self.a > 0 || (self.a == 0 && self.b > 0)
    }
}

/// The three edges of `t`, oriented so that the interior is positive (for zero area, as
/// given).
#[inline]
fn edges(t: &SliceTriangle) -> [Edge; 3] {
    let (v0, mut v1, mut v2) = (t.vertex(0), t.vertex(1), t.vertex(2));
    if t.area2() < 0 {
        std::mem::swap(&mut v1, &mut v2);
    }
    [Edge::new(v0, v1), Edge::new(v1, v2), Edge::new(v2, v0)]
}

/// Calls `emit(x, y)` for every pixel of a `width × height` map whose centre the triangle
/// covers under the standard rule (module docs), row by row.
pub fn for_each_covered(
    t: &SliceTriangle,
    width: u32,
    height: u32,
    mut emit: impl FnMut(u32, u32),
) {
    if t.area2() == 0 {
        return;
    }
    let e = edges(t);
    let (xs, ys) = ([t.x0, t.x1, t.x2], [t.y0, t.y1, t.y2]);
    let (lo_x, hi_x) = (*xs.iter().min().unwrap() as i64, *xs.iter().max().unwrap() as i64);
    let (lo_y, hi_y) = (*ys.iter().min().unwrap() as i64, *ys.iter().max().unwrap() as i64);
    // Centres c = 256·p + 128 with lo ≤ c ≤ hi.
    let half = SUBPIXEL / 2;
    let first = |lo: i64| (lo - half + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let last = |hi: i64, side: u32| (hi - half).div_euclid(SUBPIXEL).min(side as i64 - 1);
    let (x0, x1) = (first(lo_x), last(hi_x, width));
    let (y0, y1) = (first(lo_y), last(hi_y, height));
    let bias = e.map(|e| if e.top_left() { 0 } else { 1 });
    for y in y0..=y1 {
        let cy = y * SUBPIXEL + half;
        let cx = x0 * SUBPIXEL + half;
        let mut v = [e[0].at(cx, cy), e[1].at(cx, cy), e[2].at(cx, cy)];
        let step = e.map(|e| e.a * SUBPIXEL);
        for x in x0..=x1 {
            if v[0] >= bias[0] && v[1] >= bias[1] && v[2] >= bias[2] {
                emit(x as u32, y as u32);
            }
            for k in 0..3 {
                v[k] += step[k];
            }
        }
    }
}

/// Whether the closed square of pixel `(x, y)` meets the closed triangle `e` (edges) of
/// `area2` — boxes are checked by the caller.
#[inline]
fn square_meets(e: &[Edge; 3], area2: i64, x: i64, y: i64) -> bool {
    let (x0, y0) = (x * SUBPIXEL, y * SUBPIXEL);
    let (x1, y1) = (x0 + SUBPIXEL, y0 + SUBPIXEL);
    e.iter().all(|e| {
        if area2 != 0 {
            // The corner where E is largest must not be outside.
            let cx = if e.a > 0 { x1 } else { x0 };
            let cy = if e.b > 0 { y1 } else { y0 };
            e.at(cx, cy) >= 0
        } else if e.a == 0 && e.b == 0 {
            true
        } else {
            // A segment: its line must meet the square (corners not all on one side).
            let c = [e.at(x0, y0), e.at(x1, y0), e.at(x0, y1), e.at(x1, y1)];
            c.iter().any(|&v| v <= 0) && c.iter().any(|&v| v >= 0)
        }
    })
}

/// The range `[q_lo, q_hi]` of `q` over the triangle ∩ the closed square of pixel `(x, y)`
/// (module docs), or `None` if they do not meet (never for a pixel the conservative rule
/// covers).
pub fn q_range_in_square(t: &SliceTriangle, x: u32, y: u32) -> Option<(f32, f32)> {
    let (sx0, sy0) = (x as i64 * SUBPIXEL, y as i64 * SUBPIXEL);
    let (sx1, sy1) = (sx0 + SUBPIXEL, sy0 + SUBPIXEL);
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    let mut add = |q: f32| {
        lo = lo.min(q);
        hi = hi.max(q);
    };
    let v = [t.vertex(0), t.vertex(1), t.vertex(2)];
    let q = [t.q0, t.q1, t.q2];
    for i in 0..3 {
        if v[i].0 >= sx0 && v[i].0 <= sx1 && v[i].1 >= sy0 && v[i].1 <= sy1 {
            add(q[i]);
        }
    }
    let area2 = t.area2();
    if area2 != 0 {
        let e = edges(t);
        for (cx, cy) in [(sx0, sy0), (sx1, sy0), (sx0, sy1), (sx1, sy1)] {
            if e.iter().all(|e| e.at(cx, cy) >= 0) {
                let dx = (cx - v[0].0) as f32 / SUBPIXEL as f32;
                let dy = (cy - v[0].1) as f32 / SUBPIXEL as f32;
                add((t.q0 + t.dqdx * dx) + t.dqdy * dy);
            }
        }
    }
    for i in 0..3 {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let (qa, qb) = (q[i], q[(i + 1) % 3]);
        // Crossings with the vertical sides x = s, y in [sy0, sy1].
        let den = b.0 - a.0;
        if den != 0 {
            for s in [sx0, sx1] {
                let num = s - a.0;
                // 0 ≤ num/den ≤ 1 and sy0 ≤ a.y + (b.y − a.y)·num/den ≤ sy1, times |den|.
                let (n, d) = if den > 0 { (num, den) } else { (-num, -den) };
                let yn = (b.1 - a.1) * n;
                if n >= 0 && n <= d && (sy0 - a.1) * d <= yn && yn <= (sy1 - a.1) * d {
                    add(qa + (qb - qa) * (num as f32 / den as f32));
                }
            }
        }
        let den = b.1 - a.1;
        if den != 0 {
            for s in [sy0, sy1] {
                let num = s - a.1;
                let (n, d) = if den > 0 { (num, den) } else { (-num, -den) };
                let xn = (b.0 - a.0) * n;
                if n >= 0 && n <= d && (sx0 - a.0) * d <= xn && xn <= (sx1 - a.0) * d {
                    add(qa + (qb - qa) * (num as f32 / den as f32));
                }
            }
        }
    }
    // The range over part of the triangle lies within its vertices' range: clamp what
    // rounding pushed out.
    let (qmin, qmax) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
    (lo <= hi).then_some((lo.clamp(qmin, qmax), hi.clamp(qmin, qmax)))
}

/// Calls `emit(x, y, q_lo, q_hi)` for every pixel of a `width × height` map whose closed
/// square meets the triangle (conservative rule, module docs), with the range of `q` there.
pub fn for_each_conservative(
    t: &SliceTriangle,
    width: u32,
    height: u32,
    mut emit: impl FnMut(u32, u32, f32, f32),
) {
    let (xs, ys) = ([t.x0, t.x1, t.x2], [t.y0, t.y1, t.y2]);
    let (lo_x, hi_x) = (*xs.iter().min().unwrap() as i64, *xs.iter().max().unwrap() as i64);
    let (lo_y, hi_y) = (*ys.iter().min().unwrap() as i64, *ys.iter().max().unwrap() as i64);
    let (Some((x0, x1)), Some((y0, y1))) =
        (pixel_span(lo_x, hi_x, width), pixel_span(lo_y, hi_y, height))
    else {
        return;
    };
    let e = edges(t);
    let area2 = t.area2();
    for y in y0..=y1 {
        for x in x0..=x1 {
            if square_meets(&e, area2, x as i64, y as i64)
                && let Some((lo, hi)) = q_range_in_square(t, x, y)
            {
                emit(x, y, lo, hi);
            }
        }
    }
}

/// The pixel rectangle `[x0, x1] × [y0, y1]` (inclusive, clipped to the map) whose squares
/// meet the triangle's bounding box: the quad the GPU's conservative emulation draws.
pub fn conservative_bounds(t: &SliceTriangle, width: u32, height: u32) -> Option<[u32; 4]> {
    let (xs, ys) = ([t.x0, t.x1, t.x2], [t.y0, t.y1, t.y2]);
    let (lo_x, hi_x) = (*xs.iter().min().unwrap() as i64, *xs.iter().max().unwrap() as i64);
    let (lo_y, hi_y) = (*ys.iter().min().unwrap() as i64, *ys.iter().max().unwrap() as i64);
    let (x0, x1) = pixel_span(lo_x, hi_x, width)?;
    let (y0, y1) = pixel_span(lo_y, hi_y, height)?;
    Some([x0, y0, x1, y1])
}
