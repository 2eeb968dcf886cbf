//! `loam run`: the thread pool, the case built (and restored with `--resume`), the run loop
//! ([`crate::run`]) with SIGINT/SIGTERM handling, and the summary line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use loam_fem::ranks::Ranks;

use super::bad_input;
use crate::case::CaseError;
use crate::checkpoint;
use crate::interrupt::Interrupt;
use crate::output::results::ResultWriter;
use crate::run::{default_out_dir, run, RunEnd, RunOptions};
use crate::simulation::Simulation;

/// The arguments of `loam run`.
#[derive(Debug, Clone, Default)]
pub struct RunArgs {
    /// The case file.
    pub case: PathBuf,
    /// Output directory (default `out/<case name>`).
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// No progress bar.
    pub quiet: bool,
    /// Continue from a checkpoint: `Some(None)` the newest in the output directory.
    pub resume: Option<Option<PathBuf>>,
    /// Every Newton iteration on stderr.
    pub trace_newton: bool,
}

/// `loam run`: in a build with the `mpi` feature MPI is started first (rsmpi; under `mpirun`
/// every rank runs this, [`loam_fem::ranks`]), PETSc then runs on `MPI_COMM_WORLD` and is
/// ended before MPI.
pub fn run_command(args: RunArgs) -> ExitCode {
    #[cfg(feature = "mpi")]
    {
        let Some((universe, _)) = mpi::initialize_with_threading(mpi::Threading::Serialized) else {
            eprintln!("error: MPI could not be initialised");
            return ExitCode::from(1);
        };
        let code = run_on_ranks(args, Ranks::world().unwrap_or_default());
        if let Err(e) = loam_fem::ranks::finalize_petsc() {
            eprintln!("warning: {e}");
        }
        drop(universe);
        code
    }
    #[cfg(not(feature = "mpi"))]
    run_on_ranks(args, Ranks::single())
}

/// `loam run` on `ranks`: checks the thread count (default under `mpirun`: one per rank) and
/// runs the case inside a pool of that many threads.
fn run_on_ranks(args: RunArgs, ranks: Ranks) -> ExitCode {
    let RunArgs { case, mut out, threads, quiet, resume, trace_newton } = args;
    let kratos = case.is_dir()
        && (case.join("ProjectParameters.json").is_file()
            || matches!(crate::import::kratos::cosim::find(&case), Ok(Some(_))));
    let case = if kratos {
        match imported_case(&case, &mut out) {
            Ok(c) => c,
            Err(code) => return code,
        }
    } else {
        case
    };
    if let Err(problem) = check_threads(threads) {
        eprintln!("error: --threads: {problem}");
        return ExitCode::from(2);
    }
    // the whole run inside the pool: parallel loops called from one of its threads
    // run there, without waking a worker and sleeping on every call (which cost about
    // 1 ms per step at 448 material points)
    let threads = threads.or(ranks.is_distributed().then_some(1));
    match rayon::ThreadPoolBuilder::new().num_threads(threads.unwrap_or(0)).build() {
        Ok(pool) => pool.install(|| run_case(&case, out, quiet, resume, trace_newton, ranks)),
        Err(e) => {
            eprintln!("error: thread pool: {e}");
            ExitCode::from(1)
        }
    }
}

/// `loam run DIR` on a Kratos case folder: the case imported first into
/// `OUT/imported/<folder>.json` ([`crate::import::kratos`], its notes on stderr), `OUT`
/// defaulting to `out/<folder>`; returns the case file to run, or exit code 2.
fn imported_case(dir: &Path, out: &mut Option<PathBuf>) -> Result<PathBuf, ExitCode> {
    let name = dir
        .canonicalize()
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "kratos".into());
    let out_dir = out.get_or_insert_with(|| default_out_dir(&crate::case::output_name(&name))).clone();
    let target = out_dir.join("imported").join(format!("{name}.json"));
    match crate::import::kratos::import(dir, &target) {
        Ok(import) => {
            for note in &import.notes {
                eprintln!("note: {note}");
            }
            eprintln!("loam: imported the Kratos case {} as {}", dir.display(), target.display());
            Ok(target)
        }
        Err(e) => {
            eprintln!("error: {e}");
            Err(ExitCode::from(2))
        }
    }
}

/// Most worker threads per core of the machine that `--threads` accepts: more only adds
/// switching, and thousands took 22 s to create before the system refused (issue 31).
const MAX_THREADS_PER_CORE: usize = 4;

/// `--threads N` must lie in [1, [`MAX_THREADS_PER_CORE`] × the cores available to this
/// process] (`std::thread::available_parallelism`, which follows CPU affinity and cgroup
/// quotas; 1 if it cannot be told).
fn check_threads(threads: Option<usize>) -> Result<(), String> {
    let Some(n) = threads else { return Ok(()) };
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    let max = MAX_THREADS_PER_CORE * cores;
    if n == 0 {
        Err("must be at least 1, got 0".into())
    } else if n > max {
        Err(format!(
            "must be at most {max} ({MAX_THREADS_PER_CORE} per core of the {cores} available to this process), got {n}"
        ))
    } else {
        Ok(())
    }
}

