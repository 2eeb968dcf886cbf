//! Issue 25, item 5: a flexible barrier hit by a granular flow (`cases/barrier_impact.json`).
//! The Bui et al. (2008) aluminium bars (Mohr–Coulomb φ = 19.8°, c = 0, ψ = 0) slide down a
//! chute inclined α = 30° (gravity tilted, the grid axis-aligned, Coulomb basal friction
//! μ_b = tan φ) and hit a rubber cantilever barrier (FEM, Neo-Hookean, E = 1 MPa) standing
//! normal to the base, through non-conforming Coulomb contact on an unmoved grid; the flow
//! overtops it and what passes leaves the grid. At rest the tests check, against closed forms:
//!
//! - the barrier's equilibrium: the soil's force on it (`impact_force_*`), its own weight and
//!   the clamp reaction (`clamp_reaction_*`) add up to zero (1 % of the force the clamp
//!   carries, each component);
//! - its tip deflection (`barrier_tip_x`) against a Timoshenko cantilever (plane strain)
//!   loaded by the measured contact tractions, point by point, and its own weight (10 %);
//! - no material point inside the barrier;
//! - the retained deposit (`retained_volume`, `retained_mass`: the points upstream of the
//!   barrier): no more than released, and at least the triangle behind a filled barrier whose
//!   surface stands at the friction angle, `½ H² / tan(α − φ)` (the steepest deposit at rest).

mod common;

use common::{case_json, last, monitor, parse, report, run, History};
use loam::simulation::Simulation;

/// Gravity (m/s²) and the chute's inclination α.
const G: f64 = 9.81;
const ALPHA_DEG: f64 = 30.0;

/// The barrier of a barrier case: where it stands and what it is made of, read from the
/// case's JSON (the `barrier` mesh rectangle and the `rubber` material).
struct Barrier {
    /// Upstream face x (m), foot y (m), thickness t (m), height H (m).
    x: f64,
    y0: f64,
    t: f64,
    h: f64,
    /// Elements across its thickness and along its height.
    cells: [f64; 2],
    young: f64,
    poisson: f64,
    density: f64,
}

impl Barrier {
    fn of(json: &serde_json::Value) -> Self {
        let rect = &json["domains"][1]["mesh"]["rectangle"];
        let rubber = &json["materials"]["rubber"];
        let f = |v: &serde_json::Value| v.as_f64().expect("a number");
        Self {
            x: f(&rect["origin"][0]),
            y0: f(&rect["origin"][1]),
            t: f(&rect["size"][0]),
            h: f(&rect["size"][1]),
            cells: [f(&rect["cells"][0]), f(&rect["cells"][1])],
            young: f(&rubber["young_modulus"]),
            poisson: f(&rubber["poisson_ratio"]),
            density: f(&rubber["density"]),
        }
    }

    /// Plane-strain bending stiffness per unit width `D = E t³ / (12 (1 − ν²))` (N m).
    fn bending(&self) -> f64 {
        self.young * self.t.powi(3) / (12.0 * (1.0 - self.poisson * self.poisson))
    }

    /// Shear stiffness per unit width `κ G t`, κ = 5/6, `G = E / (2 (1 + ν))` (N).
    fn shear(&self) -> f64 {
        5.0 / 6.0 * self.young / (2.0 * (1.0 + self.poisson)) * self.t
    }

    /// Tip deflection (m) of the Timoshenko cantilever of length L = H clamped at its foot:
    /// a force P normal to it at height a gives `P a² (3L − a) / (6 D) + P a / (κ G t)`, a
    /// moment M (turning it the same way) `M a (2L − a) / (2 D)`, a uniform load q
    /// `q L⁴ / (8 D) + q L² / (2 κ G t)` (Timoshenko & Gere 1972).
    fn tip(&self, forces: &[(f64, f64, f64)], q: f64) -> f64 {
        let (l, d, s) = (self.h, self.bending(), self.shear());
        let from_points: f64 = forces
            .iter()
            .map(|&(a, p, m)| p * a * a * (3.0 * l - a) / (6.0 * d) + p * a / s + m * a * (2.0 * l - a) / (2.0 * d))
            .sum();
        from_points + q * l.powi(4) / (8.0 * d) + q * l * l / (2.0 * s)
    }
}

