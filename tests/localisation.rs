//! Strain localisation with the softening laws at the structural level (issue #5, item 8):
//! plane-strain compression of a 1 m × 2 m specimen between smooth platens, a weak
//! 0.1 m corner seeding one shear band, the top platen displacement-controlled
//! (`cases/biaxial_mc_softening.json`, `cases/biaxial_mcc.json`; FEM quad4 h = 0.05 m —
//! the MPM grid has no displacement-controlled platen yet, its nodes reset every step).
//!
//! Checked: the platen force peaks and then softens; the accumulated plastic deviatoric
//! strain κ localises (its maximum far above its mean, in a narrow band); the band angle
//! against Roscoe's 45° + ψ/2 and Coulomb's 45° + φ/2 (the band is fitted, by principal
//! axes, through the centres of the cells with κ above half its maximum, in the reference
//! configuration).

mod common;

use common::{case, run, BAND_FIT};
use loam::case::{Case, MeshSpec};
use loam::simulation::Simulation;

/// Per cell of domain `k`: centre (reference configuration) and the values of cell field
/// `name` (`components` per cell).
fn cell_field(sim: &Simulation, k: usize, name: &str) -> (Vec<[f64; 2]>, Vec<f64>) {
    let out = sim.model.output(&sim.case.domains[k].name).expect("the domain's output");
    let (element, conn) = out.cells.as_ref().expect("a mesh");
    let nn = element.num_nodes();
    let centres = conn
        .chunks(nn)
        .map(|c| {
            let (x, y) = c.iter().fold((0.0, 0.0), |(x, y), &n| (x + out.points[n][0], y + out.points[n][1]));
            [x / nn as f64, y / nn as f64]
        })
        .collect();
    let field = out.cell_fields.iter().find(|f| f.name == name).unwrap_or_else(|| panic!("cell field {name}"));
    (centres, field.values.clone())
}

/// Localisation measures of the specimen (domain 2) over its cells ([`common::localisation`]).
fn localisation(sim: &Simulation) -> (f64, f64, f64, f64) {
    let (centres, kappa) = cell_field(sim, 2, "accumulated_plastic_deviatoric_strain");
    common::localisation(&centres, &kappa)
}

/// [`common::force_history`] of the platen force.
fn force_history(sim: &Simulation, h: &common::History) -> (f64, f64, bool) {
    common::force_history(sim, h, "top_force")
}

/// The MC-softening specimen with its specimen cells stretched so that their diagonals
/// lie at `atan(h_y / h_x)` = 55.6° (26 rows instead of 38, the seed and base rows one
/// cell high).
fn stretched(mut c: Case) -> Case {
    for (d, rows) in c.domains.iter_mut().zip([1, 1, 26]) {
        let Some(MeshSpec::Rectangle { cells, .. }) = d.mesh.as_mut() else { panic!("rectangles") };
        cells[1] = rows;
    }
    c
}

/// Mohr–Coulomb strain softening ([`common::check_mc_softening`]) — and the band stays
/// near Roscoe's angle on a mesh whose element diagonals lie at 55.6° instead of 45°, so it
/// is not the mesh's diagonal.
#[test]
fn mohr_coulomb_softening_band() {
    for (label, c) in [
        ("square cells (diagonal 45°)", case("biaxial_mc_softening.json")),
        ("stretched cells (diagonal 55.6°)", stretched(case("biaxial_mc_softening.json"))),
    ] {
        let mut c = c;
        c.output.vtk = false;
        let (sim, h) = run(c);
        common::check_mc_softening(label, force_history(&sim, &h), localisation(&sim), "cells");
    }
}