/// Exit code of a run stopped by SIGINT/SIGTERM after writing a checkpoint (128 + SIGINT).
const INTERRUPTED: u8 = 130;

/// What SIGINT and SIGTERM set (the run finishes its step, checkpoints and stops); a second
/// signal ends the process at once, abandoning the step in progress, after writing the
/// run's report as of the last converged step with the status `interrupted`
/// ([`loam::interrupt`]).
fn interrupt_handler() -> Option<Arc<Interrupt>> {
    let interrupt = Arc::new(Interrupt::new());
    let handler = interrupt.clone();
    let installed = ctrlc::set_handler(move || {
        if handler.request() {
            let report = match handler.abandon() {
                Some(Ok(path)) => format!("; {} says so", path.display()),
                Some(Err(e)) => format!("; writing the run's report failed: {e}"),
                None => String::new(),
            };
            eprintln!(
                "\nloam: interrupted again: stopping now, the step in progress abandoned without a checkpoint{report}"
            );
            std::process::exit(i32::from(INTERRUPTED));
        }
        eprintln!("\nloam: interrupted: finishing the current step, then writing a checkpoint (again to stop now)");
    });
    installed.ok().map(|()| interrupt)
}

/// A case run on `ranks` (more than one: the replicated model of [`loam_fem::ranks`]): the
/// linear solver must be PETSc's, the only one that distributes; `auto` (the default) then
/// means `petsc`.
fn distribute(case: &mut crate::case::Case, ranks: Ranks) -> Result<(), CaseError> {
    use loam_fem::linear_solver::LinearSolverKind;
    case.solver.ranks = ranks;
    if !ranks.is_distributed() {
        return Ok(());
    }
    match case.solver.linear_solver {
        LinearSolverKind::Auto => case.solver.linear_solver = LinearSolverKind::Petsc,
        LinearSolverKind::Petsc => {}
        _ => {
            return Err(CaseError::new(
                "solver.linear_solver",
                format!(
                    "a direct solver runs on one process; a run on {} MPI ranks needs \"petsc\" (or \"auto\", the default, which is then \"petsc\")",
                    ranks.size()
                ),
            ))
        }
    }
    Ok(())
}

