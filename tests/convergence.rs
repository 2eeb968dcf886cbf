//! Convergence under refinement (BENCHMARKS.md: "where a tolerance says 'with refinement',
//! the test should also show the error falling"): the observed order of the cantilever of
//! benchmark 1 (FEM and MPM), the axisymmetric plate of benchmark 2 (MPM, quadrilateral and
//! triangular grids) and the vibrating bar of benchmark 3 (MPM, space and time refined
//! together), each on three levels halving h.
//!
//! The observed order is `p = ln(|u₁ − u₂| / |u₂ − u₃|) / ln 2` ([`common::observed_order`]);
//! bilinear and linear elements converge in displacement at order 2 on these smooth
//! problems, and so does the trapezoidal rule in time, so every order is asserted in
//! [1.8, 2.2]. The Richardson limit `u₃ + (u₃ − u₂)/(2^p − 1)` is compared with the closed
//! form. All levels are static single steps or short dynamic runs: a few seconds in all.

mod common;

use common::{case_json, nearest_point, observed_order, parse, richardson, run, timoshenko};
use serde_json::json;

/// Accepted observed orders (expected 2).
const ORDER: (f64, f64) = (1.8, 2.2);

fn assert_order(label: &str, p: f64) {
    println!("{label}: observed order {p:.3} (expected 2, asserted in [{}, {}])", ORDER.0, ORDER.1);
    assert!((ORDER.0..=ORDER.1).contains(&p), "{label}: observed order {p}");
}

const L: f64 = 7.0;

/// The beam is geometrically nonlinear (Neo-Hookean, tip rotation ≈ 0.075 rad): its
/// converged deflection lies about 0.3 % below the linear Timoshenko value (the θ² scaling
/// of the 0.6 % BENCHMARKS.md gives for benchmark 12's longer beam at 0.11 rad). Tolerance
/// of the Richardson limit against Timoshenko: 0.5 %.
const LIMIT_TOLERANCE: f64 = 0.005;

/// Benchmark 1, FEM quad4 with 4 / 8 / 16 cells through the depth (28 × 4, 56 × 8,
/// 112 × 16): the tip node's deflection (7, 0.5) converges at order 2 to within 0.5 % of
/// Timoshenko (measured: order 1.95, limit −0.3980 m, −0.25 %).
#[test]
fn cantilever_fem_converges_at_order_two() {
    let tips: Vec<f64> = [1usize, 2, 4]
        .iter()
        .map(|&n| {
            let mut c = case_json("cantilever_fem.json");
            c["domains"][0]["mesh"]["rectangle"]["cells"] = json!([28 * n, 4 * n]);
            c["solver"] = json!({ "residual_relative_tolerance": 1e-10, "residual_absolute_tolerance": 1e-6 });
            let (sim, h) = run(parse(c));
            let tip = common::last(&sim, &h, "tip_uy");
            println!(
                "FEM h = {:.4} m: tip deflection {tip:.6} m, Timoshenko {:.6} m ({:+.3} %)",
                1.0 / (4 * n) as f64,
                timoshenko(L),
                100.0 * (tip / timoshenko(L) - 1.0)
            );
            tip
        })
        .collect();
    let tips = [tips[0], tips[1], tips[2]];
    assert_order("FEM cantilever tip deflection", observed_order(tips, 2.0));
    let limit = richardson(tips, 2.0);
    let err = limit / timoshenko(L) - 1.0;
    println!(
        "FEM Richardson limit {limit:.6} m vs Timoshenko {:.6} m: {:+.3} % (tolerance {:.1} %)",
        timoshenko(L),
        100.0 * err,
        100.0 * LIMIT_TOLERANCE
    );
    assert!(err.abs() <= LIMIT_TOLERANCE);
}

