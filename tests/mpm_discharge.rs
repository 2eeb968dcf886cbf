//! Granular discharge through an orifice (issue #5 item 6, the seed's "GRANUFALL" test):
//! axisymmetric flat-bottomed silos (`cases/discharge_d08.json`, `_d12`, `_d18`) discharge a
//! cohesionless Mohr–Coulomb material through a central opening of diameter D = 8, 12 and
//! 18 mm. The volumetric flow rate is the least-squares slope of the mass in the silo
//! (`material_mass` monitor) over a steady window, divided by the bulk density ρ_b,
//! and is compared with Beverloo's law for a flat-bottomed silo,
//!
//! $$Q = W / ρ_b = C \sqrt{g} \, (D − k d)^{5/2},$$
//!
//! (Beverloo, Leniger & van de Velde 1961, Chem. Eng. Sci. 15, 260–269,
//! doi:10.1016/0009-2509(61)85030-6), here with no grain size (`k d → 0`): the exponent 5/2
//! and the coefficient C. The silos are geometrically similar (R = H = 2.5 D, grid h = D/10),
//! so each has 5 cells across the opening radius and the grid's own `k h` reduction of the
//! opening is the same fraction of D in every case.
//!
//! The flow rate is taken from the mass, not from the points' current volume: the flowing
//! material keeps loosening (points returned to the apex of the cohesionless yield surface
//! expand at zero stress and never re-compact), so the volume of the material left in the
//! silo grows by about 2 % over the run, and its rate of change underestimates the outflow by
//! up to 40 %. Beverloo's W is a mass rate and ρ_b the packed bulk density; `silo_volume` is
//! printed for comparison.

mod common;

use common::{case, monitor, run, History};
use loam::case::{Case, MonitorSpec, PointBox};
use loam::simulation::Simulation;

const G: f64 = 9.81;
/// Bulk density of the packed material in every case (kg/m³).
const RHO_B: f64 = 1500.0;
/// The seed's GRANUFALL results (Kratos MPM presentation): opening (m), flow (mL/s).
const SEED: [(f64, f64); 2] = [(0.018, 63.07), (0.008, 7.86)];
/// Tolerance on the flow rate against the seed's at the same opening. The seed's is a
/// continuum MPM of the same silo (C = 0.44 / 0.46) on a grid it does not state; the grid
/// narrows the opening by about k h (k ≈ 1.5 cells, measured below), so Q depends on the
/// resolution as (D − 1.5 h)^{5/2}: 8 instead of 10 cells across the opening lower it by
/// 11 %. 10 % admits the seed's grid within about that; measured: +2.1 % and +4.6 %.
const SEED_TOLERANCE: f64 = 0.10;
/// Beverloo coefficient of the experiments, C = 0.55–0.65 (Beverloo et al. 1961; Nedderman,
/// Tüzün, Savage & Houlsby 1982, Chem. Eng. Sci. 37, 1597, review C = 0.58 ± 0.05), fitted
/// with the grains' empty annulus D − k d. Printed, not asserted: the continuum has no grain
/// size, and the grid's own k h takes its place (C = 0.45–0.48 with it, 0.70 without it).
const C_EXPERIMENTS: (f64, f64) = (0.55, 0.65);
/// Beverloo's exponent 5/2 and the tolerance of the fitted one: the three silos are
/// geometrically similar with h ∝ D, so by dimensional analysis Q ∝ √g D^{5/2} exactly,
/// except for what breaks the similarity — the elastic compliance ρ g D / E (2.25 times
/// larger at 18 mm than at 8 mm) and the step sizes. Both are small effects; 0.15 is twice
/// the departure measured over recent code revisions (2.575–2.597).
const EXPONENT: f64 = 2.5;
const EXPONENT_TOLERANCE: f64 = 0.15;
/// Steady flow: the rates over the two halves of the window agree within this fraction.
/// The mass flow pulses with a period of about 2 √(D/g) (arches forming and breaking over
/// the opening), a third of the window; over half-windows of 3 pulses the means differ by at
/// most 7.7 % in these runs.
const STEADY_TOLERANCE: f64 = 0.10;

/// Least-squares slope of `y(t)`.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mt, my) = points.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let sty: f64 = points.iter().map(|p| (p.0 - mt) * (p.1 - my)).sum();
    let stt: f64 = points.iter().map(|p| (p.0 - mt).powi(2)).sum();
    sty / stt
}

/// Samples `(t, value)` of monitor `name` with `t` in `[from, to]`.
fn window(sim: &Simulation, history: &History, name: &str, from: f64, to: f64) -> Vec<(f64, f64)> {
    let k = monitor(sim, name);
    history.iter().filter(|(t, _)| *t >= from - 1e-12 && *t <= to + 1e-12).map(|(t, v)| (*t, v[k])).collect()
}

/// Measured discharge of one case.
struct Discharge {
    /// Opening diameter (m).
    d: f64,
    /// Flow rate −(dM/dt)/ρ_b over the window (m³/s), and over its two halves.
    q: f64,
    q_halves: (f64, f64),
    /// Rate of change of the points' current volume in the silo, −dV/dt (m³/s).
    q_volume: f64,
    /// Run time (s).
    seconds: f64,
}

