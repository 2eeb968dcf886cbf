//! Geostatic stress with implicit MPM: benchmark 5, the hydrostatic soil column (CB-Geo's
//! validation, issue #5), on three grids; and the second half of benchmark 7, a block on a
//! horizontal frictionless slip boundary that stays at rest under its lithostatic stress
//! (issue #4). Every test prints measured vs reference and asserts a stated tolerance.

mod common;

use common::{case, last, report, run};
use loam::case::{BodySpec, MeshSpec, MonitorSpec, PointBox, TensorComponent};
use loam_fem::domain::{PointQuantity, PointTensor};

const RHO: f64 = 1800.0;
const G: f64 = 9.81;
const H: f64 = 0.1;

/// Benchmark 5 on grid size `h`: (base stress extrapolated from the points, mean σ_yy of the
/// bottom row of points, largest pointwise |σ_yy − σ_exact(Y_p)| over all points, K0 of the
/// bottom row, base reaction / width).
fn column(h: f64) -> (f64, f64, f64, f64, f64) {
    let mut c = case("hydrostatic_column_mpm.json");
    let (nx, ny) = ((0.2 / h).round() as usize, (H / h).round() as usize);
    let grid = c.domains[0].grid.as_mut().unwrap();
    grid.cells = vec![nx, ny + 2];
    grid.size = vec![0.2, (ny + 2) as f64 * h];
    let Some(BodySpec::Cells { mesh: MeshSpec::Rectangle { cells, .. }, .. }) = c.domains[0].material_points.as_mut()
    else {
        panic!("the column's points come from a rectangle")
    };
    *cells = [nx, ny];
    let row = |name: &str, k: f64, component| MonitorSpec::MaterialPointStress {
        name: name.into(),
        point: None,
        within: Some(PointBox { min: vec![0.0, k * h], max: vec![0.2, (k + 1.0) * h] }),
        component,
    };
    c.monitors.retain(|m| !m.name().starts_with("row"));
    c.monitors.push(row("row1_syy", 0.0, TensorComponent::Yy));
    c.monitors.push(row("row2_syy", 1.0, TensorComponent::Yy));
    c.monitors.push(row("row1_sxx", 0.0, TensorComponent::Xx));
    let (sim, hist) = run(c);
    let (s1, s2) = (last(&sim, &hist, "row1_syy"), last(&sim, &hist, "row2_syy"));
    // the rows' points lie symmetrically about the initial heights h/2 and 3h/2
    let base = (3.0 * s1 - s2) / 2.0;
    let d = &sim.model.domains[0];
    let ids = d.points_in_box(&[-1.0, -1.0], &[1.0, 1.0]);
    assert_eq!(ids.len(), 4 * nx * ny, "every material point is still in the grid");
    let worst = ids
        .iter()
        .map(|&id| {
            let x = d.point_quantity(id, PointQuantity::Position).unwrap();
            let u = d.point_quantity(id, PointQuantity::Displacement).unwrap();
            let sigma = d.point_tensor(id, PointTensor::CauchyStress).unwrap();
            // by statics the Cauchy stress at initial height Y carries the weight above Y
            (sigma[1][1] + RHO * G * (H - (x[1] - u[1]))).abs()
        })
        .fold(0.0, f64::max);
    let k0 = last(&sim, &hist, "row1_sxx") / s1;
    (base, s1, worst, k0, -last(&sim, &hist, "base_reaction_y") / 0.2)
}

