//! `loam`: run, check and explore Loam case files.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use loam::case::CaseError;
use loam::run::{default_out_dir, run, RunEnd};
use loam::simulation::Simulation;

/// Implicit MPM and Lagrangian FEM for large-deformation solid and soil mechanics.
#[derive(Parser)]
#[command(name = "loam", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Package a case as an FMI 3.0 co-simulation FMU (inputs and outputs from its fmu section).
    Fmu {
        /// The case file (JSON).
        case: PathBuf,
        /// The FMU to write (default <case name>.fmu).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// The loam-fmu shared library (default: next to the loam executable).
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// Run a case file and write VTK results and monitors.csv.
    Run {
        /// The case file (JSON).
        case: PathBuf,
        /// Output directory (default out/<case name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Check a case file (parse, parameters, mesh, regions) without running it.
    Check {
        /// The case file (JSON).
        case: PathBuf,
    },
    /// Drive one material point of a law along a laboratory path and write path.csv.
    Law {
        /// The path file (JSON), e.g. cases/laws/mc_triaxial_drained.json.
        path: PathBuf,
        /// Output directory (default out/<path name>).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

fn bad_input(e: &CaseError) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    faer::set_global_parallelism(faer::Par::Seq);
    match cli.command {
        Command::Check { case } => match Simulation::from_file(&case) {
            Ok(sim) => {
                println!(
                    "{}: ok — {} nodes, {} domains, {} DOFs, {} steps, monitors: {}",
                    case.display(),
                    sim.model.coords.len(),
                    sim.model.domains.len(),
                    sim.model.num_dofs(),
                    sim.total_steps(),
                    sim.monitor_names().join(", ")
                );
                let measure = if sim.model.dim == 2 { ("length", "m") } else { ("area", "m²") };
                for i in &sim.interfaces {
                    println!(
                        "  interface '{}': {}, {} nodes, {} {:.6} {}",
                        i.name,
                        if i.slip { "frictionless slip" } else { "tied" },
                        i.nodes,
                        measure.0,
                        i.measure,
                        measure.1
                    );
                }
                ExitCode::SUCCESS
            }
            Err(e) => bad_input(&e),
        },
        Command::Run { case, out, threads, quiet } => {
            if threads == Some(0) {
                eprintln!("error: --threads must be at least 1");
                return ExitCode::from(2);
            }
            // the whole run inside the pool: parallel loops called from one of its threads
            // run there, without waking a worker and sleeping on every call (which cost about
            // 1 ms per step at 448 material points)
            match rayon::ThreadPoolBuilder::new().num_threads(threads.unwrap_or(0)).build() {
                Ok(pool) => pool.install(|| run_case(&case, out, quiet)),
                Err(e) => {
                    eprintln!("error: thread pool: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Fmu { case, output, library } => {
            use loam::fmu_package::{default_library_path, package, PackageError};
            let output = output.unwrap_or_else(|| {
                PathBuf::from(format!("{}.fmu", case.file_stem().unwrap_or_default().to_string_lossy()))
            });
            match package(&case, &output, &library.unwrap_or_else(default_library_path)) {
                Ok(s) => {
                    println!(
                        "loam: wrote {} (FMI 3.0 co-simulation, model identifier {}; inputs: {}; outputs: {})",
                        output.display(),
                        s.model_identifier,
                        if s.inputs.is_empty() { "none".into() } else { s.inputs.join(", ") },
                        s.outputs.join(", ")
                    );
                    ExitCode::SUCCESS
                }
                Err(PackageError::Case(e)) => bad_input(&e),
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Law { path, out } => {
            let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "law".into());
            let out = out.unwrap_or_else(|| default_out_dir(&name));
            match loam_laws::driver::run_path_file(&path, &out) {
                Ok(s) => {
                    println!(
                        "loam: {} ({} rows): peak q = {:.4} kPa, final p = {:.4} kPa, final q = {:.4} kPa; wrote {}",
                        s.law,
                        s.rows,
                        s.peak_q / 1e3,
                        s.final_p / 1e3,
                        s.final_q / 1e3,
                        out.join("path.csv").display()
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    let write_failure = matches!(e, loam_laws::driver::DriverError::Write { .. });
                    ExitCode::from(if write_failure { 1 } else { 2 })
                }
            }
        }
    }
}

/// `loam run`: builds the case, runs it with output to `out` and prints the summary line.
fn run_case(case: &std::path::Path, out: Option<PathBuf>, quiet: bool) -> ExitCode {
    let mut sim = match Simulation::from_file(case) {
        Ok(s) => s,
        Err(e) => return bad_input(&e),
    };
    let out = out.unwrap_or_else(|| default_out_dir(&sim.case.name));
    match run(&mut sim, &out, !quiet) {
        Ok((end, wall)) => {
            let t = &sim.stats.timings;
            let solver = sim.model.solver_timings();
            let gmres = if solver.krylov_iterations > 0 {
                format!(
                    "; {} factorisations, {} solves by GMRES ({} iterations)",
                    solver.factorisations, solver.krylov_solves, solver.krylov_iterations
                )
            } else {
                String::new()
            };
            let blocks = if sim.is_coupled() {
                let b = sim.stats.max_block_residuals;
                format!(
                    "; largest converged residual per block: soil {:.2e}, interface {:.2e}, structure {:.2e}",
                    b.soil, b.interface, b.structure
                )
            } else {
                String::new()
            };
            let summary = format!(
                "{} steps, {} Newton iterations, {} step cuts, wall time {:.3} s (assembly {:.2} s, factorisation {:.2} s, solve {:.2} s{gmres}){blocks}",
                sim.stats.steps, sim.stats.iterations, sim.stats.cuts, wall, t.assembly, t.factorisation, t.solve
            );
            match end {
                RunEnd::Finished => {
                    println!(
                        "loam: finished t = {:.6e} s{}: {summary}; results in {}",
                        sim.time(),
                        if sim.at_rest { " (at rest)" } else { "" },
                        out.display()
                    );
                    ExitCode::SUCCESS
                }
                RunEnd::Failed(e) => {
                    eprintln!(
                        "error: stopped at {e}; results up to t = {:.6e} s written to {} ({summary})",
                        e.time,
                        out.display()
                    );
                    ExitCode::from(1)
                }
            }
        }
        Err(e) => {
            eprintln!("error: writing results to {}: {e}", out.display());
            ExitCode::from(1)
        }
    }
}
