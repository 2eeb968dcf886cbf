//! Monitors: named scalar time histories, evaluated on the committed state.

use loam_fem::domain::PointQuantity;
use loam_fem::model::Model;

/// What a monitor measures.
#[derive(Debug, Clone, PartialEq)]
pub enum MonitorKind {
    /// Displacement of a node (component, or magnitude if `None`).
    Displacement {
        /// Global node id.
        node: usize,
        /// Component index.
        component: Option<usize>,
    },
    /// Velocity of a node.
    Velocity {
        /// Global node id.
        node: usize,
        /// Component index.
        component: Option<usize>,
    },
    /// Acceleration of a node.
    Acceleration {
        /// Global node id.
        node: usize,
        /// Component index.
        component: Option<usize>,
    },
    /// Sum of reactions over nodes.
    Reaction {
        /// Global node ids.
        nodes: Vec<usize>,
        /// Component index.
        component: Option<usize>,
    },
    /// A vector quantity of a material point.
    MaterialPoint {
        /// Index of the domain holding it.
        domain: usize,
        /// Material point id.
        id: usize,
        /// Quantity.
        quantity: PointQuantity,
        /// Component index.
        component: Option<usize>,
    },
    /// Total kinetic energy.
    KineticEnergy,
    /// Total stored work of internal forces.
    StrainEnergy,
}

/// A named monitor.
#[derive(Debug, Clone, PartialEq)]
pub struct Monitor {
    /// Column name in `monitors.csv`.
    pub name: String,
    /// What it measures.
    pub kind: MonitorKind,
}

fn pick(v: &[f64], dim: usize, node: usize, component: Option<usize>) -> f64 {
    match component {
        Some(c) => v[node * dim + c],
        None => (0..dim).map(|c| v[node * dim + c].powi(2)).sum::<f64>().sqrt(),
    }
}

impl Monitor {
    /// Value at the model's committed state.
    pub fn evaluate(&self, model: &Model) -> f64 {
        let dim = model.dim;
        let s = &model.committed;
        match &self.kind {
            MonitorKind::Displacement { node, component } => pick(&s.u, dim, *node, *component),
            MonitorKind::Velocity { node, component } => pick(&s.v, dim, *node, *component),
            MonitorKind::Acceleration { node, component } => pick(&s.a, dim, *node, *component),
            MonitorKind::Reaction { nodes, component } => {
                let mut sum = [0.0; 3];
                for &n in nodes {
                    for (c, v) in sum.iter_mut().enumerate().take(dim) {
                        *v += model.reactions[n * dim + c];
                    }
                }
                match component {
                    Some(c) => sum[*c],
                    None => sum.iter().map(|v| v * v).sum::<f64>().sqrt(),
                }
            }
            MonitorKind::MaterialPoint { domain, id, quantity, component } => {
                match model.domains[*domain].point_quantity(*id, *quantity) {
                    Some(v) => pick(&v, dim, 0, *component),
                    None => f64::NAN, // the point left the grid and was erased
                }
            }
            MonitorKind::KineticEnergy => model.kinetic_energy(),
            MonitorKind::StrainEnergy => model.strain_energy(),
        }
    }
}
