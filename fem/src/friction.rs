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
//! - the tangential reaction `R_t` (the force with which the boundary holds the node) must lie
//!   in the disc `|R_t| ≤ μ N`, `g = 0` inside it, and `R_t = −μ N g/|g|` while the node
//!   slides.
//!
//! These conditions are one equation per tangential DOF, Alart & Curnier's (1991, "A mixed
//! formulation for frictional contact problems prone to Newton like solution methods",
//! CMAME 92, doi:10.1016/0045-7825(91)90022-X; Wriggers 2006, *Computational Contact
//! Mechanics*, §10.4):
//!
//! `Φ = R_t − P_{μN}(q) = 0`,  `q = R_t − r g`,
//!
//! `P_{μN}` the projection onto the disc of radius `μ N` and `r > 0` an augmentation of the
//! system's scale (the node's tangential diagonal stiffness at the step's first tangent,
//! which does not change the solution). Inside the disc (**stick**, `|q| ≤ μ N`) the equation
//! is `r g = 0`; outside (**slip**) it is `R_t + μ N m = 0` with `m = −q/|q|`, the direction
//! of sliding at the solution. `Φ` is continuous across the stick–slip switch and
//! semi-smooth, so Newton's method with this active set converges locally fast where the
//! earlier form (the direction taken from the slip `g/|g|`, or from `−R_t/|R_t|` as a node
//! started to slide, with a jump in the residual when a node stopped) stalled in 3D: there the
//! derivative `μ N/|g|` of a direction grows without bound at a small slip, while here it is
//! `μ N/|q| < 1` (Wriggers 2006, §10.4). The tangent is the exact derivative of the branch:
//!
//! `∂Φ/∂ũ = ∂R_t/∂ũ − μ m ⊗ ∂R_n/∂ũ − (μ N/|q|) (I − m ⊗ m) (∂R_t/∂ũ − r ∂g/∂ũ)` (slip, the
//! `I − m ⊗ m` terms vanish in 2D, where `m = ±1`), `r ∂g/∂ũ` (stick).
//!
//! The rows `∂R/∂ũ` are assembled in the element blocks (the normal row is eliminated from
//! the system with the constraint), so the slip terms are added to the tangential rows of
//! every block that holds the node before the gather. The active set is re-decided from the
//! iterate at every residual; nothing forces a node's state (an earlier form held a node that
//! switched more than four times in a step, which could leave it stuck where Coulomb's law
//! has it slide): a node whose state cycles fails the step's Newton iteration, and the step is
//! cut like any other that does not converge.
//!
//! A slip node that also carries a Dirichlet condition (a base node on a symmetry plane in 3D,
//! which holds one tangential component) is not rotated ([`crate::slip`]); where its normal
//! lies along a global axis, that component is its normal constraint and friction acts on the
//! tangential components that no condition holds, in the global frame ([`FrictionFrame`]).
//! The held components' reactions are the plane's, not the base's: they are neither in the
//! disc nor rewritten. Before, such a node kept no friction: a slab one cell thick between
//! symmetry planes slid on a frictionless base.

use crate::assembly::BlockLayout;

/// Largest element block the friction rewrites (DOFs): hex8 u–p blocks have 32, the supports
/// of the smooth MPM bases 27 in 2D u–p and 108 in 3D u–p.
const MAX_BLOCK_DOFS: usize = crate::mixed_kernel::MAX_MIXED_DOFS;

/// The stick/slip state of a friction node.
#[derive(Debug, Clone, Copy, PartialEq)]
enum State {
    /// The node holds: `|q| ≤ μ N`, equation `r g = 0`.
    Stick,
    /// The node slides along the unit tangential direction `m = −q/|q|` (local components
    /// 1..dim); `contraction` is `μ N/|q| < 1`, the factor of the direction's derivative.
    Slip { direction: [f64; 2], contraction: f64 },
}

