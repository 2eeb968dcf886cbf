//! Sparse LU of a structurally symmetric, numerically unsymmetric matrix on its symmetric
//! pattern: multifrontal, with row pivoting restricted to each supernode's diagonal block.
//!
//! FEM and MPM tangents have a symmetric sparsity pattern even where their values are not
//! symmetric (non-associated plasticity: Mohr–Coulomb with ψ ≠ φ). A general sparse LU with
//! partial pivoting (faer's, as SuperLU) must allow any row to become a pivot row, so its
//! structure is bounded by the Cholesky factor of `AᵀA` under a COLAMD column ordering, which
//! on these 2D matrices costs 4–5× the `L Lᵀ` of the same pattern. Here the factors take the
//! structure of the Cholesky factor of the pattern under AMD (`L` that of the Cholesky `L`,
//! `U` its transpose), computed by faer's supernodal symbolic Cholesky, and the numeric
//! factorisation is multifrontal (Duff & Reid 1983, "The multifrontal solution of indefinite
//! sparse symmetric linear equations", ACM TOMS 9:302–325, doi:10.1145/356044.356047; for
//! unsymmetric values on a symmetric pattern, Amestoy & Duff 1989): for each supernode `s` in
//! a postorder of the supernodal elimination tree, its frontal matrix over the index set
//! `cols(s) ∪ pattern(s)`,
//!
//! ```text
//! F = [F11 F12; F21 F22] = A's entries of the front + Σ_children (extend-add) C_c,
//! P F11 = L11 U11,   U12 = L11⁻¹ P F12,   L21 = F21 U11⁻¹,   C_s = F22 − L21 U12,
//! ```
//!
//! with the update `C_s` passed to the parent. Pivots are chosen by partial pivoting among the
//! rows of `F11` only (restricted pivoting, as in PARDISO: Schenk & Gärtner 2006, "On fast
//! factorization pivoting methods for sparse symmetric indefinite systems", ETNA 23:158–179),
//! which keeps the structure. That is stable when the matrix is close to diagonally dominant
//! within the supernodes — true for stiffness plus mass — and is not guaranteed otherwise: a
//! pivot below `1e-13` of its column's largest entry in the block fails the factorisation
//! ([`PivotFailure`]), and the caller checks the residual of every solve and falls back to
//! the general LU ([`crate::linear_solver`]).

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, MatMut, Par, Side};

/// Smallest pivot, relative to the largest entry of its column in the supernode's diagonal
/// block at its elimination (the `U` entries above it included), that the factorisation
/// accepts. Relative to its own column, not to the whole block: a block may hold equations
/// of very different scales (the unit diagonal of an empty node's pressure, scaled by the
/// equilibration `(μ/h)²`, beside a displacement's unit diagonal).
pub const PIVOT_TOLERANCE: f64 = 1e-13;

/// Multiply–adds `width · below²` of a front's update from which it goes to faer's dense
/// triangular solve and matrix product; below it, plain loops (faster on the 2D fronts of
/// the Bui collapse: 5.8 against 6.5 ms per factorisation of `collapse_bui2008_tri_h2`).
pub const LARGE_UPDATE: usize = 1 << 20;

/// The factorisation met a pivot below [`PIVOT_TOLERANCE`] at this (permuted) equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("LU on the symmetric pattern: pivot too small at equation {0} of the ordering")]
pub struct PivotFailure(pub usize);

