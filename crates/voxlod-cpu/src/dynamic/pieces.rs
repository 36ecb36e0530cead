//! The piece of a triangle inside a voxel: the triangle clipped to the voxel's closed box
//! (Sutherland–Hodgman against its six planes, in `f64`), with its area and centroid. Skin
//! weights and fragment records are interpolated at these centroids.

use glam::DVec3;

/// A triangle's piece inside a box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Area of the piece.
    pub area: f64,
    /// Area centroid of the piece (the triangle's centroid for a piece of zero area).
    pub centroid: DVec3,
}

/// Clips triangle `tri` to the box `[lo, hi]`; `None` when nothing of it is inside. A
/// degenerate triangle (or a piece that degenerates to a segment or point) has zero area and
/// the mean of its clipped vertices as centroid.
pub fn clip(tri: [DVec3; 3], lo: DVec3, hi: DVec3) -> Option<Piece> {
    let mut poly: Vec<DVec3> = tri.to_vec();
    let mut next: Vec<DVec3> = Vec::with_capacity(9);
    for axis in 0..3 {
        for (bound, keep_below) in [(lo[axis], false), (hi[axis], true)] {
            next.clear();
            let inside = |p: DVec3| if keep_below { p[axis] <= bound } else { p[axis] >= bound };
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                let (ia, ib) = (inside(a), inside(b));
                if ia {
                    next.push(a);
                }
                if ia != ib {
                    let t = (bound - a[axis]) / (b[axis] - a[axis]);
                    let mut p = a + (b - a) * t;
                    p[axis] = bound;
                    next.push(p);
                }
            }
            std::mem::swap(&mut poly, &mut next);
            if poly.is_empty() {
                return None;
            }
        }
    }
    // Fan from the first vertex: area-weighted centroid of the fan triangles.
    let (mut area, mut weighted) = (0.0, DVec3::ZERO);
    for i in 1..poly.len().saturating_sub(1) {
        let (a, b, c) = (poly[0], poly[i], poly[i + 1]);
        let t = 0.5 * (b - a).cross(c - a).length();
        area += t;
        weighted += (a + b + c) / 3.0 * t;
    }
    let centroid = if area > 0.0 {
        weighted / area
    } else {
        poly.iter().copied().sum::<DVec3>() / poly.len() as f64
    };
    Some(Piece { area, centroid })
}

/// Barycentric weights `(w0, w1, w2)` of `p` in triangle `tri` (projected onto its plane),
/// clamped to non-negative and renormalized; a degenerate triangle gives `(⅓, ⅓, ⅓)`.
pub fn barycentric(tri: [DVec3; 3], p: DVec3) -> [f64; 3] {
    let (e0, e1, d) = (tri[1] - tri[0], tri[2] - tri[0], p - tri[0]);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let (d20, d21) = (d.dot(e0), d.dot(e1));
    let den = d00 * d11 - d01 * d01;
    if den.is_nan() || den <= 1e-300 {
        return [1.0 / 3.0; 3];
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    let b = [(1.0 - v - w).max(0.0), v.max(0.0), w.max(0.0)];
    let s = b[0] + b[1] + b[2];
    if s > 0.0 { b.map(|x| x / s) } else { [1.0 / 3.0; 3] }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_inside_is_kept_whole_and_a_big_one_is_cut_to_the_box() {
        let t = [DVec3::new(0.1, 0.1, 0.5), DVec3::new(0.9, 0.1, 0.5), DVec3::new(0.1, 0.9, 0.5)];
        let p = clip(t, DVec3::ZERO, DVec3::ONE).unwrap();
        assert!((p.area - 0.32).abs() < 1e-12);
        assert!((p.centroid - (t[0] + t[1] + t[2]) / 3.0).length() < 1e-12);
        // A large triangle covering the whole z = 0.5 cross-section: the piece is the unit square.
        let big =
            [DVec3::new(-5.0, -5.0, 0.5), DVec3::new(10.0, -5.0, 0.5), DVec3::new(-5.0, 10.0, 0.5)];
        let p = clip(big, DVec3::ZERO, DVec3::ONE).unwrap();
        assert!((p.area - 1.0).abs() < 1e-12, "{}", p.area);
        assert!((p.centroid - DVec3::new(0.5, 0.5, 0.5)).length() < 1e-12);
        // Outside, and touching a face (the closed box keeps a zero-area piece).
        assert_eq!(clip(t.map(|v| v + DVec3::X * 3.0), DVec3::ZERO, DVec3::ONE), None);
        let touching = t.map(|v| DVec3::new(v.x, v.y, 1.0));
        assert!(clip(touching, DVec3::ZERO, DVec3::ONE).is_some());
    }

    #[test]
    fn barycentric_weights_interpolate_and_degenerate_triangles_average() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let b = barycentric(t, DVec3::new(0.25, 0.5, 0.0));
        assert!(
            (b[0] - 0.25).abs() < 1e-12
                && (b[1] - 0.25).abs() < 1e-12
                && (b[2] - 0.5).abs() < 1e-12
        );
        assert_eq!(barycentric([DVec3::ZERO; 3], DVec3::ONE), [1.0 / 3.0; 3]);
    }
}