/// Where a frictional node's local axes are among its DOFs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionFrame {
    /// Local basis `Q` (columns; axis 0 the outward normal, then the free tangents).
    pub basis: [[f64; 3]; 3],
    /// The node's DOF (`0..dim`) that carries local axis `k`.
    pub component: [usize; 3],
    /// Sign of the outward normal along the DOF `component[0]` (the residual there is `±R_n`).
    pub normal_sign: f64,
    /// Free tangential axes (`1..=tangents`): `dim − 1`, fewer where a Dirichlet condition
    /// holds a tangential component.
    pub tangents: usize,
}

impl FrictionFrame {
    /// The frame of a rotated slip node ([`crate::slip::SlipRotations`]): its DOFs are the
    /// local components.
    pub fn rotated(dim: usize, basis: [[f64; 3]; 3]) -> Self {
        Self { basis, component: [0, 1, 2], normal_sign: 1.0, tangents: dim - 1 }
    }

    /// The frame of an unrotated node whose outward normal is `sign · e_axis` and whose
    /// components `free` no Dirichlet condition holds (global frame; see the module doc).
    pub fn along_axis(axis: usize, sign: f64, free: &[usize]) -> Self {
        debug_assert!(!free.is_empty() && free.len() <= 2 && !free.contains(&axis));
        let mut basis = [[0.0; 3]; 3];
        let mut component = [axis, 0, 0];
        basis[axis][0] = sign;
        for (t, &c) in free.iter().enumerate() {
            basis[c][1 + t] = 1.0;
            component[1 + t] = c;
        }
        Self { basis, component, normal_sign: sign, tangents: free.len() }
    }
}

