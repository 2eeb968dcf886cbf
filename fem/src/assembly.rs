//! Lock-free, deterministic parallel assembly with a reusable sparsity pattern.
//!
//! Assembly is done in two halves (as in MFEM and deal.II): element kernels write their
//! dense local matrices and vectors into one flat *element buffer* (in parallel, each
//! element its own slice), then a *gather* adds them into the global matrix. The gather is
//! precomputed with the pattern: for every nonzero of the compressed-column matrix it lists
//! the element-buffer entries that sum into it, so the values are filled in parallel over
//! nonzeros with no locks and in a fixed order (results do not depend on the thread count).
//! The pattern, the gather lists and the symbolic factorisation are kept while the set of
//! element blocks and equations does not change.

use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use rayon::prelude::*;

use crate::dofs::{DofMap, CONSTRAINED};

/// Layout of element blocks in the element buffers: for block `b`, its global DOFs
/// (`dofs[dof_ptr[b]..dof_ptr[b+1]]`), with its dense row-major matrix at
/// `matrix_offset[b]` and its vector at `dof_ptr[b]` in the element buffers.
#[derive(Debug, Clone, Default)]
pub struct BlockLayout {
    /// Global DOF ids (node·dim + component) of each block, back to back.
    pub dofs: Vec<usize>,
    /// Start of each block in `dofs` (and in the vector buffer); `len = blocks + 1`.
    pub dof_ptr: Vec<usize>,
    /// Start of each block's matrix in the matrix buffer; `len = blocks + 1`.
    pub matrix_offset: Vec<usize>,
}

impl BlockLayout {
    /// Appends a block with global DOFs `dofs`.
    pub fn push(&mut self, dofs: impl IntoIterator<Item = usize>) {
        if self.dof_ptr.is_empty() {
            self.dof_ptr.push(0);
            self.matrix_offset.push(0);
        }
        self.dofs.extend(dofs);
        let n = self.dofs.len() - self.dof_ptr.last().unwrap();
        self.dof_ptr.push(self.dofs.len());
        self.matrix_offset.push(self.matrix_offset.last().unwrap() + n * n);
    }

    /// Number of blocks.
    pub fn num_blocks(&self) -> usize {
        self.dof_ptr.len().saturating_sub(1)
    }

    /// Length of the vector buffer.
    pub fn vector_len(&self) -> usize {
        self.dofs.len()
    }

    /// Length of the matrix buffer.
    pub fn matrix_len(&self) -> usize {
        self.matrix_offset.last().copied().unwrap_or(0)
    }
}

/// Average entries of the element matrices (`n²` for a block of `n` DOFs) from which the
/// matrix gather runs in row order ([`AssemblyPattern::gather_matrix`]). Measured
/// (6 December 2026, one thread, the previous column-order gather against the row order,
/// results identical): the u–p Bui column on B-splines (27 DOFs, 729 entries) assembly
/// −18 to −22 %, the 3D cantilevers (hex8, 576; B-splines, 6 561) −10 to −37 %, the 2D
/// B-spline collapse (324) unchanged, the u–p footing on linear cells (144) +6 to +11 %.
pub const ROW_GATHER_ENTRIES: usize = 400;

/// Sparsity pattern of the global matrix with its gather lists.
#[derive(Debug, Clone)]
pub struct AssemblyPattern {
    symbolic: SymbolicSparseColMat<usize>,
    /// For the `k`-th nonzero — of the compressed-column matrix, or with [`Self::by_rows`] of
    /// the compressed-row one (the nonzero at position `transpose[k]` of the values) — the
    /// matrix-buffer entries `src[ptr[k]..ptr[k+1]]` that sum into it, in ascending order.
    matrix_gather_ptr: Vec<u32>,
    matrix_gather_src: Vec<u32>,
    /// Whether the matrix gather runs in row order (blocks of [`ROW_GATHER_ENTRIES`] entries
    /// or more on average).
    by_rows: bool,
    /// For DOF `g` (constrained or not): vector-buffer entries that sum into it.
    vector_gather_ptr: Vec<usize>,
    vector_gather_src: Vec<u32>,
    /// For nonzero `k` at (i, j): the position of (j, i) (the pattern is symmetric).
    transpose: Vec<u32>,
}

impl AssemblyPattern {
    /// Builds the pattern of the equations of `dofs` touched by the blocks of `layout`.
    pub fn new(dofs: &DofMap, layout: &BlockLayout) -> Self {
        Self::of_blocks(dofs, layout, |_| true)
    }

