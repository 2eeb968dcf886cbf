//! Monitors: named scalar time histories, evaluated on the committed state.

use loam_fem::domain::{Domain, PointExtent, PointQuantity, PointTensor};
use loam_fem::model::Model;
use loam_mpm::surface::{binned_along_x, runout_of_thickness, SurfaceProfile};

use crate::case::RigidQuantity;

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
    /// Runout of the material points from a wall ([`SurfaceProfile::runout`]).
    Runout {
        /// x of the wall.
        wall: f64,
        /// y of the base.
        base: f64,
        /// Surface height threshold.
        threshold: f64,
    },
    /// Runout of the material points from a wall by the deposit's thickness
    /// ([`runout_of_thickness`]; the case's `"measure": "thickness"`).
    ThicknessRunout {
        /// x of the wall.
        wall: f64,
        /// Thickness threshold.
        threshold: f64,
        /// Bin width along x.
        bin: f64,
        /// Depth across y over which the volumes spread in 3D (1 in plane problems).
        depth: f64,
    },
    /// Free-surface height of the material points at `x` ([`SurfaceProfile::height_at`]).
    SurfaceHeight {
        /// Abscissa.
        x: f64,
        /// y of the base.
        base: f64,
    },
    /// A component of a tensor quantity of material points, averaged over `points`.
    MaterialPointTensor {
        /// (domain index, material point id) of each point averaged.
        points: Vec<(usize, usize)>,
        /// Quantity.
        quantity: PointTensor,
        /// Component or invariant.
        component: crate::case::TensorComponent,
    },
    /// Sum of the forces a penalty wall exerts on the bodies.
    WallForce {
        /// Index of the domain (grid) holding the wall.
        domain: usize,
        /// The wall's name.
        wall: String,
        /// Component index.
        component: Option<usize>,
    },
    /// Force of the soil on the structure across an interface: the model's soil forces
    /// summed over the interface's nodes.
    InterfaceForce {
        /// Global nodes where the soil's force acts (the shared nodes, or the soil's
        /// partners of a slip interface).
        nodes: Vec<usize>,
        /// Component index.
        component: Option<usize>,
    },
    /// Total current volume `Σ_p V_p` (m³) of the material points inside a box.
    MaterialVolume {
        /// Lower corner of the box.
        min: Vec<f64>,
        /// Upper corner of the box.
        max: Vec<f64>,
    },
    /// Total mass `Σ_p m_p` (kg) of the material points inside a box.
    MaterialMass {
        /// Lower corner of the box.
        min: Vec<f64>,
        /// Upper corner of the box.
        max: Vec<f64>,
    },
    /// Kinetic energy, total or of one domain (index, name of the domain or body).
    KineticEnergy {
        /// `None`: every domain.
        domain: Option<(usize, String)>,
    },
    /// Linear momentum, total or of one domain or body (index, name).
    Momentum {
        /// `None`: every domain.
        domain: Option<(usize, String)>,
        /// Component index (`None`: magnitude).
        component: Option<usize>,
    },
    /// A rigid body's motion or reaction ([`RigidQuantity`]).
    RigidBody {
        /// Its DOFs `[u_cx, u_cy, θ]`.
        dofs: [usize; 3],
        /// What to measure.
        quantity: RigidQuantity,
        /// Component of a vector quantity (`None`: magnitude).
        component: Option<usize>,
    },
    /// Stored work of internal forces, total or of one domain.
    StrainEnergy {
        /// `None`: every domain.
        domain: Option<(usize, String)>,
    },
}

/// A named monitor.
#[derive(Debug, Clone, PartialEq)]
pub struct Monitor {
    /// Column name in `monitors.csv`.
    pub name: String,
    /// What it measures.
    pub kind: MonitorKind,
    /// Factor applied to the measured value.
    pub scale: f64,
}

fn pick(v: &[f64], dim: usize, node: usize, component: Option<usize>) -> f64 {
    match component {
        Some(c) => v[node * dim + c],
        None => (0..dim).map(|c| v[node * dim + c].powi(2)).sum::<f64>().sqrt(),
    }
}

impl Monitor {
    /// Value at the model's committed state, times the monitor's scale.
    pub fn evaluate(&self, model: &Model) -> f64 {
        self.scale * self.measure(model)
    }

