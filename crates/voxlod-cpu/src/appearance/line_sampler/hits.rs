//! The closest hits of a batch of lines on a voxel's triangles ([`HitBatch::closest`]): the
//! triangle loop outside, the line loop inside, so that without alpha materials the inner loop
//! is branch-free and the compiler vectorizes it (8 lines per instruction with AVX2, detected
//! at run time). Ties in `t` keep the earlier triangle (the lowest id, lists are ascending), so
//! the result equals a per-line loop over the triangles, whatever the order lines are done in.

use glam::Vec3;

use super::lines::LineBatch;

/// A triangle of the voxel being sampled, in voxel-local coordinates (`(p − min)/size`).
#[derive(Clone, Copy, Debug)]
pub(super) struct LocalTriangle {
    pub a: Vec3,
    /// Unit plane normal and offset (`n·p = offset` on the plane).
    pub n: Vec3,
    pub offset: f32,
    /// Barycentric planes: a point `p` of the triangle's plane has weights `u = bu·p + cu`
    /// (vertex 1) and `v = bv·p + cv` (vertex 2).
    pub bu: Vec3,
    pub cu: f32,
    pub bv: Vec3,
    pub cv: f32,
    /// Bit `j`: all three local vertices have the same coordinate `j`, namely `a[j]`.
    pub flat: u8,
    /// Whether the material's alpha filters hits (not `Opaque`).
    pub alpha: bool,
    /// World-space geometric normal `(b−a)×(c−a)`, computed as the ground truth does.
    pub normal: Vec3,
    pub triangle: u32,
    pub material: u32,
}

impl LocalTriangle {
    /// Where the whole line `entry + t·d` meets the triangle: `(t, u, v, hit)`, where `hit`
    /// says that the line crosses the triangle (edges count) at a finite `t < closer`. `t` comes
    /// from the plane, a line in (or parallel to) the plane gives a non-finite `t` and misses.
    #[inline(always)]
    pub fn intersect(&self, entry: Vec3, d: Vec3, closer: f32) -> (f32, f32, f32, bool) {
        let t = (self.offset - self.n.dot(entry)) / self.n.dot(d);
        let p = entry + d * t;
        let u = self.bu.dot(p) + self.cu;
        let v = self.bv.dot(p) + self.cv;
        let hit = (t < closer) & (t > f32::NEG_INFINITY) & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0);
        (t, u, v, hit)
    }
}

/// The closest hit of each line of a batch: `k[j]` is the index of line `j`'s closest
/// accepted triangle in the voxel's list (`u32::MAX` for none), at `t[j]` with barycentrics
/// `u[j]`, `v[j]`.
#[derive(Clone, Debug, Default)]
pub(super) struct HitBatch {
    pub t: Vec<f32>,
    pub k: Vec<u32>,
    pub u: Vec<f32>,
    pub v: Vec<f32>,
    /// Scratch: the lines whose geometric test passed, for an alpha-filtered triangle.
    candidates: Vec<u32>,
}

