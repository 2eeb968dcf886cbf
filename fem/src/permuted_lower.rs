//! The lower triangle of a symmetric matrix in the fill-reducing order of its Cholesky
//! analysis, gathered from the assembled matrix by a map computed once per pattern.
//!
//! faer's `SymbolicCholesky::factorize_numeric_llt` permutes its input at every numeric
//! factorisation (`permute_self_adjoint_to_unsorted`: a counting pass over the columns, then
//! a scatter of every entry through the permutation), although the pattern and the
//! permutation stay the same for as long as the symbolic analysis is reused. With
//! `B = P A Pᵀ` (`B_ij = A_{fwd(i), fwd(j)}`), the entry `A_rc` of the lower triangle
//! (`r ≥ c`, the triangle faer reads with `Side::Lower`) lands at
//! `B_{max(inv r, inv c), min(inv r, inv c)}`: this map is computed once, and each
//! factorisation gathers `B`'s values in one pass and hands `B` to the supernodal numeric
//! factorisation directly. The same source entries as faer's own permutation are used, so
//! the factors are bit-identical.

use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

/// `B = P A Pᵀ`'s lower triangle: its column pointers and row indices (unsorted within a
/// column, as faer's permutation writes them), and for each entry the index of its source in
/// `A`'s values.
#[derive(Debug, Clone)]
pub struct PermutedLower {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    source: Vec<usize>,
    values: Vec<f64>,
}

impl PermutedLower {
    /// The map for the square, structurally symmetric pattern `a` (full, both triangles) and
    /// the inverse permutation `inv` (`inv[r]` is the position of row `r` in `B`).
    pub fn new(a: SymbolicSparseColMatRef<'_, usize>, inv: &[usize]) -> Self {
        let n = a.ncols();
        let (a_col_ptr, a_row_idx) = (a.col_ptr(), a.row_idx());
        let mut count = vec![0usize; n + 1];
        let lower = |c: usize| a_row_idx[a_col_ptr[c]..a_col_ptr[c + 1]].iter().filter(move |&&r| r >= c);
        for c in 0..n {
            for &r in lower(c) {
                count[inv[r].min(inv[c]) + 1] += 1;
            }
        }
        for j in 0..n {
            count[j + 1] += count[j];
        }
        let col_ptr = count.clone();
        let nnz = col_ptr[n];
        let (mut row_idx, mut source) = (vec![0; nnz], vec![0; nnz]);
        let mut next = count;
        for c in 0..n {
            for k in a_col_ptr[c]..a_col_ptr[c + 1] {
                let r = a_row_idx[k];
                if r < c {
                    continue;
                }
                let (i, j) = (inv[r].max(inv[c]), inv[r].min(inv[c]));
                row_idx[next[j]] = i;
                source[next[j]] = k;
                next[j] += 1;
            }
        }
        Self { col_ptr, row_idx, source, values: vec![0.0; nnz] }
    }

    /// `B`'s lower triangle with the values of `a_values` (the nonzeros of `A` in its
    /// pattern's order).
    pub fn matrix(&mut self, a_values: &[f64]) -> SparseColMatRef<'_, usize, f64> {
        for (v, &k) in self.values.iter_mut().zip(&self.source) {
            *v = a_values[k];
        }
        let n = self.col_ptr.len() - 1;
        let symbolic = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &self.col_ptr, None, &self.row_idx);
        SparseColMatRef::new(symbolic, &self.values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 4 symmetric matrix reversed: `B = P A Pᵀ` with `fwd = [3, 2, 1, 0]` has
    /// `B_ij = A_{3−i, 3−j}`; its gathered lower triangle holds exactly those entries.
    #[test]
    fn gathers_the_permuted_lower_triangle() {
        let n = 4;
        // full pattern of a tridiagonal matrix plus the (0, 3) pair
        let mut cols: Vec<Vec<usize>> = vec![vec![0, 1, 3], vec![0, 1, 2], vec![1, 2, 3], vec![0, 2, 3]];
        let a = |r: usize, c: usize| 10.0 * r.max(c) as f64 + r.min(c) as f64 + 1.0;
        let mut col_ptr = vec![0];
        let (mut row_idx, mut values) = (Vec::new(), Vec::new());
        for (c, rows) in cols.iter_mut().enumerate() {
            for &r in rows.iter() {
                row_idx.push(r);
                values.push(a(r, c));
            }
            col_ptr.push(row_idx.len());
        }
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let inv = [3, 2, 1, 0];
        let mut lower = PermutedLower::new(pattern, &inv);
        let b = lower.matrix(&values);
        let mut seen = 0;
        for j in 0..n {
            let rows = b.symbolic().row_idx_of_col_raw(j);
            let vals = b.val_of_col(j);
            for (&i, &v) in rows.iter().zip(vals) {
                assert!(i >= j, "entry ({i}, {j}) above the diagonal");
                assert_eq!(v, a(3 - i, 3 - j), "B({i}, {j})");
                seen += 1;
            }
        }
        assert_eq!(seen, 8, "4 diagonal entries and 4 pairs");
    }

    /// On a 2D grid Laplacian (20 × 20 nodes, AMD order, supernodal): the supernodal numeric
    /// factorisation of the gathered `B` gives the factor of faer's own permuting path bit
    /// for bit.
    #[test]
    fn supernodal_factor_is_bit_identical_to_faers_permuting_path() {
        use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
        use faer::sparse::linalg::cholesky::{
            factorize_symbolic_cholesky, supernodal, CholeskySymbolicParams, SymbolicCholeskyRaw,
        };
        use faer::sparse::linalg::SupernodalThreshold;
        use faer::{Par, Side};
        let m = 20;
        let n = m * m;
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        for c in 0..n {
            let (x, y) = (c % m, c / m);
            let mut rows = vec![c];
            if x > 0 {
                rows.push(c - 1);
            }
            if x + 1 < m {
                rows.push(c + 1);
            }
            if y > 0 {
                rows.push(c - m);
            }
            if y + 1 < m {
                rows.push(c + m);
            }
            rows.sort_unstable();
            for r in rows {
                row_idx.push(r);
                // symmetric, diagonally dominant, not a multiple of a simple stencil
                values.push(if r == c { 4.5 + (c % 7) as f64 * 0.1 } else { -1.0 - ((r + c) % 5) as f64 * 0.01 });
            }
            col_ptr.push(row_idx.len());
        }
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let a = SparseColMatRef::new(pattern, &values);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(pattern, Side::Lower, Default::default(), params).unwrap();
        let par = Par::Seq;
        let mut buffer =
            MemBuffer::new(StackReq::any_of(&[symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default())]));
        let mut faers = vec![0.0; symbolic.len_val()];
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut faers,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .unwrap();
        let (SymbolicCholeskyRaw::Supernodal(sn), Some(perm)) = (symbolic.raw(), symbolic.perm()) else {
            panic!("a supernodal analysis with a permutation");
        };
        let mut lower = PermutedLower::new(pattern, perm.arrays().1);
        let mut ours = vec![0.0; symbolic.len_val()];
        supernodal::factorize_supernodal_numeric_llt(
            &mut ours,
            lower.matrix(&values),
            Default::default(),
            sn,
            par,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .unwrap();
        assert!(faers.iter().zip(&ours).all(|(x, y)| x.to_bits() == y.to_bits()), "factors differ");
    }
}