/// One frictional slip node.
#[derive(Debug, Clone)]
struct FrictionNode {
    /// Global node id.
    node: usize,
    /// Coulomb coefficient μ.
    coefficient: f64,
    /// Its local axes.
    frame: FrictionFrame,
    /// Tangential slip `g` in the step (local components 1..dim).
    slip: [f64; 2],
    /// Normal force `N` of the last residual.
    normal_force: f64,
    /// Tangential force `R_t` of the last residual before friction: the force the boundary
    /// exerts on the node at equilibrium (its tangential reaction).
    holding: [f64; 2],
    /// Augmentation `r` (the scale of the stick equations `r g = 0`; 0 until the first tangent
    /// of the step).
    stick_scale: f64,
    state: State,
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
    /// Friction on `nodes` = (node, μ, frame) over the blocks of `layout`.
    pub fn new(dim: usize, nodes: &[(usize, f64, FrictionFrame)], layout: &BlockLayout) -> Self {
        let nodes: Vec<FrictionNode> = nodes
            .iter()
            .map(|&(node, coefficient, frame)| FrictionNode {
                node,
                coefficient,
                frame,
                slip: [0.0; 2],
                normal_force: 0.0,
                holding: [0.0; 2],
                stick_scale: 0.0,
                state: State::Stick,
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
            }
        }
        let dim = self.dim;
        for n in &mut self.nodes {
            let d: [f64; 3] =
                std::array::from_fn(
                    |i| if i < dim { u[n.node * dim + i] - u_committed[n.node * dim + i] } else { 0.0 },
                );
            for t in 1..=n.frame.tangents {
                n.slip[t - 1] = (0..dim).map(|i| n.frame.basis[i][t] * d[i]).sum();
            }
        }
        let Some(matrices) = matrices else { return };
        if self.nodes.iter().all(|n| n.stick_scale > 0.0) {
            return;
        }
        let mut diagonal = vec![0.0; self.nodes.len()];
        for (&(k, mo, nd, a, _), &b) in self.occurrences.iter().zip(&self.occurrence_blocks) {
            if owners.is_none_or(|o| o.owns(b)) {
                let r = a * dim + self.nodes[k].frame.component[1];
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
        for n in &mut self.nodes {
            let FrictionFrame { component, normal_sign, tangents, .. } = n.frame;
            let base = n.node * dim;
            let normal_force = (-normal_sign * residual[base + component[0]]).max(0.0);
            let mut holding = [0.0; 2];
            for t in 0..tangents {
                holding[t] = residual[base + component[1 + t]];
            }
            // Alart–Curnier's augmented force q = R_t − r g and its projection on the disc
            let mut augmented = [0.0; 2];
            for t in 0..tangents {
                augmented[t] = holding[t] - n.stick_scale * n.slip[t];
            }
            let augmented_norm = norm(&augmented[..tangents]);
            let limit = n.coefficient * normal_force;
            n.state = if augmented_norm <= limit {
                State::Stick
            } else {
                State::Slip { direction: augmented.map(|q| -q / augmented_norm), contraction: limit / augmented_norm }
            };
            n.normal_force = normal_force;
            n.holding = holding;
            match n.state {
                State::Stick => {
                    for t in 0..tangents {
                        residual[base + component[1 + t]] = n.stick_scale * n.slip[t];
                    }
                }
                State::Slip { direction: m, .. } => {
                    for t in 0..tangents {
                        residual[base + component[1 + t]] += n.coefficient * normal_force * m[t];
                    }
                }
            }
        }
    }

    /// Writes the friction's tangent into the (rotated) element matrices before the gather:
    /// stick rows replaced by `r` on the diagonal, slip rows `−μ m ⊗ (normal row)` (where
    /// `N > 0`) and, in 3D, `−(μ N/|q|) (I − m ⊗ m) (tangential rows − r I)` (module doc). Call once per assembly, after
    /// [`NodalFriction::apply_to_residual`].
    pub fn apply_to_matrices(&self, matrices: &mut [f64]) {
        if !self.active {
            return;
        }
        let dim = self.dim;
        for &(k, mo, nd, a, is_first) in &self.occurrences {
            let n = &self.nodes[k];
            let FrictionFrame { component, normal_sign, tangents, .. } = n.frame;
            assert!(nd <= MAX_BLOCK_DOFS, "element block of {nd} DOFs beyond the friction's {MAX_BLOCK_DOFS}");
            let block = &mut matrices[mo..mo + nd * nd];
            match n.state {
                State::Stick => {
                    for t in 1..=tangents {
                        let row = a * dim + component[t];
                        block[row * nd..(row + 1) * nd].fill(0.0);
                        if is_first {
                            block[row * nd + row] = n.stick_scale;
                        }
                    }
                }
                State::Slip { direction: m, contraction } => {
                    // the natural rows n, t₁, t₂ before this block's rows change (the normal's
                    // as `∂R_n`)
                    let mut rows = [[0.0; MAX_BLOCK_DOFS]; 3];
                    for (l, row) in rows.iter_mut().enumerate().take(1 + tangents) {
                        let r = a * dim + component[l];
                        row[..nd].copy_from_slice(&block[r * nd..(r + 1) * nd]);
                    }
                    rows[0][..nd].iter_mut().for_each(|v| *v *= normal_sign);
                    // ∂Φ = ∂R_t − μ m ⊗ ∂R_n − (μN/|q|)(I − m ⊗ m)(∂R_t − r ∂g); with one
                    // free tangent (2D, or a held one) I − m ⊗ m = 0
                    let along_normal = if n.normal_force > 0.0 { n.coefficient } else { 0.0 };
                    let turning = if tangents > 1 { contraction } else { 0.0 };
                    for t in 0..tangents {
                        let row = a * dim + component[1 + t];
                        for c in 0..nd {
                            let mut d = -along_normal * m[t] * rows[0][c];
                            for s in 0..tangents {
                                let identity = if t == s { 1.0 } else { 0.0 };
                                d -= turning * (identity - m[t] * m[s]) * rows[1 + s][c];
                            }
                            block[row * nd + c] += d;
                        }
                    }
                    if is_first && turning != 0.0 {
                        let factor = turning * n.stick_scale;
                        for t in 0..tangents {
                            for s in 0..tangents {
                                let identity = if t == s { 1.0 } else { 0.0 };
                                let (row, col) = (a * dim + component[1 + t], a * dim + component[1 + s]);
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
            for t in 0..n.frame.tangents {
                out[n.node * dim + n.frame.component[1 + t]] = n.holding[t];
            }
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