    /// Value at the model's committed state.
    fn measure(&self, model: &Model) -> f64 {
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
                let d = model.domains[*domain].as_ref();
                match held_anywhere(d, d.point_quantity(*id, *quantity)) {
                    Some(v) => pick(&v, dim, 0, *component),
                    None => f64::NAN, // the point left the grid and was erased
                }
            }
            MonitorKind::Runout { wall, base, threshold } => surface_runout(model, *wall, *base, *threshold),
            MonitorKind::ThicknessRunout { wall, threshold, bin, depth } => {
                thickness_runout(model, *wall, *threshold, *bin, *depth)
            }
            MonitorKind::SurfaceHeight { x, base } => surface_height(model, *x, *base),
            MonitorKind::MaterialPointTensor { points, quantity, component } => {
                let (mut sum, mut count) = (0.0, 0);
                for &(domain, id) in points {
                    let d = model.domains[domain].as_ref();
                    let value = d.point_tensor(id, *quantity).map(|t| [tensor_component(&t, *component), 0.0, 0.0]);
                    if let Some(v) = held_anywhere(d, value) {
                        sum += v[0];
                        count += 1;
                    }
                }
                if count > 0 {
                    sum / count as f64
                } else {
                    f64::NAN // every point left the grid and was erased
                }
            }
            MonitorKind::WallForce { domain, wall, component } => {
                let f = model.domains[*domain].wall_force(wall).unwrap_or([f64::NAN; 3]);
                pick(&f, dim, 0, *component)
            }
            MonitorKind::InterfaceForce { nodes, component } => {
                let mut sum = [0.0; 3];
                for &n in nodes {
                    for (c, v) in sum.iter_mut().enumerate().take(dim) {
                        *v += model.soil_forces[n * dim + c];
                    }
                }
                pick(&sum, dim, 0, *component)
            }
            MonitorKind::MaterialVolume { min, max } => model.sum_over_domains(|d| d.points_volume_mass(min, max).0),
            MonitorKind::MaterialMass { min, max } => model.sum_over_domains(|d| d.points_volume_mass(min, max).1),
            MonitorKind::KineticEnergy { domain: None } => model.kinetic_energy(),
            MonitorKind::StrainEnergy { domain: None } => model.strain_energy(),
            MonitorKind::KineticEnergy { domain: Some((k, name)) } => {
                let d = model.domains[*k].as_ref();
                d.energies(name, &model.committed.v).map_or(f64::NAN, |e| summed(d, [e.0])[0])
            }
            MonitorKind::Momentum { domain, component } => {
                let v = &model.committed.v;
                let p = match domain {
                    Some((k, name)) => {
                        let d = model.domains[*k].as_ref();
                        d.momentum(Some(name), v).map_or([f64::NAN; 3], |p| summed(d, p))
                    }
                    None => model
                        .domains
                        .iter()
                        .filter_map(|d| d.momentum(None, v).map(|p| summed(d.as_ref(), p)))
                        .fold([0.0; 3], |a, q| std::array::from_fn(|i| a[i] + q[i])),
                };
                pick(&p, dim, 0, *component)
            }
            MonitorKind::RigidBody { dofs, quantity, component } => {
                let field: &[f64] = match quantity {
                    RigidQuantity::Displacement | RigidQuantity::Rotation => &s.u,
                    RigidQuantity::Velocity | RigidQuantity::AngularVelocity => &s.v,
                    RigidQuantity::Acceleration | RigidQuantity::AngularAcceleration => &s.a,
                    RigidQuantity::Reaction | RigidQuantity::ReactionMoment => &model.reactions,
                };
                if quantity.is_vector() {
                    pick(&[field[dofs[0]], field[dofs[1]], 0.0], dim, 0, *component)
                } else {
                    field[dofs[2]]
                }
            }
            MonitorKind::StrainEnergy { domain: Some((k, name)) } => {
                let d = model.domains[*k].as_ref();
                d.energies(name, &model.committed.v).map_or(f64::NAN, |e| summed(d, [e.1])[0])
            }
        }
    }
}

/// `local`, a domain's answer for its points, summed over the ranks where its points are
/// distributed (collective there; docs/distributed.md, stage 3).
fn summed<const N: usize>(domain: &dyn Domain, local: [f64; N]) -> [f64; N] {
    let mut v = local;
    if let Some(ranks) = domain.points_distributed() {
        ranks.sum_identically(&mut v);
    }
    v
}

/// A point's value from the rank that holds it, where a domain's points are distributed
/// (collective there); `None` if no rank holds it (erased).
fn held_anywhere(domain: &dyn Domain, local: Option<[f64; 3]>) -> Option<[f64; 3]> {
    if domain.points_distributed().is_none() {
        return local;
    }
    let [held, x, y, z] = summed(domain, local.map_or([0.0; 4], |v| [1.0, v[0], v[1], v[2]]));
    (held > 0.0).then_some([x, y, z])
}

/// Positions and sizes of the material points of every domain, as the free-surface monitors
/// see them ([`SurfaceProfile`]: `x` along the runout, the second component up). In 3D, where
/// `z` is up (gravity along −z), the points are seen from the side: `(x, z)` becomes the
/// profile's `(x, y)`, so the surface is the top envelope over all `y` and a quarter or half
/// column against symmetry planes gives its runout along `x`. Where a domain's points are
/// distributed, every rank's are gathered (collective).
pub fn point_extents(model: &Model) -> Vec<PointExtent> {
    extents_seen_by_the_surface(model, |d| every_rank_extents(d))
}

/// The extents `of` each domain, seen as the surface monitors see them (the side view in 3D:
/// [`point_extents`]).
fn extents_seen_by_the_surface(model: &Model, of: impl Fn(&dyn Domain) -> Vec<PointExtent>) -> Vec<PointExtent> {
    let side_view = model.dim == 3;
    model
        .domains
        .iter()
        .flat_map(|d| of(d.as_ref()))
        .map(|mut p| {
            if side_view {
                p.position.swap(1, 2);
            }
            p
        })
        .collect()
}

