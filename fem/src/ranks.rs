//! The ranks of a distributed run (issue 26, `docs/distributed.md`) and what each owns:
//! **replicated model, kernels by owner, distributed assembly and solve** (stage 2).
//!
//! Every rank holds the whole model; the equations are split among the ranks in contiguous
//! ranges of (nearly) equal length, as PETSc's parallel matrices own their rows
//! ([`Ownership`]). The element blocks (FEM elements, MPM supports, walls, interface blocks)
//! are partitioned among the ranks by a recursive coordinate bisection of their centroids,
//! weighted by their kernels' cost ([`rcb`], [`BlockOwners`]): each rank evaluates the
//! kernels of its blocks only and adds them to the global system, rows of other ranks through
//! PETSc's stash. The state that a kernel updates (material points' and Gauss points' stress,
//! law history, deformation gradient) is made whole again on every rank after a converged
//! step by [`Ranks::replicate`] (an `MPI_Allgatherv` of the owners' records), so that the
//! model stays replicated. The sums every rank needs (the residual, the reactions, the
//! soil's forces on the structure) are summed over the ranks.
//!
//! **Stage 3** (docs/distributed.md): an MPM domain's material points are held
//! only by the ranks that own their supports and migrate between them
//! (`loam_mpm::mpm_domain`); the grid's nodal sums, the points' counts per support and the
//! queries of the points are then summed over the ranks ([`Ranks::sum_rows_identically`],
//! `Domain::points_distributed`), and no point state is replicated.
//!
//! [`Ranks::world`] exists only in a build with the `mpi` feature, after MPI is
//! initialised; without it there is one rank ([`Ranks::single`]) and the collectives of
//! this module are identities.

use std::ops::Range;

use crate::assembly::{AssemblyPattern, BlockLayout};
use crate::dofs::{DofMap, CONSTRAINED};
use crate::kernel::PointOutput;

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

impl Ranks {
    /// The records that other ranks' owners computed, for every rank to hold them: record `i`
    /// (of `count`, each `record_len` values) is written by the rank `owner(i)` (`pack`), and
    /// one `MPI_Allgatherv` of the owned records (packed in ascending `i`) gives every rank
    /// the others' (collective; every rank must give the same `owner`). Returns the indices of
    /// the records of other ranks, ascending per rank, and their values back to back. The
    /// bytes received and the time go to [`STATS`]. One process: nothing.
    pub fn replicate(
        &self,
        count: usize,
        record_len: usize,
        owner: impl Fn(usize) -> usize,
        pack: impl Fn(usize, &mut [f64]),
    ) -> (Vec<usize>, Vec<f64>) {
        if !self.is_distributed() || record_len == 0 {
            return (Vec::new(), Vec::new());
        }
        let t = std::time::Instant::now();
        let mut mine = Vec::new();
        for i in (0..count).filter(|&i| owner(i) == self.rank) {
            let start = mine.len();
            mine.resize(start + record_len, 0.0);
            pack(i, &mut mine[start..]);
        }
        let all = self.all_gather_varcount(&mine);
        let mut ids = Vec::new();
        let mut data = Vec::new();
        let mut next = vec![0usize; self.size];
        for i in 0..count {
            let r = owner(i);
            if r != self.rank {
                let at = next[r];
                ids.push(i);
                data.extend_from_slice(&all[r][at..at + record_len]);
                next[r] += record_len;
            }
        }
        with_stats(|s| {
            s.exchange_seconds += t.elapsed().as_secs_f64();
            s.exchange_bytes += 8 * data.len() as u64;
            s.exchanges += 1;
        });
        (ids, data)
    }

    /// [`Ranks::replicate`] of integration points' kernel output: point `p` (its `out[p]`
    /// and law history `state[p·sl..(p+1)·sl]`) computed by rank `owner[p]` reaches every rank.
    pub fn replicate_points(&self, owner: &[usize], out: &mut [PointOutput], state: &mut [f64], sl: usize) {
        let len = 27 + sl;
        let (ids, data) = self.replicate(
            owner.len(),
            len,
            |p| owner[p],
            |p, rec| {
                let o = &out[p];
                rec[..9].copy_from_slice(o.deformation_gradient.as_slice());
                rec[9..18].copy_from_slice(o.cauchy.as_slice());
                rec[18..27].copy_from_slice(o.stress.as_slice());
                rec[27..].copy_from_slice(&state[p * sl..(p + 1) * sl]);
            },
        );
        for (&p, rec) in ids.iter().zip(data.chunks_exact(len)) {
            let o = &mut out[p];
            o.deformation_gradient.as_mut_slice().copy_from_slice(&rec[..9]);
            o.cauchy.as_mut_slice().copy_from_slice(&rec[9..18]);
            o.stress.as_mut_slice().copy_from_slice(&rec[18..27]);
            state[p * sl..(p + 1) * sl].copy_from_slice(&rec[27..]);
        }
    }

