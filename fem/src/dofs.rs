//! One node set, one DOF map: the seam that lets several domains share nodes.
//!
//! Every domain refers to nodes by global id. Node `n` has `dim` DOFs `n·dim + d`; a DOF is
//! either an equation of the global system or constrained (prescribed displacement, or
//! inactive: a background-grid node no material point touches). Domains that share a node
//! contribute to the same equations, so coupling is plain assembly.

/// Marker for a DOF that is not an equation.
pub const CONSTRAINED: usize = usize::MAX;

/// Map from (node, component) to global equation number.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DofMap {
    dim: usize,
    equation: Vec<usize>,
    num_equations: usize,
}

impl DofMap {
    /// Numbers the DOFs of `num_nodes` nodes with `dim` components, skipping those with
    /// `constrained[n·dim + d]` set, in node-major order.
    pub fn new(dim: usize, constrained: &[bool]) -> Self {
        let mut next = 0;
        let equation = constrained
            .iter()
            .map(|&c| {
                if c {
                    CONSTRAINED
                } else {
                    next += 1;
                    next - 1
                }
            })
            .collect();
        Self { dim, equation, num_equations: next }
    }

    /// Components per node.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of global equations.
    pub fn num_equations(&self) -> usize {
        self.num_equations
    }

    /// Number of DOFs, constrained or not (`num_nodes · dim`).
    pub fn num_dofs(&self) -> usize {
        self.equation.len()
    }

    /// Equation of DOF `dof`, or [`CONSTRAINED`].
    #[inline]
    pub fn equation(&self, dof: usize) -> usize {
        self.equation[dof]
    }

    /// Equations of all DOFs.
    pub fn equations(&self) -> &[usize] {
        &self.equation
    }
}
