//! The symmetric 3×3 eigen solver shared by the SGGX fit, the virtual mesh's eigenframe and the
//! Averages fallback normal (design note §3, §5, §2): cyclic Jacobi in f64 with a fixed sweep
//! order, so the result is a pure function of the input bits, with a canonical order, sign and
//! handedness of the eigenvectors (the reference code leaves all three to Eigen, §8.7).
//!
//! Rules (each tested below):
//! - **Sweep order** `(0,1), (0,2), (1,2)`, at most [`MAX_SWEEPS`] sweeps, stopping when the
//!   off-diagonal mass is below `10⁻³⁰` of the matrix's squared Frobenius norm.
//! - **Order**: eigenvalues descending; ties (exactly equal values) keep the lower index of the
//!   converged diagonal first.
//! - **Sign**: each of `e0`, `e1` has its largest-magnitude component positive, the first such
//!   index on ties.
//! - **Handedness**: `e2 = e0 × e1`, so `(e0, e1, e2)` is a right-handed orthonormal frame
//!   (`e2` is not re-signed).

use glam::DVec3;

/// Upper bound on Jacobi sweeps; a 3×3 matrix converges quadratically in 4–6.
pub const MAX_SWEEPS: usize = 32;

/// Eigen-decomposition of the symmetric matrix `m` (row-major; only the upper triangle is read,
/// the lower is assumed equal).
///
/// Returns `(λ, e)` with `λ[0] ≥ λ[1] ≥ λ[2]` and `m·e[k] = λ[k]·e[k]`; `e` is orthonormal and
/// right-handed with canonical signs (module docs). Non-finite input gives non-finite output
/// (never a panic).
pub fn symmetric_eigen(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    // Work on a symmetrized copy built from the upper triangle.
    let mut a =
        [[m[0][0], m[0][1], m[0][2]], [m[0][1], m[1][1], m[1][2]], [m[0][2], m[1][2], m[2][2]]];
    // v's columns are the eigenvectors.
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let frob2: f64 = a.iter().flatten().map(|x| x * x).sum();
    if frob2.is_finite() {
        for _ in 0..MAX_SWEEPS {
            let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
            if off <= 1e-30 * frob2 {
                break;
            }
            for (p, q) in [(0, 1), (0, 2), (1, 2)] {
                rotate(&mut a, &mut v, p, q);
            }
        }
    }
    let diag = [a[0][0], a[1][1], a[2][2]];
    let mut order = [0usize, 1, 2];
    // Stable: equal eigenvalues keep the lower index first.
    order.sort_by(|&i, &j| diag[j].total_cmp(&diag[i]));
    let col = |k: usize| DVec3::new(v[0][k], v[1][k], v[2][k]);
    let e0 = canonical_sign(col(order[0]));
    let e1 = canonical_sign(col(order[1]));
    let e2 = e0.cross(e1);
    (order.map(|k| diag[k]), [e0, e1, e2])
}

/// One Jacobi rotation zeroing `a[p][q]` (Golub & Van Loan, Alg. 8.4.2, the stable small-angle
/// choice of `t`), accumulated into `v`.
fn rotate(a: &mut [[f64; 3]; 3], v: &mut [[f64; 3]; 3], p: usize, q: usize) {
    let apq = a[p][q];
    if apq == 0.0 {
        return;
    }
    let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
    // For huge θ, t underflows to 0 gracefully; θ·θ overflow gives t = 0 too.
    let t = if t.is_finite() { t } else { 0.0 };
    let c = 1.0 / (t * t + 1.0).sqrt();
    let s = t * c;
    // A ← Jᵀ A J with J the rotation in the (p, q) plane.
    for row in a.iter_mut() {
        let (akp, akq) = (row[p], row[q]);
        row[p] = c * akp - s * akq;
        row[q] = s * akp + c * akq;
    }
    let (rp, rq) = (a[p], a[q]);
    a[p] = std::array::from_fn(|k| c * rp[k] - s * rq[k]);
    a[q] = std::array::from_fn(|k| s * rp[k] + c * rq[k]);
    a[p][q] = 0.0;
    a[q][p] = 0.0;
    for row in v.iter_mut() {
        let (vp, vq) = (row[p], row[q]);
        row[p] = c * vp - s * vq;
        row[q] = s * vp + c * vq;
    }
}

