//! Coulomb friction on slip boundaries: nodal, implicit and consistent.
//!
//! A slip node ([`crate::slip`]) with a friction coefficient `μ > 0` keeps its normal
//! constraint `ũ_n = 0` and gets a tangential force from the boundary. In the node's local
//! frame (axis 0 the outward normal `n`, the others tangents), with `R = f_int − f_ext + M ã`
//! the residual per DOF:
//!
//! - the normal force is the grid's reaction, `N = max(0, −R_n)` (the boundary pushes the
//!   body inwards when `R_n < 0`; a pull gives no friction), `R_n` being the residual at the
//!   constrained normal DOF (Bardenhagen, Brackbill & Sulsky 2000, "The material-point method
//!   for granular materials", CMAME 187, doi:10.1016/S0045-7825(99)00338-2, take the normal
//!   force from the grid's nodal forces the same way);
//! - the slip `g = ũ_t − ũ_{t,n}` is the node's tangential displacement in the step;
//! - **stick**: `g = 0` — the tangential equations are replaced by `k g = 0` (`k` the node's
//!   tangential stiffness, so that the row keeps the system's scale), while the force that
//!   holds the node, `λ_t = R_t`, lies in the cone `|R_t| ≤ μ N`;
//! - **slip**: `R_t + μ N m = 0`, `m = g/|g|` the direction of sliding (the boundary's force
//!   `−μ N m` opposes it).
//!
//! The stick/slip state is an active set updated at every residual evaluation, as in a
//! semi-smooth Newton method (Alart & Curnier 1991, "A mixed formulation for frictional
//! contact problems prone to Newton like solution methods", CMAME 92,
//! doi:10.1016/0045-7825(91)90022-X; Wriggers 2006, *Computational Contact Mechanics*, §10):
//! a sliding node keeps sliding while `g · m > 0`; otherwise it sticks if `|R_t| ≤ μ N`, and
//! starts to slide along `m = −R_t/|R_t|` if not; a node that changes state more than
//! [`MAX_SWITCHES`] times in a step holds for the rest of it (an active set can cycle at a
//! node whose force sits on the cone). The tangent is the exact derivative of
//! the branch taken:
//! `∂(μ N m)/∂ũ = −μ m ⊗ ∂R_n/∂ũ + μ N (I − m ⊗ m)/|g| ∂g/∂ũ` while the direction follows
//! the slip, and `−μ m ⊗ ∂R_n/∂ũ − μ N (I − m ⊗ m)/|R_t| ∂R_t/∂ũ` as the node starts to slide
//! (the second terms vanish in 2D, where `m = ±1`).
//! The row `∂R_n/∂ũ` of the normal equation is assembled in the element blocks but
//! eliminated from the system with the constraint, so it is added, scaled by `−μ m`, to the
//! tangential rows of every block that holds the node before the gather.

use crate::assembly::BlockLayout;

/// Changes between stick and slip that a node may make in one step before it holds.
const MAX_SWITCHES: u32 = 4;

/// Largest element block the friction rewrites (DOFs): hex8 u–p blocks have 32, the supports
/// of the smooth MPM bases 27 in 2D u–p and 108 in 3D u–p.
const MAX_BLOCK_DOFS: usize = crate::mixed_kernel::MAX_MIXED_DOFS;

/// The stick/slip state of a friction node.
#[derive(Debug, Clone, Copy, PartialEq)]
enum State {
    /// The node holds: `g = 0`.
    Stick,
    /// The node slides along the unit tangential direction `m` (local components 1..dim);
    /// `follows_slip` when `m = g/|g|` (else `m` was taken from the holding force as the
    /// node started to slide, and is held fixed in this iteration's tangent).
    Slip { direction: [f64; 2], follows_slip: bool },
}

/// One frictional slip node.
#[derive(Debug, Clone)]
struct FrictionNode {
    /// Global node id.
    node: usize,
    /// Coulomb coefficient μ.
    coefficient: f64,
    /// Local basis `Q` (columns; axis 0 the outward normal), as in [`crate::slip`].
    basis: [[f64; 3]; 3],
    /// Tangential slip `g` in the step (local components 1..dim).
    slip: [f64; 2],
    /// Normal force `N` of the last residual.
    normal_force: f64,
    /// Tangential force `R_t` of the last residual before friction: the force the boundary
    /// exerts on the node at equilibrium (its tangential reaction).
    holding: [f64; 2],
    /// Scale `k` of the stick equations (0 until the first tangent of the step).
    stick_scale: f64,
    state: State,
    /// Changes between stick and slip in this step.
    switches: u32,
}

