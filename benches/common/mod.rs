//! Shared by the MPM benchmarks: time a number of steps of a built simulation in a local
//! rayon pool and print the per-step phase split as a Markdown table.

use std::time::Instant;

use loam::simulation::Simulation;
use loam_fem::model::PhaseTimings;

/// Timings of `steps` consecutive steps of one run.
pub struct StepTiming {
    /// Row label (case, discretisation).
    pub label: String,
    /// Material points.
    pub points: usize,
    /// Threads of the rayon pool.
    pub threads: usize,
    /// Steps timed.
    pub steps: usize,
    /// Newton iterations in them.
    pub iterations: usize,
    /// Wall time of the timed steps (s).
    pub wall: f64,
    /// Phase split of the timed steps.
    pub timings: PhaseTimings,
    /// Extra columns (e.g. a monitor value), already formatted.
    pub extra: Vec<String>,
}

/// Runs `warm_up` steps, then times `steps` steps (all inside a pool of `threads` threads;
/// faer runs sequentially, see `main` of each benchmark). Steps that fail end the run early;
/// the timing covers the steps done.
pub fn time_steps(
    sim: &mut Simulation,
    label: &str,
    points: usize,
    threads: usize,
    warm_up: usize,
    steps: usize,
) -> StepTiming {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    pool.install(|| {
        let t = Instant::now();
        for _ in 0..warm_up {
            sim.step().expect("warm-up step converges");
        }
        let warm = t.elapsed().as_secs_f64();
        let before = sim.stats.clone();
        let t = Instant::now();
        let mut done = 0;
        while done < steps && !sim.finished() {
            sim.step().expect("step converges");
            done += 1;
        }
        let wall = t.elapsed().as_secs_f64();
        let timings = sim.stats.timings - before.timings;
        let iterations = sim.stats.iterations - before.iterations;
        eprintln!(
            "  {label}, {points} points, {threads} thread(s): warm-up {warm:.3} s, {done} steps {wall:.3} s, {iterations} iterations, {} pattern builds",
            timings.pattern_builds
        );
        StepTiming { label: label.into(), points, threads, steps: done, iterations, wall, timings, extra: Vec::new() }
    })
}

/// Prints the rows as a Markdown table: milliseconds per step by phase (per Newton iteration in
/// parentheses for assembly and the linear solver), material-point updates per second, then
/// the extra columns named `extra_headers`.
pub fn print_table(rows: &[StepTiming], extra_headers: &[&str]) {
    println!();
    println!("Milliseconds per step (mean over the timed steps); per Newton iteration in parentheses.");
    println!();
    let extra: String = extra_headers.iter().map(|h| format!(" {h} |")).collect();
    let rule: String = extra_headers.iter().map(|_| "---:|").collect();
    println!("| case | points | threads | iter/step | step | initialisation | pattern + symbolic | assembly | factorisation + solve | convective | other | MP updates/s |{extra}");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|{rule}");
    for r in rows {
        let s = r.steps.max(1) as f64;
        let it = r.iterations.max(1) as f64;
        let ms = |x: f64| 1e3 * x / s;
        let t = &r.timings;
        let pattern = t.pattern + t.symbolic;
        let fs = t.factorisation - t.symbolic + t.solve;
        let other = r.wall - (t.search + t.pattern + t.assembly + t.factorisation + t.solve + t.commit);
        let extra: String = r.extra.iter().map(|v| format!(" {v} |")).collect();
        println!(
            "| {} | {} | {} | {:.1} | {:.3} | {:.3} | {:.3} ({} builds) | {:.3} ({:.3}) | {:.3} ({:.3}) | {:.3} | {:.3} | {:.3e} |{extra}",
            r.label,
            r.points,
            r.threads,
            it / s,
            ms(r.wall),
            ms(t.search),
            ms(pattern),
            t.pattern_builds,
            ms(t.assembly),
            1e3 * t.assembly / it,
            ms(fs),
            1e3 * fs / it,
            ms(t.commit),
            ms(other),
            r.points as f64 * s / r.wall,
        );
    }
}