impl HitBatch {
    /// The closest hits of `lines` on `tris`; a geometric hit on a triangle with `alpha` set
    /// counts only where `accepts(triangle, line, u, v)`.
    pub fn closest<F>(&mut self, tris: &[LocalTriangle], lines: &LineBatch, mut accepts: F)
    where
        F: FnMut(&LocalTriangle, usize, f32, f32) -> bool,
    {
        let n = lines.chord.len();
        self.t.clear();
        self.t.resize(n, f32::INFINITY);
        self.k.clear();
        self.k.resize(n, u32::MAX);
        for v in [&mut self.u, &mut self.v] {
            v.clear();
            v.resize(n, 0.0);
        }
        self.candidates.resize(n, 0);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.closest_avx2(tris, lines, &mut accepts) };
            return;
        }
        self.closest_any(tris, lines, &mut accepts);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn closest_avx2<F>(&mut self, tris: &[LocalTriangle], lines: &LineBatch, accepts: &mut F)
    where
        F: FnMut(&LocalTriangle, usize, f32, f32) -> bool,
    {
        self.closest_any(tris, lines, accepts);
    }

    /// The loops of [`HitBatch::closest`], over the already sized and initialized arrays.
    #[inline(always)]
    fn closest_any<F>(&mut self, tris: &[LocalTriangle], lines: &LineBatch, accepts: &mut F)
    where
        F: FnMut(&LocalTriangle, usize, f32, f32) -> bool,
    {
        let n = self.t.len();
        let ([dx, dy, dz], [ex, ey, ez]) = (&lines.dir, &lines.entry);
        let (dx, dy, dz, ex, ey, ez) = (&dx[..n], &dy[..n], &dz[..n], &ex[..n], &ey[..n], &ez[..n]);
        let (bt, bk) = (&mut self.t[..n], &mut self.k[..n]);
        let (bu, bv) = (&mut self.u[..n], &mut self.v[..n]);
        let candidates = &mut self.candidates[..n];
        for (k, tri) in tris.iter().enumerate() {
            let (tri, k) = (*tri, k as u32);
            if tri.alpha {
                // The geometric test branch-free into a compacted list of candidate lines, then
                // the (costly, branchy) alpha filter on the candidates alone.
                let mut m = 0;
                for j in 0..n {
                    let (e, d) = (Vec3::new(ex[j], ey[j], ez[j]), Vec3::new(dx[j], dy[j], dz[j]));
                    let (_, _, _, hit) = tri.intersect(e, d, bt[j]);
                    candidates[m] = j as u32;
                    m += hit as usize;
                }
                for &j in &candidates[..m] {
                    let j = j as usize;
                    let (e, d) = (Vec3::new(ex[j], ey[j], ez[j]), Vec3::new(dx[j], dy[j], dz[j]));
                    let (t, u, v, _) = tri.intersect(e, d, bt[j]);
                    if accepts(&tri, j, u, v) {
                        (bt[j], bk[j], bu[j], bv[j]) = (t, k, u, v);
                    }
                }
            } else {
                // Branch-free selects: whether a line hits is random.
                for j in 0..n {
                    let (e, d) = (Vec3::new(ex[j], ey[j], ez[j]), Vec3::new(dx[j], dy[j], dz[j]));
                    let (t, u, v, hit) = tri.intersect(e, d, bt[j]);
                    bt[j] = if hit { t } else { bt[j] };
                    bk[j] = if hit { k } else { bk[j] };
                    bu[j] = if hit { u } else { bu[j] };
                    bv[j] = if hit { v } else { bv[j] };
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::rand_f32;

    /// A triangle from three local vertices, set up as the sampler does (in f32 here).
    fn local(a: Vec3, b: Vec3, c: Vec3, id: u32, alpha: bool) -> LocalTriangle {
        let n = (b - a).cross(c - a);
        let area2 = n.length_squared();
        let (bu, bv) = ((c - a).cross(n) / area2, n.cross(b - a) / area2);
        let unit = n / area2.sqrt();
        LocalTriangle {
            a,
            n: unit,
            offset: unit.dot(a),
            bu,
            cu: -bu.dot(a),
            bv,
            cv: -bv.dot(a),
            flat: 0,
            alpha,
            normal: n,
            triangle: id,
            material: 0,
        }
    }

    /// The batched closest hits (vectorized and portable) equal a per-line loop over the
    /// triangles, with and without alpha filtering.
    #[test]
    fn batched_closest_hits_equal_a_per_line_loop() {
        let r = |i: u32, k: u32| rand_f32(i, k, 99) * 2.0 - 0.5;
        let v = |i: u32, k: u32| Vec3::new(r(i, 3 * k), r(i, 3 * k + 1), r(i, 3 * k + 2));
        let mut lines = LineBatch::default();
        lines.fill(5, 0, 300, 0);
        for alpha_every in [0u32, 2, 3] {
            let tris: Vec<LocalTriangle> = (0..12)
                .map(|i| {
                    local(v(i, 0), v(i, 1), v(i, 2), i, alpha_every > 0 && i % alpha_every == 0)
                })
                .collect();
            let accepts = |tri: &LocalTriangle, j: usize, _u: f32, _v: f32| {
                !(tri.triangle + j as u32).is_multiple_of(3)
            };
            let (mut fast, mut portable) = (HitBatch::default(), HitBatch::default());
            fast.closest(&tris, &lines, accepts);
            portable.closest(&tris, &lines, accepts); // sizes the arrays
            portable.t.fill(f32::INFINITY);
            portable.k.fill(u32::MAX);
            portable.closest_any(&tris, &lines, &mut { accepts });
            let mut hits = 0;
            for j in 0..300 {
                let e = Vec3::new(lines.entry[0][j], lines.entry[1][j], lines.entry[2][j]);
                let d = Vec3::new(lines.dir[0][j], lines.dir[1][j], lines.dir[2][j]);
                let (mut bt, mut bk) = (f32::INFINITY, u32::MAX);
                for (k, tri) in tris.iter().enumerate() {
                    let (t, u, v, hit) = tri.intersect(e, d, bt);
                    if hit && (!tri.alpha || accepts(tri, j, u, v)) {
                        (bt, bk) = (t, k as u32);
                    }
                }
                for b in [&fast, &portable] {
                    assert_eq!((b.k[j], b.t[j].to_bits()), (bk, bt.to_bits()), "line {j}");
                }
                hits += (bk != u32::MAX) as u32;
            }
            assert!(hits > 30, "{hits} lines hit");
        }
    }
}
