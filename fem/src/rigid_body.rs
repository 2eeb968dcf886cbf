//! Rigid structures (issue 25, item 4): a plane body without elastic DOFs, moved by its
//! centre's translation `u_c` and its rotation `θ` about the centre.
//!
//! **Unknowns.** Three, in the model's DOF vector: the centre node's two components (a model
//! node at the body's centroid `X_c`) and the first component of a *rotation node* (a second
//! model node at `X_c` whose first DOF is `θ` in radians and whose second is held at 0). A
//! rotation so stored takes part in everything a displacement DOF does — the Newmark
//! kinematics (`θ̇`, `θ̈` are the node's velocity and acceleration), constraints (prescribed
//! rotation), the checkpoint's state vectors, the Newton log — without a fourth kind of DOF.
//!
//! **Kinematics.** A point of reference position `X` moves to
//!
//! ```text
//! x(X) = X_c + u_c + R(θ) (X − X_c),      R(θ) = [cos θ  −sin θ; sin θ  cos θ],
//! ```
//!
//! ([`RigidFrame::position`]); its derivatives are `∂x/∂u_c = I`, `∂x/∂θ = R′(θ)(X − X_c)`,
//! `∂²x/∂θ² = −R(θ)(X − X_c)` (`R″ = −R`). The contact of [`crate`]'s users
//! (`loam_coupling::interface_points`) writes its facet points with them.
//!
//! **Equations.** The body's own block is its inertia and weight (Newton–Euler about the
//! centroid, where gravity has no moment):
//!
//! ```text
//! r = [m (ã_c − g);  J θ̃̈],      K = c_M diag(m, m, J),
//! ```
//!
//! `m = ρ t A`, `J = ρ t ∫_A |X − X_c|² dA` from the body's mesh (Gauss rule of its cells,
//! exact for straight-edged triangles and parallelograms), `t` the plane thickness. The forces
//! other domains (contacts) put on its DOFs are the resultant on the centre and the moment
//! about it. Plane problems only (plane strain / plane stress).

use crate::assembly::BlockLayout;
use crate::domain::{AssemblyInput, Domain, DomainError, DomainOutput, Field, NamedOutput, NodalState};
use crate::formulation::Formulation;
use crate::mesh::Mesh;

/// Where a rigid body's three unknowns are, and the centre they refer to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidFrame {
    /// Reference position of the centre `X_c` (the centroid).
    pub centre: [f64; 2],
    /// Global node carrying `u_c` (DOFs `2 n`, `2 n + 1`).
    pub centre_node: usize,
    /// Global node whose first DOF is `θ` (DOF `2 n`; its second is held at 0).
    pub rotation_node: usize,
}

impl RigidFrame {
    /// The global DOFs `[u_cx, u_cy, θ]`.
    pub fn dofs(&self) -> [usize; 3] {
        [2 * self.centre_node, 2 * self.centre_node + 1, 2 * self.rotation_node]
    }

    /// `(u_c, θ)` in the full DOF vector `u`.
    pub fn unknowns(&self, u: &[f64]) -> ([f64; 2], f64) {
        let [x, y, t] = self.dofs();
        ([u[x], u[y]], u[t])
    }

    /// `R(θ) r` for the arm `r`.
    pub fn rotate(theta: f64, r: [f64; 2]) -> [f64; 2] {
        let (s, c) = theta.sin_cos();
        [c * r[0] - s * r[1], s * r[0] + c * r[1]]
    }

    /// The arm `X − X_c` of a reference position.
    pub fn arm(&self, reference: [f64; 2]) -> [f64; 2] {
        [reference[0] - self.centre[0], reference[1] - self.centre[1]]
    }

    /// Current position `X_c + u_c + R(θ)(X − X_c)` of the body's point at `reference`,
    /// with the unknowns in the full DOF vector `u`.
    pub fn position(&self, reference: [f64; 2], u: &[f64]) -> [f64; 2] {
        let (uc, theta) = self.unknowns(u);
        let r = Self::rotate(theta, self.arm(reference));
        [self.centre[0] + uc[0] + r[0], self.centre[1] + uc[1] + r[1]]
    }

