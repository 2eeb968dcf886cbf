//! Rigid-body motions that the tangent of a static model does not resist (issue 31).
//!
//! A static model needs supports. Without them, or with too few, the stiffness matrix `K` is
//! singular, the linear solver returns a correction of arbitrary size and the step fails
//! with a symptom that hides the cause (an inverted element, `det F = 0`). After a failed
//! static step, [`crate::model::Model::solve_step`] assembles the tangent at the step's
//! predictor once more (the last iterate may be far off and stressed) and
//! [`free_rigid_motion`] asks it which rigid-body motion it leaves free.
//!
//! **Algorithm.** For every connected component of the system's graph (a body, or bodies
//! joined by shared nodes), the rigid-body modes `R = [t_x, t_y, r_z]` (3D: three
//! translations and three rotations) about the component's centroid `c`, the rotations
//! scaled by the component's radius `ρ` (`r_z = (−(y − c_y), x − c_x)/ρ`), are written per
//! free equation (local frames at slip nodes; constrained DOFs drop out, which is how a
//! support resists). The smallest
//! $$ \mu = \min_a \frac{\|K R a\|^2}{\|R a\|^2} $$
//! over the combinations `a` is the square of the least singular value of `K R W`, with
//! `W = V Λ^{-1/2}` from the eigen-decomposition `RᵀR = V Λ Vᵀ` (3 × 3 or 6 × 6, directions
//! that `R` does not span dropped) and the displacement rows of `K R` only. The singular
//! value comes from the QR factorisation of the tall `K R W` (by blocks of rows) and the SVD
//! of its small `R` factor: the Gram matrix `WᵀRᵀKᵀKRW` would square the condition number (about `1e16`
//! between a free and a held motion) and leave round-off of the size of the answer. A
//! motion is free when
//! `√μ ≤ RIGID_TOLERANCE · max_e |K_ee|` over the component: a free motion leaves round-off
//! (measured 0, 1.0e-16 and 8.9e-17 of `max |K_ee|` for the translation, the rotation about
//! a pin and all three motions of the unit test's block); a support at even a few nodes of a
//! large body leaves orders of magnitude more than [`RIGID_TOLERANCE`] (the pinned cantilever
//! of `cases/cantilever_fem.json`: 1.5e-2 for its next freest combination).
//!
//! A translation is free at any state (a translated body has the same internal forces); a
//! rotation only while the body is unstressed (the geometric stiffness of a stressed body
//! resists it): a body held at a single point is found where its tangent is that of the
//! undeformed state, e.g. at the first iteration of the first step.

use nalgebra::{DMatrix, SymmetricEigen};

use crate::assembler::Assembler;
use crate::dofs::CONSTRAINED;

/// `√μ / max |K_ee|` at or below which a rigid-body motion is free (see the module doc).
pub const RIGID_TOLERANCE: f64 = 1e-10;

/// A rigid-body motion that a component of the system is free to make.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeMotion {
    /// Global displacement DOFs of the component.
    pub dofs: Vec<usize>,
    /// Number of independent free rigid-body motions.
    pub free: usize,
    /// Number of rigid-body motions in this dimension (3 in 2D, 6 in 3D).
    pub all: usize,
    /// The freest motion, in words: `translation in x`, `rotation about (3.5, 0.5)`.
    pub motion: String,
    /// Its `‖K R a‖/‖R a‖` relative to `max |K_ee|` (round-off).
    pub ratio: f64,
}

/// Union–find root of `i`, with path halving.
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Per-component data for the test of the module doc.
struct Component {
    /// Sum of the node positions of its free displacement DOFs, and their number.
    centroid: [f64; 3],
    count: usize,
    /// Mean squared distance to the centroid.
    radius: f64,
    /// `max |K_ee|` over its displacement equations.
    diagonal: f64,
    /// Its displacement equations.
    equations: Vec<usize>,
    /// `RᵀR` over them.
    h: DMatrix<f64>,
}