/// Benchmark 1, MPM, 4 points per cell, h = 0.25 / 0.125 / 0.0625 m: the deflection of the
/// material point nearest the tip (7, 0.5), compared with Timoshenko **at that point's own
/// position** x_p = 7 − 0.211 h. Its relative error converges at order 2 to within 0.5 % of
/// Timoshenko (measured: −3.27 / −1.01 / −0.44 %, order 1.97, limit −0.24 %). Compared with
/// the beam at x = 7 instead, the error sequence (−4.23 / −1.50 / −0.68 %) carries the
/// point's O(h) offset from the tip and converges at order 1.73: this test fails it.
#[test]
fn cantilever_mpm_converges_at_order_two_at_the_points_position() {
    let (mut errors, mut at_tip) = ([0.0; 3], [0.0; 3]);
    for (k, n) in [1usize, 2, 4].into_iter().enumerate() {
        let mut c = case_json("cantilever_mpm.json");
        c["domains"][0]["grid"]["cells"] = json!([32 * n, 12 * n]);
        c["domains"][0]["material_points"]["cells"]["mesh"]["rectangle"]["cells"] = json!([28 * n, 4 * n]);
        c["solver"] = json!({ "residual_relative_tolerance": 1e-10, "residual_absolute_tolerance": 1e-6 });
        let (sim, _) = run(parse(c));
        let (x0, u) = nearest_point(&sim, &[L, 0.5]);
        errors[k] = u[1] / timoshenko(x0[0]) - 1.0;
        at_tip[k] = u[1] / timoshenko(L) - 1.0;
        println!(
            "MPM h = {:.4} m: point at X = ({:.4}, {:.4}) deflects {:.6} m; Timoshenko there {:.6} m ({:+.3} %); at \
             x = 7: {:.6} m ({:+.3} %)",
            0.25 / n as f64,
            x0[0],
            x0[1],
            u[1],
            timoshenko(x0[0]),
            100.0 * errors[k],
            timoshenko(L),
            100.0 * (u[1] / timoshenko(L) - 1.0)
        );
    }
    assert_order("MPM cantilever, error at the point's position", observed_order(errors, 2.0));
    let limit = richardson(errors, 2.0);
    println!("MPM Richardson limit of the error: {:+.3} % (tolerance {:.1} %)", 100.0 * limit, 100.0 * LIMIT_TOLERANCE);
    assert!(limit.abs() <= LIMIT_TOLERANCE);
    let wrong = observed_order(at_tip, 2.0);
    println!("the same points against the beam at x = 7: observed order {wrong:.3} (fails the order check)");
    assert!(!(ORDER.0..=ORDER.1).contains(&wrong), "the order check must reject the un-fixed measurement point");
}

/// Benchmark 2's plate: centre deflection of the mid-surface (m, downward negative) by
/// Kirchhoff, `(5 + ν) q a⁴ / (64 (1 + ν) D)` = 0.07604 m, plus Mindlin's shear
/// deflection `q a² / (4 κ G t)` = 0.00076 m (κ = 5/6; the Kirchhoff–Mindlin relation
/// `w^M = w^K + 𝓜^K/(κ G t)` with the Marcus moment `𝓜^K = q (a² − r²)/4` of the simply
/// supported plate: Wang, Reddy & Lee 2000, *Shear Deformable Beams and Plates*, §5.2).
fn plate_reference() -> (f64, f64) {
    let (a, t, e, nu, q) = (10.0f64, 1.0f64, 1.0e7, 0.24, 101.84);
    let d = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
    let kirchhoff = (5.0 + nu) * q * a.powi(4) / (64.0 * (1.0 + nu) * d);
    let g = e / (2.0 * (1.0 + nu));
    (-kirchhoff, -(kirchhoff + q * a * a / (4.0 * 5.0 / 6.0 * g * t)))
}

/// The plate case on a grid of `cells` (quad4 or tri3), one static step: the deflection of
/// the mid-surface at the centre relative to the mid-surface at the support radius,
/// `w(0, t/2) − w(a, t/2)`, from the grid nodes there, and the centre material point's own
/// deflection. (In one static step from the reference state the grid nodes' displacement is
/// the step's, the field the points interpolate.)
fn plate(element: &str, n: usize) -> (f64, f64) {
    let mut c = case_json("plate_axisym_mpm.json");
    c["domains"][0]["grid"]["cells"] = json!([40 * n, 4 * n]);
    c["domains"][0]["grid"]["element"] = json!(element);
    let body = &mut c["domains"][0]["material_points"]["cells"];
    body["mesh"]["rectangle"]["cells"] = json!([40 * n, 4 * n]);
    body["mesh"]["rectangle"]["element"] = json!(element);
    body["points_per_cell"] = json!(if element == "quad4" { 4 } else { 3 });
    let monitors = c["monitors"].as_array_mut().expect("monitors");
    monitors.push(json!({ "name": "grid_centre", "type": "displacement", "point": [0.0, 0.5], "component": "y" }));
    monitors.push(json!({ "name": "grid_edge", "type": "displacement", "point": [10.0, 0.5], "component": "y" }));
    let (sim, h) = run(parse(c));
    assert_eq!(sim.stats.steps, 1, "one static step");
    (common::last(&sim, &h, "grid_centre") - common::last(&sim, &h, "grid_edge"), common::last(&sim, &h, "centre_uy"))
}

