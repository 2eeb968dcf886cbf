//! Frictionless slip boundaries of any inclination by local rotation of nodal DOFs.
//!
//! A slip node with unit normal `n` gets a local basis `Q = [n, t₁, t₂]` (columns in global
//! components). Element blocks that touch it are rotated before the gather,
//! `K̃ = Qᵀ K Q` on its rows and columns and `r̃ = Qᵀ r` (the standard treatment of skew
//! supports, e.g. Zienkiewicz & Taylor, *The Finite Element Method*, Vol. 1, §9.13), its
//! normal DOF becomes a constraint (`ũ_n = 0`: no motion across the boundary) and its
//! tangential DOFs stay free. Solutions are rotated back, `δu = Q δũ`. A node that also has
//! a Dirichlet condition keeps only the Dirichlet condition.
//!
//! The same rotation without the constraint serves the frictionless (slip) interface between
//! soil and structure: both nodes of an interface pair get the local frame of the interface
//! normal, and their normal DOFs share one equation (a [`crate::dofs::DofTie`]).

use std::collections::HashMap;

use crate::assembly::BlockLayout;

/// A slip condition: node and unit normal of the boundary, with a Coulomb friction
/// coefficient ([`crate::friction`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slip {
    /// Global node id.
    pub node: usize,
    /// Boundary normal (normalised when the rotations are built); outward (pointing out of
    /// the body) where `friction > 0`, which takes the normal force's sign from it.
    pub normal: [f64; 3],
    /// Coulomb coefficient μ of the boundary (0: frictionless).
    pub friction: f64,
}

/// A slip condition at a node that also carries a Dirichlet condition (which
/// [`SlipRotations::new`] leaves out of the rotations), whose normal lies along a global axis
/// whose component no Dirichlet condition fixes: the node stays unrotated and that component
/// is its normal constraint. Without it the corner node between a wall (`u_x` prescribed) and
/// a slip base (normal `y`) was free across the base: an undamped vertical mode of one node
/// (docs/granular_scaling.md). An inclined normal at such a node is left free, as before.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisSlip {
    /// Global node id.
    pub node: usize,
    /// The global axis along the normal.
    pub axis: usize,
    /// Sign of the (outward, where frictional) normal along the axis.
    pub sign: f64,
    /// Coulomb coefficient μ (0: frictionless).
    pub friction: f64,
    /// The node's components that neither a Dirichlet condition nor an axis slip holds: the
    /// directions in which it slides, with friction where `friction > 0`.
    pub free: Vec<usize>,
}

impl AxisSlip {
    /// The constrained global DOF.
    pub fn dof(&self, dim: usize) -> usize {
        self.node * dim + self.axis
    }

    /// The friction's frame at the node, where it has friction and a free component
    /// ([`crate::friction`]: a base node on a symmetry plane slides along the plane).
    pub fn friction_frame(&self) -> Option<crate::friction::FrictionFrame> {
        (self.friction > 0.0 && !self.free.is_empty())
            .then(|| crate::friction::FrictionFrame::along_axis(self.axis, self.sign, &self.free))
    }
}

/// The [`AxisSlip`]s of `slips` at nodes with a Dirichlet component (`is_dirichlet` of a
/// global DOF), one per node and axis.
pub fn axis_slips(dim: usize, slips: &[Slip], is_dirichlet: impl Fn(usize) -> bool) -> Vec<AxisSlip> {
    let mut out: Vec<AxisSlip> = Vec::new();
    for s in slips {
        let node_dofs = s.node * dim..(s.node + 1) * dim;
        if !node_dofs.clone().any(&is_dirichlet) {
            continue;
        }
        let len = s.normal[..dim].iter().map(|v| v * v).sum::<f64>().sqrt();
        for (i, d) in node_dofs.enumerate() {
            if len > 0.0 && (s.normal[i].abs() / len - 1.0).abs() < 1e-9 && !is_dirichlet(d) {
                out.retain(|a| !(a.node == s.node && a.axis == i));
                let sign = s.normal[i].signum();
                out.push(AxisSlip { node: s.node, axis: i, sign, friction: s.friction, free: Vec::new() });
            }
        }
    }
    let held =
        |node: usize, c: usize| is_dirichlet(node * dim + c) || out.iter().any(|a| a.node == node && a.axis == c);
    let free: Vec<Vec<usize>> = out.iter().map(|a| (0..dim).filter(|&c| !held(a.node, c)).collect()).collect();
    for (a, f) in out.iter_mut().zip(free) {
        a.free = f;
    }
    out
}