/// `loam run`: builds the case (and restores a checkpoint with `--resume`), runs it with
/// output to `out` (every Newton iteration on stderr with `trace_newton`) and prints the
/// summary line. On several ranks every rank builds and steps the whole model; rank 0 alone
/// writes results, checkpoints and the summary ([`run_without_output`] on the others).
fn run_case(
    case: &Path,
    out: Option<PathBuf>,
    quiet: bool,
    resume: Option<Option<PathBuf>>,
    trace_newton: bool,
    ranks: Ranks,
) -> ExitCode {
    let built = crate::case::Case::load(case).and_then(|mut c| {
        c.solver.trace = trace_newton && ranks.rank() == 0;
        distribute(&mut c, ranks)?;
        Simulation::new(c)
    });
    let mut sim = match built {
        Ok(s) => s,
        // every rank reads the same case: rank 0 says what is wrong, all exit with 2
        Err(_) if ranks.rank() != 0 => return ExitCode::from(2),
        Err(e) => return bad_input(&e),
    };
    let out = out.unwrap_or_else(|| default_out_dir(&sim.case.name));
    let fingerprints = std::fs::read_to_string(case).map(|t| checkpoint::fingerprints(&t)).unwrap_or([0, 0]);
    let mut options = RunOptions {
        progress: !quiet,
        case_fingerprint: fingerprints[0],
        resume: None,
        interrupt: interrupt_handler(),
    };
    if let Some(given) = resume {
        let path = match given.or_else(|| checkpoint::list(&out).pop()) {
            Some(p) => p,
            None => {
                eprintln!("error: --resume: no checkpoint in {}", checkpoint::directory(&out).display());
                return ExitCode::from(2);
            }
        };
        let restored = checkpoint::read(&path, fingerprints).map_err(|e| e.to_string()).and_then(|c| {
            sim.restore_state(c.simulation, c.model)
                .map_err(|e| format!("{}: does not fit this case: {e}", path.display()))
                .map(|()| c.writer)
        });
        match restored {
            Ok(writer) => {
                if !quiet {
                    println!("loam: resuming from {} (step {}, t = {:.6e} s)", path.display(), sim.step, sim.time());
                }
                // a checkpoint without results (none written yet) starts them afresh
                options.resume = writer;
            }
            Err(e) => {
                eprintln!("error: --resume: {e}");
                return ExitCode::from(2);
            }
        }
    }
    if ranks.rank() != 0 {
        let (code, interrupted) = run_other_rank(&mut sim, &out, &options);
        // rank 0 gathers every rank's measurements unless the run was interrupted (it then
        // writes the checkpoint and stops): the same collective on every rank, or none
        if !interrupted {
            loam_fem::ranks::DistributedStats::of_every_rank(ranks);
        }
        return code;
    }
    match run(&mut sim, &out, &options) {
        Ok((end, wall)) => {
            if ranks.is_distributed() && !matches!(end, RunEnd::Interrupted(_)) {
                // every rank's measurements into summary.json (the others ended with rank 0)
                let every = loam_fem::ranks::DistributedStats::of_every_rank(ranks);
                if let Ok(mut summary) = crate::output::summary::RunSummary::read(&out) {
                    summary.distributed = every;
                    if let Err(e) = summary.write(&out) {
                        eprintln!("warning: summary.json: {e}");
                    }
                }
            }
            let t = &sim.stats.timings;
            let solver = sim.model.solver_timings();
            let gmres = if solver.krylov_iterations > 0 {
                let (setups, method) =
                    if sim.model.settings.linear_solver == loam_fem::linear_solver::LinearSolverKind::Petsc {
                        ("preconditioner set-ups", "PETSc Krylov")
                    } else {
                        ("factorisations", "GMRES")
                    };
                format!(
                    "; {} {setups}, {} solves by {method} ({} iterations)",
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
                    let on =
                        if ranks.is_distributed() { format!(" on {} MPI ranks", ranks.size()) } else { String::new() };
                    println!(
                        "loam: finished t = {:.6e} s{}{on}: {summary}; results in {}",
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
                RunEnd::Interrupted(path) => {
                    eprintln!(
                        "loam: interrupted at t = {:.6e} s (step {}): results so far in {}, checkpoint {}; resume with: loam run {} --out {} --resume",
                        sim.time(),
                        sim.step,
                        out.display(),
                        path.display(),
                        case.display(),
                        out.display()
                    );
                    ExitCode::from(INTERRUPTED)
                }
            }
        }
        Err(e) => {
            eprintln!("error: writing results to {}: {e}", out.display());
            ExitCode::from(1)
        }
    }
}

/// The steps of a rank other than 0 in a distributed run: the same steps as rank 0's run loop
/// ([`run`]), whose collective operations they meet (an interruption on any rank stops all
/// of them before the same step), writing this rank's pieces of the VTK output at the steps
/// rank 0 writes them ([`ResultWriter::pieces`]). A failure to write a piece is reported and
/// the run goes on (rank 0 waits for this rank's collectives). Exit code 1 if a step fails,
/// as on rank 0; and whether the run was interrupted.
fn run_other_rank(sim: &mut Simulation, out: &Path, options: &RunOptions) -> (ExitCode, bool) {
    let rank = sim.case.solver.ranks.rank();
    let report =
        |e: std::io::Error| eprintln!("warning: rank {rank}: writing its output pieces to {}: {e}", out.display());
    // where the points are distributed (from the first partition on) the monitors' sums and a
    // checkpoint's gathered state are collectives: this rank meets them whether or not it can
    // write its pieces
    let mut writer = match ResultWriter::pieces(out, sim, options.resume.as_ref()) {
        Ok(w) => Some(w),
        Err(e) => {
            report(e);
            if sim.model.has_distributed_points() && options.resume.as_ref().is_none_or(|s| s.rows_step < sim.step) {
                sim.monitor_values();
            }
            None
        }
    };
    let write = |sim: &Simulation, force: bool, writer: &mut Option<ResultWriter>| match writer.as_mut() {
        Some(w) => {
            if let Err(e) = w.write_step(sim, force) {
                report(e);
                *writer = None;
            }
        }
        None if sim.model.has_distributed_points() => {
            sim.monitor_values();
        }
        None => {}
    };
    let mut clock = crate::run::CheckpointClock::new(sim);
    while !sim.finished() {
        if crate::run::interrupted_on_any_rank(sim, options) {
            if sim.model.has_distributed_points() {
                sim.model.save_state(); // rank 0's checkpoint gathers this rank's points
            }
            return (ExitCode::from(INTERRUPTED), true);
        }
        let result = sim.step_observed(&mut |sim| write(sim, true, &mut writer));
        match result {
            Ok(_) => {
                let last = sim.finished();
                write(sim, last, &mut writer);
                if !last && clock.due_on_every_rank(sim) && sim.model.has_distributed_points() {
                    sim.model.save_state(); // rank 0's checkpoint gathers this rank's points
                }
            }
            Err(_) => {
                if let Some(Err(e)) = writer.as_mut().map(|w| w.write_final_state(sim)) {
                    report(e);
                }
                return (ExitCode::from(1), false);
            }
        }
    }
    (ExitCode::SUCCESS, false)
}
