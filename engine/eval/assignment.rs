//! Minimum-cost perfect matching on a dense square cost matrix (the Hungarian method with
//! row/column potentials and shortest augmenting paths, O(n³) time, O(n) memory beyond the
//! matrix). Exact up to floating-point rounding in the potentials.

/// For an `n × n` row-major matrix of finite costs, returns `col[i]`, the column matched to
/// row `i`, so that `Σ cost[i][col[i]]` is minimal over all permutations.
pub fn min_cost_assignment(n: usize, cost: &[f64]) -> Vec<usize> {
    assert_eq!(cost.len(), n * n, "cost matrix must be n × n");
    // Index 0 is a virtual column that holds the row being inserted.
    let mut row_pot = vec![0.0f64; n + 1];
    let mut col_pot = vec![0.0f64; n + 1];
    let mut row_of_col = vec![0usize; n + 1]; // 1-based row, 0 = free
    let mut prev_col = vec![0usize; n + 1];
    for row in 1..=n {
        row_of_col[0] = row;
        let mut slack = vec![f64::INFINITY; n + 1];
        let mut visited = vec![false; n + 1];
        let mut col = 0;
        // Dijkstra on reduced costs until a free column is reached.
        while row_of_col[col] != 0 {
            visited[col] = true;
            let r = row_of_col[col];
            let mut delta = f64::INFINITY;
            let mut next = 0;
            for j in 1..=n {
                if visited[j] {
                    continue;
                }
                let reduced = cost[(r - 1) * n + j - 1] - row_pot[r] - col_pot[j];
                if reduced < slack[j] {
                    slack[j] = reduced;
                    prev_col[j] = col;
                }
                if slack[j] < delta {
                    delta = slack[j];
                    next = j;
                }
            }
            for j in 0..=n {
                if visited[j] {
                    row_pot[row_of_col[j]] += delta;
                    col_pot[j] -= delta;
                } else {
                    slack[j] -= delta;
                }
            }
            col = next;
        }
        // Flip the augmenting path back to the virtual column.
        while col != 0 {
            let p = prev_col[col];
            row_of_col[col] = row_of_col[p];
            col = p;
        }
    }
    let mut col_of_row = vec![0usize; n];
    for j in 1..=n {
        col_of_row[row_of_col[j] - 1] = j - 1;
    }
    col_of_row
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn brute_force(n: usize, cost: &[f64]) -> f64 {
        fn go(row: usize, n: usize, cost: &[f64], used: &mut Vec<bool>) -> f64 {
            if row == n {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for j in 0..n {
                if !used[j] {
                    used[j] = true;
                    best = best.min(cost[row * n + j] + go(row + 1, n, cost, used));
                    used[j] = false;
                }
            }
            best
        }
        go(0, n, cost, &mut vec![false; n])
    }

    #[test]
    fn optimal_against_all_permutations() {
        let mut rng = SplitMix64::new(5);
        for n in 0..=7 {
            for _ in 0..20 {
                // Few distinct values too, so ties are exercised.
                let cost: Vec<f64> = (0..n * n)
                    .map(|_| if n % 2 == 0 { rng.next_f64() } else { (rng.next_u32() % 3) as f64 })
                    .collect();
                let col = min_cost_assignment(n, &cost);
                let mut seen = vec![false; n];
                for &c in &col {
                    assert!(!seen[c], "not a permutation");
                    seen[c] = true;
                }
                let total: f64 = col.iter().enumerate().map(|(i, &j)| cost[i * n + j]).sum();
                assert!((total - brute_force(n, &cost)).abs() < 1e-9, "n = {n}");
            }
        }
    }
}
