//! LU factorisation with partial pivoting of a small dense matrix held in a fixed array, and
//! the solve with its factors (Radau13's Newton matrix, factored once per step; the phase
//! table's least-squares refit).

/// `P M = L U` of an `N x N` matrix in place: `U` on and above the diagonal, the multipliers of
/// the unit lower `L` below it, `piv[k]` the row swapped into row `k` at elimination step `k`.
pub(crate) struct Lu<const N: usize> {
    m: [[f64; N]; N],
    piv: [usize; N],
}

impl<const N: usize> Lu<N> {
    /// Factors `m` (Gaussian elimination, largest pivot of each column); `None` when a pivot
    /// is zero or not finite (the matrix is singular to working precision or not finite).
    pub(crate) fn new(mut m: [[f64; N]; N]) -> Option<Self> {
        let mut piv = [0; N];
        for k in 0..N {
            let mut p = k;
            for r in k + 1..N {
                if m[r][k].abs() > m[p][k].abs() {
                    p = r;
                }
            }
            piv[k] = p;
            m.swap(k, p);
            let d = m[k][k];
            if d == 0.0 || !d.is_finite() {
                return None;
            }
            let (top, rest) = m.split_at_mut(k + 1);
            let pivot_row = &top[k];
            for row in rest.iter_mut() {
                let l = row[k] / d;
                row[k] = l;
                if l != 0.0 {
                    for c in k + 1..N {
                        row[c] -= l * pivot_row[c];
                    }
                }
            }
        }
        Some(Self { m, piv })
    }

    /// `x` with `M x = b`: the row swaps, forward substitution with `L`, back substitution
    /// with `U`.
    pub(crate) fn solve(&self, mut b: [f64; N]) -> [f64; N] {
        for k in 0..N {
            b.swap(k, self.piv[k]);
        }
        for r in 1..N {
            let s: f64 = (0..r).map(|c| self.m[r][c] * b[c]).sum();
            b[r] -= s;
        }
        for r in (0..N).rev() {
            let s: f64 = (r + 1..N).map(|c| self.m[r][c] * b[c]).sum();
            b[r] = (b[r] - s) / self.m[r][r];
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_system_that_needs_pivoting() {
        let m = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let x = [1.0, -2.0, 0.5];
        let b = [0, 1, 2].map(|r| (0..3).map(|c| m[r][c] * x[c]).sum::<f64>());
        let got = Lu::new(m).unwrap().solve(b);
        for (g, w) in got.iter().zip(&x) {
            assert!((g - w).abs() < 1e-15, "{got:?}");
        }
        assert!(Lu::new([[1.0, 2.0], [2.0, 4.0]]).is_none());
    }
}