/// The contact points of interface `name` at the committed state: position and the force
/// `w T` (N per unit width) each carries. The points come in pairs, two Gauss points per
/// facet; a facet's weight is half its reference length (`w = L₀/2`): `face` on the
/// barrier's faces (along y), `top` on its top (along x), told apart by the pair's direction.
fn contact_forces(sim: &Simulation, name: &str, face: f64, top: f64) -> Vec<([f64; 2], [f64; 2])> {
    let m = &sim.model;
    let out = m
        .domains
        .iter()
        .flat_map(|d| d.outputs(&m.committed, false))
        .find(|o| o.name == name)
        .expect("the interface's point cloud")
        .output;
    let traction = &out.point_fields.iter().find(|f| f.name == "traction").expect("traction").values;
    let mut forces = Vec::new();
    for pair in 0..out.points.len() / 2 {
        let (a, b) = (out.points[2 * pair], out.points[2 * pair + 1]);
        let w = 0.5 * if (b[0] - a[0]).abs() > (b[1] - a[1]).abs() { top } else { face };
        for p in [2 * pair, 2 * pair + 1] {
            let x = out.points[p];
            forces.push(([x[0], x[1]], [w * traction[3 * p], w * traction[3 * p + 1]]));
        }
    }
    forces
}

/// History of monitor `name`: (time, value).
fn series(sim: &Simulation, h: &History, name: &str) -> Vec<(f64, f64)> {
    let k = monitor(sim, name);
    h.iter().map(|r| (r.0, r.1[k])).collect()
}

/// Largest value of a history and its time.
fn peak(s: &[(f64, f64)]) -> (f64, f64) {
    s.iter().fold((0.0, f64::MIN), |b, &(t, v)| if v > b.1 { (t, v) } else { b })
}

/// Largest mean of a history over `window` s (a running mean of the step values: the contact
/// force of single steps scatters), and the window's end time.
fn peak_mean(s: &[(f64, f64)], window: f64) -> (f64, f64) {
    let mut best = (0.0, f64::MIN);
    let mut start = 0;
    for end in 1..s.len() {
        while s[end].0 - s[start].0 > window {
            start += 1;
        }
        if s[end].0 - s[start].0 >= 0.9 * window {
            // trapezoidal mean over [t_start, t_end]
            let integral: f64 = s[start..=end].windows(2).map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0)).sum();
            let mean = integral / (s[end].0 - s[start].0);
            if mean > best.1 {
                best = (s[end].0, mean);
            }
        }
    }
    best
}

/// Mean of monitor `name` over the last `window` seconds of the run (trapezoidal rule): a
/// force at rest without the residual vibration of the barrier, whose own period (about
/// 3 ms) the window of `analysis.stop_at_rest` (0.05 s) spans many times.
fn rest_mean(sim: &Simulation, h: &History, name: &str, window: f64) -> f64 {
    let s = series(sim, h, name);
    let t_end = s.last().unwrap().0;
    let tail: Vec<&(f64, f64)> = s.iter().filter(|r| r.0 >= t_end - window).collect();
    let integral: f64 = tail.windows(2).map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0)).sum();
    integral / (tail.last().unwrap().0 - tail[0].0)
}