    /// Sums `v` over the ranks, every rank receiving the same bits (each rank's part gathered
    /// to all, then summed in rank order; collective).
    pub fn sum_identically(&self, v: &mut [f64]) {
        if !self.is_distributed() {
            return;
        }
        let all = self.all_gather_varcount(v);
        v.fill(0.0);
        for part in &all {
            for (x, y) in v.iter_mut().zip(part) {
                *x += y;
            }
        }
    }

    /// Whether `value` holds on some rank (collective).
    pub fn any(&self, value: bool) -> bool {
        !self.all(!value)
    }

    /// Sums the rows of the dense row-major array `values` (`width` values per row) over the
    /// ranks, every rank receiving the same bits ([`Ranks::sum_rows_identically_in`]).
    pub fn sum_rows_identically(&self, values: &mut [f64], width: usize) {
        self.sum_rows_identically_in(&mut DenseRows { values, width });
    }

    /// Sums `rows` over the ranks, every rank receiving the same bits: each rank sends only
    /// the rows it holds a non-zero value in (the nodes its points reach), and every rank
    /// clears the rows it receives and adds them in rank order (collective). One process:
    /// nothing. The rows are read and written where they are kept (the grid's nodal sums:
    /// no copy of the whole array in each step).
    pub fn sum_rows_identically_in(&self, rows: &mut impl SummedRows) {
        if !self.is_distributed() {
            return;
        }
        let width = rows.width();
        let mut row = vec![0.0; width];
        let mut mine = Vec::new();
        for r in 0..rows.rows() {
            rows.read(r, &mut row);
            if row.iter().any(|&x| x != 0.0) {
                mine.push(r as f64);
                mine.extend_from_slice(&row);
            }
        }
        let all = self.exchange(&mine);
        for rec in all.iter().flat_map(|part| part.chunks_exact(width + 1)) {
            rows.clear(rec[0] as usize);
        }
        for rec in all.iter().flat_map(|part| part.chunks_exact(width + 1)) {
            rows.add(rec[0] as usize, &rec[1..]);
        }
    }

    /// [`Ranks::all_gather_varcount`] counted in this rank's [`DistributedStats`]: its time
    /// and the bytes of the other ranks' parts go to `exchange_seconds` and `exchange_bytes`
    /// (the exchanges of distributed points: their counts, nodal sums and migrations).
    pub fn exchange(&self, mine: &[f64]) -> Vec<Vec<f64>> {
        let t = std::time::Instant::now();
        let all = self.all_gather_varcount(mine);
        let received: usize = all.iter().enumerate().filter(|(r, _)| *r != self.rank).map(|(_, p)| p.len()).sum();
        with_stats(|s| {
            s.exchange_seconds += t.elapsed().as_secs_f64();
            s.exchange_bytes += 8 * received as u64;
        });
        all
    }

    /// Every rank's `mine`, in rank order (`MPI_Allgatherv`; collective).
    pub fn all_gather_varcount(&self, mine: &[f64]) -> Vec<Vec<f64>> {
        if !self.is_distributed() {
            return vec![mine.to_vec()];
        }
        #[cfg(feature = "mpi")]
        {
            use mpi::collective::CommunicatorCollectives;
            use mpi::datatype::PartitionMut;
            let world = mpi::topology::SimpleCommunicator::world();
            let count = i32::try_from(mine.len()).expect("a rank's records fit MPI's i32 count");
            let mut counts = vec![0i32; self.size];
            world.all_gather_into(&count, &mut counts[..]);
            let displs: Vec<i32> = counts
                .iter()
                .scan(0i32, |acc, &c| {
                    let d = *acc;
                    *acc += c;
                    Some(d)
                })
                .collect();
            let total = counts.iter().map(|&c| c as usize).sum();
            let mut buf = vec![0.0f64; total];
            {
                let mut partition = PartitionMut::new(&mut buf[..], &counts[..], &displs[..]);
                world.all_gather_varcount_into(mine, &mut partition);
            }
            counts.iter().zip(&displs).map(|(&c, &d)| buf[d as usize..(d + c) as usize].to_vec()).collect()
        }
        #[cfg(not(feature = "mpi"))]
        unreachable!("more than one rank needs the `mpi` feature (Ranks::world): {}", mine.len())
    }
}

