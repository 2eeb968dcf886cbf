//! Helpers shared by the validation test binaries: load a bundled case, run it to its end
//! time recording the monitors, and report measured vs reference against a tolerance.

#![allow(dead_code)]

pub mod cli;

use std::path::Path;

use loam::case::Case;
use loam::simulation::Simulation;
use loam_fem::domain::PointQuantity;

/// Monitor history: (time, values in column order) per step, the initial state first.
pub type History = Vec<(f64, Vec<f64>)>;

/// A bundled case from `cases/`.
pub fn case(name: &str) -> Case {
    Case::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("cases").join(name)).expect("bundled case loads")
}

/// A bundled case from `cases/` as JSON, to be edited through the case-file schema (the
/// public interface) and built with [`parse`].
pub fn case_json(name: &str) -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases").join(name);
    serde_json::from_str(&std::fs::read_to_string(&path).expect("bundled case present")).expect("bundled case is JSON")
}

/// A case from its JSON.
pub fn parse(json: serde_json::Value) -> Case {
    Case::parse(&json.to_string()).expect("case parses")
}

/// Central differences `(R(δ₀ + h e_j) − R(δ₀ − h e_j))/2h` of the residual of a step's
/// nonlinear system, column by column: the dense matrix `∂R_i/∂δ_j` (row-major), for checks
/// of the consistent tangent. `after` sees the system after every evaluation (e.g. to check
/// that an active set did not change).
pub fn residual_differences(
    lin: &mut loam_fem::model::Linearisation<'_>,
    delta0: &[f64],
    h: f64,
    mut after: impl FnMut(&loam_fem::model::Linearisation<'_>),
) -> Vec<f64> {
    let n = delta0.len();
    let mut fd = vec![0.0; n * n];
    for j in 0..n {
        let mut plus = delta0.to_vec();
        plus[j] += h;
        let mut minus = delta0.to_vec();
        minus[j] -= h;
        let (rp, _) = lin.evaluate(&plus).expect("assembles");
        after(lin);
        let (rm, _) = lin.evaluate(&minus).expect("assembles");
        after(lin);
        for i in 0..n {
            fd[i * n + j] = (rp[i] - rm[i]) / (2.0 * h);
        }
    }
    fd
}

/// Runs `case` to its end time.
pub fn run(case: Case) -> (Simulation, History) {
    let mut sim = Simulation::new(case).expect("case builds");
    let mut history = vec![(0.0, sim.monitor_values())];
    while !sim.finished() {
        sim.step().expect("step converges");
        history.push((sim.time(), sim.monitor_values()));
    }
    (sim, history)
}

/// Column of monitor `name`.
pub fn monitor(sim: &Simulation, name: &str) -> usize {
    sim.monitor_names().iter().position(|n| *n == name).expect("monitor exists")
}

/// Last value of monitor `name`.
pub fn last(sim: &Simulation, h: &History, name: &str) -> f64 {
    h.last().unwrap().1[monitor(sim, name)]
}

/// Time-mean force of a plane inclined by `alpha` (rising towards +x) on a body, from the
/// forces `(f_x, f_y)` of the steps: resolved along the plane's normal (into the body) and up
/// the slope.
pub fn mean_plane_force(forces: &[(f64, f64)], alpha: f64) -> (f64, f64) {
    let n = forces.len().max(1) as f64;
    let fx = forces.iter().map(|f| f.0).sum::<f64>() / n;
    let fy = forces.iter().map(|f| f.1).sum::<f64>() / n;
    (-fx * alpha.sin() + fy * alpha.cos(), fx * alpha.cos() + fy * alpha.sin())
}

/// Prints measured vs reference and asserts the relative error is within `tolerance`.
pub fn report(what: &str, measured: f64, reference: f64, tolerance: f64) {
    let err = (measured - reference).abs() / reference.abs();
    let tolerance_text =
        if tolerance >= 1e-3 { format!("{:.1} %", tolerance * 100.0) } else { format!("{tolerance:.0e} relative") };
    println!(
        "{what}: measured {measured:.6}, reference {reference:.6}, error {:.3} % (tolerance {tolerance_text})",
        err * 100.0
    );
    assert!(err <= tolerance, "{what}: error {err} above {tolerance}");
}

/// Distance of a rigid block sliding down an incline of angle α with friction μ under
/// gravity ramped linearly from 0 to g = 9.81 m/s² over `ramp` s:
/// `x(t) = a (t²/2 − t t_r/2 + t_r²/6)`, `a = g (sin α − μ cos α)` (t ≥ t_r; the friction
/// follows the normal force, so the block's acceleration follows the ramp).
pub fn ramped_slide(alpha: f64, mu: f64, ramp: f64, t: f64) -> f64 {
    9.81 * (alpha.sin() - mu * alpha.cos()) * (t * t / 2.0 - t * ramp / 2.0 + ramp * ramp / 6.0)
}

/// Frequency of an oscillation from the downward crossings of its mean.
pub fn frequency(h: &[(f64, f64)]) -> f64 {
    let mean = h.iter().map(|r| r.1).sum::<f64>() / h.len() as f64;
    let mut crossings = Vec::new();
    for w in h.windows(2) {
        let (a, b) = (w[0].1 - mean, w[1].1 - mean);
        if a > 0.0 && b <= 0.0 {
            crossings.push(w[0].0 + (w[1].0 - w[0].0) * a / (a - b));
        }
    }
    assert!(crossings.len() >= 3, "need two periods, got crossings {crossings:?}");
    (crossings.len() - 1) as f64 / (crossings.last().unwrap() - crossings[0])
}

/// Angle (degrees from the horizontal, in [0°, 90°]) of the principal axis of `points`: the
/// direction θ of largest spread, `tan 2θ = 2 S_xy / (S_xx − S_yy)` with the central second
/// moments `S` (a band fitted through its points).
pub fn principal_angle(points: &[[f64; 2]]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |(x, y), p| (x + p[0] / n, y + p[1] / n));
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    (0.5 * (2.0 * sxy).atan2(sxx - syy)).to_degrees().abs()
}