/// Benchmark 2, MPM, h = t/4, t/8, t/16 on quadrilateral and triangular grids. Plate theory
/// gives the mid-surface's deflection with the mid-surface fixed at the support; the case
/// supports the bottom fibre on one ring of nodes, whose local indentation (a line load on
/// an elastic body: logarithmically singular) grows without bound under refinement. So the
/// measure is the centre's deflection relative to the mid-surface at r = a: it converges at
/// order 2, its limit within 0.5 % of Mindlin (Mindlin's plate theory leaves out the
/// through-thickness stress and where on the faces the load and support act: effects of
/// order ν (t/a)² ≈ 0.2 %). Measured: order 1.98 (quad) and 1.95 (tri), limits 0.015 % and
/// 0.019 % above Mindlin. The centre point's own deflection is printed: it keeps growing with
/// refinement (the indentation): orders 1.66 (quad) and 1.77 (tri) on these levels, 1.1 on the
/// quad grid's next (h = t/32).
#[test]
fn plate_mpm_converges_at_order_two() {
    let (kirchhoff, mindlin) = plate_reference();
    for element in ["quad4", "tri3"] {
        let levels: Vec<(f64, f64)> = [1usize, 2, 4].iter().map(|&n| plate(element, n)).collect();
        for (n, (rel, point)) in [1, 2, 4].iter().zip(&levels) {
            println!(
                "plate {element}, h = {:.4} m: w(0) − w(a) at mid-surface {rel:.6} m (Mindlin {mindlin:.6}, {:+.3} %; \
                 Kirchhoff {kirchhoff:.6}); centre point's own deflection {point:.6} m",
                0.25 / *n as f64,
                100.0 * (rel / mindlin - 1.0)
            );
        }
        let rel = [levels[0].0, levels[1].0, levels[2].0];
        assert_order(&format!("plate {element}, w(0) − w(a)"), observed_order(rel, 2.0));
        let limit = richardson(rel, 2.0);
        let err = limit / mindlin - 1.0;
        println!(
            "plate {element}: Richardson limit {limit:.6} m vs Mindlin {mindlin:.6} m: {:+.3} % (tolerance 0.5 %); \
             centre point's order {:.2} (not asserted)",
            100.0 * err,
            observed_order([levels[0].1, levels[1].1, levels[2].1], 2.0)
        );
        assert!(err.abs() <= 0.005);
    }
}

/// Period of the free end's velocity (s) from its downward zero crossings, the bar of
/// benchmark 3 refined `n` times in space and time, with initial velocity amplitude `v0`.
fn bar_period(n: usize, v0: f64) -> f64 {
    let mut c = case_json("vibrating_bar_mpm.json");
    c["domains"][0]["grid"]["cells"] = json!([27 * n, 1]);
    c["domains"][0]["material_points"]["cells"]["mesh"]["rectangle"]["cells"] = json!([25 * n, 1]);
    c["domains"][0]["initial_velocity"]["sine"]["amplitude"] = json!([v0, 0.0]);
    c["analysis"]["time_step"] = json!(0.1 / n as f64);
    c["output"] = json!({ "vtk": false });
    let (sim, h) = run(parse(c));
    let k = common::monitor(&sim, "end_vx");
    let mut crossings = Vec::new();
    for w in h.windows(2) {
        let (a, b) = (w[0].1[k], w[1].1[k]);
        if a > 0.0 && b <= 0.0 {
            crossings.push(w[0].0 + (w[1].0 - w[0].0) * a / (a - b));
        }
    }
    assert_eq!(crossings.len(), 5, "five periods");
    (crossings[4] - crossings[0]) / 4.0
}

/// Benchmark 3, h = 1 / 0.5 / 0.25 m with Δt = 0.1 / 0.05 / 0.025 s: the period's error
/// against 2π/ω₁ = 10 s falls at order 2 (lumped-mass dispersion (kh)²/24 and the
/// trapezoidal rule's (ωΔt)²/12). Measured: 8.4e-4, 2.1e-4, 5.2e-5 (orders 1.99 and 2.03).
///
/// Run at v₀ = 0.01 m/s, a tenth of the benchmark's: the free end then moves ±1.6 cm and no
/// material point leaves its cell at any level. At the benchmark's 0.1 m/s (±16 cm) the
/// outer points cross into the empty cell beyond the bar as soon as h ≤ 0.5 m, and the
/// linear-shape-function MPM loses energy at each crossing (13 % over five periods at
/// h = 0.5 m, 19 % at 0.25 m): the cell-crossing error, which h = 1 m escapes only because
/// its outermost points stay 5 mm inside their cell (docs/validation.md, "What is not validated").
#[test]
fn vibrating_bar_period_converges_at_order_two() {
    let exact = 10.0;
    let periods: Vec<f64> = [1usize, 2, 4].iter().map(|&n| bar_period(n, 0.01)).collect();
    let errors: Vec<f64> = periods.iter().map(|p| (p - exact) / exact).collect();
    for (n, (p, e)) in [1, 2, 4].iter().zip(periods.iter().zip(&errors)) {
        println!(
            "bar h = {} m, Δt = {} s: period {p:.7} s, error {e:.3e} (exact 10 s)",
            1.0 / *n as f64,
            0.1 / *n as f64
        );
    }
    for k in 0..2 {
        assert_order(&format!("bar period error, levels {} and {}", k + 1, k + 2), (errors[k] / errors[k + 1]).log2());
    }
    assert_order("bar period, self-convergence", observed_order([periods[0], periods[1], periods[2]], 2.0));
}