/// What a distributed run measured of its communication and its shares, accumulated over the
/// run in this process (written to `summary.json` under `distributed`).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DistributedStats {
    /// Time in this rank's element kernels (s).
    pub kernel_seconds: f64,
    /// Time of PETSc's matrix assembly, `MatSetValues` with the stash and
    /// `MatAssemblyBegin/End` (s).
    pub matrix_assembly_seconds: f64,
    /// Time of the exchange of the points' (and Gauss points') updated state (s); where the
    /// points are distributed, of the migrations, the point counts per support and the nodal
    /// sums of the projection.
    pub exchange_seconds: f64,
    /// Bytes this rank received in those exchanges.
    pub exchange_bytes: u64,
    /// Exchanges made (one per domain with owned kernels and converged step).
    pub exchanges: u64,
    /// Matrix entries this rank added to rows of other ranks (through PETSc's stash), per
    /// matrix assembly, summed over the assemblies.
    pub off_process_entries: u64,
    /// Matrix entries this rank added in all, per assembly, summed over the assemblies.
    pub matrix_entries: u64,
    /// Matrix assemblies.
    pub matrix_assemblies: u64,
    /// Kernel cost (material points and Gauss points) of this rank's blocks and of every
    /// block, summed over the partitions made (their ratio times the ranks is the balance).
    pub own_cost: f64,
    /// See `own_cost`.
    pub total_cost: f64,
    /// Largest rank share of the cost over the mean, of the last partition.
    pub imbalance: f64,
    /// Partitions computed (a new pattern, or a rebalance).
    pub partitions: u64,
    /// Of `partitions`: those made because the points' moves unbalanced the last one
    /// (`Assembler::rebalance`).
    #[serde(default)]
    pub rebalances: u64,
    /// CPU time of the process (user + system, from `/proc/self/stat`) when the statistics
    /// were gathered: the work of a rank, whatever else shares the cores.
    #[serde(default)]
    pub cpu_seconds: f64,
    /// Material points this rank held at the end (domains whose points are distributed:
    /// docs/distributed.md, stage 3; 0 where the model is replicated).
    #[serde(default)]
    pub points_held: u64,
    /// Material points this rank sent to and received from other ranks as they moved into
    /// other ranks' supports, and the migrations (exchanges) made.
    #[serde(default)]
    pub points_sent: u64,
    /// See `points_sent`.
    #[serde(default)]
    pub points_received: u64,
    /// See `points_sent`.
    #[serde(default)]
    pub migrations: u64,
}

/// User + system CPU time of this process (s; 0 where `/proc/self/stat` is not readable).
fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else { return 0.0 };
    // the fields after the command name (which may hold spaces) in parentheses
    let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else { return 0.0 };
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after the name
    let ticks: f64 = [11, 12].iter().filter_map(|&k| fields.get(k)?.parse::<f64>().ok()).sum();
    ticks / 100.0
}

impl DistributedStats {
    /// The statistics of every rank, in rank order (collective: `MPI_Allgatherv`).
    pub fn of_every_rank(ranks: Ranks) -> Vec<Self> {
        let mut mine = Self::default();
        with_stats(|s| mine = *s);
        mine.cpu_seconds = process_cpu_seconds();
        if !ranks.is_distributed() {
            return vec![mine];
        }
        let record = [
            mine.kernel_seconds,
            mine.matrix_assembly_seconds,
            mine.exchange_seconds,
            mine.exchange_bytes as f64,
            mine.exchanges as f64,
            mine.off_process_entries as f64,
            mine.matrix_entries as f64,
            mine.matrix_assemblies as f64,
            mine.own_cost,
            mine.total_cost,
            mine.imbalance,
            mine.partitions as f64,
            mine.cpu_seconds,
            mine.rebalances as f64,
            mine.points_held as f64,
            mine.points_sent as f64,
            mine.points_received as f64,
            mine.migrations as f64,
        ];
        ranks
            .all_gather_varcount(&record)
            .iter()
            .map(|r| Self {
                kernel_seconds: r[0],
                matrix_assembly_seconds: r[1],
                exchange_seconds: r[2],
                exchange_bytes: r[3] as u64,
                exchanges: r[4] as u64,
                off_process_entries: r[5] as u64,
                matrix_entries: r[6] as u64,
                matrix_assemblies: r[7] as u64,
                own_cost: r[8],
                total_cost: r[9],
                imbalance: r[10],
                partitions: r[11] as u64,
                cpu_seconds: r[12],
                rebalances: r[13] as u64,
                points_held: r[14] as u64,
                points_sent: r[15] as u64,
                points_received: r[16] as u64,
                migrations: r[17] as u64,
            })
            .collect()
    }
}