    /// Velocity `v_c + ω × R(θ)(X − X_c)` of the body's point at `reference` (state `s`).
    pub fn velocity(&self, reference: [f64; 2], s: &NodalState) -> [f64; 2] {
        let (vc, omega) = self.unknowns(&s.v);
        let (_, theta) = self.unknowns(&s.u);
        let r = Self::rotate(theta, self.arm(reference));
        [vc[0] - omega * r[1], vc[1] + omega * r[0]]
    }
}

/// Area, centroid and polar second moment of area about the centroid of a 2D mesh,
/// `(A, X_c, ∫ |X − X_c|² dA)`, by the Gauss rule of its cells.
pub fn area_properties(mesh: &Mesh) -> (f64, [f64; 2], f64) {
    let (area, centre, polar, _) = mass_properties(mesh, |_| 1.0);
    (area, centre, polar)
}

/// As [`area_properties`], and the measure `∫ t(X) dA` with the weight `t(X)` (the plane
/// thickness, or `2πr` in axisymmetry) and its polar moment `∫ t(X) |X − X_c|² dA`:
/// `(A, X_c, ∫ |X − X_c|² dA, [∫ t dA, ∫ t |X − X_c|² dA])`.
fn mass_properties(mesh: &Mesh, weight: impl Fn([f64; 2]) -> f64) -> (f64, [f64; 2], f64, [f64; 2]) {
    let element = mesh.element;
    let nn = element.num_nodes();
    let (mut n, mut dn) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
    let mut points = Vec::new(); // (x, y, dA)
    for e in 0..mesh.num_cells() {
        let coords: Vec<[f64; 3]> = mesh.cell(e).iter().map(|&a| mesh.coords[a]).collect();
        for g in element.gauss_points_high() {
            element.shape_functions(&g.xi, &mut n);
            element.shape_gradients(&g.xi, &mut dn);
            let det = element.jacobian(&coords, &dn).determinant();
            let x: [f64; 2] = std::array::from_fn(|d| (0..nn).map(|a| n[a] * coords[a][d]).sum());
            points.push((x, det * g.weight));
        }
    }
    let area: f64 = points.iter().map(|p| p.1).sum();
    let centre = [0, 1].map(|d| points.iter().map(|(x, w)| x[d] * w).sum::<f64>() / area);
    let arm = |x: &[f64; 2]| (x[0] - centre[0]).powi(2) + (x[1] - centre[1]).powi(2);
    let polar = points.iter().map(|(x, w)| w * arm(x)).sum();
    let measure = points.iter().map(|(x, w)| w * weight(*x)).sum();
    let weighted_polar = points.iter().map(|(x, w)| w * weight(*x) * arm(x)).sum();
    (area, centre, polar, [measure, weighted_polar])
}

/// A rigid plane body (see the module doc).
pub struct RigidBody {
    name: String,
    formulation: Formulation,
    thickness: f64,
    /// The body's mesh in its reference configuration (geometry and output).
    mesh: Mesh,
    frame: RigidFrame,
    /// Mass `ρ t A` (kg).
    mass: f64,
    /// Moment of inertia about the centre `ρ t ∫ |X − X_c|² dA` (kg m²).
    inertia: f64,
    /// Whether its three unknowns are all prescribed ([`RigidBody::driven`]).
    driven: bool,
}

