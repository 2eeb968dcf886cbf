//! The ranks of a distributed run (issue 26, `docs/distributed.md`) and what each owns, for
//! the first stage: **replicated model, distributed assembly and solve**.
//!
//! Every rank holds the whole model; the equations are split among the ranks in contiguous
//! ranges of (nearly) equal length, as PETSc's parallel matrices own their rows
//! ([`Ownership`]), and an element block is assembled into the global system by the rank
//! that owns the lowest equation it touches (the owner-computes rule: most of a block's
//! rows are then the assembling rank's own, and only the rows beyond a range boundary go
//! through PETSc's stash to their owner). Blocks with no equation (every DOF prescribed)
//! carry only reactions and are assembled by rank 0. This is a deterministic split by
//! equation numbers, not yet the recursive coordinate bisection of the design: with the
//! node-ordered numbering of Loam's meshes and grids it gives every rank a slab of nodes.
//!
//! [`Ranks::world`] exists only in a build with the `mpi` feature, after MPI is
//! initialised; without it there is one rank ([`Ranks::single`]) and the collectives of
//! this module are identities.

use std::ops::Range;

use crate::assembly::{AssemblyPattern, BlockLayout};
use crate::dofs::{DofMap, CONSTRAINED};

/// This process's rank among the processes of the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ranks {
    rank: usize,
    size: usize,
}

impl Default for Ranks {
    fn default() -> Self {
        Self::single()
    }
}

impl Ranks {
    /// One process.
    pub const fn single() -> Self {
        Self { rank: 0, size: 1 }
    }

    /// The ranks of `MPI_COMM_WORLD`, if MPI is initialised (by rsmpi: `mpi::initialize`).
    #[cfg(feature = "mpi")]
    pub fn world() -> Option<Self> {
        use mpi::topology::Communicator;
        if !mpi::environment::is_initialized() || mpi::environment::is_finalized() {
            return None;
        }
        let world = mpi::topology::SimpleCommunicator::world();
        Some(Self { rank: world.rank() as usize, size: world.size() as usize })
    }

    /// This process's rank (0 for one process).
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// Number of ranks.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Whether the run has more than one rank.
    pub fn is_distributed(&self) -> bool {
        self.size > 1
    }

    /// Whether `value` holds on every rank (collective: `MPI_Allreduce` with logical and).
    pub fn all(&self, value: bool) -> bool {
        if !self.is_distributed() {
            return value;
        }
        #[cfg(feature = "mpi")]
        {
            use mpi::collective::{CommunicatorCollectives, SystemOperation};
            let mut all = 0i32;
            mpi::topology::SimpleCommunicator::world().all_reduce_into(
                &i32::from(value),
                &mut all,
                SystemOperation::logical_and(),
            );
            all != 0
        }
        #[cfg(not(feature = "mpi"))]
        unreachable!("more than one rank needs the `mpi` feature (Ranks::world)")
    }
}

/// Ends PETSc (after every solver is dropped), before MPI's owner (rsmpi's `Universe`) ends
/// MPI.
#[cfg(feature = "mpi")]
pub fn finalize_petsc() -> Result<(), String> {
    loam_petsc::finalize().map_err(|e| e.to_string())
}

/// Which equations each rank owns, and which element blocks this rank assembles (module
/// doc).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ownership {
    ranks: Ranks,
    /// Rank `r` owns the equations `starts[r]..starts[r + 1]`.
    starts: Vec<usize>,
}

impl Ownership {
    /// `equations` split in contiguous ranges: rank `r` owns `⌊n/P⌋` of them, one more if
    /// `r < n mod P` (PETSc's own split).
    pub fn new(ranks: Ranks, equations: usize) -> Self {
        let (p, n) = (ranks.size, equations);
        let starts = (0..=p).map(|r| r * (n / p) + r.min(n % p)).collect();
        Self { ranks, starts }
    }