/// Resolution of a fitted shear-band angle (degrees): the band is fitted through cells or
/// points h = 0.05 m apart along a band about 1.4 m long, so an offset of one cell at its
/// ends turns it by atan(0.05 / 1.4) = 2°.
pub const BAND_FIT: f64 = 2.0;

/// Localisation measures of a field `kappa` (accumulated plastic deviatoric strain) at
/// positions `x`: (κ max, κ mean, share of positions with κ > κ_max / 2, angle of that band
/// in degrees by [`principal_angle`]).
pub fn localisation(x: &[[f64; 2]], kappa: &[f64]) -> (f64, f64, f64, f64) {
    let max = kappa.iter().copied().fold(0.0, f64::max);
    let mean = kappa.iter().sum::<f64>() / kappa.len() as f64;
    let band: Vec<[f64; 2]> = x.iter().zip(kappa).filter(|(_, &k)| k > 0.5 * max).map(|(c, _)| *c).collect();
    (max, mean, band.len() as f64 / kappa.len() as f64, principal_angle(&band))
}

/// Peak of the force monitor `name` sign-flipped (compression positive, N/m), its value at
/// the end, and whether the peak lies before the last tenth of the run.
pub fn force_history(sim: &Simulation, h: &History, name: &str) -> (f64, f64, bool) {
    let col = monitor(sim, name);
    let forces: Vec<f64> = h.iter().map(|r| -r.1[col]).collect();
    let (i_peak, peak) = forces.iter().enumerate().fold((0, 0.0), |b, (i, &f)| if f > b.1 { (i, f) } else { b });
    (peak, *forces.last().unwrap(), i_peak < forces.len() * 9 / 10)
}