/// The first connected component of `assembler`'s last tangent that is free to move as a
/// rigid body (see the module doc); `positions` are the current node positions (m), `dim`
/// the components per node. `None` if every component is held, or the tangent is not
/// finite or not assembled yet.
pub fn free_rigid_motion(assembler: &Assembler, positions: &[[f64; 3]], dim: usize) -> Option<FreeMotion> {
    let (pattern, values) = assembler.tangent_matrix();
    let dofs = assembler.dofs();
    let n = pattern.num_equations();
    if n == 0 || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let (col_ptr, row_idx) = (pattern.symbolic().col_ptr(), pattern.symbolic().row_idx());
    let mut parent: Vec<usize> = (0..n).collect();
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            let (a, b) = (root(&mut parent, c), root(&mut parent, r));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let displacement_dofs = dofs.displacement_dofs();
    let modes = if dim == 2 { 3 } else { 6 };
    // the component of each node with a free displacement equation
    let mut node_component = vec![usize::MAX; displacement_dofs / dim];
    let mut displacement_equation = vec![false; n];
    for g in 0..displacement_dofs {
        let e = dofs.equation(g);
        if e != CONSTRAINED {
            displacement_equation[e] = true;
            if node_component[g / dim] == usize::MAX {
                node_component[g / dim] = root(&mut parent, e);
            }
        }
    }
    let mut components: std::collections::BTreeMap<usize, Component> = std::collections::BTreeMap::new();
    for (node, &c) in node_component.iter().enumerate().filter(|&(_, &c)| c != usize::MAX) {
        let comp = components.entry(c).or_insert_with(|| Component {
            centroid: [0.0; 3],
            count: 0,
            radius: 0.0,
            diagonal: 0.0,
            equations: Vec::new(),
            h: DMatrix::zeros(modes, modes),
        });
        for i in 0..3 {
            comp.centroid[i] += positions[node][i];
        }
        comp.count += 1;
    }
    for comp in components.values_mut() {
        comp.centroid = comp.centroid.map(|s| s / comp.count as f64);
    }
    for (node, &c) in node_component.iter().enumerate().filter(|&(_, &c)| c != usize::MAX) {
        let comp = components.get_mut(&c).expect("listed");
        comp.radius += (0..dim).map(|i| (positions[node][i] - comp.centroid[i]).powi(2)).sum::<f64>();
    }
    for comp in components.values_mut() {
        comp.radius = (comp.radius / comp.count as f64).sqrt().max(f64::MIN_POSITIVE);
    }
    for e in 0..n {
        if !displacement_equation[e] {
            continue;
        }
        let c = root(&mut parent, e);
        if let Some(comp) = components.get_mut(&c) {
            for k in col_ptr[e]..col_ptr[e + 1] {
                if row_idx[k] == e {
                    comp.diagonal = comp.diagonal.max(values[k].abs());
                }
            }
        }
    }
    // the modes per equation and K times them
    let mut r = Vec::with_capacity(modes);
    let mut y = Vec::with_capacity(modes);
    for m in 0..modes {
        let mut full = vec![0.0; dofs.num_dofs()];
        for (node, &c) in node_component.iter().enumerate().filter(|&(_, &c)| c != usize::MAX) {
            let comp = &components[&c];
            let x: Vec<f64> = (0..3).map(|i| (positions[node][i] - comp.centroid[i]) / comp.radius).collect();
            let u: [f64; 3] = match (dim, m) {
                (_, m) if m < dim => {
                    let mut t = [0.0; 3];
                    t[m] = 1.0;
                    t
                }
                (2, _) => [-x[1], x[0], 0.0],
                (_, 3) => [0.0, -x[2], x[1]],
                (_, 4) => [x[2], 0.0, -x[0]],
                _ => [-x[1], x[0], 0.0],
            };
            full[node * dim..node * dim + dim].copy_from_slice(&u[..dim]);
        }
        let rm = assembler.to_equations(&full);
        let mut ym = vec![0.0; n];
        pattern.multiply(values, &rm, &mut ym);
        r.push(rm);
        y.push(ym);
    }
    for e in 0..n {
        if !displacement_equation[e] {
            continue;
        }
        let c = root(&mut parent, e);
        let Some(comp) = components.get_mut(&c) else { continue };
        comp.equations.push(e);
        for a in 0..modes {
            for b in 0..modes {
                comp.h[(a, b)] += r[a][e] * r[b][e];
            }
        }
    }
    for (&c, comp) in &components {
        if comp.diagonal <= 0.0 {
            continue;
        }
        let Some((free, a, smallest)) = free_combinations(comp, &y, RIGID_TOLERANCE * comp.diagonal) else {
            continue;
        };
        let dofs_of: Vec<usize> = (0..displacement_dofs).filter(|&g| node_component[g / dim] == c).collect();
        let (motion, ratio) = (describe(&a, comp, dim), smallest / comp.diagonal);
        return Some(FreeMotion { dofs: dofs_of, free, all: modes, motion, ratio });
    }
    None
}

