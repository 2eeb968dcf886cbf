//! Benchmark 8: non-cohesive column collapse against the aluminium-bar experiment of Bui et
//! al. (2008), on quadrilateral and triangular grids. The runs end at rest
//! (`analysis.stop_at_rest`); the final runout, height at the wall, free surface and failure
//! line are compared with the digitised experiment in `tests/data/bui2008/`.

mod common;

use std::path::Path;

use common::{case, last, report, run};
use loam::monitor::point_extents;
use loam::simulation::Simulation;
use loam_fem::domain::PointQuantity;
use loam_mpm::surface::SurfaceProfile;

/// Experiment: runout (surface below 2 mm) and height at the wall (m).
const RUNOUT: f64 = 0.42;
const HEIGHT_AT_WALL: f64 = 0.099;
/// RMS of the vertical distance between the final surface and the experiment's (m): 5 % of
/// the column height, a few times the digitising error of the data.
const SURFACE_RMS_TOLERANCE: f64 = 0.005;
/// Failure-line inclination tolerance (degrees).
const ANGLE_TOLERANCE: f64 = 5.0;

fn read_xy(name: &str) -> Vec<(f64, f64)> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bui2008").join(name);
    std::fs::read_to_string(&path)
        .expect("experiment data present")
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut it = l.split(',').map(|v| v.trim().parse::<f64>().expect("number"));
            (it.next().expect("x"), it.next().expect("y"))
        })
        .collect()
}

/// Least-squares line `y = a + b x`: returns `(a, b)`.
fn fit_line(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (sx, sy) = points.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
    let (mx, my) = (sx / n, sy / n);
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let b = sxy / sxx;
    (my - b * mx, b)
}

/// The failure line of the final state: in each row of initial heights (2.5 mm bands), the
/// last point of the contiguous unmoved stretch from the wall (displacement below 2 mm), at
/// its initial position; then the least-squares line through them.
fn failure_line(sim: &Simulation) -> (f64, f64) {
    let band = 0.0025;
    let mut rows: std::collections::BTreeMap<i64, Vec<(f64, f64)>> = Default::default();
    for d in &sim.model.domains {
        for id in d.points_in_box(&[f64::MIN, f64::MIN], &[f64::MAX, f64::MAX]) {
            let x = d.point_quantity(id, PointQuantity::Position).expect("position");
            let u = d.point_quantity(id, PointQuantity::Displacement).expect("displacement");
            let (x0, y0) = (x[0] - u[0], x[1] - u[1]);
            rows.entry((y0 / band).floor() as i64).or_default().push((x0, u[0].hypot(u[1])));
        }
    }
    let mut line = Vec::new();
    for (row, mut pts) in rows {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let unmoved = pts.iter().take_while(|p| p.1 < 0.002).last();
        if let Some(p) = unmoved {
            line.push((p.0, (row as f64 + 0.5) * band));
        }
    }
    fit_line(&line)
}

fn collapse(case_name: &str) {
    let (sim, history) = run(case(case_name));
    println!("{case_name}: {} steps, ended at t = {:.3} s", sim.stats.steps, sim.time());
    assert!(sim.at_rest, "{case_name}: the column must come to rest before the end time");
    report(&format!("{case_name} runout"), last(&sim, &history, "runout"), RUNOUT, 0.12);
    report(&format!("{case_name} height at the wall"), last(&sim, &history, "height_at_wall"), HEIGHT_AT_WALL, 0.10);

    let extents = point_extents(&sim.model);
    let surface = SurfaceProfile::new(&extents, 0.0);
    let rms = surface.rms_distance(&read_xy("surface.csv"));
    println!(
        "{case_name} final surface: RMS distance from the experiment {:.2} mm (tolerance {:.1} mm)",
        rms * 1e3,
        SURFACE_RMS_TOLERANCE * 1e3
    );
    assert!(rms <= SURFACE_RMS_TOLERANCE, "surface RMS {rms}");

    let (a_exp, b_exp) = fit_line(&read_xy("failure.csv"));
    let (a, b) = failure_line(&sim);
    let (angle_exp, angle) = ((-b_exp).atan().to_degrees(), (-b).atan().to_degrees());
    println!(
        "{case_name} failure line: {angle:.1}° from the horizontal, meets the base at x = {:.3} m; experiment {angle_exp:.1}°, x = {:.3} m (tolerance {ANGLE_TOLERANCE}°)",
        -a / b,
        -a_exp / b_exp
    );
    assert!((angle - angle_exp).abs() <= ANGLE_TOLERANCE, "failure line angle {angle} vs {angle_exp}");
}

#[test]
fn bui2008_collapse_quadrilateral_grid() {
    collapse("collapse_bui2008_quad.json");
}

#[test]
fn bui2008_collapse_triangular_grid() {
    collapse("collapse_bui2008_tri.json");
}
