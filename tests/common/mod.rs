//! Helpers shared by the validation test binaries: load a bundled case, run it to its end
//! time recording the monitors, and report measured vs reference against a tolerance.

#![allow(dead_code)]

use std::path::Path;

use loam::case::Case;
use loam::simulation::Simulation;

/// Monitor history: (time, values in column order) per step, the initial state first.
pub type History = Vec<(f64, Vec<f64>)>;

/// A bundled case from `cases/`.
pub fn case(name: &str) -> Case {
    Case::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("cases").join(name)).expect("bundled case loads")
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

/// Prints measured vs reference and asserts the relative error is within `tolerance`.
pub fn report(what: &str, measured: f64, reference: f64, tolerance: f64) {
    let err = (measured - reference).abs() / reference.abs();
    println!(
        "{what}: measured {measured:.6}, reference {reference:.6}, error {:.3} % (tolerance {:.1} %)",
        err * 100.0,
        tolerance * 100.0
    );
    assert!(err <= tolerance, "{what}: error {err} above {tolerance}");
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