    /// The pattern and gather lists of the blocks `b` of `layout` for which `selected(b)`
    /// holds (a rank's share of a distributed assembly, [`crate::ranks`]): the matrix has all
    /// the equations of `dofs` (empty columns where no selected block reaches), and the
    /// gathers read the selected blocks' entries of the whole element buffers.
    pub fn of_blocks(dofs: &DofMap, layout: &BlockLayout, selected: impl Fn(usize) -> bool) -> Self {
        let n = dofs.num_equations();
        // u32 gather sources and pointers: the element buffer bounds both
        assert!(layout.matrix_len() < u32::MAX as usize, "element buffer exceeds u32 indexing");
        let blocks: Vec<usize> = (0..layout.num_blocks()).filter(|&b| selected(b)).collect();
        // the free couplings as keys `row << 32 | source` bucketed by column (a counting sort:
        // two passes over the blocks), each column's few keys then sorted (by row, then source)
        let mut equations = Vec::new();
        let block_equations = |b: usize, equations: &mut Vec<usize>| {
            equations.clear();
            equations.extend(layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]].iter().map(|&g| dofs.equation(g)));
        };
        let mut bucket_ptr = vec![0usize; n + 1];
        for &b in &blocks {
            block_equations(b, &mut equations);
            let rows = equations.iter().filter(|&&e| e != CONSTRAINED).count();
            for &ec in &equations {
                if ec != CONSTRAINED {
                    bucket_ptr[ec + 1] += rows;
                }
            }
        }
        for c in 0..n {
            bucket_ptr[c + 1] += bucket_ptr[c];
        }
        let mut keys = vec![0u64; bucket_ptr[n]];
        let mut fill = bucket_ptr.clone();
        for &b in &blocks {
            block_equations(b, &mut equations);
            let nd = equations.len();
            let off = layout.matrix_offset[b];
            for (c, &ec) in equations.iter().enumerate() {
                if ec == CONSTRAINED {
                    continue;
                }
                let column = &mut keys[fill[ec]..];
                let mut k = 0;
                for (r, &er) in equations.iter().enumerate() {
                    if er != CONSTRAINED {
                        column[k] = (er as u64) << 32 | (off + r * nd + c) as u64;
                        k += 1;
                    }
                }
                fill[ec] += k;
            }
        }
        drop(fill);
        let mut rest = keys.as_mut_slice();
        for c in 0..n {
            let (column, tail) = rest.split_at_mut(bucket_ptr[c + 1] - bucket_ptr[c]);
            column.sort_unstable();
            rest = tail;
        }
        // one nonzero per distinct (column, row); every key is a gather source, in key order
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::with_capacity(keys.len());
        let mut matrix_gather_ptr: Vec<u32> = Vec::with_capacity(keys.len() + 1);
        for c in 0..n {
            let mut last = u64::MAX;
            for (i, &key) in keys.iter().enumerate().take(bucket_ptr[c + 1]).skip(bucket_ptr[c]) {
                let r = key >> 32;
                if r != last {
                    matrix_gather_ptr.push(i as u32);
                    row_idx.push(r as usize);
                    last = r;
                }
            }
            col_ptr[c + 1] = row_idx.len();
        }
        matrix_gather_ptr.push(keys.len() as u32);
        // transpose positions: the pattern is symmetric (block structure), so column `r` holds
        // row `c` exactly when column `c` holds row `r`, and a sweep over the columns in order
        // meets the rows of column `r` in their stored (ascending) order
        let mut transpose = vec![0u32; row_idx.len()];
        let mut next = col_ptr[..n].to_vec();
        for c in 0..n {
            for k in col_ptr[c]..col_ptr[c + 1] {
                let r = row_idx[k];
                debug_assert_eq!(row_idx[next[r]], c, "symmetric block pattern");
                transpose[k] = next[r] as u32;
                next[r] += 1;
            }
        }
        // the gather lists in row order for large blocks: a block's matrix is row-major, so
        // the entries of one row of a block that a row of the matrix gathers are neighbours in
        // the buffer, where the column order reads one entry per row of the block (a cache
        // line each once the blocks are wider than one); for small blocks the element
        // buffer stays in cache and the permutation back to column order costs more
        let block_entries: usize = blocks.iter().map(|&b| layout.matrix_offset[b + 1] - layout.matrix_offset[b]).sum();
        let by_rows = !blocks.is_empty() && block_entries >= ROW_GATHER_ENTRIES * blocks.len();
        let (matrix_gather_ptr, matrix_gather_src) = if by_rows {
            let mut ptr: Vec<u32> = Vec::with_capacity(row_idx.len() + 1);
            let mut src: Vec<u32> = Vec::with_capacity(keys.len());
            ptr.push(0);
            for &t in &transpose {
                let (from, to) = (matrix_gather_ptr[t as usize] as usize, matrix_gather_ptr[t as usize + 1] as usize);
                src.extend(keys[from..to].iter().map(|&k| k as u32));
                ptr.push(src.len() as u32);
            }
            (ptr, src)
        } else {
            let src = keys.iter().map(|&k| k as u32).collect();
            (matrix_gather_ptr, src)
        };
        drop(keys);
        // vector gather over all DOFs
        let entries = || blocks.iter().flat_map(|&b| layout.dof_ptr[b]..layout.dof_ptr[b + 1]);
        let mut counts = vec![0usize; dofs.num_dofs() + 1];
        for i in entries() {
            counts[layout.dofs[i] + 1] += 1;
        }
        for g in 0..dofs.num_dofs() {
            counts[g + 1] += counts[g];
        }
        let vector_gather_ptr = counts.clone();
        let mut fill = counts;
        let mut vector_gather_src = vec![0u32; fill[dofs.num_dofs()]];
        for i in entries() {
            let g = layout.dofs[i];
            vector_gather_src[fill[g]] = i as u32;
            fill[g] += 1;
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Self {
            symbolic,
            matrix_gather_ptr,
            matrix_gather_src,
            by_rows,
            vector_gather_ptr,
            vector_gather_src,
            transpose,
        }
    }

    /// Number of equations.
    pub fn num_equations(&self) -> usize {
        self.symbolic.nrows()
    }

    /// The DOFs (constrained or not) that the gathered blocks reach.
    pub fn reached_dofs(&self) -> Vec<usize> {
        (0..self.vector_gather_ptr.len() - 1)
            .filter(|&g| self.vector_gather_ptr[g + 1] > self.vector_gather_ptr[g])
            .collect()
    }

    /// Number of stored nonzeros.
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// The symbolic matrix (for symbolic factorisations).
    pub fn symbolic(&self) -> &SymbolicSparseColMat<usize> {
        &self.symbolic
    }

    /// `y = A x` for the matrix with nonzeros `values` (column-compressed).
    pub fn multiply(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for (c, &xc) in x.iter().enumerate() {
            for k in col_ptr[c]..col_ptr[c + 1] {
                y[row_idx[k]] += values[k] * xc;
            }
        }
    }

    /// The factors `d_i d_j` of `A ← D A D` (`D = diag(d)`, one entry per equation) for every
    /// stored nonzero `(i, j)`, in the order of the values: with them the scaling is one
    /// streaming product over the values ([`scale_values`]), where a sweep over the columns
    /// reads `d` at every row index.
    pub fn symmetric_scale_factors(&self, d: &[f64]) -> Vec<f64> {
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        let mut factors = vec![0.0; row_idx.len()];
        for (c, &dc) in d.iter().enumerate() {
            for k in col_ptr[c]..col_ptr[c + 1] {
                factors[k] = d[row_idx[k]] * dc;
            }
        }
        factors
    }

    /// Sums the element matrices of `matrix_buffer` into `values` (one per nonzero, in
    /// column order). With large blocks ([`ROW_GATHER_ENTRIES`]) the sums are formed in row
    /// order in `scratch` (resized to the nonzeros), whose reads of the row-major element
    /// matrices are contiguous within a block, then permuted into column order. Each nonzero
    /// sums the same entries in the same order in either order and whatever the thread count.
    pub fn gather_matrix(&self, matrix_buffer: &[f64], values: &mut [f64], scratch: &mut Vec<f64>) {
        let sum = |k: usize| -> f64 {
            let src =
                &self.matrix_gather_src[self.matrix_gather_ptr[k] as usize..self.matrix_gather_ptr[k + 1] as usize];
            src.iter().map(|&s| matrix_buffer[s as usize]).sum()
        };
        if !self.by_rows {
            values.par_iter_mut().enumerate().with_min_len(4096).for_each(|(k, v)| *v = sum(k));
            return;
        }
        scratch.resize(values.len(), 0.0);
        scratch.par_iter_mut().enumerate().with_min_len(4096).for_each(|(k, v)| *v = sum(k));
        values
            .par_iter_mut()
            .zip(self.transpose.par_iter())
            .with_min_len(4096)
            .for_each(|(v, &t)| *v = scratch[t as usize]);
    }

    /// Sums the element vectors of `vector_buffer` into `out` (one entry per DOF,
    /// constrained DOFs included: there the sum is the reaction).
    pub fn gather_vector(&self, vector_buffer: &[f64], out: &mut [f64]) {
        out.par_iter_mut().enumerate().with_min_len(4096).for_each(|(g, v)| {
            let src = &self.vector_gather_src[self.vector_gather_ptr[g]..self.vector_gather_ptr[g + 1]];
            *v = src.iter().map(|&s| vector_buffer[s as usize]).sum();
        });
    }

    /// The symmetric part `(A + Aᵀ)/2` of the matrix with nonzeros `values`, on the same
    /// (structurally symmetric) pattern.
    pub fn symmetric_part(&self, values: &[f64], out: &mut Vec<f64>) {
        out.resize(values.len(), 0.0);
        out.par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(k, s)| *s = 0.5 * (values[k] + values[self.transpose[k] as usize]));
    }

    /// Largest asymmetry `max |a_ij − a_ji|` relative to `max |a_ij|`.
    pub fn asymmetry(&self, values: &[f64]) -> f64 {
        let amax = values.par_iter().fold(|| 0.0f64, |m, v| m.max(v.abs())).reduce(|| 0.0, f64::max);
        let d = values
            .par_iter()
            .zip(self.transpose.par_iter())
            .fold(|| 0.0f64, |m, (v, &t)| m.max((v - values[t as usize]).abs()))
            .reduce(|| 0.0, f64::max);
        if amax > 0.0 {
            d / amax
        } else {
            0.0
        }
    }

    /// Whether `|a_ij − a_ji| ≤ tolerance · max |a_ij|` for every pair: [`Self::asymmetry`]
    /// `≤ tolerance`, but stopping at the first chunk of entries with an offending pair.
    pub fn is_symmetric(&self, values: &[f64], tolerance: f64) -> bool {
        let amax = values.par_chunks(1 << 14).map(max_abs).reduce(|| 0.0, f64::max);
        let limit = tolerance * amax;
        // each pair twice, branch-free within a chunk; the chunks stop at the first offending one
        let chunk = 1 << 14;
        !(0..values.len().div_ceil(chunk)).into_par_iter().any(|c| {
            let range = c * chunk..((c + 1) * chunk).min(values.len());
            let mut offending = false;
            for (v, &t) in values[range.clone()].iter().zip(&self.transpose[range]) {
                offending |= (v - values[t as usize]).abs() > limit;
            }
            offending
        })
    }

    /// For every stored nonzero `k` at `(i, j)`, the position of `(j, i)`: with the
    /// column pointers and row indices (the pattern is structurally symmetric) it gives the
    /// compressed-row order of the matrix, row `i`'s entry `(i, j)` at position
    /// `transpose_positions()[k]` of the values.
    pub fn transpose_positions(&self) -> &[u32] {
        &self.transpose
    }

    /// A faer view of the matrix with `values`.
    pub fn matrix<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        SparseColMatRef::new(self.symbolic.as_ref(), values)
    }
}

