//! Geostatic stress with implicit MPM: benchmark 5, the hydrostatic soil column (CB-Geo's
//! validation, issue #5), on three grids, its settlement and stress field at each point; and the second half of benchmark 7, a block on a
//! horizontal frictionless slip boundary that stays at rest under its lithostatic stress
//! (issue #4). Every test prints measured vs reference and asserts a stated tolerance.

mod common;

use approx::assert_relative_eq;
use common::{case, case_json, last, parse, report, run};
use loam_fem::domain::{PointQuantity, PointTensor};
use serde_json::json;

const RHO: f64 = 1800.0;
const G: f64 = 9.81;
const H: f64 = 0.1;

/// Lamé constants of the column's Neo-Hookean soil (E = 1.2 MPa, ν = 0.3).
const LAMBDA: f64 = 1.2e6 * 0.3 / (1.3 * 0.4);
const MU: f64 = 1.2e6 / 2.6;

/// Closed-form settlement of the laterally confined column: under uniaxial strain
/// `F = diag(1, J, 1)` the first Piola stress of the Neo-Hookean law is
/// `P_yy = μ J + (λ ln J − μ)/J`, equal to the Cauchy stress (the cross-section does not
/// change), and statics gives `P_yy(Y) = −ρ g (H − Y)` at every reference height `Y`. Solving
/// for `J(Y)` and integrating, `u(Y) = ∫₀^Y (J − 1) dY'` (trapezoidal rule on 4000 intervals,
/// then linear interpolation: errors below 1e-13 m). Small strain: `ρ g (H Y − Y²/2)/M`,
/// `M = λ + 2μ`.
struct Settlement(Vec<f64>);

impl Settlement {
    const N: usize = 4000;

    fn new() -> Self {
        let stretch = |y: f64| {
            let target = -RHO * G * (H - y);
            let mut j = 1.0f64;
            for _ in 0..50 {
                let f = MU * j + (LAMBDA * j.ln() - MU) / j - target;
                let df = MU + (LAMBDA - LAMBDA * j.ln() + MU) / (j * j);
                j -= f / df;
            }
            j
        };
        let dy = H / Self::N as f64;
        let mut u = vec![0.0; Self::N + 1];
        for k in 1..=Self::N {
            u[k] = u[k - 1] + 0.5 * dy * (stretch((k - 1) as f64 * dy) - 1.0 + stretch(k as f64 * dy) - 1.0);
        }
        Settlement(u)
    }

    fn at(&self, y: f64) -> f64 {
        let s = (y / H * Self::N as f64).clamp(0.0, Self::N as f64 - 1e-9);
        let k = s.floor() as usize;
        self.0[k] + (s - k as f64) * (self.0[k + 1] - self.0[k])
    }
}

/// What one level of benchmark 5 measured.
struct Column {
    /// Largest pointwise settlement error |u_y,p − u(Y_p)| (m) and the top settlement (m).
    settlement_error: f64,
    top_settlement: f64,
    /// Largest pointwise stress error max_p |σ_yy,p + ρ g (H − Y_p)| (Pa).
    stress_error: f64,
    /// Bottom-row mean σ_yy, base σ_yy extrapolated from the bottom two rows, K0 of the
    /// bottom row, base reaction / width.
    bottom_row: f64,
    base_extrapolated: f64,
    k0: f64,
    reaction: f64,
}

/// Benchmark 5 on grid size `h` (4 points per cell at the Gauss positions).
fn column(h: f64, settlement: &Settlement) -> Column {
    let mut c = case_json("hydrostatic_column_mpm.json");
    let (nx, ny) = ((0.2 / h).round() as usize, (H / h).round() as usize);
    c["domains"][0]["grid"]["cells"] = json!([nx, ny + 2]);
    c["domains"][0]["grid"]["size"] = json!([0.2, (ny + 2) as f64 * h]);
    c["domains"][0]["material_points"]["cells"]["mesh"]["rectangle"]["cells"] = json!([nx, ny]);
    c["output"] = json!({ "vtk": false });
    let row = |name: &str, k: f64, component: &str| {
        json!({ "name": name, "type": "material_point_stress", "component": component,
                "box": { "min": [0.0, k * h], "max": [0.2, (k + 1.0) * h] } })
    };
    let monitors = c["monitors"].as_array_mut().expect("monitors");
    monitors.retain(|m| !m["name"].as_str().unwrap_or("").starts_with("row"));
    monitors.extend([row("row1_syy", 0.0, "yy"), row("row2_syy", 1.0, "yy"), row("row1_sxx", 0.0, "xx")]);
    let (sim, hist) = run(parse(c));
    let d = &sim.model.domains[0];
    let ids = d.points_in_box(&[-1.0, -1.0], &[1.0, 1.0]);
    assert_eq!(ids.len(), 4 * nx * ny, "every material point is still in the grid");
    let (mut settlement_error, mut stress_error, mut top_settlement) = (0.0f64, 0.0f64, 0.0f64);
    for &id in &ids {
        let x = d.point_quantity(id, PointQuantity::Position).expect("position");
        let u = d.point_quantity(id, PointQuantity::Displacement).expect("displacement");
        let sigma = d.point_tensor(id, PointTensor::CauchyStress).expect("stress");
        let y0 = x[1] - u[1];
        settlement_error = settlement_error.max((u[1] - settlement.at(y0)).abs());
        stress_error = stress_error.max((sigma[1][1] + RHO * G * (H - y0)).abs());
        top_settlement = top_settlement.max(-u[1]);
    }
    let (s1, s2) = (last(&sim, &hist, "row1_syy"), last(&sim, &hist, "row2_syy"));
    Column {
        settlement_error,
        top_settlement,
        stress_error,
        bottom_row: s1,
        // the rows' points lie symmetrically about the initial heights h/2 and 3h/2
        base_extrapolated: (3.0 * s1 - s2) / 2.0,
        k0: last(&sim, &hist, "row1_sxx") / s1,
        reaction: -last(&sim, &hist, "base_reaction_y") / 0.2,
    }
}