impl RigidBody {
    /// The body of `mesh` (2D) with density `density`, its unknowns at `frame` (whose centre
    /// must be the mesh's centroid, [`area_properties`]); its mass and inertia integrate the
    /// formulation's measure (the thickness, or `2πr` in axisymmetry, where the body is a
    /// ring that moves along the axis only: its radial motion and rotation must be held).
    pub fn new(
        name: &str,
        mesh: Mesh,
        frame: RigidFrame,
        density: f64,
        formulation: Formulation,
        thickness: f64,
    ) -> Self {
        let (_, _, _, [measure, polar]) = mass_properties(&mesh, |x| formulation.measure_factor(thickness, x[0]));
        Self {
            name: name.to_string(),
            formulation,
            thickness,
            mesh,
            frame,
            mass: density * measure,
            inertia: density * polar,
            driven: false,
        }
    }

    /// The same body with all three unknowns prescribed (a moving wall): its motion is an
    /// input to the model, and its kinetic energy is not the model's (the energy monitors and
    /// `analysis.stop_at_rest` leave it out; the trapezoidal rule's velocities of prescribed
    /// DOFs also alternate about the true one after a kink of the motion, as when a wall
    /// stops). Its momentum is still `m v_c`.
    pub fn driven(mut self) -> Self {
        self.driven = true;
        self
    }

    /// Where the body's unknowns are.
    pub fn frame(&self) -> RigidFrame {
        self.frame
    }

    /// Mass (kg, per the plane thickness) and moment of inertia about the centre (kg m²).
    pub fn mass_and_inertia(&self) -> (f64, f64) {
        (self.mass, self.inertia)
    }

    /// The body's mesh (reference configuration).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }
}

impl Domain for RigidBody {
    fn name(&self) -> &str {
        &self.name
    }

    fn formulation(&self) -> Formulation {
        self.formulation
    }

    fn thickness(&self) -> f64 {
        self.thickness
    }

    fn blocks(&self, layout: &mut BlockLayout) {
        layout.push(self.frame.dofs());
    }

    /// `r = [m (ã_c − g); J θ̃̈]`, `K = c_M diag(m, m, J)` (module doc).
    fn assemble(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        let dofs = self.frame.dofs();
        let masses = [self.mass, self.mass, self.inertia];
        let gravity = [input.gravity[0], input.gravity[1], 0.0];
        for k in 0..3 {
            let inertia = input.inertial_acceleration.map_or(0.0, |a| masses[k] * a[dofs[k]]);
            vectors[k] = inertia - masses[k] * gravity[k];
        }
        if input.with_tangent {
            matrices[..9].fill(0.0);
            for k in 0..3 {
                matrices[4 * k] = input.mass_coefficient * masses[k];
            }
        }
        Ok(())
    }