/// The number of combinations of the modes with `‖K R a‖/‖R a‖ ≤ limit` and the freest
/// one (coefficients `a` of the scaled modes) with its `‖K R a‖/‖R a‖`, or `None` if there is
/// none; `y[m]` is `K` times mode `m`, per equation.
fn free_combinations(comp: &Component, y: &[Vec<f64>], limit: f64) -> Option<(usize, Vec<f64>, f64)> {
    let h = SymmetricEigen::new(comp.h.clone());
    let largest = h.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let kept: Vec<usize> = (0..h.eigenvalues.len()).filter(|&i| h.eigenvalues[i] > 1e-8 * largest).collect();
    if kept.is_empty() {
        return None;
    }
    let modes = comp.h.nrows();
    // W = V diag(1/√λ): ‖R W z‖ = ‖z‖
    let w = DMatrix::from_fn(modes, kept.len(), |i, j| h.eigenvectors[(i, kept[j])] / h.eigenvalues[kept[j]].sqrt());
    // the R factor of K R W, by QR over blocks of rows (R of [R; next rows]): no tall matrix
    let mut r = DMatrix::<f64>::zeros(0, kept.len());
    for rows in comp.equations.chunks(4096) {
        let stacked = DMatrix::from_fn(r.nrows() + rows.len(), kept.len(), |i, j| {
            if i < r.nrows() {
                r[(i, j)]
            } else {
                (0..modes).map(|m| y[m][rows[i - r.nrows()]] * w[(m, j)]).sum::<f64>()
            }
        });
        r = stacked.qr().r();
    }
    let svd = r.svd(false, true);
    let v_t = svd.v_t.as_ref()?;
    let free = svd.singular_values.iter().filter(|&&s| s <= limit).count();
    let (k, &smallest) = svd.singular_values.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    if smallest.is_nan() || smallest > limit {
        return None;
    }
    let a = &w * v_t.row(k).transpose();
    Some((free, a.iter().cloned().collect(), smallest))
}

