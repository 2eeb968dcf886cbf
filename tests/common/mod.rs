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