    /// The ranks.
    pub fn ranks(&self) -> Ranks {
        self.ranks
    }

    /// The equations this rank owns.
    pub fn rows(&self) -> Range<usize> {
        self.starts[self.ranks.rank]..self.starts[self.ranks.rank + 1]
    }

    /// The rank that owns equation `e`.
    pub fn owner(&self, e: usize) -> usize {
        self.starts.partition_point(|&s| s <= e) - 1
    }

    /// Whether this rank assembles the block whose free equations are `equations`: the owner
    /// of the lowest of them; rank 0 for a block without one.
    pub fn assembles(&self, equations: impl IntoIterator<Item = usize>) -> bool {
        let owner = equations.into_iter().min().map_or(0, |e| self.owner(e));
        owner == self.ranks.rank
    }
}

/// The rows of the global matrix that this rank owns, in compressed-row form with global
/// column indices: what PETSc preallocates on this rank (the union of every rank's
/// contributions to these rows, which the replicated pattern gives without communication).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OwnedRows {
    /// Which equations each rank owns.
    pub ownership: Ownership,
    /// Start of each owned row in `cols` (`rows().len() + 1` entries, from 0).
    pub row_ptr: Vec<usize>,
    /// Global column indices, sorted within each row.
    pub cols: Vec<usize>,
}

impl OwnedRows {
    /// This rank's rows of the (whole, structurally symmetric) `pattern`: column `c` of the
    /// compressed-column pattern is row `c`.
    pub fn of(ownership: Ownership, pattern: &AssemblyPattern) -> Self {
        let (col_ptr, row_idx) = (pattern.symbolic().col_ptr(), pattern.symbolic().row_idx());
        let rows = ownership.rows();
        let first = col_ptr[rows.start];
        let row_ptr = col_ptr[rows.start..=rows.end].iter().map(|&k| k - first).collect();
        let cols = row_idx[first..col_ptr[rows.end]].to_vec();
        Self { ownership, row_ptr, cols }
    }
}

/// A rank's share of the global system in a distributed run: the element blocks it
/// assembles ([`Ownership::assembles`]), their pattern (all equations, global numbers) and
/// matrix values, and the sum of the residual over the ranks (PETSc's `VECMPI`, gathered
/// back to every rank, so that every rank holds the same residual and the same norms).
#[derive(Debug)]
pub struct RankShare {
    /// Pattern and gather lists of this rank's blocks.
    pub pattern: AssemblyPattern,
    /// Matrix values of this rank's blocks on `pattern`.
    pub values: Vec<f64>,
    /// The owned rows of the whole pattern (the solver's preallocation).
    pub owned_rows: OwnedRows,
    #[cfg(feature = "mpi")]
    residual_sum: Option<loam_petsc::VectorSum>,
}