/// The symbolic analysis of one pattern with the numeric factors and every workspace kept
/// (a refactorisation allocates nothing).
pub struct PatternLu {
    n: usize,
    /// The fill-reducing ordering: permuted equation `i` is original equation `ordering[i]`.
    ordering: Vec<usize>,
    /// Supernode `s` holds the permuted columns `begin[s]..begin[s + 1]`.
    begin: Vec<usize>,
    /// The rows of each supernode's factor below its diagonal block (permuted, ascending),
    /// back to back: `pattern[pattern_ptr[s]..pattern_ptr[s + 1]]`.
    pattern_ptr: Vec<usize>,
    pattern: Vec<usize>,
    /// Supernodes in a postorder of the supernodal elimination tree.
    postorder: Vec<usize>,
    /// Number of children of each supernode.
    children: Vec<usize>,
    /// For each entry of `pattern`: its position in the parent supernode's front.
    position_in_parent: Vec<u32>,
    /// The matrix entries of each front: (nonzero of `A`, column-major index in the front).
    front_entries_ptr: Vec<usize>,
    front_entries: Vec<(u32, u32)>,
    /// Factors of each supernode at `factor_ptr[s]`: `[L11\U11; L21]` (front rows × width,
    /// column-major), then `U12` (width × pattern, column-major).
    factor_ptr: Vec<usize>,
    factor: Vec<f64>,
    /// Row `k` of a supernode's block was swapped with its row `pivot[begin + k]`.
    pivot: Vec<usize>,
    front: Vec<f64>,
    /// Updates `C_s` waiting for their parent, and where each starts with its supernode.
    updates: Vec<f64>,
    pending: Vec<(usize, usize)>,
    work: Vec<f64>,
}

impl std::fmt::Debug for PatternLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PatternLu").field("n", &self.n).field("factor_entries", &self.factor.len()).finish()
    }
}

impl PatternLu {
    /// Symbolic analysis of a structurally symmetric pattern (AMD ordering, supernodes of
    /// faer's symbolic Cholesky); `None` if faer gives no supernodal structure.
    pub fn analyse(a: SymbolicSparseColMatRef<'_, usize>) -> Option<Self> {
        let n = a.nrows();
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(a, Side::Lower, Default::default(), params).ok()?;
        let ordering: Vec<usize> = symbolic.perm().map_or_else(|| (0..n).collect(), |p| p.arrays().0.to_vec());
        let mut permuted = vec![0usize; n];
        for (i, &o) in ordering.iter().enumerate() {
            permuted[o] = i;
        }
        let SymbolicCholeskyRaw::Supernodal(supernodal) = symbolic.raw() else { return None };
        let supernodes = supernodal.n_supernodes();
        let mut begin = supernodal.supernode_begin().to_vec();
        begin.push(n);
        let mut supernode_of = vec![0usize; n];
        let mut pattern_ptr = vec![0usize];
        let mut pattern = Vec::new();
        for s in 0..supernodes {
            supernode_of[begin[s]..begin[s + 1]].fill(s);
            pattern.extend_from_slice(supernodal.supernode(s).pattern());
            pattern_ptr.push(pattern.len());
        }
        let rows = |s: usize| &pattern[pattern_ptr[s]..pattern_ptr[s + 1]];
        if (0..supernodes).any(|s| rows(s).windows(2).any(|w| w[0] >= w[1])) {
            return None;
        }
        let parent: Vec<Option<usize>> = (0..supernodes).map(|s| rows(s).first().map(|&i| supernode_of[i])).collect();
        let mut kids: Vec<Vec<usize>> = vec![Vec::new(); supernodes];
        for s in 0..supernodes {
            if let Some(p) = parent[s] {
                kids[p].push(s);
            }
        }
        // where each front's indices sit: `cols(s)` first, then `pattern(s)`
        let mut slot = vec![u32::MAX; n];
        let mut position_in_parent = vec![0u32; pattern.len()];
        for s in 0..supernodes {
            let front: Vec<usize> = (begin[s]..begin[s + 1]).chain(rows(s).iter().copied()).collect();
            front.iter().enumerate().for_each(|(k, &i)| slot[i] = k as u32);
            for &c in &kids[s] {
                for q in pattern_ptr[c]..pattern_ptr[c + 1] {
                    position_in_parent[q] = slot[pattern[q]];
                    if position_in_parent[q] == u32::MAX {
                        return None; // a child's update reaches outside its parent's front
                    }
                }
            }
            front.iter().for_each(|&i| slot[i] = u32::MAX);
        }
        let mut postorder = Vec::with_capacity(supernodes);
        let mut stack: Vec<(usize, usize)> =
            (0..supernodes).rev().filter(|&s| parent[s].is_none()).map(|s| (s, 0)).collect();
        while let Some((s, k)) = stack.pop() {
            if let Some(&c) = kids[s].get(k) {
                stack.push((s, k + 1));
                stack.push((c, 0));
            } else {
                postorder.push(s);
            }
        }
        // each nonzero (i, j) of the permuted matrix belongs to the front of min(i, j)
        let mut per_front: Vec<Vec<(u32, u32)>> = vec![Vec::new(); supernodes];
        let (col_ptr, row_idx) = (a.col_ptr(), a.row_idx());
        for j in 0..n {
            for (k, &row) in row_idx.iter().enumerate().take(col_ptr[j + 1]).skip(col_ptr[j]) {
                let (pi, pj) = (permuted[row], permuted[j]);
                let s = supernode_of[pi.min(pj)];
                let width = begin[s + 1] - begin[s];
                let m = width + rows(s).len();
                let at = |i: usize| {
                    if i < begin[s + 1] {
                        Some(i - begin[s])
                    } else {
                        rows(s).binary_search(&i).ok().map(|q| width + q)
                    }
                };
                per_front[s].push((k as u32, (at(pi)? + at(pj)? * m) as u32));
            }
        }
        let mut front_entries_ptr = vec![0usize];
        let mut front_entries = Vec::with_capacity(a.row_idx().len());
        for list in per_front {
            front_entries.extend(list);
            front_entries_ptr.push(front_entries.len());
        }
        let mut factor_ptr = vec![0usize];
        let mut largest_front = 0;
        for s in 0..supernodes {
            let (width, below) = (begin[s + 1] - begin[s], rows(s).len());
            largest_front = largest_front.max((width + below) * (width + below));
            factor_ptr.push(factor_ptr[s] + (width + below) * width + width * below);
        }
        Some(Self {
            n,
            ordering,
            factor: vec![0.0; factor_ptr[supernodes]],
            begin,
            pattern_ptr,
            pattern,
            postorder,
            children: kids.iter().map(Vec::len).collect(),
            position_in_parent,
            front_entries_ptr,
            front_entries,
            factor_ptr,
            pivot: vec![0; n],
            front: vec![0.0; largest_front],
            updates: Vec::new(),
            pending: Vec::new(),
            work: vec![0.0; n],
        })
    }

