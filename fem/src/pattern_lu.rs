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

use std::mem::MaybeUninit;

use faer::dyn_stack::MemStack;
use faer::linalg::lu::partial_pivoting::factor::{lu_in_place, lu_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_unit_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, MatMut, MatRef, Par, Side};
use rayon::prelude::*;

/// Smallest pivot, relative to the largest entry of its column in the supernode's diagonal
/// block at its elimination (the `U` entries above it included), that the factorisation
/// accepts. Relative to its own column, not to the whole block: a block may hold equations
/// of very different scales (the unit diagonal of an empty node's pressure, scaled by the
/// equilibration `(μ/h)²`, beside a displacement's unit diagonal).
pub const PIVOT_TOLERANCE: f64 = 1e-13;

/// Multiply–adds `width · below²` of a front's update from which it goes to faer's dense
/// triangular solve and matrix product (register-tiled, fused multiply–add); below it, plain
/// loops. Measured per factorisation against 2²⁰ (docs/performance.md, LU kernels): −25 % on
/// the u–p B-spline Bui case, −18 % on `collapse_bui2008_tri_h2`; 2¹², 2¹⁵ and 2¹⁶ lie within
/// the noise of 2¹⁴.
pub const LARGE_UPDATE: usize = 1 << 14;

/// Width of a supernode from which its panel is factorised by blocks
/// ([`factor_panel_blocked`]: faer's recursive LU on the diagonal block, `L21` by a triangular
/// solve); narrower panels column by column ([`factor_panel`]).
pub const BLOCKED_PANEL: usize = 32;

/// Width of a supernode from which [`PatternLu::solve_in_place`] applies its panel with
/// faer's dense triangular solve and matrix–vector product (the rows below gathered and
/// scattered once); narrower panels column by column.
pub const DENSE_SOLVE_WIDTH: usize = 16;

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
    /// For each entry of `pattern`: how many entries from it on (within its supernode) sit
    /// at consecutive positions of the parent's front — the extend-add adds such a run as
    /// one slice.
    run_length: Vec<u32>,
    /// The matrix entries of each front: (nonzero of `A`, column-major index in the front).
    front_entries_ptr: Vec<usize>,
    front_entries: Vec<(u32, u32)>,
    /// Factors of each supernode at `factor_ptr[s]`: `[L11\U11; L21]` (front rows × width,
    /// column-major), then `U12` (width × pattern, column-major).
    factor_ptr: Vec<usize>,
    factor: Vec<f64>,
    /// Row `k` of a supernode's block was swapped with its row `pivot[begin + k]`.
    pivot: Vec<usize>,
    /// The workspace of the elimination in one thread (the serial part's).
    main: Workspace,
    /// Position of each supernode in `postorder`, and of the first supernode of its subtree
    /// (a subtree is a contiguous range of a postorder).
    position: Vec<usize>,
    /// Parent of each supernode in the elimination tree (`None` for a root).
    parent: Vec<Option<usize>>,
    subtree_first: Vec<usize>,
    /// Estimated multiply–adds of each supernode's elimination ([`front_work`]).
    work_of: Vec<f64>,
    /// The subtrees eliminated in parallel, for the number of threads it was made for.
    schedule: Option<Schedule>,
    work: Vec<f64>,
    /// The rows below a panel, gathered by the solve.
    below_rows: Vec<f64>,
}

/// Where one thread eliminates its fronts: the front, and the updates `C_s` waiting for
/// their parent with where each starts and its supernode (a stack in postorder).
#[derive(Default)]
struct Workspace {
    front: Vec<f64>,
    updates: Vec<f64>,
    pending: Vec<(usize, usize)>,
    panel: PanelScratch,
}

/// The scratch of [`factor_panel_blocked`], grown to the widest blocked panel on the first
/// factorisation and reused after.
#[derive(Default)]
struct PanelScratch {
    /// faer's row permutation of the diagonal block and its inverse.
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    /// While the permutation is turned into swaps: the original row at each position, and
    /// the position of each original row.
    row_at: Vec<usize>,
    position_of: Vec<usize>,
    /// faer's stack (the transpositions of its recursive LU).
    stack: Vec<MaybeUninit<u8>>,
}