/// Runs `name` (opening `d`) and measures the flow from `t = 2 √(D/g)` (the flow has set
/// up) to the end of the run (8 √(D/g)).
fn discharge(name: &str, d: f64) -> Discharge {
    let started = std::time::Instant::now();
    let (sim, history) = run(case(name));
    let seconds = started.elapsed().as_secs_f64();
    let (from, to) = (2.0 * (d / G).sqrt(), sim.time());
    let mid = 0.5 * (from + to);
    let rate = |a, b| -slope(&window(&sim, &history, "silo_mass", a, b)) / RHO_B;
    let q_volume = -slope(&window(&sim, &history, "silo_volume", from, to));
    println!(
        "{name}: {} steps, {} Newton iterations, {seconds:.0} s; window {from:.3}–{to:.3} s",
        sim.stats.steps, sim.stats.iterations
    );
    Discharge { d, q: rate(from, to), q_halves: (rate(from, mid), rate(mid, to)), q_volume, seconds }
}

/// Beverloo coefficient `C = Q / (√g D^{5/2})`.
fn beverloo_c(q: f64, d: f64) -> f64 {
    q / (G.sqrt() * d.powf(2.5))
}

#[test]
#[ignore = "long (about 1.5 min on 2 cores with the suite: four silo runs); LOAM_LONG=1 scripts/test.sh"]
fn discharge_through_orifice_follows_beverloo() {
    let runs: Vec<Discharge> =
        [("discharge_d08.json", 0.008), ("discharge_d12.json", 0.012), ("discharge_d18.json", 0.018)]
            .iter()
            .map(|&(name, d)| discharge(name, d))
            .collect();

    println!("  D (mm) | Q (mL/s) | halves (mL/s) | -dV/dt (mL/s) | C     | seed Q (mL/s) | seed C | run (s)");
    for r in &runs {
        let seed = SEED.iter().find(|s| (s.0 - r.d).abs() < 1e-9);
        println!(
            "  {:6.0} | {:8.2} | {:6.2} {:6.2} | {:13.2} | {:.3} | {:>13} | {:>6} | {:.0}",
            r.d * 1e3,
            r.q * 1e6,
            r.q_halves.0 * 1e6,
            r.q_halves.1 * 1e6,
            r.q_volume * 1e6,
            beverloo_c(r.q, r.d),
            seed.map_or("—".to_string(), |s| format!("{:.2}", s.1)),
            seed.map_or("—".to_string(), |s| format!("{:.3}", beverloo_c(s.1 * 1e-6, s.0))),
            r.seconds
        );
    }

    // (a) steady: the two halves of the window give the same rate
    for r in &runs {
        let spread = (r.q_halves.0 - r.q_halves.1).abs() / r.q;
        println!(
            "D = {:.0} mm: halves differ by {:.1} % (tolerance {:.0} %)",
            r.d * 1e3,
            spread * 100.0,
            STEADY_TOLERANCE * 100.0
        );
        assert!(spread <= STEADY_TOLERANCE, "D = {} m: unsteady flow {:?}", r.d, r.q_halves);
    }

    // (b) Beverloo's exponent: least squares of ln Q against ln D
    let logs: Vec<(f64, f64)> = runs.iter().map(|r| (r.d.ln(), r.q.ln())).collect();
    let exponent = slope(&logs);
    let seed_exponent = (SEED[0].1 / SEED[1].1).ln() / (SEED[0].0 / SEED[1].0).ln();
    println!(
        "fitted exponent of Q ∝ D^n: n = {exponent:.3} (Beverloo {EXPONENT} ± {EXPONENT_TOLERANCE}; seed's two openings: {seed_exponent:.3})"
    );
    assert!((exponent - EXPONENT).abs() <= EXPONENT_TOLERANCE, "exponent {exponent}");

    // (c) the seed's flow rates at 8 and 18 mm; Beverloo's coefficient printed
    for r in &runs {
        let c = beverloo_c(r.q, r.d);
        println!(
            "D = {:.0} mm: C = {c:.3} (experiments {:.2}–{:.2}, with the grains' k d; not asserted)",
            r.d * 1e3,
            C_EXPERIMENTS.0,
            C_EXPERIMENTS.1
        );
        if let Some(seed) = SEED.iter().find(|s| (s.0 - r.d).abs() < 1e-9) {
            let err = r.q * 1e6 / seed.1 - 1.0;
            println!(
                "D = {:.0} mm: Q = {:.2} mL/s, seed's GRANUFALL {:.2} mL/s, {:+.1} % (tolerance {:.0} %)",
                r.d * 1e3,
                r.q * 1e6,
                seed.1,
                100.0 * err,
                100.0 * SEED_TOLERANCE
            );
            assert!(err.abs() <= SEED_TOLERANCE, "D = {} m: Q {} vs the seed's {}", r.d, r.q, seed.1);
        }
    }

    // The grid's share of the opening: the 12 mm silo again with h = D/6 (3 cells across the
    // opening radius instead of 5). Beverloo's empty annulus D − k d becomes D − k h, so
    // (Q_coarse / Q_fine)^{2/5} = (D − k h_coarse) / (D − k h_fine) gives k, and C without
    // the grid's reduction is C (1 − k h/D)^{−5/2}.
    let coarse = discharge("discharge_d12_coarse.json", 0.012);
    let fine = &runs[1];
    let (h_fine, h_coarse) = (fine.d / 10.0, fine.d / 6.0);
    let ratio = (coarse.q / fine.q).powf(0.4);
    let k = fine.d * (1.0 - ratio) / (h_coarse - ratio * h_fine);
    let c_continuum = beverloo_c(fine.q, fine.d) / (1.0 - k * h_fine / fine.d).powf(2.5);
    println!(
        "D = 12 mm, h = D/6: Q = {:.2} mL/s (halves {:.2}, {:.2}), C = {:.3}; h = D/10: Q = {:.2} mL/s, C = {:.3}",
        coarse.q * 1e6,
        coarse.q_halves.0 * 1e6,
        coarse.q_halves.1 * 1e6,
        beverloo_c(coarse.q, coarse.d),
        fine.q * 1e6,
        beverloo_c(fine.q, fine.d)
    );
    println!(
        "grid reduction of the opening: k = {k:.2} cells (Beverloo's empty annulus: k = 1.4 grain diameters); C without it: {c_continuum:.3}"
    );
    // The coarser grid narrows the opening, by about a cell width like the grains' annulus
    // (k = 1–3 in the experiments Nedderman et al. 1982 review).
    assert!(coarse.q < fine.q, "the coarser grid must narrow the opening");
    assert!(k > 0.0 && k < 3.0, "k = {k}");
}

