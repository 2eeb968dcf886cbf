//! A background grid attached to structures: which grid nodes sit on a structure and how the
//! rest of the grid follows them (the coupling crate builds it from the case's interfaces).
//!
//! At the start of every step the grid is placed in the configuration where the soil's
//! cells meet the structure: an interface node sits where its structure node is
//! (`X + u_n` of the structure), the grid nodes far from the interfaces at their reference
//! positions, and a band in between where a mesh-motion rule ([`GridMotion`]) puts them.
//! Tied interface nodes *are* structure nodes (one set of DOFs: the structure keeps its
//! state, the soil's cells assemble there too); on a frictionless (slip) interface the soil
//! has its own node at the structure node's position, which takes the structure's normal
//! velocity and acceleration and the soil's tangential ones, and whose normal DOF is tied to
//! the structure node's in the DOF map.

/// A rule that moves the grid nodes between the interfaces and the far field.
pub trait GridMotion: Send + Sync {
    /// Fills the displacement `w` (reference → start of step) of every grid node from the
    /// entries of the anchored nodes, which the caller has set.
    fn extend(&mut self, w: &mut [[f64; 3]]);

    /// Spreads the motion over more of the grid (a structure that moved farther than the
    /// rule can follow within its present reach), returning a description of the new reach
    /// for messages (e.g. `"band 2.0 m"`), or `None` if it already covers the whole grid.
    fn widen(&mut self) -> Option<String> {
        None
    }
}

/// Worst cell quality (corner `det J` over its reference value) that the placement of an
/// attached grid accepts before it widens the mesh motion ([`GridMotion::widen`]).
pub const MIN_CELL_QUALITY: f64 = 0.2;

/// What a grid node is with respect to the structures attached to the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GridNodeKind {
    /// A grid node only: reset every step from the projection.
    Free,
    /// A structure node shared by the grid (a tied interface): its state is the structure's.
    Tied,
    /// The soil's node of a slip-interface pair, placed on structure node `source`: normal
    /// velocity and acceleration from it, tangential ones from the projection.
    Slip {
        /// The global structure node it sits on.
        source: usize,
        /// Unit normal of the interface there.
        normal: [f64; 3],
    },
}

/// The structures a grid is attached to (see the module doc).
pub struct GridAttachment {
    /// Names of the interfaces, for messages (e.g. `'wall_interface'`).
    pub interfaces: String,
    /// Per grid node: what it is.
    pub kind: Vec<GridNodeKind>,
    /// Per grid node: the global node whose displacement places it (itself for tied
    /// nodes, the structure node for slip nodes), or `None` for free nodes.
    pub anchor: Vec<Option<usize>>,
    /// The mesh-motion rule.
    pub motion: Box<dyn GridMotion>,
}