/// Local basis `Q` (columns `q[.][k]`, axis 0 the normal) for a normal in `dim` dimensions.
pub fn local_basis(normal: [f64; 3], dim: usize) -> [[f64; 3]; 3] {
    let len = normal[..dim].iter().map(|v| v * v).sum::<f64>().sqrt();
    let n = normal.map(|v| v / len);
    let mut q = [[0.0; 3]; 3];
    if dim == 2 {
        let t = [-n[1], n[0]];
        for i in 0..2 {
            q[i][0] = n[i];
            q[i][1] = t[i];
        }
        return q;
    }
    // t1 ⟂ n from the axis least aligned with n, t2 = n × t1
    let a = if n[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
    let mut t1 = [a[0] - d * n[0], a[1] - d * n[1], a[2] - d * n[2]];
    let l = (t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]).sqrt();
    t1 = t1.map(|v| v / l);
    let t2 = [n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]];
    for i in 0..3 {
        q[i] = [n[i], t1[i], t2[i]];
    }
    q
}

/// The rotations of one sparsity pattern.
#[derive(Debug, Clone, Default)]
pub struct SlipRotations {
    dim: usize,
    basis: HashMap<usize, [[f64; 3]; 3]>,
    /// Nodes whose normal DOF is a constraint (slip boundaries), ascending.
    constrained: Vec<usize>,
    /// Friction coefficient of the constrained nodes that have one.
    friction: HashMap<usize, f64>,
    /// (matrix offset, vector offset, block DOFs, local node, global node) per occurrence.
    occurrences: Vec<(usize, usize, usize, usize, usize)>,
}