impl RankShare {
    /// The share of this rank (`ranks`) of the system of `dofs`, the blocks of `layout` and
    /// their whole `pattern`.
    pub fn new(ranks: Ranks, dofs: &DofMap, layout: &BlockLayout, pattern: &AssemblyPattern) -> Self {
        let ownership = Ownership::new(ranks, dofs.num_equations());
        let assembles = |b: usize| {
            let free = layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]]
                .iter()
                .map(|&g| dofs.equation(g))
                .filter(|&e| e != CONSTRAINED);
            ownership.assembles(free)
        };
        let share = AssemblyPattern::of_blocks(dofs, layout, assembles);
        Self {
            values: vec![0.0; share.nnz()],
            pattern: share,
            owned_rows: OwnedRows::of(ownership, pattern),
            #[cfg(feature = "mpi")]
            residual_sum: None,
        }
    }

    /// Replaces this rank's part of a DOF vector (its blocks' gather) by the sum over the
    /// ranks (collective).
    pub fn sum_over_ranks(&mut self, v: &mut [f64]) {
        #[cfg(feature = "mpi")]
        {
            let pattern = &self.pattern;
            let sum = self.residual_sum.get_or_insert_with(|| {
                loam_petsc::VectorSum::new(v.len(), &pattern.reached_dofs())
                    .expect("PETSc creates the residual's sum over the ranks (collective, valid sizes)")
            });
            sum.sum(v).expect("PETSc sums the residual over the ranks (indices within the vector)");
        }
        #[cfg(not(feature = "mpi"))]
        unreachable!("a rank share exists only with more than one rank (the `mpi` feature): {}", v.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ranks(rank: usize, size: usize) -> Ranks {
        Ranks { rank, size }
    }

    /// 10 equations on 3 ranks: 4, 3, 3 in order (PETSc's split); every equation has exactly
    /// one owner, and a block goes to the owner of its lowest equation.
    #[test]
    fn equations_are_split_in_contiguous_ranges_and_blocks_follow_their_lowest_row() {
        let owned: Vec<Range<usize>> = (0..3).map(|r| Ownership::new(ranks(r, 3), 10).rows()).collect();
        assert_eq!(owned, vec![0..4, 4..7, 7..10]);
        for r in 0..3 {
            let o = Ownership::new(ranks(r, 3), 10);
            for e in 0..10 {
                assert_eq!(o.owner(e) == r, owned[r].contains(&e), "equation {e} on rank {r}");
            }
        }
        let block = [8, 3, 5];
        let assemblers: Vec<usize> =
            (0..3).filter(|&r| Ownership::new(ranks(r, 3), 10).assembles(block.iter().copied())).collect();
        assert_eq!(assemblers, vec![0], "lowest equation 3 lies on rank 0");
        let none: Vec<usize> = (0..3).filter(|&r| Ownership::new(ranks(r, 3), 10).assembles([])).collect();
        assert_eq!(none, vec![0]);
        // more ranks than equations: the last ones own nothing
        let o = Ownership::new(ranks(3, 4), 2);
        assert!(o.rows().is_empty());
        assert_eq!(Ownership::new(ranks(0, 4), 2).owner(1), 1);
    }

    /// Three springs on four 1D nodes, node 0 fixed (equations 0, 1, 2 for nodes 1, 2, 3), on
    /// 2 ranks: rank 0 owns equations 0–1 and assembles every spring (their lowest equations
    /// are 0, 0 and 1); rank 1 owns row 2 and assembles nothing, yet preallocates row 2's
    /// whole pattern (columns 1 and 2), to which rank 0 contributes.
    #[test]
    fn a_rank_share_has_its_blocks_and_its_rows_of_the_whole_pattern() {
        let dofs = DofMap::new(1, &[true, false, false, false]);
        let mut layout = BlockLayout::default();
        layout.push([0, 1]);
        layout.push([1, 2]);
        layout.push([2, 3]);
        let whole = AssemblyPattern::new(&dofs, &layout);
        let first = RankShare::new(ranks(0, 2), &dofs, &layout, &whole);
        assert_eq!(first.owned_rows.ownership.rows(), 0..2);
        assert_eq!(first.owned_rows.row_ptr, vec![0, 2, 5]);
        assert_eq!(first.owned_rows.cols, vec![0, 1, 0, 1, 2]);
        assert_eq!(first.pattern.nnz(), whole.nnz(), "rank 0 assembles every spring here");
        let second = RankShare::new(ranks(1, 2), &dofs, &layout, &whole);
        assert_eq!(second.owned_rows.row_ptr, vec![0, 2]);
        assert_eq!(second.owned_rows.cols, vec![1, 2]);
        assert_eq!(second.pattern.nnz(), 0);
        assert!(second.pattern.reached_dofs().is_empty());
    }

    #[test]
    fn one_rank_owns_everything() {
        let o = Ownership::new(Ranks::single(), 5);
        assert_eq!(o.rows(), 0..5);
        assert!(o.assembles([4]));
        assert!(Ranks::single().all(true) && !Ranks::single().all(false));
    }
}