/// The checks of the Mohr–Coulomb strain-softening biaxial test (φ 30° → 20°, c 20 → 5 kPa,
/// ψ 5° → 0°, unconfined), shared by the FEM and MPM runs: from the platen force history
/// (`peak`, `end`, whether the peak is `interior`) and the [`localisation`] measures over
/// the specimen's `unit`s (cells or points), prints the measured values against the
/// references and asserts: the peak axial stress is the unconfined strength
/// 2c cos φ/(1 − sin φ) = 69.28 kPa within 10 % (the weak corner lowers it); the force
/// falls below 70 % of the peak but stays above the residual strength 14.28 kPa;
/// κ_max ≥ 5 κ_mean with the band (κ > κ_max/2) under 15 % of the specimen; the band angle
/// within 5° of Roscoe's range 45°–47.5°, below Coulomb's 55°–60°.
pub fn check_mc_softening(label: &str, force: (f64, f64, bool), measures: (f64, f64, f64, f64), unit: &str) {
    let ucs = |c: f64, phi: f64| 2.0 * c * phi.to_radians().cos() / (1.0 - phi.to_radians().sin());
    let (peak_strength, residual_strength) = (ucs(20e3, 30.0), ucs(5e3, 20.0));
    let (peak, end, interior) = force;
    let (max, mean, share, angle) = measures;
    println!("MC softening, {label}:");
    println!(
        "  peak axial stress {:.2} kPa (unconfined strength {:.2} kPa, {:+.1} %); at 50 mm {:.2} kPa = {:.0} % of \
         the peak (residual strength {:.2} kPa)",
        peak / 1e3,
        peak_strength / 1e3,
        100.0 * (peak / peak_strength - 1.0),
        end / 1e3,
        100.0 * end / peak,
        residual_strength / 1e3
    );
    println!(
        "  κ max {max:.3}, mean {mean:.4} (ratio {:.1}); band (κ > κ_max/2) {:.1} % of the {unit}; band angle \
         {angle:.1}° (Roscoe 45°–47.5°, Coulomb 55°–60°)",
        max / mean,
        100.0 * share
    );
    assert!(interior, "the force peaks before the end");
    assert!((peak / peak_strength - 1.0).abs() < 0.1, "peak near the unconfined strength");
    assert!(end < 0.7 * peak && end > residual_strength, "softening towards, not below, the residual");
    assert!(max >= 5.0 * mean && share < 0.15, "the strain localises");
    assert!((40.0..=52.5).contains(&angle), "band angle {angle}° outside Roscoe ± 5°");
}

/// Observed order of convergence from three levels refined by `ratio` (h, h/r, h/r²):
/// `p = ln(|u₁ − u₂| / |u₂ − u₃|) / ln r` (self-convergence: no reference needed).
pub fn observed_order(values: [f64; 3], ratio: f64) -> f64 {
    ((values[0] - values[1]).abs() / (values[1] - values[2]).abs()).ln() / ratio.ln()
}

/// Richardson extrapolation of the finest two of three levels with the observed order:
/// `u* = u₃ + (u₃ − u₂) / (r^p − 1)`.
pub fn richardson(values: [f64; 3], ratio: f64) -> f64 {
    let p = observed_order(values, ratio);
    values[2] + (values[2] - values[1]) / (ratio.powf(p) - 1.0)
}

/// Newton convergence orders of one step from its residual norms `r_0, r_1, …` (the last
/// one at the round-off floor: the step ran until its correction was round-off):
///
/// $$ p_k = \frac{\ln(r_{k+1} / r_k)}{\ln(r_k / r_{k-1})} $$
///
/// over the asymptotic iterations: those where the previous iteration already contracted
/// the residual tenfold (`r_k ≤ 0.1 r_{k−1}`: past the global phase) and `r_{k+1}` lies at
/// least ten times above the floor (the last residual), so that round-off does not enter
/// the estimate. Returns `(k, p_k)`. Quadratic convergence gives p → 2; a linearly
/// converging solver gives p = 1 whatever its rate.
pub fn newton_orders(residuals: &[f64]) -> Vec<(usize, f64)> {
    let floor = *residuals.last().expect("residuals");
    (1..residuals.len().saturating_sub(1))
        .filter(|&k| residuals[k] <= 0.1 * residuals[k - 1] && residuals[k + 1] >= 10.0 * floor)
        .map(|k| (k, (residuals[k + 1] / residuals[k]).ln() / (residuals[k] / residuals[k - 1]).ln()))
        .collect()
}