/// Subtrees of the supernodal elimination tree assigned to threads (subtree-to-thread
/// mapping, Geist & Ng 1989, "Task scheduling for parallel sparse Cholesky factorization",
/// Int. J. Parallel Programming 18:291–314): the subtrees of different threads share no
/// supernode and no update, so each thread eliminates its own in postorder with its own
/// workspace, and the supernodes above them (the serial part) follow in one thread, taking
/// each subtree root's update where the sequential postorder would have made it. Every
/// front sees the same operations in the same order as in one thread, so the factors are
/// bit for bit those of the sequential elimination.
struct Schedule {
    threads: usize,
    /// Per thread: its workspace (fronts up to its subtrees' largest).
    workspaces: Vec<Workspace>,
    /// Every subtree as (its first supernode, root, thread), ascending: the supernodes
    /// `first..=root` in the numbering, which is a postorder.
    subtrees: Vec<(usize, usize, usize)>,
}

/// Least estimated work ([`front_work`]) of a factorisation that is split among threads:
/// below it (about 0.2 ms) the threads' start costs more than they save.
const PARALLEL_WORK: f64 = 4e5;

/// Least speed-up of the schedule's estimated makespan over one thread for it to be used.
const PARALLEL_GAIN: f64 = 1.15;

impl Schedule {
    /// The subtree-to-thread mapping of `lu` for `threads` threads, `None` if it would not
    /// pay ([`PARALLEL_WORK`], [`PARALLEL_GAIN`]). Starting from the roots, the heaviest
    /// subtree is split (its root joins the serial part, its children become subtrees) as
    /// long as that lowers the estimated makespan — the serial part plus the largest load
    /// of a longest-processing-time assignment of the subtrees to the threads — for a
    /// bounded number of splits; the best assignment seen is kept.
    fn new(lu: &PatternLu, threads: usize) -> Option<Self> {
        let supernodes = lu.postorder.len();
        let total: f64 = lu.work_of.iter().sum();
        if total < PARALLEL_WORK {
            return None;
        }
        let mut kids: Vec<Vec<usize>> = vec![Vec::new(); supernodes];
        // subtree work, children before parents in the postorder
        let mut subtree = lu.work_of.clone();
        for &s in &lu.postorder {
            if let Some(p) = lu.parent[s] {
                kids[p].push(s);
                subtree[p] += subtree[s];
            }
        }
        let assign = |candidates: &[usize]| -> (f64, Vec<Vec<usize>>) {
            let mut sorted = candidates.to_vec();
            sorted.sort_by(|a, b| subtree[*b].total_cmp(&subtree[*a]).then(a.cmp(b)));
            let mut loads = vec![0.0f64; threads];
            let mut groups = vec![Vec::new(); threads];
            for r in sorted {
                let t = (0..threads).min_by(|&a, &b| loads[a].total_cmp(&loads[b])).expect("threads");
                loads[t] += subtree[r];
                groups[t].push(r);
            }
            (loads.iter().fold(0.0, |m: f64, &l| m.max(l)), groups)
        };
        let mut candidates: Vec<usize> = (0..supernodes).filter(|&s| lu.parent[s].is_none()).collect();
        let mut serial = 0.0;
        let mut best: Option<(f64, Vec<Vec<usize>>)> = None;
        for _ in 0..4 * supernodes.min(256) {
            let (load, groups) = assign(&candidates);
            if best.as_ref().is_none_or(|b| serial + load < b.0) {
                best = Some((serial + load, groups));
            }
            let Some(k) =
                (0..candidates.len()).max_by(|&a, &b| subtree[candidates[a]].total_cmp(&subtree[candidates[b]]))
            else {
                break;
            };
            let r = candidates.swap_remove(k);
            serial += lu.work_of[r];
            candidates.extend_from_slice(&kids[r]);
        }
        let (makespan, mut groups) = best?;
        if total / makespan < PARALLEL_GAIN {
            return None;
        }
        let mut subtrees = Vec::new();
        let mut workspaces = Vec::with_capacity(threads);
        for (t, roots) in groups.iter_mut().enumerate() {
            roots.sort_by_key(|&r| lu.position[r]);
            let mut largest = 0;
            for &r in roots.iter() {
                // a subtree must be the supernodes first..=r in the numbering (faer numbers
                // them in a postorder) for its factors to be one contiguous range
                let members = &lu.postorder[lu.subtree_first[r]..=lu.position[r]];
                let first = r + 1 - members.len();
                if members.iter().enumerate().any(|(k, &s)| s != first + k) {
                    return None;
                }
                subtrees.push((first, r, t));
                for &s in members {
                    let m = lu.begin[s + 1] - lu.begin[s] + lu.pattern_ptr[s + 1] - lu.pattern_ptr[s];
                    largest = largest.max(m * m);
                }
            }
            workspaces.push(Workspace { front: vec![0.0; largest], ..Default::default() });
        }
        subtrees.sort_unstable();
        Some(Self { threads, workspaces, subtrees })
    }
}