/// Benchmark 5: hydrostatic column, 0.2 m × 0.1 m, ρ = 1800 kg/m³, K = 1 MPa (Neo-Hookean,
/// ν = 0.3), rollers on the walls and the base, gravity, static; base vertical stress
/// −ρ g H = −1765.8 Pa. Explicit MPM (CB-Geo) errors: 4.8 / 2.3 / 1.1 % at h = 0.01 /
/// 0.005 / 0.0025 m.
///
/// The base stress is measured from the material points alone: the mean σ_yy of the points
/// of the bottom two rows of cells (initial mean heights h/2 and 3h/2) extrapolated
/// linearly to y = 0. Asserted at every level: error ≤ the explicit-MPM figure, and in fact
/// ≤ 1e-9 — the column is statically determinate row by row (a cell row carries the weight
/// above its centre whatever the law), so the linear extrapolation is exact and its error is
/// round-off that cannot fall further. What does fall with refinement is the pointwise
/// error of the point stresses, max_p |σ_yy,p − σ_exact(Y_p)| / (ρ g H) = h / (2√3 H)
/// (cell-constant stress sampled at Gauss points): asserted ≤ the explicit figures and
/// halving with h. The raw bottom-row stress (the sampling offset h/2, 5 / 2.5 / 1.25 %)
/// and the base reaction per width (exact by equilibrium) are printed for comparison.
#[test]
fn hydrostatic_column_base_stress_converges() {
    let exact = -RHO * G * H;
    let mut previous = f64::INFINITY;
    for (h, explicit) in [(0.01, 0.048), (0.005, 0.023), (0.0025, 0.011)] {
        let (base, s1, worst, k0, reaction) = column(h);
        println!("h = {h} m:");
        report("  base σ_yy extrapolated from the bottom two rows of points [Pa]", base, exact, explicit);
        let err = ((base - exact) / exact).abs();
        println!("  (relative error {err:.1e}; asserted < 1e-9)");
        assert!(err < 1e-9, "row-by-row statics makes the extrapolation exact; error {err}");
        println!(
            "  bottom-row mean σ_yy {s1:.3} Pa: {:.3} % from ρgH (the sampling offset h/2H = {:.3} %; explicit MPM {:.1} %)",
            100.0 * ((s1 - exact) / exact).abs(),
            100.0 * h / (2.0 * H),
            100.0 * explicit
        );
        let pointwise = worst / (RHO * G * H);
        println!(
            "  largest pointwise stress error {worst:.4} Pa = {:.3} % of ρgH (h/(2√3 H) = {:.3} %; tolerance: explicit MPM {:.1} %)",
            100.0 * pointwise,
            100.0 * h / (2.0 * 3f64.sqrt() * H),
            100.0 * explicit
        );
        assert!(pointwise <= explicit);
        assert!(pointwise < 0.55 * previous, "the pointwise error halves with h: {pointwise} after {previous}");
        previous = pointwise;
        println!("  K0 = σ_xx/σ_yy of the bottom row {k0:.5} (linear elasticity ν/(1−ν) = {:.5})", 0.3 / 0.7);
        assert!((k0 - 0.3 / 0.7).abs() < 0.01 * 0.3 / 0.7);
        println!("  base reaction / width {reaction:.6} Pa (equilibrium: exact)");
        assert!((reaction - exact).abs() < 1e-9 * exact.abs());
    }
}

/// Benchmark 7, second half: the block of the 30° slope test on the same frictionless
/// slip boundary, horizontal. Gravity is ramped smoothly over 0.2 s and held to 0.5 s. The
/// block stays at rest — no horizontal drift (|u_x| < 10 µm at the centre, elastic Poisson
/// motion only, against the 0.61 m slide on the slope) and the centre settles by the
/// elastic compression ρ g (H y − y²/2)(1 − ν²)/E of a laterally free column (within 3 %)
/// — and carries the lithostatic stress σ_yy = −ρ g (H − y): mean σ_yy over a bottom and a
/// middle row of cells within 1 %; σ_xx of the bottom row below 5 % of ρ g H; base
/// reaction = weight within 1 %.
#[test]
fn block_rests_on_horizontal_slip_boundary() {
    let (sim, h) = run(case("slip_flat_mpm.json"));
    let (rho, g, e, nu) = (1000.0, 9.81, 1.0e8, 0.3);
    let (ux, uy) = (last(&sim, &h, "centre_ux"), last(&sim, &h, "centre_uy"));
    println!("centre horizontal displacement at t = 0.5 s: {ux:.3e} m (asserted |·| < 1e-5 m)");
    assert!(ux.abs() < 1e-5);
    let y = 0.5;
    report("centre settlement [µm]", 1e6 * uy, -1e6 * rho * g * (1.0 * y - y * y / 2.0) * (1.0 - nu * nu) / e, 0.03);
    report("bottom row (mean depth 0.95 m) σ_yy [Pa]", last(&sim, &h, "bottom_syy"), -rho * g * 0.95, 0.01);
    report("middle row (mean depth 0.55 m) σ_yy [Pa]", last(&sim, &h, "middle_syy"), -rho * g * 0.55, 0.01);
    let sxx = last(&sim, &h, "bottom_sxx");
    println!("bottom row σ_xx {sxx:.1} Pa (exact 0; asserted |·| < 5 % of ρ g H = {:.0} Pa)", 0.05 * rho * g);
    assert!(sxx.abs() < 0.05 * rho * g);
    report("base reaction [N]", last(&sim, &h, "base_reaction_y"), rho * g * 1.0, 0.01);
}