/// Runs a barrier case to rest and checks it (see the module doc); `label` names it.
fn check_barrier(json: serde_json::Value, label: &str) {
    let b = Barrier::of(&json);
    let (sin, cos) = ALPHA_DEG.to_radians().sin_cos();
    let phi = json["materials"]["aluminium_bars"]["friction_angle"].as_f64().expect("φ").to_radians();
    let wall = std::time::Instant::now();
    let (sim, h) = run(parse(json));
    println!(
        "{label}: at rest {} at t = {:.3} s after {} steps, {} Newton iterations, {} step cuts, {:.1} s",
        sim.at_rest,
        sim.time(),
        sim.stats.steps,
        sim.stats.iterations,
        sim.stats.cuts,
        wall.elapsed().as_secs_f64()
    );
    assert!(sim.at_rest, "{label}: the flow comes to rest");

    // the impact: force and tip histories (printed, not asserted)
    let force = series(&sim, &h, "impact_force_x");
    let tip = series(&sim, &h, "barrier_tip_x");
    let (t_peak, f_peak) = peak(&force);
    let (t_mean, f_mean) = peak_mean(&force, 0.01);
    let (t_tip, tip_peak) = peak(&tip);
    let (f_x, f_y) = (last(&sim, &h, "impact_force_x"), last(&sim, &h, "impact_force_y"));
    let tip_rest = last(&sim, &h, "barrier_tip_x");
    println!(
        "{label}: impact force along the chute: one-step peak {f_peak:.1} N/m at {t_peak:.3} s, peak of its 10 ms mean \
         {f_mean:.1} N/m ending at {t_mean:.3} s, at rest {f_x:.2} N/m (normal to the chute {f_y:.2} N/m)"
    );
    println!(
        "{label}: barrier tip along the chute: peak {:.3} mm at {t_tip:.3} s, at rest {:.3} mm",
        tip_peak * 1e3,
        tip_rest * 1e3
    );

    // equilibrium of the barrier at rest: soil force + weight + clamp reaction = 0, each the
    // mean over the window in which the run was judged at rest
    let window = 0.05;
    let rest = |name: &str| rest_mean(&sim, &h, name, window);
    let (f_x, f_y) = (rest("impact_force_x"), rest("impact_force_y"));
    let weight = b.density * b.t * b.h * G;
    let (w_x, w_y) = (weight * sin, -weight * cos);
    report(
        &format!(
            "{label}: at rest (means over the last {window} s), minus the clamp reaction vs soil force + barrier weight along the chute [N/m]"
        ),
        -rest("clamp_reaction_x"),
        f_x + w_x,
        0.01,
    );
    // normal to the chute the soil's friction and the weight nearly cancel: that component's
    // error is measured against the resultant the clamp carries
    let (r_y, resultant) = (-rest("clamp_reaction_y"), (f_x + w_x).hypot(f_y + w_y));
    let error = (r_y - (f_y + w_y)).abs() / resultant;
    println!(
        "{label}: at rest, minus the clamp reaction vs soil force + barrier weight normal to the chute [N/m]: measured \
         {r_y:.6}, reference {:.6}, error {:.3} % of the resultant {resultant:.3} N/m (tolerance 1.0 %)",
        f_y + w_y,
        100.0 * error
    );
    assert!(error <= 0.01, "{label}: the barrier is not in equilibrium normal to the chute");

    // the tip deflection against the Timoshenko cantilever under the measured tractions
    let points = contact_forces(&sim, "barrier_contact", b.h / b.cells[1], b.t / b.cells[0]);
    let sum = points.iter().fold([0.0; 2], |s, (_, f)| [s[0] + f[0], s[1] + f[1]]);
    let f_last = last(&sim, &h, "impact_force_x");
    report(&format!("{label}: Σ w T of the contact points vs impact_force_x [N/m]"), sum[0], f_last, 0.01);
    let centre = b.x + 0.5 * b.t;
    let loads: Vec<(f64, f64, f64)> = points
        .iter()
        .map(|&(x, f)| {
            let a = (x[1] - b.y0).clamp(0.0, b.h);
            // the axis at this height (deflected roughly as (a/H)² of the tip), and the arm of
            // the force along the barrier about it: ∓t/2 on the faces, its place on the top
            let axis = centre + tip_rest * (a / b.h).powi(2);
            let on_top = x[1] > b.y0 + b.h - 0.25 * b.t;
            let arm = if on_top { x[0] - (centre + tip_rest) } else { (x[0] - axis).signum() * 0.5 * b.t };
            // a force f_y at arm e turns the barrier by −e f_y (clockwise = towards +x)
            (a, f[0], -arm * f[1])
        })
        .collect();
    let reference = b.tip(&loads, b.density * b.t * G * sin);
    let arm = loads.iter().map(|l| l.0 * l.1).sum::<f64>() / loads.iter().map(|l| l.1).sum::<f64>();
    println!(
        "{label}: {} contact points carry {:.2} N/m along the chute at {:.1} mm above the foot ({:.2} H)",
        points.len(),
        sum[0],
        arm * 1e3,
        arm / b.h
    );
    report(
        &format!("{label}: barrier tip at rest vs Timoshenko cantilever under the measured contact tractions [m]"),
        tip_rest,
        reference,
        0.10,
    );

    // no soil inside the barrier
    let corners = [[b.x, b.y0], [b.x + b.t, b.y0], [b.x + b.t, b.y0 + b.h], [b.x, b.y0 + b.h]];
    let inside = common::points_inside_structure(&sim, corners, 1e-3);
    println!("{label}: material points inside the barrier (more than 1 mm from its faces): {inside}");
    assert_eq!(inside, 0, "{label}: soil entered the barrier");

    // the retained deposit
    let released = series(&sim, &h, "retained_mass")[0].1;
    let (retained, volume) = (last(&sim, &h, "retained_mass"), last(&sim, &h, "retained_volume"));
    let density = retained / volume;
    let top = b.h + last(&sim, &h, "barrier_tip_y");
    let triangle = 0.5 * top * top / (ALPHA_DEG.to_radians() - phi).tan();
    let deposit = last(&sim, &h, "deposit_height");
    println!(
        "{label}: retained {retained:.3} of {released:.3} kg/m ({:.1} %), volume {volume:.6} m² (mean density {density:.0} \
         kg/m³; at the released density {:.6} m²); deposit {:.1} mm high at the barrier ({:.1} mm)",
        100.0 * retained / released,
        retained / 2650.0,
        deposit * 1e3,
        top * 1e3
    );
    println!(
        "{label}: retained volume {volume:.6} m² vs the triangle at the friction angle behind the filled barrier \
         ½ H²/tan(α − φ) = {triangle:.6} m² (ratio {:.3}, at least 1 asserted; at the released density {:.3})",
        volume / triangle,
        retained / 2650.0 / triangle
    );
    assert!(retained > 0.0 && retained <= released, "{label}: retained {retained} kg/m of {released}");
    assert!(deposit >= top, "{label}: the deposit reaches the barrier's top ({deposit} m, top {top} m)");
    assert!(volume >= triangle, "{label}: the deposit {volume} m² is smaller than the steepest one {triangle} m²");
}

/// The barrier case on a grid twice as coarse (h = 10 mm, 400 points), for the default suite
/// (about 7 s): the same checks as the full case.
#[test]
fn barrier_impact_coarse() {
    let mut json = case_json("barrier_impact.json");
    json["domains"][0]["grid"]["cells"] = serde_json::json!([40, 10]);
    json["domains"][0]["material_points"]["cells"]["mesh"]["rectangle"]["cells"] = serde_json::json!([20, 5]);
    json["output"] = serde_json::json!({ "vtk": false });
    check_barrier(json, "barrier_impact, h = 10 mm");
}

/// The bundled case (`cases/barrier_impact.json`, h = 5 mm, 1 600 points): about 65 s on one
/// thread. Long: `LOAM_LONG=1 scripts/test.sh`.
#[test]
#[ignore = "long: the barrier case to rest (about 65 s); LOAM_LONG=1 scripts/test.sh runs it"]
fn barrier_impact() {
    let mut json = case_json("barrier_impact.json");
    json["output"] = serde_json::json!({ "vtk": false });
    check_barrier(json, "barrier_impact");
}
