//! `loam`: run, check and explore Loam case files. This file parses the command line; the
//! commands themselves are [`loam::cli`].

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use loam::cli;

/// `loam --version`: the version and the cargo features of this build (build.rs).
const VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), " (features: ", env!("LOAM_BUILD_FEATURES"), ")");

/// Implicit MPM and Lagrangian FEM for large-deformation solid and soil mechanics.
#[derive(Parser)]
#[command(name = "loam", version = VERSION, about)]
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
        /// Print every Newton iteration on stderr: time, step, iteration, residual norm (per
        /// block of a coupled system), correction norms, line-search backtracks.
        #[arg(long)]
        trace_newton: bool,
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
    /// Export a Loam case as another code's input: `loam export kratos CASE.json -o DIR`
    /// (docs/kratos.md#export).
    Export {
        /// The format to write.
        #[arg(value_enum)]
        format: loam::export::Format,
        /// The case file (JSON).
        case: PathBuf,
        /// The folder to write (default <case name>_kratos).
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
    /// Calibrate a law to laboratory curves (docs/fit.md): fitted parameters with 95 %
    /// intervals, fit.csv, material.json.
    Fit {
        /// The fit file (JSON), e.g. cases/laws/fit_mc_triaxial.json.
        fit: PathBuf,
        /// Output directory (default out/<fit file name>).
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

/// The options of `loam plot` from its arguments.
fn plot_options(a: PlotArgs) -> (PathBuf, loam::plot::PlotOptions) {
    use loam::plot::{PlotOptions, TimeSelection};
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
    (a.dir, options)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    faer::set_global_parallelism(faer::Par::Seq);
    match cli.command {
        Command::Check { case } => cli::check::check_command(&case),
        Command::Run { case, out, threads, quiet, resume, trace_newton } => {
            cli::run::run_command(cli::run::RunArgs { case, out, threads, quiet, resume, trace_newton })
        }
        Command::Fmu { case, output, library } => cli::fmu::fmu_command(&case, output, library),
        Command::Plot(args) => {
            let (dir, options) = plot_options(*args);
            cli::plot::plot_command(&dir, &options)
        }
        Command::Import { format, dir, output } => loam::import::cli(format, &dir, output.as_deref()),
        Command::Export { format, case, output } => loam::export::cli(format, &case, output.as_deref()),
        Command::Law { path, out } => cli::law::law_command(&path, out),
        Command::Fit { fit, out } => cli::fit::fit_command(&fit, out),
    }
}
