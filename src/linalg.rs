//! Small dense linear algebra that the solver needs and glam does not have.
//!
//! [`sym_eigen`] diagonalises a symmetric matrix with the cyclic Jacobi method. It serves
//! two callers: the CMA-ES covariance (up to ~100 x 100) and the 3 x 3 inertia tensors of
//! meshes. Jacobi is chosen over faster QR methods because it is short, deterministic
//! (no data-dependent pivoting other than the fixed sweep order) and accurate to working
//! precision for the small eigenvalues of real inertia tensors (a 30 g pawn has
//! I ~ 1e-5 kg m^2; the field notes record a library that gets those wrong).

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
    // V from V^T, in place.
    for i in 0..n {
        for k in (i + 1)..n {
            vt.swap(i * n + k, k * n + i);
        }
    }
    let v = vt;
    // Sort eigenpairs ascending with a selection sort: n is small and this keeps the
    // routine allocation-free.
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
        let mut s = 99u64;
        for n in [3, 10, 50, 96] {
            // A covariance-like matrix: B^T B plus a diagonal, exactly symmetric.
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
                        + if i == j { 0.1 } else { 0.0 };
                    a[i * n + j] = x;
                    a[j * n + i] = x;
                }
            }
            let (want_values, want_vectors) = reference(n, &a);
            let (mut values, mut vectors, mut work) =
                (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
            sym_eigen(n, &a, &mut values, &mut vectors, &mut work);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&values), bits(&want_values), "n = {n}");
            assert_eq!(bits(&vectors), bits(&want_vectors), "n = {n}");
        }
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
