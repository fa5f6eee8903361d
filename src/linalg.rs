//! Small dense linear algebra that the solver needs and glam does not have.
//!
//! Two symmetric eigensolvers, one output convention:
//! - [`sym_eigen`], the cyclic Jacobi method, for the 3 x 3 inertia tensors of meshes:
//!   short, and accurate to working precision for the small eigenvalues of real inertia
//!   tensors (a 30 g pawn has I ~ 1e-5 kg m^2; the field notes record a library that gets
//!   those wrong);
//! - [`sym_eigen_ql`], Householder reduction to tridiagonal form then the implicit QL
//!   method (EISPACK's `tred2` and `tql2`), for the CMA-ES covariance (up to a few hundred
//!   dimensions): about a fifth of Jacobi's work at 72 to 96 dimensions, where Jacobi
//!   took 11 % of tbc's solve and 29 % of a solve of 32 balls.

/// Eigen-decomposition of the symmetric `n x n` matrix `a` (row-major, only read).
///
/// On return `values[k]` is the k-th eigenvalue and column `k` of `vectors` (row-major
/// `n x n`, i.e. `vectors[i * n + k]`) its unit eigenvector. Eigenvalues are sorted in
/// ascending order. `work` must hold `n * n` values; it is overwritten. Nothing is
/// allocated, so the optimizer can call it every generation without touching the heap.
pub fn sym_eigen(n: usize, a: &[f64], values: &mut [f64], vectors: &mut [f64], work: &mut [f64]) {
    assert!(a.len() >= n * n && vectors.len() >= n * n && work.len() >= n * n);
    assert!(values.len() >= n);
    let m = &mut work[..n * n];
    m.copy_from_slice(&a[..n * n]);
    // The eigenvectors are accumulated as the rows of V^T, so that a rotation updates two
    // contiguous rows; V is transposed into `vectors` at the end.
    let vt = &mut vectors[..n * n];
    vt.iter_mut().for_each(|x| *x = 0.0);
    for i in 0..n {
        vt[i * n + i] = 1.0;
    }
    // Scale-aware stopping: sweep until the off-diagonal mass is negligible relative to
    // the whole matrix (so tiny inertia tensors converge as well as large ones).
    let total: f64 = m.iter().map(|x| x * x).sum::<f64>().max(f64::MIN_POSITIVE);
    for _sweep in 0..100 {
        let mut off = 0.0;
        for p in 0..n {
            for q in (p + 1)..n {
                off += m[p * n + q] * m[p * n + q];
            }
        }
        if off <= 1e-30 * total {
            break;
        }
        for p in 0..n {
            for q in (p + 1)..n {
                let apq = m[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let app = m[p * n + p];
                let aqq = m[q * n + q];
                // Rotation angle that zeroes m[p][q] (Numerical Recipes' stable form).
                let theta = (aqq - app) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                rotate(m, n, p, q, c, s);
                let (head, tail) = vt.split_at_mut(q * n);
                let (vp, vq) = (&mut head[p * n..(p + 1) * n], &mut tail[..n]);
                for (x, y) in vp.iter_mut().zip(vq.iter_mut()) {
                    let (vkp, vkq) = (*x, *y);
                    *x = c * vkp - s * vkq;
                    *y = s * vkp + c * vkq;
                }
            }
        }
    }
    for i in 0..n {
        values[i] = m[i * n + i];
    }
    sort_ascending(n, values, vt);
    transpose(n, vt);
}

/// Eigen-decomposition of the symmetric `n x n` matrix `a` (row-major, only read, and
/// only its upper triangle), with [`sym_eigen`]'s convention: `values` ascending, column
/// `k` of `vectors` (row-major) the unit eigenvector of `values[k]`; `work` must hold `n`
/// values. Householder
/// reduction to a tridiagonal matrix, then implicit QL with shifts on it (Bowdler,
/// Martin, Reinsch and Wilkinson's `tred2` and `tql2`, as JAMA writes them). Nothing is
/// allocated. A matrix with a non-finite entry gives non-finite values (each eigenvalue
/// has at most 60 QL iterations, so the loop ends whatever the input).
pub fn sym_eigen_ql(
    n: usize,
    a: &[f64],
    values: &mut [f64],
    vectors: &mut [f64],
    work: &mut [f64],
) {
    assert!(a.len() >= n * n && vectors.len() >= n * n && work.len() >= n);
    assert!(values.len() >= n);
    if n == 0 {
        return;
    }
    let (d, e, v) = (&mut values[..n], &mut work[..n], &mut vectors[..n * n]);
    // `a` row-major is `a^T` column-major: its upper triangle is the lower triangle that
    // `tred2` reads, and it leaves V column-major, which is V^T row-major, whose rows QL
    // rotates (pairs of columns of V, contiguous).
    v.copy_from_slice(&a[..n * n]);
    tridiagonalize(n, v, d, e);
    tridiagonal_ql(n, v, d, e);
    sort_ascending(n, d, v);
    transpose(n, v);
}

/// Sort the eigenvalues `values[..n]` ascending, the rows of `vt` (the eigenvectors, as
/// rows of V^T) with them: a selection sort, allocation-free, and n is small.
fn sort_ascending(n: usize, values: &mut [f64], vt: &mut [f64]) {
    for i in 0..n {
        let mut best = i;
        for j in (i + 1)..n {
            if values[j] < values[best] {
                best = j;
            }
        }
        if best != i {
            values.swap(i, best);
            let (head, tail) = vt.split_at_mut(best * n);
            head[i * n..(i + 1) * n].swap_with_slice(&mut tail[..n]);
        }
    }
}

/// `tred2`: `v` (holding the matrix, column-major) becomes the orthogonal `V` (column-major)
/// with `V^T A V` tridiagonal, of diagonal `d` and subdiagonal `e[1..]` (`e[0] = 0`).
/// Column-major because its inner loops run down a column: so they read contiguous
/// memory, and the updates vectorise.
fn tridiagonalize(n: usize, v: &mut [f64], d: &mut [f64], e: &mut [f64]) {
    let at = |i: usize, j: usize| j * n + i;
    for j in 0..n {
        d[j] = v[at(n - 1, j)];
    }
    for i in (1..n).rev() {
        let scale: f64 = d[..i].iter().map(|x| x.abs()).sum();
        let mut h = 0.0;
        if scale == 0.0 {
            e[i] = d[i - 1];
            for j in 0..i {
                d[j] = v[at(i - 1, j)];
                v[at(i, j)] = 0.0;
                v[at(j, i)] = 0.0;
            }
        } else {
            for x in &mut d[..i] {
                *x /= scale;
                h += *x * *x;
            }
            let f = d[i - 1];
            let g = if f > 0.0 { -h.sqrt() } else { h.sqrt() };
            e[i] = scale * g;
            h -= f * g;
            d[i - 1] = f - g;
            e[..i].iter_mut().for_each(|x| *x = 0.0);
            for j in 0..i {
                let f = d[j];
                v[at(j, i)] = f;
                let mut g = e[j] + v[at(j, j)] * f;
                let column = &v[at(j + 1, j)..at(i, j)];
                for ((&x, &dk), ek) in column.iter().zip(&d[j + 1..i]).zip(&mut e[j + 1..i]) {
                    g += x * dk;
                    *ek += x * f;
                }
                e[j] = g;
            }
            let mut f = 0.0;
            for j in 0..i {
                e[j] /= h;
                f += e[j] * d[j];
            }
            let hh = f / (h + h);
            for j in 0..i {
                e[j] -= hh * d[j];
            }
            for j in 0..i {
                let (f, g) = (d[j], e[j]);
                let column = &mut v[at(j, j)..at(i, j)];
                for ((x, &ek), &dk) in column.iter_mut().zip(&e[j..i]).zip(&d[j..i]) {
                    *x -= f * ek + g * dk;
                }
                d[j] = v[at(i - 1, j)];
                v[at(i, j)] = 0.0;
            }
        }
        d[i] = h;
    }
    // Accumulate the transformations.
    for i in 0..n - 1 {
        v[at(n - 1, i)] = v[at(i, i)];
        v[at(i, i)] = 1.0;
        let h = d[i + 1];
        if h != 0.0 {
            // Columns 0..=i, and column i + 1 (its first i + 1 rows).
            let (left, right) = v.split_at_mut(at(0, i + 1));
            let next = &right[..=i];
            for (dk, &x) in d[..=i].iter_mut().zip(next) {
                *dk = x / h;
            }
            for column in left.chunks_exact_mut(n).take(i + 1) {
                let column = &mut column[..=i];
                let g: f64 = next.iter().zip(column.iter()).map(|(&a, &b)| a * b).sum();
                for (x, &dk) in column.iter_mut().zip(&d[..=i]) {
                    *x -= g * dk;
                }
            }
        }
        for k in 0..=i {
            v[at(k, i + 1)] = 0.0;
        }
    }
    for j in 0..n {
        d[j] = v[at(n - 1, j)];
        v[at(n - 1, j)] = 0.0;
    }
    v[at(n - 1, n - 1)] = 1.0;
    e[0] = 0.0;
}

/// `tql2`: the eigenvalues of the tridiagonal matrix (`d`, `e` as [`tridiagonalize`]
/// leaves them) into `d`, unsorted, and its rotations applied to the rows of `vt`.
fn tridiagonal_ql(n: usize, vt: &mut [f64], d: &mut [f64], e: &mut [f64]) {
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = 0.0;
    let (mut f, mut tst1) = (0.0f64, 0.0f64);
    for l in 0..n {
        tst1 = tst1.max(d[l].abs() + e[l].abs());
        let mut m = l;
        while m < n - 1 && e[m].abs() > f64::EPSILON * tst1 {
            m += 1;
        }
        if m > l {
            for _ in 0..60 {
                let g = d[l];
                let mut p = (d[l + 1] - g) / (2.0 * e[l]);
                let r = p.hypot(1.0);
                let r = if p < 0.0 { -r } else { r };
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                let dl1 = d[l + 1];
                let h = g - d[l];
                for x in &mut d[l + 2..n] {
                    *x -= h;
                }
                f += h;
                p = d[m];
                let (mut c, mut c2, mut c3) = (1.0, 1.0, 1.0);
                let el1 = e[l + 1];
                let (mut s, mut s2) = (0.0, 0.0);
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    let g = c * e[i];
                    let h = c * p;
                    let r = p.hypot(e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    let (head, tail) = vt.split_at_mut((i + 1) * n);
                    let (vi, vi1) = (&mut head[i * n..], &mut tail[..n]);
                    for (x, y) in vi.iter_mut().zip(vi1.iter_mut()) {
                        let h = *y;
                        *y = s * *x + c * h;
                        *x = c * *x - s * h;
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                // Also false for NaN, which then ends with the iterations.
                if e[l].abs() <= f64::EPSILON * tst1 {
                    break;
                }
            }
        }
        d[l] += f;
        e[l] = 0.0;
    }
}

/// Transpose the `n x n` row-major matrix `m` in place.
pub fn transpose(n: usize, m: &mut [f64]) {
    for i in 0..n {
        for k in (i + 1)..n {
            m.swap(i * n + k, k * n + i);
        }
    }
}

/// `m <- R^T m R` for the Jacobi rotation `R` in the plane `(p, q)`: the columns `p`
/// and `q` first, then the rows. Rounding leaves the 2 x 2 block slightly asymmetric, so
/// the columns cannot be taken from the rows: both are updated, in this order, and the
/// results depend on it bit for bit.
fn rotate(m: &mut [f64], n: usize, p: usize, q: usize, c: f64, s: f64) {
    for k in 0..n {
        let mkp = m[k * n + p];
        let mkq = m[k * n + q];
        m[k * n + p] = c * mkp - s * mkq;
        m[k * n + q] = s * mkp + c * mkq;
    }
    let (head, tail) = m.split_at_mut(q * n);
    let (mp, mq) = (&mut head[p * n..(p + 1) * n], &mut tail[..n]);
    for (x, y) in mp.iter_mut().zip(mq.iter_mut()) {
        let (mpk, mqk) = (*x, *y);
        *x = c * mpk - s * mqk;
        *y = s * mpk + c * mqk;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reconstruct(n: usize, vals: &[f64], vecs: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                out[i * n + j] = (0..n)
                    .map(|k| vecs[i * n + k] * vals[k] * vecs[j * n + k])
                    .sum();
            }
        }
        out
    }

    /// The cyclic Jacobi method as first written: every rotation updates the columns
    /// `p`, `q` and then the rows, and V directly. `sym_eigen` must match it bit for bit
    /// (CMA-ES samples along its eigenvectors, so solutions depend on these bits).
    fn reference(n: usize, a: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut m = a.to_vec();
        let mut v = vec![0.0; n * n];
        for i in 0..n {
            v[i * n + i] = 1.0;
        }
        let total: f64 = m.iter().map(|x| x * x).sum::<f64>().max(f64::MIN_POSITIVE);
        for _ in 0..100 {
            let mut off = 0.0;
            for p in 0..n {
                for q in (p + 1)..n {
                    off += m[p * n + q] * m[p * n + q];
                }
            }
            if off <= 1e-30 * total {
                break;
            }
            for p in 0..n {
                for q in (p + 1)..n {
                    let apq = m[p * n + q];
                    if apq == 0.0 {
                        continue;
                    }
                    let theta = (m[q * n + q] - m[p * n + p]) / (2.0 * apq);
                    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                    let t = if theta == 0.0 { 1.0 } else { t };
                    let c = 1.0 / (t * t + 1.0).sqrt();
                    let s = t * c;
                    for k in 0..n {
                        let (x, y) = (m[k * n + p], m[k * n + q]);
                        m[k * n + p] = c * x - s * y;
                        m[k * n + q] = s * x + c * y;
                    }
                    for k in 0..n {
                        let (x, y) = (m[p * n + k], m[q * n + k]);
                        m[p * n + k] = c * x - s * y;
                        m[q * n + k] = s * x + c * y;
                    }
                    for k in 0..n {
                        let (x, y) = (v[k * n + p], v[k * n + q]);
                        v[k * n + p] = c * x - s * y;
                        v[k * n + q] = s * x + c * y;
                    }
                }
            }
        }
        let mut values: Vec<f64> = (0..n).map(|i| m[i * n + i]).collect();
        for i in 0..n {
            let mut best = i;
            for j in (i + 1)..n {
                if values[j] < values[best] {
                    best = j;
                }
            }
            if best != i {
                values.swap(i, best);
                for k in 0..n {
                    v.swap(k * n + i, k * n + best);
                }
            }
        }
        (values, v)
    }

    #[test]
    fn matches_the_reference_jacobi_bit_for_bit() {
        for n in [3, 10, 50, 96] {
            let a = covariance(n, 99 + n as u64, 0.1);
            let (want_values, want_vectors) = reference(n, &a);
            let (mut values, mut vectors, mut work) =
                (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
            sym_eigen(n, &a, &mut values, &mut vectors, &mut work);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&values), bits(&want_values), "n = {n}");
            assert_eq!(bits(&vectors), bits(&want_vectors), "n = {n}");
        }
    }

    /// A covariance-like `n x n` matrix: `R^T R` plus `ridge` on the diagonal.
    fn covariance(n: usize, seed: u64, ridge: f64) -> Vec<f64> {
        let mut s = seed;
        let r: Vec<f64> = (0..n * n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in i..n {
                let x: f64 = (0..n).map(|k| r[k * n + i] * r[k * n + j]).sum::<f64>()
                    + if i == j { ridge } else { 0.0 };
                a[i * n + j] = x;
                a[j * n + i] = x;
            }
        }
        a
    }

    /// `sym_eigen_ql` of `a`, checked: ascending values, orthonormal vectors, `V D V^T`
    /// equal to `a` to `tol` of its largest entry. Returns the values.
    fn ql_checked(n: usize, a: &[f64], tol: f64) -> Vec<f64> {
        let (mut values, mut vectors, mut work) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n]);
        sym_eigen_ql(n, a, &mut values, &mut vectors, &mut work);
        assert!(
            values.windows(2).all(|w| w[0] <= w[1]),
            "n = {n}: {values:?}"
        );
        let scale = a.iter().fold(f64::MIN_POSITIVE, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(&reconstruct(n, &values, &vectors)) {
            assert!((x - y).abs() <= tol * scale, "n = {n}: {x} vs {y}");
        }
        for i in 0..n {
            for j in 0..n {
                let dot: f64 = (0..n)
                    .map(|k| vectors[k * n + i] * vectors[k * n + j])
                    .sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (dot - want).abs() < 1e-12,
                    "n = {n}: columns {i}, {j}: {dot}"
                );
            }
        }
        values
    }

    #[test]
    fn ql_gives_jacobis_eigenvalues_and_a_true_decomposition() {
        for (n, seed) in [(1, 1), (2, 2), (3, 3), (10, 4), (50, 5), (96, 6), (200, 7)] {
            let a = covariance(n, seed, 0.1);
            let values = ql_checked(n, &a, 1e-12);
            let (mut want, mut v, mut w) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
            sym_eigen(n, &a, &mut want, &mut v, &mut w);
            for (x, y) in values.iter().zip(&want) {
                assert!((x - y).abs() <= 1e-12 * want[n - 1], "n = {n}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn ql_handles_repeated_zero_and_diagonal_matrices() {
        let n = 6;
        let identity: Vec<f64> = (0..n * n)
            .map(|k| if k % (n + 1) == 0 { 1.0 } else { 0.0 })
            .collect();
        assert!(ql_checked(n, &identity, 1e-15).iter().all(|&x| x == 1.0));
        assert!(ql_checked(n, &vec![0.0; n * n], 0.0)
            .iter()
            .all(|&x| x == 0.0));
        let diagonal: Vec<f64> = (0..n * n)
            .map(|k| {
                if k % (n + 1) == 0 {
                    [3.0, 1.0, 2.0, 1.0, 5.0, 2.0][k / n]
                } else {
                    0.0
                }
            })
            .collect();
        assert_eq!(
            ql_checked(n, &diagonal, 1e-15),
            [1.0, 1.0, 2.0, 2.0, 3.0, 5.0]
        );
        // A tiny covariance (a step size of 1e-4 squared) is as exact as a large one.
        let tiny: Vec<f64> = covariance(20, 8, 0.1).iter().map(|x| x * 1e-8).collect();
        ql_checked(20, &tiny, 1e-12);
    }

    #[test]
    fn ql_ends_on_a_non_finite_matrix() {
        let n = 5;
        let mut a = covariance(n, 9, 0.1);
        (a[n + 2], a[2 * n + 1]) = (f64::NAN, f64::NAN);
        let (mut values, mut vectors, mut work) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n]);
        sym_eigen_ql(n, &a, &mut values, &mut vectors, &mut work);
        assert!(values.iter().any(|x| !x.is_finite()));
    }

    #[test]
    fn diagonalises_random_symmetric_matrix() {
        let n = 7;
        let mut a = vec![0.0; n * n];
        let mut s = 12345u64;
        for i in 0..n {
            for j in i..n {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let x = ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
                a[i * n + j] = x;
                a[j * n + i] = x;
            }
        }
        let (mut vals, mut vecs, mut work) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
        sym_eigen(n, &a, &mut vals, &mut vecs, &mut work);
        let r = reconstruct(n, &vals, &vecs);
        for (x, y) in a.iter().zip(&r) {
            assert!((x - y).abs() < 1e-12, "{x} vs {y}");
        }
        assert!(vals.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn tiny_inertia_tensor_keeps_its_axes() {
        // A pawn-sized inertia tensor (1e-6 kg m^2 scale) rotated off-axis: the symmetry
        // axis (the distinct eigenvalue) must come back exactly, unlike the library bug
        // recorded in the field notes.
        let (c, s) = (0.6f64, 0.8f64);
        // R = rotation about x by angle with cos c, sin s; I = R diag(2,2,1)e-6 R^T.
        let r = [1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c];
        let d = [2e-6, 2e-6, 1e-6];
        let mut a = vec![0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                a[i * 3 + j] = (0..3).map(|k| r[i * 3 + k] * d[k] * r[j * 3 + k]).sum();
            }
        }
        let (mut vals, mut vecs, mut work) = ([0.0; 3], [0.0; 9], [0.0; 9]);
        sym_eigen(3, &a, &mut vals, &mut vecs, &mut work);
        assert!((vals[0] - 1e-6).abs() < 1e-18);
        // Axis of the smallest eigenvalue: third column of R = (0, -s, c).
        let axis = [vecs[0], vecs[3], vecs[6]];
        let dot = axis[1] * -s + axis[2] * c;
        assert!((dot.abs() - 1.0).abs() < 1e-12, "{axis:?}");
    }
}
