//! Minimum-cost assignment of rows to distinct columns (the Hungarian method with
//! potentials, O(n^2 m)): which launch slot each object gets.

/// For an `n x m` cost matrix with `n <= m`, the column of each row such that no two
/// rows share a column and the total cost is least.
pub fn assign(cost: &[Vec<f64>]) -> Vec<usize> {
    let n = cost.len();
    if n == 0 {
        return Vec::new();
    }
    let m = cost[0].len();
    assert!(n <= m, "more rows than columns");
    // 1-based arrays as in the classic formulation; column 0 is a sentinel.
    let (mut u, mut v) = (vec![0.0f64; n + 1], vec![0.0f64; m + 1]);
    let mut p = vec![0usize; m + 1];
    let mut way = vec![0usize; m + 1];
    for i in 1..=n {
        p[0] = i;
        let mut j0 = 0usize;
        let mut minv = vec![f64::INFINITY; m + 1];
        let mut used = vec![false; m + 1];
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let mut delta = f64::INFINITY;
            let mut j1 = 0usize;
            for j in 1..=m {
                if used[j] {
                    continue;
                }
                let cur = cost[i0 - 1][j - 1] - u[i0] - v[j];
                if cur < minv[j] {
                    minv[j] = cur;
                    way[j] = j0;
                }
                if minv[j] < delta {
                    delta = minv[j];
                    j1 = j;
                }
            }
            for j in 0..=m {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    let mut out = vec![0usize; n];
    for j in 1..=m {
        if p[j] != 0 {
            out[p[j] - 1] = j - 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total(cost: &[Vec<f64>], a: &[usize]) -> f64 {
        a.iter().enumerate().map(|(i, &j)| cost[i][j]).sum()
    }

    #[test]
    fn assignment_is_the_cheapest_of_all() {
        // Every assignment of 4 rows to 6 columns, against a pseudo-random matrix.
        let mut x = 12345u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 1000) as f64 / 10.0
        };
        for _ in 0..20 {
            let cost: Vec<Vec<f64>> = (0..4).map(|_| (0..6).map(|_| next()).collect()).collect();
            let a = assign(&cost);
            let mut seen = a.clone();
            seen.sort();
            seen.dedup();
            assert_eq!(seen.len(), 4);
            let mut best = f64::INFINITY;
            for j0 in 0..6 {
                for j1 in 0..6 {
                    for j2 in 0..6 {
                        for j3 in 0..6 {
                            let js = [j0, j1, j2, j3];
                            let mut s = js.to_vec();
                            s.sort();
                            s.dedup();
                            if s.len() == 4 {
                                best = best.min(total(&cost, &js));
                            }
                        }
                    }
                }
            }
            assert!((total(&cost, &a) - best).abs() < 1e-9);
        }
    }

    #[test]
    fn distances_give_paths_that_do_not_cross() {
        // Slots on a line, targets beyond it in reverse order of index: the cheapest
        // matching by distance keeps the left-to-right order.
        let slots: Vec<f64> = (0..5).map(|k| k as f64).collect();
        let targets = [(3.9, 2.0), (0.2, 3.0), (2.1, 2.5), (1.0, 1.0)];
        let cost: Vec<Vec<f64>> = targets
            .iter()
            .map(|&(x, y)| {
                slots
                    .iter()
                    .map(|&s| ((x - s) * (x - s) + y * y).sqrt())
                    .collect()
            })
            .collect();
        let a = assign(&cost);
        let mut by_x: Vec<usize> = (0..4).collect();
        by_x.sort_by(|&i, &j| targets[i].0.total_cmp(&targets[j].0));
        for w in by_x.windows(2) {
            assert!(a[w[0]] < a[w[1]], "{a:?}");
        }
    }
}