/// Short decimal form of a coordinate (at most 4 decimals, no trailing zeros).
pub(crate) fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// The rigid-body motion with coefficients `a` of the scaled modes, in words.
fn describe(a: &[f64], comp: &Component, dim: usize) -> String {
    let (t, w) = a.split_at(dim);
    let tn = t.iter().map(|v| v * v).sum::<f64>().sqrt();
    let wn = w.iter().map(|v| v * v).sum::<f64>().sqrt();
    const AXES: [&str; 3] = ["x", "y", "z"];
    if wn <= 1e-3 * tn {
        let dir: Vec<f64> = t.iter().map(|v| v / tn).collect();
        return match dir.iter().position(|d| d.abs() >= 0.999) {
            Some(i) => format!("translation in {}", AXES[i]),
            None => format!("translation along ({})", dir.iter().map(|&d| short(d)).collect::<Vec<_>>().join(", ")),
        };
    }
    if dim == 2 {
        // displacement t + ω ẑ × (x − c) vanishes at p = c + (−t_y, t_x)/ω
        let omega = w[0] / comp.radius;
        let p = [comp.centroid[0] - t[1] / omega, comp.centroid[1] + t[0] / omega];
        format!("rotation about ({}, {})", short(p[0]), short(p[1]))
    } else {
        let axis: Vec<String> = w.iter().map(|v| short(v / wn)).collect();
        format!("rotation about an axis along ({})", axis.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use loam_laws::neo_hookean::NeoHookean;

    use crate::element::ElementType;
    use crate::formulation::Formulation;
    use crate::mesh::Mesh;
    use crate::model::{Constraint, Model, NewtonSettings, StepError};
    use crate::scheme::TimeScheme;
    use crate::solid_domain::FemDomain;

    use super::RIGID_TOLERANCE;

    /// A Neo-Hookean block `mesh` under gravity `g` (m/s²) with the components `held` (node,
    /// component) prescribed to 0, one static step: its error.
    fn static_step(
        mesh: Mesh,
        dim: usize,
        g: f64,
        held: &[(usize, usize)],
        settings: NewtonSettings,
    ) -> Option<StepError> {
        let n = mesh.coords.len();
        let formulation = if dim == 2 { Formulation::PlaneStrain } else { Formulation::ThreeD };
        let law = Arc::new(NeoHookean::new(1000.0, 9e7, 0.3));
        let domain = FemDomain::new("block", mesh.clone(), (0..n).collect(), formulation, 1.0, law, false).unwrap();
        let mut model = Model::new(dim, mesh.coords, TimeScheme::Static, settings);
        model.domains.push(Box::new(domain));
        model.gravity.0 = if dim == 2 { [0.0, -g, 0.0] } else { [0.0, 0.0, -g] };
        model.constraints.push(Constraint {
            dofs: held.iter().map(|&(node, i)| node * dim + i).collect(),
            values: vec![0.0; held.len()],
            amplitude: Default::default(),
        });
        model.solve_step(1.0).err()
    }

    fn node_at(mesh: &Mesh, x: [f64; 3]) -> usize {
        (0..mesh.coords.len())
            .min_by(|&a, &b| {
                let d = |k: usize| (0..3).map(|i| (mesh.coords[k][i] - x[i]).powi(2)).sum::<f64>();
                d(a).total_cmp(&d(b))
            })
            .unwrap()
    }

    /// Issue 31: a static block held by rollers (x fixed on its left edge) is free to
    /// translate in y; pinned at one node, to rotate about it; with nothing held, free in
    /// all 3 (2D) or 6 (3D) rigid-body motions; clamped, it is not reported as free even when
    /// Newton fails (one iteration allowed), and that failure names the node with the largest
    /// residual.
    #[test]
    fn free_rigid_motions_are_found_and_held_ones_are_not() {
        let mesh = Mesh::rectangle([0.0, 0.0], [4.0, 1.0], [16, 4], ElementType::Quad4);
        let left: Vec<usize> = (0..mesh.coords.len()).filter(|&k| mesh.coords[k][0] == 0.0).collect();
        let pin = node_at(&mesh, [4.0, 0.5, 0.0]);
        let rollers: Vec<(usize, usize)> = left.iter().map(|&k| (k, 0)).collect();
        let clamp: Vec<(usize, usize)> = left.iter().flat_map(|&k| [(k, 0), (k, 1)]).collect();
        let cases = [
            ("rollers", rollers, "translation in y"),
            ("pinned", vec![(pin, 0), (pin, 1)], "rotation about (4, 0.5)"),
            ("nothing", vec![], ""),
        ];
        for (name, held, motion) in cases {
            let e = static_step(mesh.clone(), 2, 9.81, &held, NewtonSettings::default());
            println!("{name}: {}", e.as_ref().map_or("converged".into(), |e| e.to_string()));
            let Some(StepError::Unsupported(u)) = e else { panic!("{name}: not found") };
            println!("  ‖K R a‖/‖R a‖ = {:.1e} max |K_ee| (tolerance {RIGID_TOLERANCE:.0e})", u.motion.ratio);
            assert_eq!(u.domains, ["block"]);
            if name == "nothing" {
                assert_eq!((u.motion.free, u.motion.all), (3, 3));
            } else {
                assert_eq!(u.motion.free, 1);
                assert_eq!(u.motion.motion, motion);
            }
        }
        let one_iteration = NewtonSettings { max_iterations: 1, ..NewtonSettings::default() };
        let clamp = static_step(mesh.clone(), 2, 9.81, &clamp, one_iteration);
        println!("clamped, one iteration: {}", clamp.as_ref().unwrap());
        let Some(StepError::NoConvergence { largest: Some(peak), .. }) = clamp else { panic!("{clamp:?}") };
        assert_eq!(peak.owner, "domain 'block'");
        assert_eq!(peak.position.len(), 2);
        assert!(peak.force > 0.0 && peak.position[0] > 0.0, "a free node");
        let cube = Mesh::cuboid([0.0; 3], [2.0, 1.0, 1.0], [4, 2, 2], ElementType::Hex8);
        let e = static_step(cube, 3, 9.81, &[], NewtonSettings::default());
        println!("3D, nothing held: {}", e.as_ref().unwrap());
        let Some(StepError::Unsupported(u)) = e else { panic!("3D: not found") };
        assert_eq!((u.motion.free, u.motion.all), (6, 6));
    }
}