/// The material point of domain 0 that starts nearest to `target`: its reference position
/// `X = x − u` and its displacement `u` (as many components as the model's dimension).
pub fn nearest_point(sim: &Simulation, target: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let d = &sim.model.domains[0];
    let dim = target.len();
    let mut best = (f64::MAX, vec![], vec![]);
    for id in d.points_in_box(&[f64::MIN; 3][..dim], &[f64::MAX; 3][..dim]) {
        let x = d.point_quantity(id, PointQuantity::Position).expect("position");
        let u = d.point_quantity(id, PointQuantity::Displacement).expect("displacement");
        let x0: Vec<f64> = (0..dim).map(|i| x[i] - u[i]).collect();
        let dist = x0.iter().zip(target).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        if dist < best.0 {
            best = (dist, x0, (0..dim).map(|i| u[i]).collect());
        }
    }
    (best.1, best.2)
}

/// Timoshenko deflection (m, downward negative) of benchmark 1's cantilever (L = 7 m,
/// h = b = 1 m, E = 9e7 Pa, ν = 0, ρ g = 9810 N/m³) under its weight at distance `x` from
/// the clamp: Euler–Bernoulli `q x² (6L² − 4Lx + x²)/(24 EI)` plus shear
/// `q (L x − x²/2)/(κ G A)`, κ = 5/6; at x = L: −0.39256 − 0.00641 = −0.39897 m.
pub fn timoshenko(x: f64) -> f64 {
    let (q, ei, kga, l) = (1000.0 * 9.81, 9.0e7 / 12.0, 5.0 / 6.0 * 4.5e7, 7.0);
    -(q * x * x * (6.0 * l * l - 4.0 * l * x + x * x) / (24.0 * ei) + q * (l * x - x * x / 2.0) / kga)
}

/// Euler–Bernoulli part of [`timoshenko`]; −0.39256 m at x = L (BENCHMARKS.md benchmark 1).
pub fn euler_bernoulli(x: f64) -> f64 {
    let (q, ei, l) = (1000.0 * 9.81, 9.0e7 / 12.0, 7.0);
    -(q * x * x * (6.0 * l * l - 4.0 * l * x + x * x) / (24.0 * ei))
}

/// How many material points lie inside an FEM structure's current outline: the convex
/// quadrilateral through its structure nodes nearest to the reference `corners` (counter-
/// clockwise), shrunk by `inset` (m) from each edge (2D).
pub fn points_inside_structure(sim: &Simulation, corners: [[f64; 2]; 4], inset: f64) -> usize {
    let m = &sim.model;
    let current = |n: usize| [m.coords[n][0] + m.committed.u[2 * n], m.coords[n][1] + m.committed.u[2 * n + 1]];
    let structure: Vec<usize> =
        (0..m.coords.len()).filter(|&n| m.roles[n] == loam_fem::dofs::NodeRole::Structure).collect();
    let nearest = |c: [f64; 2]| {
        *structure
            .iter()
            .min_by(|&&a, &&b| {
                let d = |n: usize| (m.coords[n][0] - c[0]).powi(2) + (m.coords[n][1] - c[1]).powi(2);
                d(a).total_cmp(&d(b))
            })
            .expect("the case has an FEM plate")
    };
    points_inside_quadrilateral(sim, corners.map(|c| current(nearest(c))), inset)
}

/// How many material points lie inside the convex quadrilateral `quad` (current corners,
/// counter-clockwise), at least `inset` (m) from each edge (2D).
pub fn points_inside_quadrilateral(sim: &Simulation, quad: [[f64; 2]; 4], inset: f64) -> usize {
    let centre = [quad.iter().map(|q| q[0]).sum::<f64>() / 4.0, quad.iter().map(|q| q[1]).sum::<f64>() / 4.0];
    let inside = |x: [f64; 2]| {
        (0..4).all(|e| {
            let (a, b) = (quad[e], quad[(e + 1) % 4]);
            let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
            let len = (tx * tx + ty * ty).sqrt();
            let side = (tx * (x[1] - a[1]) - ty * (x[0] - a[0])) / len;
            let centre_side = tx * (centre[1] - a[1]) - ty * (centre[0] - a[0]);
            centre_side > 0.0 && side > inset
        })
    };
    loam::monitor::point_extents(&sim.model).iter().filter(|p| inside([p.position[0], p.position[1]])).count()
}