    fn commit(&mut self, _input: &AssemblyInput<'_>) {}

    /// `½ m |v_c|² + ½ J ω²`; 0 for a driven body ([`RigidBody::driven`]).
    fn kinetic_energy(&self, v: &[f64]) -> f64 {
        if self.driven {
            return 0.0;
        }
        let (vc, omega) = self.frame.unknowns(v);
        0.5 * self.mass * (vc[0] * vc[0] + vc[1] * vc[1]) + 0.5 * self.inertia * omega * omega
    }

    fn strain_energy(&self) -> f64 {
        0.0
    }

    /// `m v_c`.
    fn momentum(&self, name: Option<&str>, v: &[f64]) -> Option<[f64; 3]> {
        if name.is_some_and(|n| n != self.name) {
            return None;
        }
        let (vc, _) = self.frame.unknowns(v);
        Some([self.mass * vc[0], self.mass * vc[1], 0.0])
    }

    fn boundary_facets(&self) -> Vec<Vec<usize>> {
        Vec::new()
    }

    fn save_state(&self) -> Vec<u8> {
        Vec::new() // every unknown is nodal
    }

    fn restore_state(&mut self, _state: &[u8]) -> Result<(), String> {
        Ok(())
    }

    /// The body's mesh in its reference configuration with the rigid motion's nodal
    /// `displacement` and `velocity`, and per cell the `rotation` θ (rad).
    fn outputs(&self, committed: &NodalState, _with_grid: bool) -> Vec<NamedOutput> {
        let reference: Vec<[f64; 2]> = self.mesh.coords.iter().map(|x| [x[0], x[1]]).collect();
        let displacement = reference
            .iter()
            .flat_map(|&x| {
                let p = self.frame.position(x, &committed.u);
                [p[0] - x[0], p[1] - x[1], 0.0]
            })
            .collect();
        let velocity = reference
            .iter()
            .flat_map(|&x| {
                let v = self.frame.velocity(x, committed);
                [v[0], v[1], 0.0]
            })
            .collect();
        let (_, theta) = self.frame.unknowns(&committed.u);
        let field = |name: &str, components: usize, values: Vec<f64>| Field { name: name.into(), components, values };
        let output = DomainOutput {
            points: self.mesh.coords.clone(),
            cells: Some((self.mesh.element, self.mesh.connectivity.clone())),
            point_fields: vec![field("displacement", 3, displacement), field("velocity", 3, velocity)],
            cell_fields: vec![field("rotation", 1, vec![theta; self.mesh.num_cells()])],
        };
        vec![NamedOutput { name: self.name.clone(), output }]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::ElementType;

    /// A 0.4 × 0.2 rectangle on triangles and on quads: `A = 0.08`, centroid (0.3, 0.2),
    /// `J/ρ = A (a² + b²)/12 = 0.08 · 0.2/12`; the inertial residual `m ã − m g`, `J θ̈`, and
    /// the tangent `c_M diag(m, m, J)`.
    #[test]
    fn a_rectangle_has_the_mass_and_inertia_of_a_rectangle() {
        for element in [ElementType::Quad4, ElementType::Tri3] {
            let mesh = Mesh::rectangle([0.1, 0.1], [0.4, 0.2], [4, 3], element);
            let (area, centre, polar) = area_properties(&mesh);
            let exact = 0.08 * (0.16 + 0.04) / 12.0;
            println!("{element:?}: A = {area}, X_c = {centre:?}, polar {polar:.6e} (exact {exact:.6e})");
            assert!((area - 0.08).abs() < 1e-14 && (centre[0] - 0.3).abs() < 1e-14 && (centre[1] - 0.2).abs() < 1e-14);
            assert!((polar - exact).abs() < 1e-12 * exact);
            let frame = RigidFrame { centre, centre_node: 1, rotation_node: 0 };
            let mut body = RigidBody::new("block", mesh, frame, 2000.0, Formulation::PlaneStrain, 1.0);
            let (m, j) = body.mass_and_inertia();
            assert!((m - 160.0).abs() < 1e-9 && (j - 2000.0 * exact).abs() < 1e-9);
            let state = NodalState::zeros(4);
            let acceleration = [0.5, 0.0, 2.0, -3.0];
            let input = AssemblyInput {
                inertial_acceleration: Some(&acceleration),
                mass_coefficient: 7.0,
                gravity: [0.0, -9.81, 0.0],
                ..AssemblyInput::static_tangent(&state, &state)
            };
            let (mut k, mut r) = (vec![0.0; 9], vec![0.0; 3]);
            body.assemble(&input, &mut k, &mut r).unwrap();
            assert_eq!(r, vec![2.0 * m, (-3.0 + 9.81) * m, 0.5 * j]);
            assert_eq!(k, vec![7.0 * m, 0.0, 0.0, 0.0, 7.0 * m, 0.0, 0.0, 0.0, 7.0 * j]);
        }
    }

    /// A quarter turn about the centre maps the arm (1, 0) to (0, 1), after the translation.
    #[test]
    fn the_rigid_map_turns_about_the_centre() {
        let frame = RigidFrame { centre: [1.0, 2.0], centre_node: 0, rotation_node: 1 };
        let u = [0.1, -0.2, std::f64::consts::FRAC_PI_2, 0.0];
        let x = frame.position([2.0, 2.0], &u);
        assert!((x[0] - 1.1).abs() < 1e-15 && (x[1] - 2.8).abs() < 1e-15, "{x:?}");
    }
}
