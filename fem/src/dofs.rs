//! One node set, one DOF map: the seam that lets several domains share nodes.
//!
//! Every domain refers to nodes by global id. Node `n` has `dim` displacement DOFs
//! `n·dim + d`; a DOF is either an equation of the global system or constrained (prescribed
//! displacement, or inactive: a background-grid node no material point touches). Domains that
//! share a node contribute to the same equations, so coupling is plain assembly.
//!
//! **Pressure DOFs** (the mixed u–p formulation) come after all displacement DOFs: the `k`-th
//! pressure DOF is `num_nodes·dim + k`, at node `pressure_nodes[k]`. Only nodes of u–p
//! domains carry one (a node shared with a displacement-only domain has it, used by the
//! u–p domain alone); two u–p domains sharing a node share its pressure. A pressure DOF
//! takes the role (and so the Newton-log block) of its node; it has no velocity or
//! acceleration.
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
    /// The block's name in messages: `soil`, `interface` or `structure`.
    pub fn name(self) -> &'static str {
        match self {
            Block::Soil => "soil",
            Block::Interface => "interface",
            Block::Structure => "structure",
        }
    }

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
    /// Number of displacement DOFs (`num_nodes · dim`); pressure DOFs follow.
    displacement_dofs: usize,
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
        Self::with_roles(dim, constrained, &roles, &[], &[])
    }

    /// Numbers the DOFs as [`DofMap::new`] — the displacement DOFs of the `roles.len()` nodes,
    /// then one pressure DOF at each node of `pressure_nodes` (`constrained` covers both) —
    /// with the node `roles` deciding the block of each equation, and every tie's follower
    /// taking its leader's equation (constrained if the leader is).
    pub fn with_roles(
        dim: usize,
        constrained: &[bool],
        roles: &[NodeRole],
        pressure_nodes: &[usize],
        ties: &[DofTie],
    ) -> Self {
        let displacement_dofs = roles.len() * dim;
        debug_assert_eq!(constrained.len(), displacement_dofs + pressure_nodes.len());
        let node = |g: usize| if g < displacement_dofs { g / dim } else { pressure_nodes[g - displacement_dofs] };
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
            block.push(Block::of(roles[node(g)]));
        }
        for t in ties {
            let e = equation[t.leader];
            equation[t.follower] = e;
            if e != CONSTRAINED && roles[node(t.follower)] != roles[node(t.leader)] {
                block[e] = Block::Interface;
            }
        }
        let num_equations = block.len();
        Self { dim, displacement_dofs, equation, num_equations, block }
    }

    /// Number of displacement DOFs (`num_nodes · dim`): DOFs from here on are pressures.
    pub fn displacement_dofs(&self) -> usize {
        self.displacement_dofs
    }

    /// Whether DOF `dof` is a pressure.
    #[inline]
    pub fn is_pressure(&self, dof: usize) -> bool {
        dof >= self.displacement_dofs
    }

    /// Components per node.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of global equations.
    pub fn num_equations(&self) -> usize {
        self.num_equations
    }

    /// Number of DOFs, constrained or not (`num_nodes · dim` and the pressures).
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
        let map = DofMap::with_roles(2, &constrained, &roles, &[], &[DofTie { leader: 1, follower: 2 }]);
        assert_eq!(map.equations(), &[CONSTRAINED, 0, 0, 1, 2, 3]);
        assert_eq!(map.num_equations(), 4);
        assert_eq!(map.block(0), Block::Interface);
        assert_eq!(map.block(1), Block::Soil);
        assert_eq!(map.block(2), Block::Interface);
        // a follower of a constrained leader is constrained
        let map = DofMap::with_roles(2, &constrained, &roles, &[], &[DofTie { leader: 0, follower: 3 }]);
        assert_eq!(map.equation(3), CONSTRAINED);
    }

    /// Pressure DOFs follow the displacement DOFs and take the block of their node.
    #[test]
    fn pressure_dofs_follow_and_take_their_nodes_block() {
        let roles = [NodeRole::Structure, NodeRole::Grid];
        let constrained = [false, false, true, false, false, false];
        let map = DofMap::with_roles(2, &constrained, &roles, &[1, 0], &[]);
        assert_eq!(map.equations(), &[0, 1, CONSTRAINED, 2, 3, 4]);
        assert_eq!(map.displacement_dofs(), 4);
        assert!(map.is_pressure(4) && !map.is_pressure(3));
        assert_eq!(map.block(3), Block::Soil);
        assert_eq!(map.block(4), Block::Structure);
    }
}
