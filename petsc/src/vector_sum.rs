//! [`VectorSum`]: `v ← Σ_ranks v_r` for a vector of which every rank holds a part, the sum
//! then on every rank. The parts go into a `VECMPI` with `ADD_VALUES` (entries of other ranks
//! through PETSc's stash), and the assembled vector is gathered to every rank with
//! `VecScatterCreateToAll`: each entry is summed once, by its owner, so every rank receives
//! the same bits.

use std::ptr;

use crate::{check, initialize, lock, petsc_indices, sys, Error};

/// The sum over the ranks of a vector of fixed length (see the module doc).
pub struct VectorSum {
    /// The distributed vector (contiguous ranges of entries per rank).
    parallel: sys::Vec,
    /// The whole vector on this rank.
    whole: sys::Vec,
    gather: sys::VecScatter,
    /// Length of the vector.
    len: usize,
    /// The entries this rank contributes to (PETSc indices).
    indices: Vec<sys::PetscInt>,
    /// Their values of the current sum.
    values: Vec<f64>,
}

// SAFETY: as for `KrylovSolver`: the PETSc objects are owned by this value alone and every
// PETSc call that touches them holds the process-wide lock.
unsafe impl Send for VectorSum {}

impl std::fmt::Debug for VectorSum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VectorSum").field("len", &self.len).field("indices", &self.indices.len()).finish()
    }
}

impl VectorSum {
    /// A sum of vectors of `len` entries, this rank contributing to the entries `indices`
    /// (collective: every rank calls it, with its own indices).
    pub fn new(len: usize, indices: &[usize]) -> Result<Self, Error> {
        initialize()?;
        let mut sum = Self {
            parallel: ptr::null_mut(),
            whole: ptr::null_mut(),
            gather: ptr::null_mut(),
            len,
            indices: petsc_indices(indices, "the entries")?,
            values: vec![0.0; indices.len()],
        };
        let global = petsc_indices(&[len], "the entries")?[0];
        let _guard = lock();
        // SAFETY: PETSc is initialised; the handles are written by the Create calls and owned
        // by `sum` (destroyed by its Drop, also on an early return). -1 is PETSC_DECIDE (PETSc
        // splits the entries in contiguous ranges).
        unsafe {
            check("VecCreateMPI", sys::VecCreateMPI(sys::PETSC_COMM_WORLD, -1, global, &mut sum.parallel))?;
            check("VecScatterCreateToAll", sys::VecScatterCreateToAll(sum.parallel, &mut sum.gather, &mut sum.whole))?;
        }
        Ok(sum)
    }

    /// Replaces `v` (this rank's part: non-zero at most at its indices) by the sum of every
    /// rank's part (collective).
    pub fn sum(&mut self, v: &mut [f64]) -> Result<(), Error> {
        assert_eq!(v.len(), self.len, "vector of the sum's length");
        for (value, &i) in self.values.iter_mut().zip(&self.indices) {
            *value = v[i as usize];
        }
        let _guard = lock();
        // SAFETY: the vectors and the scatter are live and of length `len`; indices and
        // values are alive during VecSetValues, which copies (or stashes) them; the array
        // PETSc lends holds all `len` entries of the sequential vector until the restore.
        unsafe {
            check("VecZeroEntries", sys::VecZeroEntries(self.parallel))?;
            check(
                "VecSetValues",
                sys::VecSetValues(
                    self.parallel,
                    self.indices.len() as sys::PetscInt,
                    self.indices.as_ptr(),
                    self.values.as_ptr(),
                    sys::InsertMode::ADD_VALUES,
                ),
            )?;
            check("VecAssemblyBegin", sys::VecAssemblyBegin(self.parallel))?;
            check("VecAssemblyEnd", sys::VecAssemblyEnd(self.parallel))?;
            let (forward, insert) = (sys::ScatterMode::SCATTER_FORWARD, sys::InsertMode::INSERT_VALUES);
            check("VecScatterBegin", sys::VecScatterBegin(self.gather, self.parallel, self.whole, insert, forward))?;
            check("VecScatterEnd", sys::VecScatterEnd(self.gather, self.parallel, self.whole, insert, forward))?;
            let mut x: *const f64 = ptr::null();
            check("VecGetArrayRead", sys::VecGetArrayRead(self.whole, &mut x))?;
            if self.len > 0 {
                v.copy_from_slice(std::slice::from_raw_parts(x, self.len));
            }
            check("VecRestoreArrayRead", sys::VecRestoreArrayRead(self.whole, &mut x))?;
        }
        Ok(())
    }
}

impl Drop for VectorSum {
    fn drop(&mut self) {
        let _guard = lock();
        // SAFETY: each handle is null or a live object owned by self alone; errors cannot be
        // reported from Drop and are ignored.
        unsafe {
            sys::VecScatterDestroy(&mut self.gather);
            sys::VecDestroy(&mut self.whole);
            sys::VecDestroy(&mut self.parallel);
        }
    }
}