/// This process's [`DistributedStats`].
pub static STATS: std::sync::Mutex<DistributedStats> = std::sync::Mutex::new(DistributedStats {
    kernel_seconds: 0.0,
    matrix_assembly_seconds: 0.0,
    exchange_seconds: 0.0,
    exchange_bytes: 0,
    exchanges: 0,
    off_process_entries: 0,
    matrix_entries: 0,
    matrix_assemblies: 0,
    own_cost: 0.0,
    total_cost: 0.0,
    imbalance: 0.0,
    partitions: 0,
    rebalances: 0,
    cpu_seconds: 0.0,
    points_held: 0,
    points_sent: 0,
    points_received: 0,
    migrations: 0,
});

/// Runs `f` on this process's [`DistributedStats`].
pub fn with_stats(f: impl FnOnce(&mut DistributedStats)) {
    f(&mut STATS.lock().unwrap_or_else(|e| e.into_inner()));
}

/// Which rank evaluates each element block's kernel (and gathers it into the global system):
/// a partition of the blocks ([`rcb`]), or of one domain's part of them.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct BlockOwners {
    ranks: Ranks,
    owner: Vec<u32>,
}

impl BlockOwners {
    /// Blocks with owners `owner` (ranks of `ranks`).
    pub fn new(ranks: Ranks, owner: Vec<u32>) -> Self {
        Self { ranks, owner }
    }

    /// The ranks.
    pub fn ranks(&self) -> Ranks {
        self.ranks
    }

    /// Number of blocks.
    pub fn len(&self) -> usize {
        self.owner.len()
    }

    /// Whether there is no block.
    pub fn is_empty(&self) -> bool {
        self.owner.is_empty()
    }

    /// The rank that evaluates block `b`.
    pub fn owner(&self, b: usize) -> usize {
        self.owner[b] as usize
    }

    /// Whether this rank evaluates block `b`.
    pub fn owns(&self, b: usize) -> bool {
        self.owner[b] as usize == self.ranks.rank
    }

    /// The largest rank's share of the blocks' `costs` over the mean share (1: balanced).
    pub fn imbalance(&self, costs: &[f64]) -> f64 {
        let mut load = vec![0.0; self.ranks.size];
        for (b, c) in costs.iter().enumerate().take(self.owner.len()) {
            load[self.owner[b] as usize] += c;
        }
        let mean = load.iter().sum::<f64>() / load.len() as f64;
        if mean > 0.0 {
            load.iter().fold(0.0f64, |m, &l| m.max(l)) / mean
        } else {
            1.0
        }
    }

    /// The owners of the blocks `range` (a domain's part), numbered from 0.
    pub fn part(&self, range: Range<usize>) -> Self {
        Self { ranks: self.ranks, owner: self.owner[range].to_vec() }
    }
}

/// Recursive coordinate bisection (RCB) of weighted points into `parts` parts: the set is cut
/// across its longest extent (of the points' coordinates) at the weighted median that gives
/// the two halves `⌊parts/2⌋` and `parts − ⌊parts/2⌋` parts in proportion to their weights,
/// and each half is cut again (Berger & Bokhari 1987). Ties in a coordinate are broken by the
/// point's index, so that the partition is a deterministic function of its input (every rank
/// computes the same one). Returns the part of each point. `O(n log n log parts)`.
pub fn rcb(points: &[[f64; 3]], weights: &[f64], parts: usize) -> Vec<u32> {
    let mut part = vec![0u32; points.len()];
    let mut ids: Vec<usize> = (0..points.len()).collect();
    bisect(points, weights, &mut ids, 0, parts.max(1), &mut part);
    part
}

fn bisect(points: &[[f64; 3]], weights: &[f64], ids: &mut [usize], first: usize, parts: usize, part: &mut [u32]) {
    if parts == 1 || ids.is_empty() {
        for &i in ids.iter() {
            part[i] = first as u32;
        }
        return;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &i in ids.iter() {
        for d in 0..3 {
            lo[d] = lo[d].min(points[i][d]);
            hi[d] = hi[d].max(points[i][d]);
        }
    }
    let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])).then(b.cmp(&a))).unwrap_or(0);
    ids.sort_unstable_by(|&a, &b| points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b)));
    let left_parts = parts / 2;
    let total: f64 = ids.iter().map(|&i| weights[i]).sum();
    let target = total * left_parts as f64 / parts as f64;
    let mut sum = 0.0;
    let mut cut = ids.len();
    for (k, &i) in ids.iter().enumerate() {
        // the cut before `k` if that is nearer the target than the cut after it
        if sum + 0.5 * weights[i] > target {
            cut = k;
            break;
        }
        sum += weights[i];
    }
    let (left, right) = ids.split_at_mut(cut);
    bisect(points, weights, left, first, left_parts, part);
    bisect(points, weights, right, first + left_parts, parts - left_parts, part);
}