/// Estimated multiply–adds of eliminating a supernode of `width` columns with `below` rows
/// under it: the panel, `U12`, the update `C = F22 − L21 U12` and the extend-add.
fn front_work(width: usize, below: usize) -> f64 {
    let (w, b) = (width as f64, below as f64);
    w * w * (w + b) + w * w * b + 2.0 * w * b * b + (w + b) * (w + b)
}

/// The pattern and the values an elimination reads, shared by the threads.
struct Structure<'a> {
    begin: &'a [usize],
    pattern_ptr: &'a [usize],
    children: &'a [usize],
    position_in_parent: &'a [u32],
    run_length: &'a [u32],
    front_entries_ptr: &'a [usize],
    front_entries: &'a [(u32, u32)],
    factor_ptr: &'a [usize],
    values: &'a [f64],
}

/// A contiguous range of supernodes (a subtree, numbered in postorder, or one supernode)
/// with their factors and pivots: `factor` starts at the factor offset of supernode
/// `supernodes.start`, `pivot` at its first column.
struct Part<'f> {
    supernodes: std::ops::Range<usize>,
    factor: &'f mut [f64],
    pivot: &'f mut [usize],
}

/// Eliminates the supernodes of `parts` (each in ascending order: a postorder) with
/// workspace `ws`, inside pulp's instruction-set dispatch ([`PatternLu::factorise`]).
fn dispatch(structure: &Structure<'_>, parts: &mut [Part<'_>], ws: &mut Workspace) -> Result<(), PivotFailure> {
    struct Eliminate<'s, 'a, 'p, 'f> {
        structure: &'s Structure<'a>,
        parts: &'p mut [Part<'f>],
        ws: &'s mut Workspace,
    }
    impl pulp::WithSimd for Eliminate<'_, '_, '_, '_> {
        type Output = Result<(), PivotFailure>;
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, _simd: S) -> Self::Output {
            let st = self.structure;
            let mut result = Ok(());
            'parts: for part in self.parts.iter_mut() {
                let (f0, c0) = (st.factor_ptr[part.supernodes.start], st.begin[part.supernodes.start]);
                for s in part.supernodes.clone() {
                    let factor = &mut part.factor[st.factor_ptr[s] - f0..st.factor_ptr[s + 1] - f0];
                    let pivot = &mut part.pivot[st.begin[s] - c0..st.begin[s + 1] - c0];
                    result = eliminate(st, s, self.ws, factor, pivot);
                    if result.is_err() {
                        break 'parts;
                    }
                }
            }
            crate::simd_state::clear_upper_state();
            result
        }
    }
    pulp::Arch::new().dispatch(Eliminate { structure, parts, ws })
}

