//! One node set, one DOF map: the seam that lets several domains share nodes.
//!
//! Every domain refers to nodes by global id. Node `n` has `dim` DOFs `n·dim + d`; a DOF is
//! either an equation of the global system or constrained (prescribed displacement, or
//! inactive: a background-grid node no material point touches). Domains that share a node
//! contribute to the same equations, so coupling is plain assembly.
//!
//! **Node roles are data** ([`NodeRole`]): a grid node is reset every step from the
//! projection of the material points, a structure node keeps its state, an interface node
//! keeps the structure's state and also receives the soil's contributions. The role decides
//! what the step start does to a node and to which block of the Newton log ([`Block`]) its
//! equations belong; it never follows from where a node came from. Two DOFs may also be
//! **tied** to one equation ([`DofTie`]): the normal components of a soil node and a
//! structure node on a frictionless (slip) interface, each in its local frame, so that the
//! Newton corrections of the two are equal and their residuals add.

/// Marker for a DOF that is not an equation.
pub const CONSTRAINED: usize = usize::MAX;

/// What a node is (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NodeRole {
    /// A node of an FEM mesh: its state is kept from step to step.
    #[default]
    Structure,
    /// A node of an MPM background grid: reset every step, its velocity and acceleration
    /// projected from the material points.
    Grid,
    /// A structure node shared with a background grid: the structure's state is kept, the
    /// soil's cells also assemble there.
    Interface,
}

/// The blocks of the monolithic system, `[K_S K_SΓ 0; K_ΓS K_ΓΓ K_ΓSt; 0 K_StΓ K_St]`: the
/// soil (grid), the interface and the structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Block {
    /// Equations of grid nodes.
    Soil = 0,
    /// Equations of interface nodes, and equations shared by DOFs of different roles.
    Interface = 1,
    /// Equations of structure nodes.
    Structure = 2,
}

impl Block {
    /// The block of an equation whose DOFs belong to nodes of these roles.
    fn of(role: NodeRole) -> Self {
        match role {
            NodeRole::Grid => Block::Soil,
            NodeRole::Interface => Block::Interface,
            NodeRole::Structure => Block::Structure,
        }
    }
}

/// DOF `follower` takes the equation of DOF `leader` (both global DOF ids).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DofTie {
    /// The DOF whose equation is shared.
    pub leader: usize,
    /// The DOF that joins it.
    pub follower: usize,
}

/// Map from (node, component) to global equation number.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DofMap {
    dim: usize,
    equation: Vec<usize>,
    num_equations: usize,
    /// Block of each equation.
    block: Vec<Block>,
}

impl DofMap {
    /// Numbers the DOFs of `num_nodes` nodes with `dim` components, skipping those with
    /// `constrained[n·dim + d]` set, in node-major order; all nodes structure nodes, no ties.
    pub fn new(dim: usize, constrained: &[bool]) -> Self {
        let roles = vec![NodeRole::Structure; constrained.len() / dim.max(1)];
        Self::with_roles(dim, constrained, &roles, &[])
    }

    /// Numbers the DOFs as [`DofMap::new`], with the node `roles` deciding the block of
    /// each equation, and every tie's follower taking its leader's equation (constrained
    /// if the leader is).
    pub fn with_roles(dim: usize, constrained: &[bool], roles: &[NodeRole], ties: &[DofTie]) -> Self {
        let mut leader: Vec<usize> = (0..constrained.len()).collect();
        for t in ties {
            leader[t.follower] = t.leader;
        }
        let mut equation = vec![CONSTRAINED; constrained.len()];
        let mut block = Vec::new();
        for g in 0..constrained.len() {
            if leader[g] != g || constrained[g] {
                continue;
            }
            equation[g] = block.len();
            block.push(Block::of(roles[g / dim]));
        }
        for t in ties {
            let e = equation[t.leader];
            equation[t.follower] = e;
            if e != CONSTRAINED && roles[t.follower / dim] != roles[t.leader / dim] {
                block[e] = Block::Interface;
            }
        }
        let num_equations = block.len();
        Self { dim, equation, num_equations, block }
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

    /// Block of equation `e`.
    #[inline]
    pub fn block(&self, e: usize) -> Block {
        self.block[e]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid node tied to a structure node by its first component: one shared equation in
    /// the interface block, the other components in their own blocks.
    #[test]
    fn tied_dofs_share_an_equation_in_the_interface_block() {
        let roles = [NodeRole::Structure, NodeRole::Grid, NodeRole::Interface];
        let constrained = [true, false, false, false, false, false];
        let map = DofMap::with_roles(2, &constrained, &roles, &[DofTie { leader: 1, follower: 2 }]);
        assert_eq!(map.equations(), &[CONSTRAINED, 0, 0, 1, 2, 3]);
        assert_eq!(map.num_equations(), 4);
        assert_eq!(map.block(0), Block::Interface);
        assert_eq!(map.block(1), Block::Soil);
        assert_eq!(map.block(2), Block::Interface);
        // a follower of a constrained leader is constrained
        let map = DofMap::with_roles(2, &constrained, &roles, &[DofTie { leader: 0, follower: 3 }]);
        assert_eq!(map.equation(3), CONSTRAINED);
    }
}