/// Ends PETSc (after every solver is dropped), before MPI's owner (rsmpi's `Universe`) ends
/// MPI.
#[cfg(feature = "mpi")]
pub fn finalize_petsc() -> Result<(), String> {
    loam_petsc::finalize().map_err(|e| e.to_string())
}

/// Which equations (rows of PETSc's matrix) each rank owns (module doc). PETSc's parallel
/// matrices give each rank a contiguous range of rows, so the equations are renumbered for
/// PETSc: an equation belongs to the lowest rank among the owners of the blocks that touch it
/// (so that a rank's blocks add mostly to its own rows), and its PETSc row is its place in
/// the ranks' order, ascending within a rank.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ownership {
    ranks: Ranks,
    /// Rank `r` owns the PETSc rows `starts[r]..starts[r + 1]`.
    starts: Vec<usize>,
    /// The PETSc row of each equation (empty: the equation's own number).
    row_of: Vec<usize>,
}

impl Ownership {
    /// `equations` split in contiguous ranges, unpermuted: rank `r` owns `⌊n/P⌋` of them,
    /// one more if `r < n mod P` (PETSc's own split).
    pub fn new(ranks: Ranks, equations: usize) -> Self {
        let (p, n) = (ranks.size, equations);
        let starts = (0..=p).map(|r| r * (n / p) + r.min(n % p)).collect();
        Self { ranks, starts, row_of: Vec::new() }
    }

    /// The equations of `dofs` owned by the lowest rank among the `owners` of the blocks of
    /// `layout` that touch them (rank 0 for an equation no block touches).
    pub fn of_blocks(owners: &BlockOwners, dofs: &DofMap, layout: &BlockLayout) -> Self {
        let ranks = owners.ranks();
        let n = dofs.num_equations();
        let mut owner = vec![u32::MAX; n];
        for b in 0..layout.num_blocks() {
            let r = owners.owner(b) as u32;
            for &g in &layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]] {
                let e = dofs.equation(g);
                if e != CONSTRAINED {
                    owner[e] = owner[e].min(r);
                }
            }
        }
        let mut starts = vec![0usize; ranks.size + 1];
        for o in owner.iter_mut() {
            if *o == u32::MAX {
                *o = 0;
            }
            starts[*o as usize + 1] += 1;
        }
        for r in 0..ranks.size {
            starts[r + 1] += starts[r];
        }
        let mut next = starts.clone();
        let row_of = owner
            .iter()
            .map(|&o| {
                next[o as usize] += 1;
                next[o as usize] - 1
            })
            .collect();
        Self { ranks, starts, row_of }
    }

    /// The ranks.
    pub fn ranks(&self) -> Ranks {
        self.ranks
    }

    /// The PETSc rows this rank owns.
    pub fn rows(&self) -> Range<usize> {
        self.starts[self.ranks.rank]..self.starts[self.ranks.rank + 1]
    }

    /// The PETSc row of equation `e`.
    pub fn row(&self, e: usize) -> usize {
        self.row_of.get(e).copied().unwrap_or(e)
    }

    /// The PETSc row of every equation (empty: unpermuted).
    pub fn rows_of_equations(&self) -> &[usize] {
        &self.row_of
    }

    /// The rank that owns equation `e`.
    pub fn owner(&self, e: usize) -> usize {
        let row = self.row(e);
        self.starts.partition_point(|&s| s <= row) - 1
    }

    /// The equations this rank owns, in the order of their PETSc rows.
    pub fn equations(&self) -> Vec<usize> {
        let n = *self.starts.last().unwrap_or(&0);
        let mut eqs: Vec<usize> = (0..n).filter(|&e| self.owner(e) == self.ranks.rank).collect();
        eqs.sort_unstable_by_key(|&e| self.row(e));
        eqs
    }
}