/// The elimination of supernode `s` (see the module doc): its front assembled from `A` and
/// its children's pending updates, the panel factorised with restricted pivoting, `U12` and
/// the update `C_s` formed, the factors written to `factor` (the supernode's range) and
/// `pivot` (its columns'), and `C_s` pushed for the parent.
#[inline(always)]
fn eliminate(
    st: &Structure<'_>,
    s: usize,
    ws: &mut Workspace,
    factor: &mut [f64],
    pivot: &mut [usize],
) -> Result<(), PivotFailure> {
    let (b0, b1) = (st.begin[s], st.begin[s + 1]);
    let width = b1 - b0;
    let (p0, p1) = (st.pattern_ptr[s], st.pattern_ptr[s + 1]);
    let below = p1 - p0;
    let m = width + below;
    let front = &mut ws.front[..m * m];
    front.fill(0.0);
    for &(k, at) in &st.front_entries[st.front_entries_ptr[s]..st.front_entries_ptr[s + 1]] {
        front[at as usize] += st.values[k as usize];
    }
    // extend-add the children's updates: the last `children[s]` pending ones
    for _ in 0..st.children[s] {
        let (c, start) = ws.pending.pop().expect("a child's update is pending");
        let positions = &st.position_in_parent[st.pattern_ptr[c]..st.pattern_ptr[c + 1]];
        let runs = &st.run_length[st.pattern_ptr[c]..st.pattern_ptr[c + 1]];
        let mc = positions.len();
        let update = &ws.updates[start..start + mc * mc];
        for (column, &pj) in update.chunks_exact(mc).zip(positions) {
            let target = &mut front[pj as usize * m..(pj as usize + 1) * m];
            // the column's entries in runs of consecutive positions, each run as one slice
            let mut q = 0;
            while q < mc {
                let (len, at) = (runs[q] as usize, positions[q] as usize);
                for (t, &value) in target[at..at + len].iter_mut().zip(&column[q..q + len]) {
                    *t += value;
                }
                q += len;
            }
        }
        ws.updates.truncate(start);
    }
    if width >= BLOCKED_PANEL {
        factor_panel_blocked(front, m, width, pivot, &mut ws.panel)
    } else {
        factor_panel(front, m, width, pivot)
    }
    .map_err(|k| PivotFailure(b0 + k))?;
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
    let (panel, u12) = factor.split_at_mut(m * width);
    panel.copy_from_slice(&front[..m * width]);
    for (j, dst) in u12.chunks_exact_mut(width.max(1)).enumerate().take(below) {
        let column = (width + j) * m;
        dst.copy_from_slice(&front[column..column + width]);
    }
    if below > 0 {
        let start = ws.updates.len();
        for j in width..m {
            ws.updates.extend_from_slice(&front[j * m + width..(j + 1) * m]);
        }
        ws.pending.push((s, start));
    }
    Ok(())
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
        let mut run_length = vec![1u32; pattern.len()];
        for s in 0..supernodes {
            for q in (pattern_ptr[s]..pattern_ptr[s + 1].saturating_sub(1)).rev() {
                if position_in_parent[q + 1] == position_in_parent[q] + 1 {
                    run_length[q] = run_length[q + 1] + 1;
                }
            }
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
        let mut position = vec![0usize; supernodes];
        let mut subtree_first = vec![0usize; supernodes];
        for (i, &s) in postorder.iter().enumerate() {
            position[s] = i;
            subtree_first[s] = kids[s].iter().map(|&c| subtree_first[c]).min().unwrap_or(i);
        }
        let work_of: Vec<f64> =
            (0..supernodes).map(|s| front_work(begin[s + 1] - begin[s], pattern_ptr[s + 1] - pattern_ptr[s])).collect();
        let mut factor_ptr = vec![0usize];
        let (mut largest_front, mut largest_below) = (0, 0);
        for s in 0..supernodes {
            let (width, below) = (begin[s + 1] - begin[s], rows(s).len());
            largest_front = largest_front.max((width + below) * (width + below));
            largest_below = largest_below.max(below);
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
            run_length,
            front_entries_ptr,
            front_entries,
            factor_ptr,
            pivot: vec![0; n],
            main: Workspace { front: vec![0.0; largest_front], ..Default::default() },
            position,
            parent,
            subtree_first,
            work_of,
            schedule: None,
            work: vec![0.0; n],
            below_rows: vec![0.0; largest_below],
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
    /// (Rust does not fuse `a * b + c`), in about 15 % less time on the Bui collapse. With more
    /// than one rayon thread, independent subtrees of the elimination tree are eliminated in
    /// parallel ([`Schedule`]); the factors are the same bit for bit.
    pub fn factorise(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), PivotFailure> {
        let threads = rayon::current_num_threads();
        if threads > 1 && self.schedule.as_ref().is_none_or(|s| s.threads != threads) {
            self.schedule = Schedule::new(self, threads);
        }
        let structure = Structure {
            begin: &self.begin,
            pattern_ptr: &self.pattern_ptr,
            children: &self.children,
            position_in_parent: &self.position_in_parent,
            run_length: &self.run_length,
            front_entries_ptr: &self.front_entries_ptr,
            front_entries: &self.front_entries,
            factor_ptr: &self.factor_ptr,
            values: a.val(),
        };
        let schedule = if threads > 1 { self.schedule.as_mut() } else { None };
        // the schedule's subtrees, each thread its own, their factors and pivots split off
        let (subtrees, workspaces): (&[(usize, usize, usize)], &[Workspace]) = match schedule {
            Some(schedule) => {
                let mut parts: Vec<Vec<Part<'_>>> = (0..schedule.threads).map(|_| Vec::new()).collect();
                let (mut factor, mut pivot): (&mut [f64], &mut [usize]) = (&mut self.factor, &mut self.pivot);
                let (mut factor_at, mut pivot_at) = (0, 0);
                for &(first, root, thread) in &schedule.subtrees {
                    let (f0, f1) = (self.factor_ptr[first], self.factor_ptr[root + 1]);
                    let (c0, c1) = (self.begin[first], self.begin[root + 1]);
                    let (mine, rest) = std::mem::take(&mut factor)[f0 - factor_at..].split_at_mut(f1 - f0);
                    let (mine_pivot, rest_pivot) = std::mem::take(&mut pivot)[c0 - pivot_at..].split_at_mut(c1 - c0);
                    (factor, pivot, factor_at, pivot_at) = (rest, rest_pivot, f1, c1);
                    parts[thread].push(Part { supernodes: first..root + 1, factor: mine, pivot: mine_pivot });
                }
                let failure = parts
                    .par_iter_mut()
                    .zip(schedule.workspaces.par_iter_mut())
                    .map(|(parts, ws)| {
                        ws.updates.clear();
                        ws.pending.clear();
                        dispatch(&structure, parts, ws).err()
                    })
                    .collect::<Vec<_>>()
                    .into_iter()
                    .flatten()
                    .next();
                if let Some(failure) = failure {
                    return Err(failure);
                }
                let schedule: &Schedule = schedule;
                (&schedule.subtrees, &schedule.workspaces)
            }
            None => (&[], &[]),
        };
        // the serial part: every supernode outside the subtrees, in postorder; a subtree's root
        // update joins the stack where the sequential elimination would have made it
        let main = &mut self.main;
        main.updates.clear();
        main.pending.clear();
        let (mut i, mut next) = (0, 0);
        while i < self.postorder.len() {
            let s = self.postorder[i];
            match subtrees.get(next) {
                Some(&(first, root, thread)) if first == s => {
                    let ws = &workspaces[thread];
                    if let Some(&(_, at)) = ws.pending.iter().find(|&&(r, _)| r == root) {
                        let mc = self.pattern_ptr[root + 1] - self.pattern_ptr[root];
                        main.pending.push((root, main.updates.len()));
                        main.updates.extend_from_slice(&ws.updates[at..at + mc * mc]);
                    }
                    i += root + 1 - first;
                    next += 1;
                }
                _ => {
                    let part = Part {
                        supernodes: s..s + 1,
                        factor: &mut self.factor[self.factor_ptr[s]..self.factor_ptr[s + 1]],
                        pivot: &mut self.pivot[self.begin[s]..self.begin[s + 1]],
                    };
                    dispatch(&structure, &mut [part], main)?;
                    i += 1;
                }
            }
        }
        Ok(())
    }

    /// Overwrites `b` with `A⁻¹ b` from the factors of the last [`PatternLu::factorise`]:
    /// per supernode in order, `y₁ ← L11⁻¹ P y₁` and `y₂ −= L21 y₁`, then in reverse order
    /// `y₁ ← U11⁻¹ (y₁ − U12 y₂)` (`y₁` the supernode's equations, `y₂` the rows below it).
    /// Panels from [`DENSE_SOLVE_WIDTH`] columns go through faer's dense kernels with `y₂`
    /// gathered once, narrower ones column by column.
    pub fn solve_in_place(&mut self, b: &mut [f64]) {
        let Self { work: y, below_rows, begin, pattern, pattern_ptr, factor, factor_ptr, pivot, ordering, .. } = self;
        for (yi, &o) in y.iter_mut().zip(ordering.iter()) {
            *yi = b[o];
        }
        let supernodes = begin.len() - 1;
        for s in 0..supernodes {
            let (b0, b1) = (begin[s], begin[s + 1]);
            let width = b1 - b0;
            let rows = &pattern[pattern_ptr[s]..pattern_ptr[s + 1]];
            let m = width + rows.len();
            let panel = &factor[factor_ptr[s]..factor_ptr[s] + m * width];
            for k in 0..width {
                y.swap(b0 + k, b0 + pivot[b0 + k]);
            }
            if width >= DENSE_SOLVE_WIDTH {
                let (l11, l21) = MatRef::from_column_major_slice(panel, m, width).split_at_row(width);
                let head = &mut y[b0..b1];
                solve_unit_lower_triangular_in_place(
                    l11,
                    MatMut::from_column_major_slice_mut(head, width, 1),
                    Par::Seq,
                );
                let below = &mut below_rows[..rows.len()];
                matmul(
                    MatMut::from_column_major_slice_mut(below, rows.len(), 1),
                    Accum::Replace,
                    l21,
                    MatRef::from_column_major_slice(&y[b0..b1], width, 1),
                    1.0,
                    Par::Seq,
                );
                for (&v, &r) in below.iter().zip(rows) {
                    y[r] -= v;
                }
                continue;
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
            let (b0, b1) = (begin[s], begin[s + 1]);
            let width = b1 - b0;
            let rows = &pattern[pattern_ptr[s]..pattern_ptr[s + 1]];
            let m = width + rows.len();
            let (panel, u12) = factor[factor_ptr[s]..factor_ptr[s + 1]].split_at(m * width);
            if width >= DENSE_SOLVE_WIDTH {
                let below = &mut below_rows[..rows.len()];
                for (v, &r) in below.iter_mut().zip(rows) {
                    *v = y[r];
                }
                let head = &mut y[b0..b1];
                let mut head = MatMut::from_column_major_slice_mut(head, width, 1);
                matmul(
                    head.rb_mut(),
                    Accum::Add,
                    MatRef::from_column_major_slice(u12, width, rows.len()),
                    MatRef::from_column_major_slice(&*below, rows.len(), 1),
                    -1.0,
                    Par::Seq,
                );
                let u11 = MatRef::from_column_major_slice(panel, m, width).split_at_row(width).0;
                solve_upper_triangular_in_place(u11, head, Par::Seq);
                continue;
            }
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
        crate::simd_state::clear_upper_state();
        for (&yi, &o) in y.iter().zip(ordering.iter()) {
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

/// [`factor_panel`] by blocks, for wide panels: `P F11 = L11 U11` by faer's recursive LU
/// with partial pivoting on the diagonal block only (the restricted pivoting of the module
/// doc, register-tiled kernels with fused multiply–add), its permutation turned into the
/// sequence of swaps `pivot` that [`PatternLu::solve_in_place`] reads and applied to the rows
/// of `F12`, then `L21 = F21 U11⁻¹` by a triangular solve (`U11ᵀ L21ᵀ = F21ᵀ`). The pivot
/// test of [`factor_panel`] is made on the factors: at its elimination, column `k` of the
/// block holds `U[..k, k]` above the pivot `U[k, k]` and `L[k+1.., k] U[k, k]` below it, with
/// `|L| ≤ 1`, so its largest entry is `max_{i≤k} |U[i, k]|`. `Err(k)` at the first column
/// whose pivot fails it (the factors past it are not used).
#[inline(always)]
fn factor_panel_blocked(
    front: &mut [f64],
    m: usize,
    width: usize,
    pivot: &mut [usize],
    scratch: &mut PanelScratch,
) -> Result<(), usize> {
    let PanelScratch { perm, perm_inv, row_at, position_of, stack } = scratch;
    let stack_bytes =
        lu_in_place_scratch::<usize, f64>(width, width, Par::Seq, Default::default()).unaligned_bytes_required();
    if stack.len() < stack_bytes {
        stack.resize(stack_bytes, MaybeUninit::uninit());
    }
    for v in [&mut *perm, &mut *perm_inv, &mut *row_at, &mut *position_of] {
        v.resize(v.len().max(width), 0);
    }
    {
        let panel = MatMut::from_column_major_slice_mut(&mut front[..m * width], m, width);
        let (mut f11, mut f21) = panel.split_at_row_mut(width);
        lu_in_place(
            f11.rb_mut(),
            &mut perm[..width],
            &mut perm_inv[..width],
            Par::Seq,
            MemStack::new(stack),
            Default::default(),
        );
        for k in 0..width {
            let diagonal = f11[(k, k)].abs();
            let largest = (0..=k).map(|i| f11[(i, k)].abs()).fold(0.0f64, f64::max);
            if diagonal <= PIVOT_TOLERANCE * largest || !diagonal.is_finite() {
                return Err(k);
            }
        }
        solve_lower_triangular_in_place(f11.rb().transpose(), f21.rb_mut().transpose_mut(), Par::Seq);
    }
    // the permutation (perm[i]: the block's original row now at i) as swaps of row k with
    // row pivot[k] ≥ k, applied in order
    for i in 0..width {
        row_at[i] = i;
        position_of[i] = i;
    }
    for k in 0..width {
        let p = position_of[perm[k]];
        pivot[k] = p;
        row_at.swap(k, p);
        position_of[row_at[k]] = k;
        position_of[row_at[p]] = p;
    }
    for column in front[m * width..].chunks_exact_mut(m) {
        for (k, &p) in pivot.iter().enumerate() {
            if p != k {
                column.swap(k, p);
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
        // 12²: every front's update by the loops; 160²: the top fronts by faer's kernels,
        // the widest panels by blocks
        for side in [12, 160] {
            solves_on_a_grid(side);
        }
    }

    /// [`factor_panel_blocked`] is [`factor_panel`] with faer's kernels: on a dense 90 × 90
    /// front with a 56-column panel whose diagonal is weak in some rows (pivoting exercised),
    /// the same swaps, the same factors and swapped rows of `F12` to round-off (the
    /// kernels' fused multiply–adds and order differ), and a zero column of the panel refused
    /// at the same column by both.
    #[test]
    fn blocked_panel_matches_the_column_by_column_panel() {
        let (m, width) = (90usize, 56usize);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut random = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut front: Vec<f64> = (0..m * m).map(|_| random()).collect();
        for i in 0..m {
            front[i * m + i] += if i % 7 == 3 { 0.0 } else { 3.0 };
        }
        let factorise = |front: &[f64], blocked: bool| {
            let mut f = front.to_vec();
            let mut pivot = vec![0; width];
            let result = if blocked {
                factor_panel_blocked(&mut f, m, width, &mut pivot, &mut PanelScratch::default())
            } else {
                factor_panel(&mut f, m, width, &mut pivot)
            };
            (f, pivot, result)
        };
        let (columns, pivot_columns, result_columns) = factorise(&front, false);
        let (blocks, pivot_blocks, result_blocks) = factorise(&front, true);
        assert_eq!((result_columns, result_blocks), (Ok(()), Ok(())));
        let swaps = pivot_columns.iter().enumerate().filter(|(k, p)| *k != **p).count();
        // the panel's columns and the first `width` rows of the others (F22 is untouched)
        let compared = |f: &[f64]| -> Vec<f64> {
            (0..m)
                .flat_map(|j| (0..if j < width { m } else { width }).map(move |i| (i, j)))
                .map(|(i, j)| f[j * m + i])
                .collect()
        };
        let (a, b) = (compared(&columns), compared(&blocks));
        let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let difference = a.iter().zip(&b).fold(0.0f64, |s, (x, y)| s.max((x - y).abs())) / scale;
        println!("{swaps} row swaps; factors differ by {difference:.1e} of the largest entry");
        assert!(swaps > 0, "the test exercises pivoting");
        assert_eq!(pivot_columns, pivot_blocks);
        assert!(difference < 1e-12, "factors differ by {difference:e}");
        for j in 0..m {
            front[j * m + 5] = 0.0;
            front[5 * m + j] = 0.0;
        }
        assert_eq!(factorise(&front, false).2, Err(5));
        assert_eq!(factorise(&front, true).2, Err(5));
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

    /// The tree-parallel elimination ([`Schedule`]) gives the sequential factors bit for bit:
    /// the 80 × 80 grid matrix of [`solves_on_a_grid`] factorised in pools of 1, 2, 3 and 4
    /// threads (the parallel ones split into subtrees), identical factors and pivots, and the
    /// solve exact to round-off; a pivot failure inside a subtree is reported as in one thread.
    #[test]
    fn parallel_subtrees_give_the_sequential_factors_bit_for_bit() {
        let a = grid_matrix(80);
        let factorise_in = |threads: usize, a: &SparseColMat<usize, f64>| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut lu = PatternLu::analyse(a.symbolic()).expect("supernodal analysis");
            let result = pool.install(|| lu.factorise(a.as_ref()));
            (lu, result)
        };
        let (sequential, result) = factorise_in(1, &a);
        result.expect("factorisation");
        assert!(sequential.schedule.is_none());
        for threads in [2, 3, 4] {
            let (mut lu, result) = factorise_in(threads, &a);
            result.expect("factorisation");
            let schedule = lu.schedule.as_ref().expect("the elimination was split among the threads");
            let serial: f64 = (0..lu.postorder.len())
                .filter(|&s| !schedule.subtrees.iter().any(|&(first, root, _)| (first..=root).contains(&s)))
                .map(|s| lu.work_of[s])
                .sum();
            println!(
                "{threads} threads: {} subtrees, serial part {:.1} % of the work",
                schedule.subtrees.len(),
                100.0 * serial / lu.work_of.iter().sum::<f64>()
            );
            assert!(
                lu.factor == sequential.factor && lu.pivot == sequential.pivot,
                "{threads} threads: factors differ"
            );
            let relative = solve_residual(&mut lu, &a);
            assert!(relative < 1e-12, "relative residual {relative:e}");
        }
        // a zero row and column inside a subtree: refused in parallel as in one thread
        let (lu, _) = factorise_in(2, &a);
        let schedule = lu.schedule.as_ref().unwrap();
        let (first, _, _) = schedule.subtrees[0];
        let equation = lu.ordering[lu.begin[first]];
        let zero: Vec<_> = triplets(80)
            .into_iter()
            .map(|t| Triplet::new(t.row, t.col, if t.row == equation || t.col == equation { 0.0 } else { t.val }))
            .collect();
        let singular = SparseColMat::<usize, f64>::try_new_from_triplets(a.nrows(), a.ncols(), &zero).unwrap();
        let (_, one) = factorise_in(1, &singular);
        let (_, two) = factorise_in(2, &singular);
        assert!(one.is_err() && two.is_err(), "{one:?} {two:?}");
    }

    /// The entries of the grid matrix of [`solves_on_a_grid`].
    fn triplets(side: usize) -> Vec<Triplet<usize, usize, f64>> {
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
        entries
    }

    fn grid_matrix(side: usize) -> SparseColMat<usize, f64> {
        SparseColMat::<usize, f64>::try_new_from_triplets(side * side, side * side, &triplets(side)).unwrap()
    }

    fn solves_on_a_grid(side: usize) {
        let n = side * side;
        let entries = triplets(side);
        let a = grid_matrix(side);
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
        let blocked = (0..lu.begin.len() - 1).filter(|&s| lu.begin[s + 1] - lu.begin[s] >= BLOCKED_PANEL).count();
        println!("{side}²: {large} fronts by faer's kernels, largest update {biggest:?}, {blocked} panels by blocks");
        assert_eq!(large > 0, side > 100, "the test covers both kernels");
        assert_eq!(blocked > 0, side > 100, "the test covers both panel factorisations");
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