/// Friction forces and their tangent on the frictional slip nodes of one sparsity pattern
/// (see the module doc).
#[derive(Debug, Clone, Default)]
pub struct NodalFriction {
    dim: usize,
    nodes: Vec<FrictionNode>,
    /// (friction node, matrix offset, block DOFs, local node, first) per block that holds a
    /// node; a node's first occurrence carries its diagonal terms.
    occurrences: Vec<(usize, usize, usize, usize, bool)>,
    /// The block of each occurrence.
    occurrence_blocks: Vec<usize>,
    /// Whether the last assembly was of the equilibrium equations (not the initial
    /// acceleration's mass system), so that friction acts.
    active: bool,
    /// The step `(t_{n+1}, Δt)` of the last assembly, as bits.
    step: Option<(u64, u64)>,
}

impl NodalFriction {
    /// Friction on `nodes` = (node, μ, local basis) over the blocks of `layout`.
    pub fn new(dim: usize, nodes: &[(usize, f64, [[f64; 3]; 3])], layout: &BlockLayout) -> Self {
        let nodes: Vec<FrictionNode> = nodes
            .iter()
            .map(|&(node, coefficient, basis)| FrictionNode {
                node,
                coefficient,
                basis,
                slip: [0.0; 2],
                normal_force: 0.0,
                holding: [0.0; 2],
                stick_scale: 0.0,
                state: State::Stick,
                switches: 0,
            })
            .collect();
        let mut occurrences = Vec::new();
        let mut occurrence_blocks = Vec::new();
        if !nodes.is_empty() {
            let index: std::collections::HashMap<usize, usize> =
                nodes.iter().enumerate().map(|(k, n)| (n.node, k)).collect();
            let mut seen = vec![false; nodes.len()];
            for b in 0..layout.num_blocks() {
                let dofs = &layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]];
                for (a, chunk) in dofs.chunks(dim).enumerate() {
                    if let Some(&k) = index.get(&(chunk[0] / dim)) {
                        let first = !std::mem::replace(&mut seen[k], true);
                        occurrences.push((k, layout.matrix_offset[b], dofs.len(), a, first));
                        occurrence_blocks.push(b);
                    }
                }
            }
        }
        Self { dim, nodes, occurrences, occurrence_blocks, active: false, step: None }
    }

    /// Whether there is any frictional node.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// After an assembly of the step to `time` with length `time_step`: the slips
    /// `g = Qᵀ (u − u_n)` of the iterate and, at the step's first assembly with matrices, the
    /// stick scales from the (rotated) blocks' diagonals. What a step decides depends on the
    /// step alone (not on when the pattern was built), so that a resumed run repeats the
    /// uninterrupted one bit for bit. In a distributed run (`owners` of the blocks given) a
    /// rank holds the matrices of its own blocks only: the diagonals are summed over the ranks.
    pub fn after_assembly(
        &mut self,
        (u, u_committed): (&[f64], &[f64]),
        (time, time_step): (f64, f64),
        matrices: Option<&[f64]>,
        active: bool,
        owners: Option<&crate::ranks::BlockOwners>,
    ) {
        self.active = active;
        let step = Some((time.to_bits(), time_step.to_bits()));
        if self.step != step {
            self.step = step;
            for n in &mut self.nodes {
                n.stick_scale = 0.0;
                n.switches = 0;
            }
        }
        let dim = self.dim;
        for n in &mut self.nodes {
            let d: [f64; 3] =
                std::array::from_fn(
                    |i| if i < dim { u[n.node * dim + i] - u_committed[n.node * dim + i] } else { 0.0 },
                );
            for t in 1..dim {
                n.slip[t - 1] = (0..dim).map(|i| n.basis[i][t] * d[i]).sum();
            }
        }
        let Some(matrices) = matrices else { return };
        if self.nodes.iter().all(|n| n.stick_scale > 0.0) {
            return;
        }
        let mut diagonal = vec![0.0; self.nodes.len()];
        for (&(k, mo, nd, a, _), &b) in self.occurrences.iter().zip(&self.occurrence_blocks) {
            if owners.is_none_or(|o| o.owns(b)) {
                let r = a * dim + 1;
                diagonal[k] += matrices[mo + r * nd + r];
            }
        }
        if let Some(o) = owners {
            o.ranks().sum_identically(&mut diagonal);
        }
        for (n, d) in self.nodes.iter_mut().zip(diagonal) {
            if n.stick_scale == 0.0 {
                n.stick_scale = if d.is_finite() && d > 0.0 { d } else { 1.0 };
            }
        }
    }

    /// Updates the stick/slip states from the residual `R` per DOF (local frames at the slip
    /// nodes, before the constraints) and writes the friction into its tangential rows.
    pub fn apply_to_residual(&mut self, residual: &mut [f64]) {
        if !self.active {
            return;
        }
        let dim = self.dim;
        let tangents = dim - 1;
        for n in &mut self.nodes {
            let base = n.node * dim;
            let normal_force = (-residual[base]).max(0.0);
            let mut holding = [0.0; 2];
            holding[..tangents].copy_from_slice(&residual[base + 1..base + dim]);
            let holding_norm = norm(&holding[..tangents]);
            let slip_norm = norm(&n.slip[..tangents]);
            let keeps_sliding = match n.state {
                State::Slip { direction, .. } => dot(&direction[..tangents], &n.slip[..tangents]) > 0.0,
                State::Stick => false,
            };
            let state = if keeps_sliding {
                State::Slip { direction: n.slip.map(|g| g / slip_norm), follows_slip: true }
            } else if holding_norm <= n.coefficient * normal_force {
                State::Stick
            } else {
                State::Slip { direction: holding.map(|r| -r / holding_norm), follows_slip: false }
            };
            if (state == State::Stick) != (n.state == State::Stick) {
                n.switches += 1;
            }
            // an active set can cycle at a node whose force sits on the cone: after
            // MAX_SWITCHES changes in a step the node holds (the dissipative choice)
            n.state = if n.switches > MAX_SWITCHES { State::Stick } else { state };
            n.normal_force = normal_force;
            n.holding = holding;
            match n.state {
                State::Stick => {
                    for t in 0..tangents {
                        residual[base + 1 + t] = n.stick_scale * n.slip[t];
                    }
                }
                State::Slip { direction: m, .. } => {
                    for t in 0..tangents {
                        residual[base + 1 + t] += n.coefficient * normal_force * m[t];
                    }
                }
            }
        }
    }

    /// Writes the friction's tangent into the (rotated) element matrices before the gather:
    /// stick rows replaced by `k` on the diagonal, slip rows `−μ m ⊗ (normal row)` (where
    /// `N > 0`) and, in 3D, `μ N (I − m ⊗ m)/|g|`. Call once per assembly, after
    /// [`NodalFriction::apply_to_residual`].
    pub fn apply_to_matrices(&self, matrices: &mut [f64]) {
        if !self.active {
            return;
        }
        let dim = self.dim;
        let tangents = dim - 1;
        for &(k, mo, nd, a, is_first) in &self.occurrences {
            let n = &self.nodes[k];
            assert!(nd <= MAX_BLOCK_DOFS, "element block of {nd} DOFs beyond the friction's {MAX_BLOCK_DOFS}");
            let block = &mut matrices[mo..mo + nd * nd];
            match n.state {
                State::Stick => {
                    for t in 1..dim {
                        let row = a * dim + t;
                        block[row * nd..(row + 1) * nd].fill(0.0);
                        if is_first {
                            block[row * nd + row] = n.stick_scale;
                        }
                    }
                }
                State::Slip { direction: m, follows_slip } => {
                    // the natural rows n, t₁, t₂ before this block's rows change
                    let mut rows = [[0.0; MAX_BLOCK_DOFS]; 3];
                    for (l, row) in rows.iter_mut().enumerate().take(dim) {
                        let r = a * dim + l;
                        row[..nd].copy_from_slice(&block[r * nd..(r + 1) * nd]);
                    }
                    let holding_norm = norm(&n.holding[..tangents]);
                    // d(μ N m)/dR_t when m = −R_t/|R_t| (3D; 0 in 2D): −μ N (I − m ⊗ m)/|R_t|
                    let turning = if follows_slip || holding_norm == 0.0 {
                        0.0
                    } else {
                        n.coefficient * n.normal_force / holding_norm
                    };
                    for t in 0..tangents {
                        let row = a * dim + 1 + t;
                        let along_normal = if n.normal_force > 0.0 { -n.coefficient * m[t] } else { 0.0 };
                        for c in 0..nd {
                            let mut d = along_normal * rows[0][c];
                            if turning != 0.0 {
                                for s in 0..tangents {
                                    let identity = if t == s { 1.0 } else { 0.0 };
                                    d -= turning * (identity - m[t] * m[s]) * rows[1 + s][c];
                                }
                            }
                            block[row * nd + c] += d;
                        }
                    }
                    let slip_norm = norm(&n.slip[..tangents]);
                    if is_first && follows_slip && tangents > 1 && slip_norm > 0.0 {
                        let factor = n.coefficient * n.normal_force / slip_norm;
                        for t in 0..tangents {
                            for s in 0..tangents {
                                let identity = if t == s { 1.0 } else { 0.0 };
                                let (row, col) = (a * dim + 1 + t, a * dim + 1 + s);
                                block[row * nd + col] += factor * (identity - m[t] * m[s]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Writes the tangential reactions of the last residual (the friction forces at
    /// equilibrium) into `out`, per DOF in the local frames.
    pub fn write_reactions(&self, out: &mut [f64]) {
        let dim = self.dim;
        for n in &self.nodes {
            out[n.node * dim + 1..n.node * dim + dim].copy_from_slice(&n.holding[..dim - 1]);
        }
    }

    /// Number of frictional nodes that stick and that slide in the last residual.
    pub fn counts(&self) -> (usize, usize) {
        let stick = self.nodes.iter().filter(|n| n.state == State::Stick).count();
        (stick, self.nodes.len() - stick)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}
