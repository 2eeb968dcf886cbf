//! `loam`: run, check and explore Loam case files.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use clap::{Parser, Subcommand};
use loam::case::CaseError;
use loam::checkpoint;
use loam::interrupt::Interrupt;
use loam::run::{default_out_dir, run, RunEnd, RunOptions};
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
        /// Continue from a checkpoint: the given file, or without one the newest in
        /// DIR/checkpoints (results in DIR continue without duplicate or missing rows).
        #[arg(long, value_name = "CHECKPOINT", num_args = 0..=1)]
        resume: Option<Option<PathBuf>>,
    },
    /// Check a case file (parse, parameters, mesh, regions) without running it.
    Check {
        /// The case file (JSON).
        case: PathBuf,
    },
    /// Draw a run's results as PNG files: the bodies coloured by a field at chosen times,
    /// and the monitors (one picture per group of one unit).
    Plot(Box<PlotArgs>),
    /// Import another code's case as a Loam case: `loam import kratos DIR` (docs/kratos.md).
    Import {
        /// The format of the case.
        #[arg(value_enum)]
        format: loam::import::Format,
        /// The case folder.
        dir: PathBuf,
        /// The Loam case to write (default <folder name>.json); meshes are written beside it.
        #[arg(short, long)]
        output: Option<PathBuf>,
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

/// `loam plot` arguments.
#[derive(clap::Args)]
struct PlotArgs {
    /// The results directory (the --out of `loam run`).
    dir: PathBuf,
    /// Field colouring the bodies: NAME (scalar), NAME:x|y|z|magnitude (vector),
    /// NAME:xx|yy|zz|xy|yz|xz (tensor), e.g. accumulated_plastic_deviatoric_strain,
    /// cauchy_stress:yy. Default displacement (magnitude).
    #[arg(long)]
    field: Option<String>,
    /// Draw the outputs nearest to these times (s), e.g. 0.6,0.88,1.28,2.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["every", "last"])]
    times: Option<Vec<f64>>,
    /// Draw every N-th output (and the last).
    #[arg(long, conflicts_with = "last")]
    every: Option<usize>,
    /// Draw the last output only.
    #[arg(long)]
    last: bool,
    /// Where the pictures go (default DIR/plots).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write an animated GIF of the frames.
    #[arg(long)]
    gif: bool,
    /// Delay between GIF frames (ms).
    #[arg(long, default_value_t = 150)]
    delay: u32,
    /// Colour range MIN,MAX (default: the range of the values over the frames drawn).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_numbers::<2>)]
    range: Option<[f64; 2]>,
    /// Colour map.
    #[arg(long, value_enum, default_value_t = loam::plot::colormap::Colormap::Viridis)]
    colormap: loam::plot::colormap::Colormap,
    /// Picture size WIDTHxHEIGHT in pixels.
    #[arg(long, default_value = "800x500", value_parser = parse_size)]
    size: (u32, u32),
    /// Reference curve FILE.csv[:LABEL] drawn on the frames (x,y in m per line); repeatable.
    #[arg(long)]
    overlay: Vec<String>,
    /// Monitor plots against this monitor instead of time (e.g. force against settlement).
    #[arg(long)]
    x: Option<String>,
    /// Monitors drawn (default all).
    #[arg(long, value_delimiter = ',')]
    monitors: Option<Vec<String>>,
    /// Plane of 3D pictures (a projection, nearer material in front).
    #[arg(long, value_enum, default_value_t = loam::plot::scene::Plane::Xy)]
    plane: loam::plot::scene::Plane,
    /// Extent drawn XMIN,XMAX,YMIN,YMAX in m (widened to equal scales).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_numbers::<4>)]
    view: Option<[f64; 4]>,
    /// Draw the MPM background grid (written with output.grid).
    #[arg(long)]
    grid: bool,
    /// Draw a material point no larger than this many times the side of its initial volume
    /// (V / det F): degenerate points with a huge det F otherwise cover their neighbours.
    #[arg(long)]
    max_stretch: Option<f64>,
    /// No frames, monitor plots only.
    #[arg(long, conflicts_with = "no_monitors")]
    no_frames: bool,
    /// No monitor plots, frames only.
    #[arg(long)]
    no_monitors: bool,
}

/// `N` comma-separated finite numbers.
fn parse_numbers<const N: usize>(s: &str) -> Result<[f64; N], String> {
    let values: Vec<f64> =
        s.split(',').map(|v| v.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("`{s}`: {e}"))?;
    match <[f64; N]>::try_from(values) {
        Ok(v) if v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(format!("`{s}`: expected {N} comma-separated finite numbers")),
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("`{s}`: expected WIDTHxHEIGHT, e.g. 800x500"))?;
    let px = |v: &str| v.trim().parse::<u32>().ok().filter(|&p| (100..=8000).contains(&p));
    match (px(w), px(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("`{s}`: width and height must be whole numbers of pixels in [100, 8000]")),
    }
}

/// `loam plot`: draws, prints what it wrote, and maps errors to exit codes.
fn plot_results(a: PlotArgs) -> ExitCode {
    use loam::plot::{plot, PlotOptions, TimeSelection};
    let times = match (a.times, a.every, a.last) {
        (Some(t), _, _) => TimeSelection::Times(t),
        (_, Some(n), _) => TimeSelection::Every(n),
        (_, _, true) => TimeSelection::Last,
        _ => TimeSelection::All,
    };
    let options = PlotOptions {
        field: a.field,
        times,
        out: a.out,
        gif: a.gif,
        delay_ms: a.delay,
        range: a.range.map(|[min, max]| (min, max)),
        colormap: a.colormap,
        size: a.size,
        overlays: a.overlay,
        x: a.x,
        monitors: a.monitors,
        plane: a.plane,
        view: a.view,
        grid: a.grid,
        max_stretch: a.max_stretch,
        frames: !a.no_frames,
        monitor_plots: !a.no_monitors,
    };
    match plot(&a.dir, &options) {
        Ok(report) => {
            for note in &report.notes {
                eprintln!("note: {note}");
            }
            for (file, time) in &report.files {
                match time {
                    Some(t) => println!("loam: wrote {} (t = {t} s)", file.display()),
                    None => println!("loam: wrote {}", file.display()),
                }
            }
            if let Some((field, min, max, unit)) = &report.field {
                println!(
                    "loam: {field} from {min:.4e} to {max:.4e}{}; {:.3} s per frame",
                    if unit.is_empty() || unit == "1" { String::new() } else { format!(" {unit}") },
                    report.seconds_per_frame
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
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
        Command::Run { case, out, threads, quiet, resume } => {
            if let Err(problem) = check_threads(threads) {
                eprintln!("error: --threads: {problem}");
                return ExitCode::from(2);
            }
            // the whole run inside the pool: parallel loops called from one of its threads
            // run there, without waking a worker and sleeping on every call (which cost about
            // 1 ms per step at 448 material points)
            match rayon::ThreadPoolBuilder::new().num_threads(threads.unwrap_or(0)).build() {
                Ok(pool) => pool.install(|| run_case(&case, out, quiet, resume)),
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
        Command::Plot(args) => plot_results(*args),
        Command::Import { format, dir, output } => loam::import::cli(format, &dir, output.as_deref()),
        Command::Law { path, out } => {
            let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let out = out.unwrap_or_else(|| default_out_dir(&loam::case::output_name(&name)));
            let file = match read_path_file(&path) {
                Ok(f) => f,
                Err(e) => return bad_input(&e),
            };
            match loam_laws::driver::run_parsed_path(&file, &out) {
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
                    use loam_laws::driver::DriverError;
                    eprintln!("error: {}", loam::input::compact_numbers(&e.to_string()));
                    // bad input 2; a material point that cannot follow the path, or a write
                    // failure, 1 (issue 16: a divergence was reported as bad input)
                    ExitCode::from(match e {
                        DriverError::Input { .. } | DriverError::Read { .. } => 2,
                        DriverError::Law { .. }
                        | DriverError::ControlNotConverged { .. }
                        | DriverError::Write { .. } => 1,
                    })
                }
            }
        }
    }
}

/// Reads a `loam law` path file as strictly as a case file (size limit, duplicate keys,
/// text after the object, full JSON paths: [`loam::input`]).
fn read_path_file(path: &std::path::Path) -> Result<loam_laws::driver::PathFile, CaseError> {
    let text = loam::input::read_json_text(path, "path file")?;
    loam::input::parse(&text).map(|(file, _)| file).map_err(|mut e| {
        e.location = if e.location.is_empty() {
            path.display().to_string()
        } else if e.location.starts_with("line") {
            format!("{}:{}", path.display(), e.location)
        } else {
            e.location
        };
        e
    })
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

/// `loam run`: builds the case (and restores a checkpoint with `--resume`), runs it with
/// output to `out` and prints the summary line.
fn run_case(case: &std::path::Path, out: Option<PathBuf>, quiet: bool, resume: Option<Option<PathBuf>>) -> ExitCode {
    let mut sim = match Simulation::from_file(case) {
        Ok(s) => s,
        Err(e) => return bad_input(&e),
    };
    let out = out.unwrap_or_else(|| default_out_dir(&sim.case.name));
    let fingerprint = std::fs::read_to_string(case).map(|t| checkpoint::fingerprint(&t)).unwrap_or(0);
    let mut options =
        RunOptions { progress: !quiet, case_fingerprint: fingerprint, resume: None, interrupt: interrupt_handler() };
    if let Some(given) = resume {
        let path = match given.or_else(|| checkpoint::list(&out).pop()) {
            Some(p) => p,
            None => {
                eprintln!("error: --resume: no checkpoint in {}", checkpoint::directory(&out).display());
                return ExitCode::from(2);
            }
        };
        let restored = checkpoint::read(&path, fingerprint).map_err(|e| e.to_string()).and_then(|c| {
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
    match run(&mut sim, &out, &options) {
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