/// Rows of `width` values summed over the ranks by [`Ranks::sum_rows_identically_in`], read
/// and written where they are kept.
pub trait SummedRows {
    /// Number of rows.
    fn rows(&self) -> usize;
    /// Values per row.
    fn width(&self) -> usize;
    /// Row `r`'s values into `out` (`width` of them).
    fn read(&self, r: usize, out: &mut [f64]);
    /// Sets row `r` to zero.
    fn clear(&mut self, r: usize);
    /// Adds `values` to row `r`.
    fn add(&mut self, r: usize, values: &[f64]);
}

/// A dense row-major array as [`SummedRows`].
struct DenseRows<'a> {
    values: &'a mut [f64],
    width: usize,
}

impl SummedRows for DenseRows<'_> {
    fn rows(&self) -> usize {
        self.values.len() / self.width
    }

    fn width(&self) -> usize {
        self.width
    }

    fn read(&self, r: usize, out: &mut [f64]) {
        out.copy_from_slice(&self.values[r * self.width..(r + 1) * self.width]);
    }

    fn clear(&mut self, r: usize) {
        self.values[r * self.width..(r + 1) * self.width].fill(0.0);
    }

    fn add(&mut self, r: usize, values: &[f64]) {
        for (x, y) in self.values[r * self.width..(r + 1) * self.width].iter_mut().zip(values) {
            *x += y;
        }
    }
}

/// The rows of the global matrix that this rank owns, in compressed-row form with global
/// column indices: what PETSc preallocates on this rank (the union of every rank's
/// contributions to these rows, which the replicated block layout gives without
/// communication).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OwnedRows {
    /// Which equations each rank owns.
    pub ownership: Ownership,
    /// Start of each owned row (in PETSc's order) in `cols` (`rows().len() + 1` entries,
    /// from 0).
    pub row_ptr: Vec<usize>,
    /// Global column indices, sorted within each row.
    pub cols: Vec<usize>,
}

impl OwnedRows {
    /// This rank's rows of the matrix of every block of `layout` (every rank's): row `e`
    /// holds the equations of the blocks that hold `e` (the block pattern is structurally
    /// symmetric), in PETSc's numbering ([`Ownership::row`]), sorted within each row. Built
    /// from the layout, so that no rank holds the whole matrix's pattern (at 10⁶ points it
    /// was about a gigabyte on every rank): two passes over the blocks, the first counting
    /// each owned row's entries with repeats, the second writing them; each row is then sorted
    /// and its repeats dropped.
    pub fn of(ownership: Ownership, dofs: &DofMap, layout: &BlockLayout) -> Self {
        let equations = ownership.equations();
        let mut local = vec![usize::MAX; dofs.num_equations()];
        for (i, &e) in equations.iter().enumerate() {
            local[e] = i;
        }
        let free = |b: usize| {
            layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]]
                .iter()
                .map(|&g| dofs.equation(g))
                .filter(|&e| e != CONSTRAINED)
        };
        let mut start = vec![0usize; equations.len() + 1];
        for b in 0..layout.num_blocks() {
            let width = free(b).count();
            for e in free(b) {
                if local[e] != usize::MAX {
                    start[local[e] + 1] += width;
                }
            }
        }
        for i in 0..equations.len() {
            start[i + 1] += start[i];
        }
        let mut repeated = vec![0usize; start[equations.len()]];
        let mut fill = start.clone();
        for b in 0..layout.num_blocks() {
            for e in free(b) {
                if local[e] != usize::MAX {
                    let i = local[e];
                    for c in free(b) {
                        repeated[fill[i]] = ownership.row(c);
                        fill[i] += 1;
                    }
                }
            }
        }
        drop(fill);
        let mut row_ptr = Vec::with_capacity(equations.len() + 1);
        row_ptr.push(0);
        let mut cols = Vec::new();
        for i in 0..equations.len() {
            let row = &mut repeated[start[i]..start[i + 1]];
            row.sort_unstable();
            let first = cols.len();
            cols.extend_from_slice(row);
            let mut kept = first;
            for k in first..cols.len() {
                if k == first || cols[k] != cols[kept - 1] {
                    cols[kept] = cols[k];
                    kept += 1;
                }
            }
            cols.truncate(kept);
            row_ptr.push(cols.len());
        }
        cols.shrink_to_fit();
        Self { ownership, row_ptr, cols }
    }
}