/// `e` or `−e`, whichever has its largest-magnitude component positive (the first such index
/// on ties).
pub fn canonical_sign(e: DVec3) -> DVec3 {
    let a = e.abs();
    let k = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    if e[k] < 0.0 { -e } else { e }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn mul(m: [[f64; 3]; 3], x: DVec3) -> DVec3 {
        DVec3::new(
            m[0][0] * x.x + m[0][1] * x.y + m[0][2] * x.z,
            m[1][0] * x.x + m[1][1] * x.y + m[1][2] * x.z,
            m[2][0] * x.x + m[2][1] * x.y + m[2][2] * x.z,
        )
    }

    /// Asserts the decomposition's contract: eigen-equation, descending order, orthonormal,
    /// right-handed, canonical signs of e0 and e1.
    fn check(m: [[f64; 3]; 3], tol: f64) {
        let (l, e) = symmetric_eigen(m);
        let scale = m.iter().flatten().map(|x| x.abs()).fold(1.0, f64::max);
        for k in 0..3 {
            let r = (mul(m, e[k]) - e[k] * l[k]).length();
            assert!(
                r <= tol * scale,
                "m {m:?}: residual {r} > {} for λ{k} = {}",
                tol * scale,
                l[k]
            );
            assert!((e[k].length() - 1.0).abs() < 1e-12, "|e{k}| = {}", e[k].length());
        }
        assert!(l[0] >= l[1] && l[1] >= l[2], "not descending: {l:?}");
        assert!(e[0].dot(e[1]).abs() < 1e-12 && e[0].dot(e[2]).abs() < 1e-12);
        assert!(e[1].dot(e[2]).abs() < 1e-12);
        assert!((e[0].cross(e[1]) - e[2]).length() < 1e-12, "left-handed");
        for (k, ek) in e.iter().enumerate().take(2) {
            assert_eq!(canonical_sign(*ek), *ek, "sign of e{k}");
        }
    }

    #[test]
    fn diagonal_matrix_sorts_descending_with_axis_vectors() {
        let (l, e) = symmetric_eigen([[1.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 2.0]]);
        assert_eq!(l, [3.0, 2.0, 1.0]);
        assert_eq!(e[0], DVec3::Y);
        assert_eq!(e[1], DVec3::Z);
        assert_eq!(e[2], DVec3::X); // Y × Z
    }

    #[test]
    fn identity_and_zero_ties_keep_index_order() {
        for s in [1.0, 0.0] {
            let (l, e) = symmetric_eigen([[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]);
            assert_eq!(l, [s; 3]);
            assert_eq!(e, [DVec3::X, DVec3::Y, DVec3::Z]);
        }
        // Two equal eigenvalues on the diagonal: lower index first.
        let (l, e) = symmetric_eigen([[2.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 2.0]]);
        assert_eq!(l, [5.0, 2.0, 2.0]);
        assert_eq!(e, [DVec3::Y, DVec3::X, DVec3::Y.cross(DVec3::X)]);
    }

    #[test]
    fn rank_one_gives_the_direction_and_a_null_space() {
        // All normals equal: E = n nᵀ.
        let n = DVec3::new(0.48, -0.6, 0.64).normalize();
        let m = [0, 1, 2].map(|i| [0, 1, 2].map(|j| n[i] * n[j]));
        check(m, 1e-13);
        let (l, e) = symmetric_eigen(m);
        assert!((l[0] - 1.0).abs() < 1e-14 && l[1].abs() < 1e-14 && l[2].abs() < 1e-14);
        assert!((e[0] - canonical_sign(n)).length() < 1e-13, "{:?}", e[0]);
    }

    #[test]
    fn repeated_eigenvalues_give_an_orthonormal_basis_of_the_eigenspace() {
        // λ = (3, 1, 1) around a tilted axis: any basis of the plane is valid.
        let a = DVec3::new(1.0, 2.0, -2.0).normalize();
        let m = [0, 1, 2]
            .map(|i| [0, 1, 2].map(|j| 2.0 * a[i] * a[j] + if i == j { 1.0 } else { 0.0 }));
        check(m, 1e-13);
        let (l, e) = symmetric_eigen(m);
        assert!((l[0] - 3.0).abs() < 1e-13 && (l[1] - 1.0).abs() < 1e-13);
        assert!((e[0].dot(a).abs() - 1.0).abs() < 1e-13);
        assert!(e[1].dot(a).abs() < 1e-13 && e[2].dot(a).abs() < 1e-13);
    }

    #[test]
    fn deterministic_bit_for_bit() {
        let m = [[0.3, 0.1, -0.2], [0.1, 0.5, 0.05], [-0.2, 0.05, 0.2]];
        let first = symmetric_eigen(m);
        for _ in 0..10 {
            let again = symmetric_eigen(m);
            assert_eq!(first.0.map(f64::to_bits), again.0.map(f64::to_bits));
            for k in 0..3 {
                assert_eq!(
                    first.1[k].to_array().map(f64::to_bits),
                    again.1[k].to_array().map(f64::to_bits)
                );
            }
        }
        check(m, 1e-13);
    }

    #[test]
    fn non_finite_input_does_not_panic() {
        let (l, _) = symmetric_eigen([[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        assert!(l.iter().any(|x| x.is_nan()));
        let (l, _) = symmetric_eigen([[f64::INFINITY, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        assert!(l.iter().any(|x| !x.is_finite()));
    }

    #[test]
    fn canonical_sign_rule() {
        assert_eq!(canonical_sign(DVec3::new(0.1, -0.9, 0.2)), DVec3::new(-0.1, 0.9, -0.2));
        // Tie between x and z magnitudes: x (first) decides.
        assert_eq!(canonical_sign(DVec3::new(-0.5, 0.1, 0.5)), DVec3::new(0.5, -0.1, -0.5));
        assert_eq!(canonical_sign(DVec3::new(0.5, 0.1, -0.5)), DVec3::new(0.5, 0.1, -0.5));
    }

    proptest! {
        #[test]
        fn random_symmetric_matrices_decompose(
            d in prop::array::uniform3(-10.0f64..10.0),
            o in prop::array::uniform3(-10.0f64..10.0),
        ) {
            check([[d[0], o[0], o[1]], [o[0], d[1], o[2]], [o[1], o[2], d[2]]], 1e-12);
        }

        #[test]
        fn second_moment_matrices_of_unit_normals_decompose(
            ns in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 1..20)
        ) {
            let mut m = [[0.0; 3]; 3];
            for n in &ns {
                let n = DVec3::from_array(*n).normalize_or(DVec3::Z);
                for i in 0..3 { for j in 0..3 { m[i][j] += n[i] * n[j] / ns.len() as f64; } }
            }
            check(m, 1e-13);
            let (l, _) = symmetric_eigen(m);
            prop_assert!(l[2] > -1e-14 && (l.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }
}