/// `values_k ← values_k · factors_k` (the factors of [`AssemblyPattern::symmetric_scale_factors`]).
pub fn scale_values(values: &mut [f64], factors: &[f64]) {
    values.iter_mut().zip(factors).for_each(|(v, f)| *v *= f);
}

/// `max |v|` over `values` (NaN ignored, 0 for none), in eight independent lanes: a single
/// running maximum waits on the latency of every comparison (4 cycles), eight keep a vector
/// unit busy (the symmetry test of every Newton solve was 4 % of an MPM cantilever step).
fn max_abs(values: &[f64]) -> f64 {
    let mut lanes = [0.0f64; 8];
    let chunks = values.chunks_exact(8);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (m, v) in lanes.iter_mut().zip(chunk) {
            let a = v.abs();
            if a > *m {
                *m = a;
            }
        }
    }
    rest.iter().chain(&lanes).fold(0.0, |m, v| if v.abs() > m { v.abs() } else { m })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Blocks of 21 DOFs (441 entries: the gather in row order) sharing DOFs, some DOFs
    /// constrained: the gathered matrix equals the dense sum of the blocks' free entries, bit
    /// for bit (each nonzero sums its entries in block order in either gather order), and the
    /// same blocks cut to 8 DOFs take the column order.
    #[test]
    fn row_order_gather_sums_large_blocks_as_a_dense_assembly() {
        let n = 40;
        let fixed: Vec<bool> = (0..n).map(|g| g % 7 == 3).collect();
        let dofs = DofMap::new(1, &fixed);
        for width in [21, 8] {
            let mut layout = BlockLayout::default();
            let starts = [0, 9, 19];
            for &a in &starts {
                layout.push((0..width).map(|i| (a + 2 * i) % n));
            }
            let pattern = AssemblyPattern::new(&dofs, &layout);
            assert_eq!(pattern.by_rows, width * width >= ROW_GATHER_ENTRIES);
            // entries that do not round alike in any order: k-th entry (k + 1)·√2 scaled
            let buffer: Vec<f64> = (0..layout.matrix_len()).map(|k| (k as f64 + 1.0) * 2f64.sqrt() * 1e-3).collect();
            let mut values = vec![0.0; pattern.nnz()];
            pattern.gather_matrix(&buffer, &mut values, &mut Vec::new());
            let m = dofs.num_equations();
            let mut dense = vec![0.0; m * m];
            for b in 0..layout.num_blocks() {
                let block = &layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]];
                for (r, &gr) in block.iter().enumerate() {
                    for (c, &gc) in block.iter().enumerate() {
                        let (er, ec) = (dofs.equation(gr), dofs.equation(gc));
                        if er != CONSTRAINED && ec != CONSTRAINED {
                            dense[er * m + ec] += buffer[layout.matrix_offset[b] + r * width + c];
                        }
                    }
                }
            }
            let gathered = pattern.matrix(&values).to_dense();
            for i in 0..m {
                for j in 0..m {
                    assert_eq!(gathered[(i, j)].to_bits(), dense[i * m + j].to_bits(), "width {width}: ({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn two_springs_assemble_into_a_tridiagonal_matrix() {
        // three nodes in 1D, node 0 fixed; springs (0,1) and (1,2) with k = 2 and 3
        let dofs = DofMap::new(1, &[true, false, false]);
        let mut layout = BlockLayout::default();
        layout.push([0, 1]);
        layout.push([1, 2]);
        let pattern = AssemblyPattern::new(&dofs, &layout);
        let buf = [2.0, -2.0, -2.0, 2.0, 3.0, -3.0, -3.0, 3.0];
        let mut values = vec![0.0; pattern.nnz()];
        let mut by_rows = Vec::new();
        pattern.gather_matrix(&buf, &mut values, &mut by_rows);
        let dense = pattern.matrix(&values).to_dense();
        assert_eq!(dense[(0, 0)], 5.0);
        assert_eq!(dense[(0, 1)], -3.0);
        assert_eq!(dense[(1, 0)], -3.0);
        assert_eq!(dense[(1, 1)], 3.0);
        let mut r = vec![0.0; 3];
        pattern.gather_vector(&[1.0, 2.0, 3.0, 4.0], &mut r);
        assert_eq!(r, vec![1.0, 5.0, 4.0]);
        assert_eq!(pattern.asymmetry(&values), 0.0);
        assert!(pattern.is_symmetric(&values, 0.0));
        // the second spring alone: rows and columns of equations 0 and 1, and DOFs 1 and 2
        let second = AssemblyPattern::of_blocks(&dofs, &layout, |b| b == 1);
        let mut part = vec![0.0; second.nnz()];
        second.gather_matrix(&buf, &mut part, &mut by_rows);
        let dense_part = second.matrix(&part).to_dense();
        assert_eq!((dense_part[(0, 0)], dense_part[(0, 1)], dense_part[(1, 1)]), (3.0, -3.0, 3.0));
        second.gather_vector(&[1.0, 2.0, 3.0, 4.0], &mut r);
        assert_eq!(r, vec![0.0, 3.0, 4.0]);
        assert_eq!(second.reached_dofs(), vec![1, 2]);
        values[pattern.transpose[1] as usize] += 1e-6;
        let spread: Vec<f64> = (0..37).map(|k| (k as f64 - 20.0) * if k == 29 { 10.0 } else { 1.0 }).collect();
        assert_eq!(max_abs(&spread), 90.0);
        assert_eq!(max_abs(&[f64::NAN, -3.0, 2.0]), 3.0);
        assert_eq!(max_abs(&[]), 0.0);
        assert!(!pattern.is_symmetric(&values, 1e-9));
        assert!(pattern.is_symmetric(&values, 1e-6));
    }
}