/// A rank's share of the global system in a distributed run: the element blocks it
/// evaluates and assembles ([`BlockOwners`]), their pattern (all equations, global numbers) and
/// matrix values, and the sum of the residual over the ranks (PETSc's `VECMPI`, gathered
/// back to every rank, so that every rank holds the same residual and the same norms).
#[derive(Debug)]
pub struct RankShare {
    /// Pattern and gather lists of this rank's blocks.
    pub pattern: AssemblyPattern,
    /// Matrix values of this rank's blocks on `pattern`.
    pub values: Vec<f64>,
    #[cfg(feature = "mpi")]
    residual_sum: Option<loam_petsc::VectorSum>,
}

impl RankShare {
    /// The share of this rank of the system of `dofs`, the blocks of `layout` with their
    /// `owners`, and the rows of the whole matrix that PETSc keeps on this rank (the solver's
    /// preallocation, handed to it: [`crate::linear_solver::LinearSolver::distribute`]).
    pub fn new(owners: &BlockOwners, dofs: &DofMap, layout: &BlockLayout) -> (Self, OwnedRows) {
        let ownership = Ownership::of_blocks(owners, dofs, layout);
        let share = AssemblyPattern::of_blocks(dofs, layout, |b| owners.owns(b));
        let share = Self {
            values: vec![0.0; share.nnz()],
            pattern: share,
            #[cfg(feature = "mpi")]
            residual_sum: None,
        };
        (share, OwnedRows::of(ownership, dofs, layout))
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

    /// The owned rows built from the layout are the rows of the whole pattern: quad blocks of
    /// a 5 × 4 grid of cells (2 DOFs per node, the nodes of one edge held) on 3 ranks, blocks
    /// dealt round-robin; on each rank, every owned row against the whole matrix's column of
    /// the same equation (the pattern is structurally symmetric), in PETSc's numbering.
    #[test]
    fn owned_rows_from_the_layout_are_the_rows_of_the_whole_pattern() {
        let (nx, ny) = (5, 4);
        let node = |i: usize, j: usize| j * (nx + 1) + i;
        let held: Vec<bool> = (0..(nx + 1) * (ny + 1) * 2).map(|g| (g / 2) % (nx + 1) == 0).collect();
        let dofs = DofMap::new(2, &held);
        let mut layout = BlockLayout::default();
        for j in 0..ny {
            for i in 0..nx {
                let nodes = [node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)];
                layout.push(nodes.iter().flat_map(|&a| [2 * a, 2 * a + 1]));
            }
        }
        let whole = AssemblyPattern::new(&dofs, &layout);
        let (col_ptr, row_idx) = (whole.symbolic().col_ptr(), whole.symbolic().row_idx());
        let owner: Vec<u32> = (0..layout.num_blocks()).map(|b| (b % 3) as u32).collect();
        let mut total = 0;
        for r in 0..3 {
            let owners = BlockOwners::new(ranks(r, 3), owner.clone());
            let rows = OwnedRows::of(Ownership::of_blocks(&owners, &dofs, &layout), &dofs, &layout);
            let o = &rows.ownership;
            for (i, e) in o.equations().into_iter().enumerate() {
                let mut expected: Vec<usize> = row_idx[col_ptr[e]..col_ptr[e + 1]].iter().map(|&c| o.row(c)).collect();
                expected.sort_unstable();
                assert_eq!(
                    &rows.cols[rows.row_ptr[i]..rows.row_ptr[i + 1]],
                    expected.as_slice(),
                    "rank {r}, equation {e}"
                );
            }
            total += rows.cols.len();
        }
        assert_eq!(total, whole.nnz(), "the ranks' rows make the whole matrix");
    }

    /// 10 equations on 3 ranks: 4, 3, 3 in order (PETSc's split); every equation has exactly
    /// one owner.
    #[test]
    fn equations_are_split_in_contiguous_ranges() {
        let owned: Vec<Range<usize>> = (0..3).map(|r| Ownership::new(ranks(r, 3), 10).rows()).collect();
        assert_eq!(owned, vec![0..4, 4..7, 7..10]);
        for r in 0..3 {
            let o = Ownership::new(ranks(r, 3), 10);
            for e in 0..10 {
                assert_eq!(o.owner(e) == r, owned[r].contains(&e), "equation {e} on rank {r}");
            }
        }
        // more ranks than equations: the last ones own nothing
        let o = Ownership::new(ranks(3, 4), 2);
        assert!(o.rows().is_empty());
        assert_eq!(Ownership::new(ranks(0, 4), 2).owner(1), 1);
    }