/// Modified Cam Clay, heavily overconsolidated (OCR 4), drained: the platen force peaks
/// and then falls below 90 % of its peak; κ_max ≥ 3 κ_mean with the band under 30 % of the
/// specimen; the band angle lies between Roscoe's 45° and Coulomb's 45° + φ_mob/2, each
/// widened by [`BAND_FIT`] for the fit, φ_mob the friction angle mobilised at the peak, sin φ_mob = (σ₁ − σ₃)/(σ₁ + σ₃)
/// from the mean platen stress and the 50 kPa confinement; the band cells lie on their
/// yield surface q²/M² + p (p − p_c) = 0 (Kirchhoff p, q from the cell stresses; within 2 %
/// of p_c²) with the stress ratio η = q/p within 10 % above M = 1: on their way to the
/// critical state.
#[test]
fn modified_cam_clay_band() {
    let mut c = case("biaxial_mcc.json");
    c.output.vtk = false;
    let (sim, h) = run(c);
    let (peak, end, interior) = force_history(&sim, &h);
    let (max, mean, share, angle) = localisation(&sim);
    let (s1, s3) = (peak / 1.0, 50e3);
    let phi_mob = ((s1 - s3) / (s1 + s3)).asin().to_degrees();
    println!(
        "MCC: initial platen stress 50 kPa; peak {:.2} kPa (φ_mob = {phi_mob:.1}°); at 0.2 m {:.2} kPa = {:.0} % of the peak",
        peak / 1e3,
        end / 1e3,
        100.0 * end / peak
    );
    println!(
        "  κ max {max:.3}, mean {mean:.4} (ratio {:.1}); band (κ > κ_max/2) {:.1} % of the cells; band angle {angle:.1}° \
         (Roscoe 45°, Coulomb 45° + φ_mob/2 = {:.1}°; accepted [{:.1}°, {:.1}°])",
        max / mean,
        100.0 * share,
        45.0 + phi_mob / 2.0,
        45.0 - BAND_FIT,
        45.0 + phi_mob / 2.0 + BAND_FIT
    );
    assert!(interior && end < 0.9 * peak, "peak, then softening");
    assert!(max >= 3.0 * mean && share < 0.3, "the strain localises");
    assert!((45.0 - BAND_FIT..=45.0 + phi_mob / 2.0 + BAND_FIT).contains(&angle), "band angle {angle}°");
    // the band cells: on the yield surface, near the critical state line
    let (_, kappa) = cell_field(&sim, 2, "accumulated_plastic_deviatoric_strain");
    let (_, sigma) = cell_field(&sim, 2, "cauchy_stress");
    let (_, green) = cell_field(&sim, 2, "green_lagrange_strain");
    let (_, pc) = cell_field(&sim, 2, "preconsolidation_pressure");
    let (mut worst_f, mut eta_sum, mut n) = (0.0f64, 0.0, 0);
    for c in 0..kappa.len() {
        if kappa[c] <= 0.5 * max {
            continue;
        }
        let s = &sigma[9 * c..9 * c + 9];
        let e = &green[9 * c..9 * c + 9];
        let cm = nalgebra::Matrix3::from_fn(|i, j| 2.0 * e[3 * i + j] + if i == j { 1.0 } else { 0.0 });
        let jac = cm.determinant().sqrt();
        let tau = nalgebra::Matrix3::from_fn(|i, j| jac * s[3 * i + j]);
        let p = -tau.trace() / 3.0;
        let dev = tau + nalgebra::Matrix3::identity() * p;
        let q = (1.5 * dev.norm_squared()).sqrt();
        worst_f = worst_f.max(((q * q + p * (p - pc[c])) / (pc[c] * pc[c])).abs());
        eta_sum += q / p;
        n += 1;
    }
    let eta = eta_sum / n as f64;
    println!(
        "  band cells: largest |q²/M² + p(p − p_c)| / p_c² = {worst_f:.4} (asserted < 0.02); mean η = q/p {eta:.3} \
         (M = 1; asserted in [1, 1.1])"
    );
    assert!(worst_f < 0.02);
    assert!((1.0..=1.1).contains(&eta));
}