    /// Stored entries of the factors `L` and `U`.
    pub fn factor_entries(&self) -> usize {
        self.factor.len()
    }

    /// Numeric factorisation of `a` (a matrix of the analysed pattern). The loops of the small
    /// fronts, the extend-add and the panels are compiled for AVX2 as well and chosen at run
    /// time (`pulp`'s dispatch, safe; the baseline x86-64 build has 128-bit SSE2 only): the same
    /// operations in the same order, so the factors are bit for bit those of the SSE2 build
    /// (Rust does not fuse `a * b + c`), in about 15 % less time on the Bui collapse.
    pub fn factorise(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), PivotFailure> {
        /// [`PatternLu::factorise_body`] inside pulp's instruction-set dispatch.
        struct Factorise<'l, 'a> {
            lu: &'l mut PatternLu,
            a: SparseColMatRef<'a, usize, f64>,
        }
        impl pulp::WithSimd for Factorise<'_, '_> {
            type Output = Result<(), PivotFailure>;
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) -> Self::Output {
                self.lu.factorise_body(self.a)
            }
        }
        pulp::Arch::new().dispatch(Factorise { lu: self, a })
    }

    #[inline(always)]
    fn factorise_body(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), PivotFailure> {
        let values = a.val();
        self.updates.clear();
        self.pending.clear();
        for &s in &self.postorder {
            let (b0, b1) = (self.begin[s], self.begin[s + 1]);
            let width = b1 - b0;
            let (p0, p1) = (self.pattern_ptr[s], self.pattern_ptr[s + 1]);
            let below = p1 - p0;
            let m = width + below;
            let front = &mut self.front[..m * m];
            front.fill(0.0);
            for &(k, at) in &self.front_entries[self.front_entries_ptr[s]..self.front_entries_ptr[s + 1]] {
                front[at as usize] += values[k as usize];
            }
            // extend-add the children's updates: the last `children[s]` pending ones
            for _ in 0..self.children[s] {
                let (c, start) = self.pending.pop().expect("a child's update is pending");
                let positions = &self.position_in_parent[self.pattern_ptr[c]..self.pattern_ptr[c + 1]];
                let mc = positions.len();
                let update = &self.updates[start..start + mc * mc];
                for (column, &pj) in update.chunks_exact(mc).zip(positions) {
                    let target = &mut front[pj as usize * m..(pj as usize + 1) * m];
                    for (&value, &pi) in column.iter().zip(positions) {
                        target[pi as usize] += value;
                    }
                }
                self.updates.truncate(start);
            }
            factor_panel(front, m, width, &mut self.pivot[b0..b1]).map_err(|k| PivotFailure(b0 + k))?;
            if below > 0 && width * below * below < LARGE_UPDATE {
                // small fronts: U12 = L11⁻¹ F12 and C −= L21 U12 column by column, a column
                // of `[F12; F22]` eliminated against the panel's `width` columns
                let (panel, rest) = front.split_at_mut(m * width);
                for column in rest.chunks_exact_mut(m) {
                    for k in 0..width {
                        let u = column[k];
                        if u != 0.0 {
                            let l = &panel[k * m..(k + 1) * m];
                            for i in k + 1..m {
                                column[i] -= l[i] * u;
                            }
                        }
                    }
                }
            } else if below > 0 {
                let mut f = MatMut::from_column_major_slice_mut(front, m, m);
                let (top, bottom) = f.rb_mut().split_at_row_mut(width);
                let (l11, mut u12) = top.split_at_col_mut(width);
                solve_unit_lower_triangular_in_place(l11.rb(), u12.rb_mut(), Par::Seq);
                let (l21, c) = bottom.split_at_col_mut(width);
                matmul(c, Accum::Add, l21.rb(), u12.rb(), -1.0, Par::Seq);
            }
            let out = &mut self.factor[self.factor_ptr[s]..self.factor_ptr[s + 1]];
            let (panel, u12) = out.split_at_mut(m * width);
            panel.copy_from_slice(&front[..m * width]);
            for (j, dst) in u12.chunks_exact_mut(width.max(1)).enumerate().take(below) {
                let column = (width + j) * m;
                dst.copy_from_slice(&front[column..column + width]);
            }
            if below > 0 {
                let start = self.updates.len();
                for j in width..m {
                    self.updates.extend_from_slice(&front[j * m + width..(j + 1) * m]);
                }
                self.pending.push((s, start));
            }
        }
        crate::simd_state::clear_upper_state();
        Ok(())
    }

    /// Overwrites `b` with `A⁻¹ b` from the factors of the last [`PatternLu::factorise`].
    pub fn solve_in_place(&mut self, b: &mut [f64]) {
        let y = &mut self.work;
        for (yi, &o) in y.iter_mut().zip(&self.ordering) {
            *yi = b[o];
        }
        let supernodes = self.begin.len() - 1;
        for s in 0..supernodes {
            let (b0, b1) = (self.begin[s], self.begin[s + 1]);
            let width = b1 - b0;
            let rows = &self.pattern[self.pattern_ptr[s]..self.pattern_ptr[s + 1]];
            let m = width + rows.len();
            let panel = &self.factor[self.factor_ptr[s]..self.factor_ptr[s] + m * width];
            for k in 0..width {
                y.swap(b0 + k, b0 + self.pivot[b0 + k]);
            }
            for (j, column) in panel.chunks_exact(m).enumerate() {
                let yj = y[b0 + j];
                if yj != 0.0 {
                    for i in j + 1..width {
                        y[b0 + i] -= column[i] * yj;
                    }
                    for (&l, &r) in column[width..].iter().zip(rows) {
                        y[r] -= l * yj;
                    }
                }
            }
        }
        for s in (0..supernodes).rev() {
            let (b0, b1) = (self.begin[s], self.begin[s + 1]);
            let width = b1 - b0;
            let rows = &self.pattern[self.pattern_ptr[s]..self.pattern_ptr[s + 1]];
            let m = width + rows.len();
            let (panel, u12) = self.factor[self.factor_ptr[s]..self.factor_ptr[s + 1]].split_at(m * width);
            for (column, &r) in u12.chunks_exact(width.max(1)).zip(rows) {
                let yr = y[r];
                if yr != 0.0 {
                    for (i, &u) in column.iter().enumerate() {
                        y[b0 + i] -= u * yr;
                    }
                }
            }
            for j in (0..width).rev() {
                let column = &panel[j * m..];
                y[b0 + j] /= column[j];
                let yj = y[b0 + j];
                for i in 0..j {
                    y[b0 + i] -= column[i] * yj;
                }
            }
        }
        for (&yi, &o) in y.iter().zip(&self.ordering) {
            b[o] = yi;
        }
    }
}