    /// Three springs on four 1D nodes, node 0 fixed (equations 0, 1, 2 for nodes 1, 2, 3), on
    /// 2 ranks. Springs 0, 1 on rank 1 and spring 2 on rank 0: equation 0 (springs 0, 1)
    /// belongs to rank 1, equations 1 and 2 (spring 2 among theirs) to rank 0, so PETSc's rows
    /// are 0, 1 for equations 1, 2 (rank 0) and 2 for equation 0 (rank 1); each rank
    /// preallocates its rows' whole pattern in PETSc's numbering, and gathers its springs.
    #[test]
    fn a_rank_share_has_its_blocks_and_its_rows_of_the_whole_pattern() {
        let dofs = DofMap::new(1, &[true, false, false, false]);
        let mut layout = BlockLayout::default();
        layout.push([0, 1]);
        layout.push([1, 2]);
        layout.push([2, 3]);
        let (first, first_rows) = RankShare::new(&BlockOwners::new(ranks(0, 2), vec![1, 1, 0]), &dofs, &layout);
        let ownership = &first_rows.ownership;
        assert_eq!((ownership.row(0), ownership.row(1), ownership.row(2)), (2, 0, 1));
        assert_eq!((ownership.owner(0), ownership.owner(1), ownership.owner(2)), (1, 0, 0));
        assert_eq!(ownership.rows(), 0..2);
        assert_eq!(first_rows.row_ptr, vec![0, 3, 5]);
        assert_eq!(first_rows.cols, vec![0, 1, 2, 0, 1]);
        assert_eq!(first.pattern.nnz(), 4, "spring 2: equations 1 and 2");
        let (second, second_rows) = RankShare::new(&BlockOwners::new(ranks(1, 2), vec![1, 1, 0]), &dofs, &layout);
        assert_eq!(second_rows.ownership.rows(), 2..3);
        assert_eq!(second_rows.row_ptr, vec![0, 2]);
        assert_eq!(second_rows.cols, vec![0, 2]);
        assert_eq!(second.pattern.nnz(), 4, "springs 0 and 1: equations 0 and 1");
        assert_eq!(second.pattern.reached_dofs(), vec![0, 1, 2]);
    }

    /// RCB of a 8 × 2 lattice of unit weights into 4 parts: cut across x (the longest extent)
    /// into 4 blocks of 2 × 2, each part's points contiguous in x; the weight is balanced
    /// exactly, and a heavier half moves the cut towards it.
    #[test]
    fn rcb_cuts_across_the_longest_extent_at_the_weighted_median() {
        let points: Vec<[f64; 3]> = (0..16).map(|k| [(k % 8) as f64, (k / 8) as f64, 0.0]).collect();
        let part = rcb(&points, &[1.0; 16], 4);
        for (k, &p) in part.iter().enumerate() {
            assert_eq!(p as usize, (k % 8) / 2, "point {k}");
        }
        // the points with x < 2 weigh 3 each: the first cut (2 parts) falls at x = 2
        let weights: Vec<f64> = points.iter().map(|p| if p[0] < 2.0 { 3.0 } else { 1.0 }).collect();
        let part = rcb(&points, &weights, 2);
        for (k, &p) in part.iter().enumerate() {
            assert_eq!(p, u32::from(points[k][0] >= 2.0), "point {k}");
        }
        assert_eq!(rcb(&points, &[1.0; 16], 1), vec![0; 16]);
        // 3 parts: weights 5, 5, 6 (or as near as whole points allow) and deterministic
        let three = rcb(&points, &[1.0; 16], 3);
        let counts: Vec<usize> = (0..3).map(|r| three.iter().filter(|&&p| p == r).count()).collect();
        assert!(counts.iter().all(|&c| (4..=6).contains(&c)), "{counts:?}");
        assert_eq!(three, rcb(&points, &[1.0; 16], 3));
        // the balance of a partition: after material moved to the first 4 points (weight 5
        // each), the even split by count leaves rank 0 with 20 + 4 of 32 (1.5× the mean)
        let even = BlockOwners::new(ranks(0, 2), rcb(&points, &[1.0; 16], 2));
        assert_eq!(even.imbalance(&[1.0; 16]), 1.0);
        let moved: Vec<f64> = (0..16).map(|k| if k % 8 < 2 { 5.0 } else { 1.0 }).collect();
        assert_eq!(even.imbalance(&moved), 1.5);
        let again = BlockOwners::new(ranks(0, 2), rcb(&points, &moved, 2));
        assert!(again.imbalance(&moved) <= 1.1, "{}", again.imbalance(&moved));
    }

    #[test]
    fn one_rank_owns_everything() {
        let o = Ownership::new(Ranks::single(), 5);
        assert_eq!(o.rows(), 0..5);
        assert!(Ranks::single().all(true) && !Ranks::single().all(false));
    }
}