/// The ranks over which some domain's points are distributed, if any.
fn points_ranks(model: &Model) -> Option<loam_fem::ranks::Ranks> {
    model.domains.iter().find_map(|d| d.points_distributed())
}

/// The runout monitor ([`SurfaceProfile::runout`]) over every domain's points. Where points
/// are distributed, each rank joins its own points' squares into runs and only the runs are
/// gathered (three values each, a few per rank), whose joined runout is that of all the
/// points bit for bit ([`SurfaceProfile::runout_runs`]); replicated domains' points are on
/// every rank, and their runs repeated do not change it.
fn surface_runout(model: &Model, wall: f64, base: f64, threshold: f64) -> f64 {
    let Some(ranks) = points_ranks(model) else {
        return SurfaceProfile::new(&point_extents(model), base).runout(wall, threshold);
    };
    let local = extents_seen_by_the_surface(model, |d| d.point_extents());
    let runs = SurfaceProfile::new(&local, base).runout_runs(wall, threshold);
    let mine: Vec<f64> = runs.iter().flat_map(|&(l, r, s)| [l, r, s]).collect();
    let all = ranks.all_gather_varcount(&mine);
    let runs = all.iter().flat_map(|part| part.chunks_exact(3)).map(|r| (r[0], r[1], r[2])).collect();
    loam_mpm::surface::runout_of_spans(runs, wall)
}

/// The runout by the deposit's thickness ([`runout_of_thickness`]): each point's area (in 3D
/// its volume, the sums then divided by `depth`) binned along x from the wall. Where points
/// are distributed, each rank bins its own points of the distributed domains and the bins are
/// summed over the ranks; the points of replicated domains, on every rank, are binned once.
fn thickness_runout(model: &Model, wall: f64, threshold: f64, bin: f64, depth: f64) -> f64 {
    let amount = |p: &PointExtent| p.size.powi(model.dim as i32);
    let (mut own, mut replicated) = (Vec::new(), Vec::new());
    for domain in &model.domains {
        let points = domain.point_extents();
        if domain.points_distributed().is_some() {
            own.extend(points);
        } else {
            replicated.extend(points);
        }
    }
    let mut bins = binned_along_x(&own, wall, bin, amount);
    if let Some(ranks) = points_ranks(model) {
        let all = ranks.all_gather_varcount(&bins);
        bins.clear();
        for part in &all {
            add_bins(&mut bins, part);
        }
    }
    add_bins(&mut bins, &binned_along_x(&replicated, wall, bin, amount));
    let thickness: Vec<f64> = bins.iter().map(|a| a / (bin * depth)).collect();
    runout_of_thickness(&thickness, bin, threshold)
}

/// `sum += other`, entry by entry, `sum` lengthened as needed.
fn add_bins(sum: &mut Vec<f64>, other: &[f64]) {
    if sum.len() < other.len() {
        sum.resize(other.len(), 0.0);
    }
    for (s, o) in sum.iter_mut().zip(other) {
        *s += o;
    }
}

/// The surface height monitor ([`SurfaceProfile::height_at`]): the highest point covering
/// `x`, where points are distributed the largest of the ranks' own (exact).
fn surface_height(model: &Model, x: f64, base: f64) -> f64 {
    let Some(ranks) = points_ranks(model) else {
        return SurfaceProfile::new(&point_extents(model), base).height_at(x);
    };
    let local = extents_seen_by_the_surface(model, |d| d.point_extents());
    let height = SurfaceProfile::new(&local, base).height_at(x);
    ranks.all_gather_varcount(&[height]).iter().flatten().fold(0.0, |m: f64, &h| m.max(h))
}

/// A domain's [`Domain::point_extents`], of every rank where its points are distributed
/// (collective there: five values per point gathered to every rank).
fn every_rank_extents(domain: &dyn Domain) -> Vec<PointExtent> {
    let local = domain.point_extents();
    match domain.points_distributed() {
        Some(ranks) => PointExtent::gathered(ranks, local),
        None => local,
    }
}

/// A component or invariant of a 3×3 tensor `t` (row-major).
pub fn tensor_component(t: &[[f64; 3]; 3], c: crate::case::TensorComponent) -> f64 {
    use crate::case::TensorComponent as C;
    match c {
        C::Xx => t[0][0],
        C::Yy => t[1][1],
        C::Zz => t[2][2],
        C::Xy => t[0][1],
        C::Yz => t[1][2],
        C::Xz => t[0][2],
        C::Mean => (t[0][0] + t[1][1] + t[2][2]) / 3.0,
        C::VonMises => {
            let m = (t[0][0] + t[1][1] + t[2][2]) / 3.0;
            let mut s2 = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    let s = t[i][j] - if i == j { m } else { 0.0 };
                    s2 += s * s;
                }
            }
            (1.5 * s2).sqrt()
        }
    }
}