/// LU of the first `width` columns of the column-major `m × m` front, the pivot of column
/// `k` chosen among rows `k..width` (swapped across all `m` columns, `pivot[k]` records
/// the row); the first `width` rows beyond the panel are left for the triangular solve.
/// `Err(k)` if column `k` has no pivot above [`PIVOT_TOLERANCE`].
#[inline(always)]
fn factor_panel(front: &mut [f64], m: usize, width: usize, pivot: &mut [usize]) -> Result<(), usize> {
    for k in 0..width {
        let column = &front[k * m..(k + 1) * m];
        let largest = column[..width].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let (p, best) = (k..width).map(|i| (i, column[i].abs())).fold((k, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        if best <= PIVOT_TOLERANCE * largest || !best.is_finite() {
            return Err(k);
        }
        pivot[k] = p;
        if p != k {
            for j in 0..m {
                front.swap(j * m + k, j * m + p);
            }
        }
        let (left, right) = front.split_at_mut((k + 1) * m);
        let lk = &mut left[k * m..];
        let d = lk[k];
        lk[k + 1..].iter_mut().for_each(|l| *l /= d);
        for j in 0..width - k - 1 {
            let cj = &mut right[j * m..(j + 1) * m];
            let u = cj[k];
            if u != 0.0 {
                for (c, &l) in cj[k + 1..].iter_mut().zip(&lk[k + 1..]) {
                    *c -= l * u;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    /// A structurally symmetric, unsymmetric 2D Laplacian-like matrix with a convection
    /// term, `n × n` grid: `PatternLu` solves it to round-off, with pivoting exercised by a
    /// small diagonal in a few rows.
    #[test]
    fn solves_an_unsymmetric_matrix_on_its_symmetric_pattern() {
        // 30²: every front's update by the loops; 160²: the top fronts by faer's kernels
        for side in [30, 160] {
            solves_on_a_grid(side);
        }
    }

    /// A grid matrix in which every fifth equation is decoupled in value but not in
    /// structure and has a diagonal of 10¹⁶ (an empty node's pressure, equilibrated by
    /// `(μ/h)²`, in the fronts of its neighbours' unit-scale equations): every pivot is
    /// accepted, the tolerance being relative to each column, not to the block (a
    /// block-relative one refused it: 4.3 < 10⁻¹³ · 10¹⁶), and the solve is exact to round-off.
    #[test]
    fn accepts_equations_of_very_different_scales_in_one_front() {
        let (side, large) = (20usize, 1e16);
        let n = side * side;
        let decoupled = |i: usize| i % 5 == 0;
        let mut entries = Vec::new();
        for y in 0..side {
            for x in 0..side {
                let i = y * side + x;
                entries.push(Triplet::new(i, i, if decoupled(i) { large } else { 4.3 }));
                for (dx, dy, w) in [(1i64, 0i64, -1.3), (-1, 0, -0.7), (0, 1, -1.1), (0, -1, -0.9)] {
                    let (xn, yn) = (x as i64 + dx, y as i64 + dy);
                    if (0..side as i64).contains(&xn) && (0..side as i64).contains(&yn) {
                        let j = (yn as usize) * side + xn as usize;
                        entries.push(Triplet::new(i, j, if decoupled(i) || decoupled(j) { 0.0 } else { w }));
                    }
                }
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &entries).unwrap();
        let mut lu = PatternLu::analyse(a.symbolic()).expect("supernodal analysis");
        let mixed_fronts = (0..lu.begin.len() - 1)
            .filter(|&s| {
                let eqs = &lu.ordering[lu.begin[s]..lu.begin[s + 1]];
                eqs.iter().any(|&i| decoupled(i)) && eqs.iter().any(|&i| !decoupled(i))
            })
            .count();
        println!("{mixed_fronts} supernodes hold both scales");
        assert!(mixed_fronts > 0, "the test puts both scales in one front");
        lu.factorise(a.as_ref()).expect("every pivot accepted");
        let relative = solve_residual(&mut lu, &a);
        println!("relative residual {relative:.2e}");
        assert!(relative < 1e-12, "relative residual {relative:e}");
    }

    /// `‖b − A x‖ / ‖b‖` of the solve of `A x = b` with the factors in `lu`, for a fixed `b`
    /// of order one.
    fn solve_residual(lu: &mut PatternLu, a: &SparseColMat<usize, f64>) -> f64 {
        let n = a.nrows();
        let b: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        let mut residual = b.clone();
        for j in 0..n {
            for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                residual[i] -= v * x[j];
            }
        }
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        norm(&residual) / norm(&b)
    }

    fn solves_on_a_grid(side: usize) {
        let n = side * side;
        let mut entries = Vec::new();
        for y in 0..side {
            for x in 0..side {
                let i = y * side + x;
                let small = if i % 97 == 0 { 1e-3 } else { 1.0 };
                entries.push(Triplet::new(i, i, 4.0 * small + 0.3));
                for (dx, dy, w) in [(1i64, 0i64, -1.3), (-1, 0, -0.7), (0, 1, -1.1), (0, -1, -0.9)] {
                    let (xn, yn) = (x as i64 + dx, y as i64 + dy);
                    if (0..side as i64).contains(&xn) && (0..side as i64).contains(&yn) {
                        entries.push(Triplet::new(i, (yn as usize) * side + xn as usize, w));
                    }
                }
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &entries).unwrap();
        let mut lu = PatternLu::analyse(a.symbolic()).expect("supernodal analysis");
        let large = (0..lu.begin.len() - 1)
            .filter(|&s| {
                let (width, below) = (lu.begin[s + 1] - lu.begin[s], lu.pattern_ptr[s + 1] - lu.pattern_ptr[s]);
                width * below * below >= LARGE_UPDATE
            })
            .count();
        let biggest = (0..lu.begin.len() - 1)
            .map(|s| (lu.begin[s + 1] - lu.begin[s]) * (lu.pattern_ptr[s + 1] - lu.pattern_ptr[s]).pow(2))
            .max();
        println!("{side}²: {large} fronts by faer's kernels, largest update {biggest:?}");
        assert_eq!(large > 0, side > 100, "the test covers both kernels");
        lu.factorise(a.as_ref()).expect("factorisation");
        let relative = solve_residual(&mut lu, &a);
        println!("relative residual {relative:.2e}, factor entries {}", lu.factor_entries());
        assert!(relative < 1e-12, "relative residual {relative:e}");
        // a singular block is refused, not divided by
        let zero: Vec<_> = entries
            .iter()
            .map(|t| Triplet::new(t.row, t.col, if t.row == 0 || t.col == 0 { 0.0 } else { t.val }))
            .collect();
        let singular = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &zero).unwrap();
        assert!(lu.factorise(singular.as_ref()).is_err());
    }
}