/// The `material_volume` and `material_mass` monitors on the 8 mm silo at the start: the
/// revolved volume π r² z of the points in a box, and ρ_b times it; boxes cut along cell
/// lines (2×2 Gauss points integrate 2πr exactly on each cell); bad boxes name their path.
#[test]
fn material_volume_and_mass_monitors() {
    let (r, h) = (0.020, 0.020);
    let boxed = |name: &str, volume: bool, min: [f64; 2], max: [f64; 2]| {
        let within = Some(PointBox { min: min.to_vec(), max: max.to_vec() });
        let name = name.to_string();
        if volume {
            MonitorSpec::MaterialVolume { name, within }
        } else {
            MonitorSpec::MaterialMass { name, within }
        }
    };
    let mut c = case("discharge_d08.json");
    c.monitors.push(MonitorSpec::MaterialVolume { name: "all_volume".into(), within: None });
    c.monitors.push(boxed("core_volume", true, [0.0, 0.0], [0.4 * r, h]));
    c.monitors.push(boxed("core_mass", false, [0.0, 0.0], [0.4 * r, h]));
    c.monitors.push(boxed("lower_volume", true, [0.0, 0.0], [r, 0.4 * h]));
    c.monitors.push(boxed("empty_volume", true, [0.0, -0.003], [r, -0.001]));
    let sim = Simulation::new(c).expect("case builds");
    let values = sim.monitor_values();
    let value = |name: &str| values[monitor(&sim, name)];
    let pi = std::f64::consts::PI;
    let checks = [
        ("silo_volume", pi * r * r * h),
        ("silo_mass", RHO_B * pi * r * r * h),
        ("all_volume", pi * r * r * h),
        ("core_volume", pi * (0.4 * r).powi(2) * h),
        ("core_mass", RHO_B * pi * (0.4 * r).powi(2) * h),
        ("lower_volume", pi * r * r * 0.4 * h),
    ];
    for (name, exact) in checks {
        let v = value(name);
        println!("{name}: {v:.6e}, exact {exact:.6e}");
        assert!((v - exact).abs() <= 1e-12 * exact, "{name}: {v} vs {exact}");
    }
    assert_eq!(value("empty_volume"), 0.0);

    let bad = |edit: &dyn Fn(&mut serde_json::Value), path: &str| {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/discharge_d08.json");
        let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        edit(&mut json);
        let err = Case::parse(&json.to_string()).and_then(Simulation::new).err().expect("bad input is an error");
        println!("{err}");
        assert!(err.to_string().starts_with(path), "error should name {path}: {err}");
    };
    use serde_json::json;
    bad(&|j| j["monitors"][0]["box"]["min"] = json!([0.0, 0.0, 0.0]), "monitors[0].box.min");
    bad(&|j| j["monitors"][1]["box"]["max"] = json!([-0.01, 0.1]), "monitors[1].box.max[0]");
    // the unknown key named at its own path inside the tagged monitor (issue 16)
    bad(&|j| j["monitors"][1]["box"]["lower"] = json!([0.0, 0.0]), "monitors[1].box.lower: unknown field `lower`");
    let mut fem = case("cantilever_fem.json");
    fem.monitors.push(MonitorSpec::MaterialMass { name: "m".into(), within: None });
    let err = Simulation::new(fem).err().expect("no material points is an error");
    println!("{err}");
    assert!(err.to_string().contains(".type: the model has no material points"), "{err}");
}