impl SlipRotations {
    /// Rotations for `slips` (normal DOF constrained) and `frames` (local frames only) on
    /// the blocks of `layout`, skipping nodes for which `has_dirichlet` holds.
    pub fn new(
        dim: usize,
        slips: &[Slip],
        frames: &[Slip],
        layout: &BlockLayout,
        has_dirichlet: impl Fn(usize) -> bool,
    ) -> Self {
        let mut basis: HashMap<usize, [[f64; 3]; 3]> = HashMap::new();
        let mut constrained = Vec::new();
        let mut friction = HashMap::new();
        for s in slips.iter().filter(|s| !has_dirichlet(s.node)) {
            basis.insert(s.node, local_basis(s.normal, dim));
            constrained.push(s.node);
            if s.friction > 0.0 {
                friction.insert(s.node, s.friction);
            } else {
                friction.remove(&s.node);
            }
        }
        for s in frames.iter().filter(|s| !has_dirichlet(s.node)) {
            basis.entry(s.node).or_insert_with(|| local_basis(s.normal, dim));
        }
        constrained.sort_unstable();
        constrained.dedup();
        let mut occurrences = Vec::new();
        if !basis.is_empty() {
            for b in 0..layout.num_blocks() {
                let dofs = &layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]];
                for (a, chunk) in dofs.chunks(dim).enumerate() {
                    let node = chunk[0] / dim;
                    if basis.contains_key(&node) {
                        occurrences.push((layout.matrix_offset[b], layout.dof_ptr[b], dofs.len(), a, node));
                    }
                }
            }
        }
        Self { dim, basis, constrained, friction, occurrences }
    }

    /// The frictional slip nodes: (node, μ, frame), ascending by node.
    pub fn frictional_nodes(&self) -> Vec<(usize, f64, crate::friction::FrictionFrame)> {
        let frame = |n: usize| crate::friction::FrictionFrame::rotated(self.dim, self.basis[&n]);
        let mut out: Vec<_> = self.friction.iter().map(|(&n, &mu)| (n, mu, frame(n))).collect();
        out.sort_unstable_by_key(|e| e.0);
        out
    }

    /// Global DOFs that become constraints: the normal DOF of every slip node.
    pub fn normal_dofs(&self) -> impl Iterator<Item = usize> + '_ {
        self.constrained.iter().map(|&n| n * self.dim)
    }

    /// Whether `node` has a local frame.
    pub fn is_rotated(&self, node: usize) -> bool {
        self.basis.contains_key(&node)
    }

    /// Rotates element matrices and vectors to the local frames of slip nodes.
    pub fn rotate_blocks(&self, matrices: &mut [f64], vectors: &mut [f64]) {
        let dim = self.dim;
        for &(mo, vo, nd, a, node) in &self.occurrences {
            let q = &self.basis[&node];
            let k = &mut matrices[mo..mo + nd * nd];
            for c in 0..nd {
                let mut col = [0.0; 3];
                for l in 0..dim {
                    col[l] = (0..dim).map(|i| q[i][l] * k[(a * dim + i) * nd + c]).sum();
                }
                for l in 0..dim {
                    k[(a * dim + l) * nd + c] = col[l];
                }
            }
            for r in 0..nd {
                let row = &mut k[r * nd..(r + 1) * nd];
                let mut v = [0.0; 3];
                for l in 0..dim {
                    v[l] = (0..dim).map(|i| row[a * dim + i] * q[i][l]).sum();
                }
                row[a * dim..a * dim + dim].copy_from_slice(&v[..dim]);
            }
            let f = &mut vectors[vo + a * dim..vo + a * dim + dim];
            let mut v = [0.0; 3];
            for l in 0..dim {
                v[l] = (0..dim).map(|i| q[i][l] * f[i]).sum();
            }
            f.copy_from_slice(&v[..dim]);
        }
    }

    /// `v ← Qᵀ v` on the slip nodes of a full DOF vector (global to local).
    pub fn to_local(&self, full: &mut [f64]) {
        self.transform(full, true);
    }

    /// `v ← Q v` on the slip nodes of a full DOF vector (local to global).
    pub fn to_global(&self, full: &mut [f64]) {
        self.transform(full, false);
    }

    fn transform(&self, full: &mut [f64], transpose: bool) {
        let dim = self.dim;
        for (&node, q) in &self.basis {
            let x = &mut full[node * dim..node * dim + dim];
            let mut y = [0.0; 3];
            for l in 0..dim {
                y[l] = (0..dim).map(|i| if transpose { q[i][l] * x[i] } else { q[l][i] * x[i] }).sum();
            }
            x.copy_from_slice(&y[..dim]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dirichlet_corner_keeps_its_axis_slip_component() {
        let slip = |node, normal| Slip { node, normal, friction: 0.36 };
        // 2D: node 0 the wall-base corner (u_x held by the wall, base normal −y), node 1 a
        // base node without Dirichlet (rotated, not listed), node 2 a Dirichlet node on an
        // inclined boundary (left free), node 3 fully held (nothing to add)
        let slips =
            [slip(0, [0.0, -2.0, 0.0]), slip(1, [0.0, -1.0, 0.0]), slip(2, [0.6, 0.8, 0.0]), slip(3, [0.0, 1.0, 0.0])];
        let dirichlet = |d: usize| d == 0 || d == 4 || d == 6 || d == 7;
        let corner = axis_slips(2, &slips, dirichlet);
        assert_eq!(corner.iter().map(|a| a.dof(2)).collect::<Vec<_>>(), vec![1]);
        // nothing left to slide along: no friction
        assert!(corner[0].free.is_empty() && corner[0].friction_frame().is_none());
        // 3D: a node with u_x, u_y held on a base of normal z gives u_z
        let slips = [slip(5, [0.0, 0.0, 1.0])];
        let held_xy = axis_slips(3, &slips, |d| d == 15 || d == 16);
        assert_eq!(held_xy.iter().map(|a| a.dof(3)).collect::<Vec<_>>(), vec![17]);
        assert!(held_xy[0].friction_frame().is_none());
        // the normal's component already held: nothing
        assert!(axis_slips(3, &slips, |d| d == 17).is_empty());
        // a base node on a symmetry plane (u_y held, outward normal −z): it slides along x with
        // friction, in the global frame
        let slips = [slip(5, [0.0, 0.0, -1.0])];
        let on_plane = axis_slips(3, &slips, |d| d == 16);
        assert_eq!(on_plane[0].free, vec![0]);
        let frame = on_plane[0].friction_frame().expect("frictional");
        assert_eq!((frame.component, frame.normal_sign, frame.tangents), ([2, 0, 0], -1.0, 1));
        assert_eq!((frame.basis[2][0], frame.basis[0][1]), (-1.0, 1.0));
    }

    #[test]
    fn bases_are_orthonormal_with_the_normal_first() {
        for (n, dim) in [([0.6, 0.8, 0.0], 2), ([1.0, 2.0, -2.0], 3), ([1.0, 0.0, 0.0], 3)] {
            let q = local_basis(n, dim);
            for a in 0..dim {
                for b in 0..dim {
                    let d: f64 = (0..dim).map(|i| q[i][a] * q[i][b]).sum();
                    assert!((d - if a == b { 1.0 } else { 0.0 }).abs() < 1e-14);
                }
            }
            let len = n[..dim].iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!((0..dim).all(|i| (q[i][0] - n[i] / len).abs() < 1e-14));
        }
    }
}