/// Benchmark 5: hydrostatic column, 0.2 m × 0.1 m, ρ = 1800 kg/m³, K = 1 MPa (Neo-Hookean,
/// ν = 0.3), rollers on the walls and the base, gravity, one static step; h = 0.01 / 0.005 /
/// 0.0025 m, 4 points per cell. Each point is compared with the closed form **at its own
/// reference height Y_p**:
///
/// - **settlement** `u(Y_p)` of the laterally confined column ([`Settlement`]): this is
///   where the law, the stiffness, the point volumes and the gravity load all enter (a
///   stiffness wrong by its Poisson factor, M = λ + 2μ against E, is 35 % off). Linear
///   elements reproduce the 1D column's nodal displacements exactly; the points interpolate
///   a quadratic linearly between nodes, so the error is at most `ρ g h² / (8 M)`: asserted
///   at every point, and its order under refinement in [1.8, 2.2] (measured: 2.00).
/// - **vertical stress** `σ_yy(Y_p) = −ρ g (H − Y_p)`: the stress is constant in each cell
///   and equals the exact value at the cell's centre, so the points at the Gauss heights
///   differ by `ρ g h / (2√3)` (2.9 / 1.4 / 0.7 % of ρ g H): asserted within 1 % of that
///   bound, first order (measured 1.00).
/// - **K0** = σ_xx/σ_yy of the bottom row = ν/(1 − ν) within 1 % (law-dependent).
///
/// Printed, not asserted as validation: the base stress extrapolated from the bottom two rows
/// and the base reaction, exact by statics whatever the law (equilibrium checks, 1e-9), and
/// the bottom row's mean σ_yy against ρ g H, whose error is the rows' height h/2 above the
/// base (5 / 2.5 / 1.25 %). CB-Geo's explicit-MPM figures (4.8 / 2.3 / 1.1 %, BENCHMARKS.md)
/// look like that same offset of the bottom points rather than an accuracy; they are not
/// compared.
#[test]
fn hydrostatic_column_settlement_and_stress_converge() {
    let settlement = Settlement::new();
    let m = LAMBDA + 2.0 * MU;
    let levels = [0.01, 0.005, 0.0025];
    let columns: Vec<Column> = levels.iter().map(|&h| column(h, &settlement)).collect();
    for (h, c) in levels.iter().zip(&columns) {
        let bound_u = RHO * G * h * h / (8.0 * m);
        let bound_s = RHO * G * h / (2.0 * 3f64.sqrt());
        println!("h = {h} m:");
        println!(
            "  settlement: top {:.4e} m (closed form {:.4e}, small strain {:.4e}); largest pointwise error {:.3e} m = \
             {:.3} % of the top's (bound ρgh²/8M = {bound_u:.3e} m)",
            c.top_settlement,
            -settlement.at(H),
            RHO * G * H * H / (2.0 * m),
            c.settlement_error,
            100.0 * c.settlement_error / c.top_settlement
        );
        assert!(c.settlement_error <= bound_u, "settlement error {} above {bound_u}", c.settlement_error);
        println!(
            "  σ_yy: largest pointwise error {:.4} Pa = {:.3} % of ρgH (cell-constant stress at the Gauss heights: \
             ρgh/(2√3) = {bound_s:.4} Pa)",
            c.stress_error,
            100.0 * c.stress_error / (RHO * G * H)
        );
        assert_relative_eq!(c.stress_error, bound_s, max_relative = 0.01);
        println!("  K0 = σ_xx/σ_yy of the bottom row {:.5} (ν/(1−ν) = {:.5}, tolerance 1 %)", c.k0, 0.3 / 0.7);
        assert_relative_eq!(c.k0, 0.3 / 0.7, max_relative = 0.01);
        let exact = -RHO * G * H;
        println!(
            "  equilibrium (not validation): base σ_yy extrapolated from the bottom two rows {:.6} Pa, base reaction / \
             width {:.6} Pa, ρgH {exact:.6} Pa; bottom-row mean σ_yy {:.3} Pa, {:.2} % off (its height h/2)",
            c.base_extrapolated,
            c.reaction,
            c.bottom_row,
            100.0 * (c.bottom_row / exact - 1.0)
        );
        assert_relative_eq!(c.base_extrapolated, exact, max_relative = 1e-9);
        assert_relative_eq!(c.reaction, exact, max_relative = 1e-9);
    }
    let order = |f: &dyn Fn(&Column) -> f64| {
        [(f(&columns[0]) / f(&columns[1])).log2(), (f(&columns[1]) / f(&columns[2])).log2()]
    };
    let (ou, os) = (order(&|c| c.settlement_error), order(&|c| c.stress_error));
    println!(
        "orders: settlement error {:.3}, {:.3} (expected 2); stress error {:.3}, {:.3} (expected 1)",
        ou[0], ou[1], os[0], os[1]
    );
    assert!(ou.iter().all(|p| (1.8..=2.2).contains(p)));
    assert!(os.iter().all(|p| (0.9..=1.1).contains(p)));
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
