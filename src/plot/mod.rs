//! `loam plot`: pictures of a run's results without ParaView.
//!
//! Reads what `loam run` wrote (the `.pvd` series of each domain, `monitors.csv` and
//! `summary.json`) and writes PNG files: one per selected output time, the bodies coloured
//! by a field with a colour bar of fixed range, and one per group of monitors of one unit
//! against time (or another monitor). The key decision: plotters' bitmap backend with
//! text from an embedded font (DejaVu Sans through ab_glyph), so nothing is needed from
//! the system, and no anti-aliasing of the bodies, so a pixel holds exactly the colour of
//! its value.
//!
//! - [`results`]: the `.pvd`/`.vtu` series and what each shows;
//! - [`field`]: the field and component coloured, units;
//! - [`scene`]: one time as flat geometry (material points as squares of their volume,
//!   meshes deformed, 3D projected on a plane);
//! - [`frame`]: drawing a frame (equal scales, colour bar, title);
//! - [`colormap`], [`overlay`] (reference curves), [`walls`] (wall lines from the case);
//! - [`monitors`]: monitor plots; [`animation`]: the GIF;
//! - [`fit`]: the measured and fitted curves of a `loam fit` output (`fit.csv`).

pub mod animation;
pub mod colormap;
pub mod field;
pub mod fit;
pub mod frame;
pub mod monitors;
pub mod overlay;
pub mod results;
pub mod scene;
pub mod walls;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

use plotters::prelude::*;

use crate::output::summary::RunSummary;
use colormap::{ColorScale, Colormap};
use field::{DisplayUnit, FieldSelection};
use frame::{draw_frame, fit_view, FrameStyle, View};
use monitors::{MonitorPlot, MonitorTable};
use overlay::Overlay;
use results::{Piece, Series, SeriesKind};
use scene::{add_piece, Geometry, ModelKind, Plane, Scene};

/// Why `loam plot` failed. Every message is one line.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The results directory does not exist.
    #[error("{}: no such directory", .0.display())]
    NoDirectory(PathBuf),
    /// Nothing to plot in the directory.
    #[error("{}: no results (no .pvd series, no monitors.csv, no fit.csv); give the --out directory of a `loam run` or `loam fit`", .0.display())]
    NoResults(PathBuf),
    /// The field is not written by any domain.
    #[error("no field `{field}` in {}; fields: {available}", dir.display())]
    UnknownField {
        /// The field asked for.
        field: String,
        /// The results directory.
        dir: PathBuf,
        /// The fields that exist, comma-separated, with their kind.
        available: String,
    },
    /// `--x` or `--monitors` names a monitor that is not in `monitors.csv`.
    #[error("no monitor `{name}` in {}; monitors: {available}", file.display())]
    UnknownMonitor {
        /// The name asked for.
        name: String,
        /// monitors.csv.
        file: PathBuf,
        /// The monitors that exist, comma-separated.
        available: String,
    },
    /// An option that does not fit the results.
    #[error("{0}")]
    BadInput(String),
    /// A results file that cannot be read.
    #[error("{}: {reason}", file.display())]
    Read {
        /// The file.
        file: PathBuf,
        /// Why.
        reason: String,
    },
    /// Drawing failed.
    #[error("drawing: {0}")]
    Draw(String),
    /// A picture could not be written.
    #[error("{}: cannot write: {reason}", file.display())]
    Write {
        /// The file.
        file: PathBuf,
        /// Why.
        reason: String,
    },
}

impl PlotError {
    /// Exit code of the CLI: 2 for bad input (directory, field, options, unreadable
    /// results), 1 for failures to draw or write.
    pub fn exit_code(&self) -> u8 {
        match self {
            PlotError::Draw(_) | PlotError::Write { .. } => 1,
            _ => 2,
        }
    }
}

/// Which output times are drawn.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum TimeSelection {
    /// Every output time.
    #[default]
    All,
    /// The outputs nearest to these times (s).
    Times(Vec<f64>),
    /// Every n-th output, and the last.
    Every(usize),
    /// The last output.
    Last,
}

/// What `loam plot` draws and where.
#[derive(Debug, Clone)]
pub struct PlotOptions {
    /// Field (and component) colouring the bodies; default `displacement` (magnitude).
    pub field: Option<String>,
    /// Output times drawn.
    pub times: TimeSelection,
    /// Where the pictures go (default `DIR/plots`).
    pub out: Option<PathBuf>,
    /// Also an animated GIF of the frames.
    pub gif: bool,
    /// Delay between GIF frames (ms).
    pub delay_ms: u32,
    /// Colour range (default: the values' range over the frames drawn).
    pub range: Option<(f64, f64)>,
    /// Colour map.
    pub colormap: Colormap,
    /// Picture size (px).
    pub size: (u32, u32),
    /// Reference curves `FILE.csv[:LABEL]`.
    pub overlays: Vec<String>,
    /// Monitor on the horizontal axis of the monitor plots (default time).
    pub x: Option<String>,
    /// Monitors drawn (default all).
    pub monitors: Option<Vec<String>>,
    /// Plane of 3D pictures.
    pub plane: Plane,
    /// Extent drawn `[xmin, xmax, ymin, ymax]` (m; widened to equal scales).
    pub view: Option<View>,
    /// Draw the MPM background grid (`output.grid`).
    pub grid: bool,
    /// Largest side of a drawn material point, in sides of its initial volume.
    pub max_stretch: Option<f64>,
    /// Draw frames of the series.
    pub frames: bool,
    /// Draw monitor plots.
    pub monitor_plots: bool,
}

impl Default for PlotOptions {
    fn default() -> Self {
        Self {
            field: None,
            times: TimeSelection::All,
            out: None,
            gif: false,
            delay_ms: 150,
            range: None,
            colormap: Colormap::Viridis,
            size: (800, 500),
            overlays: Vec::new(),
            x: None,
            monitors: None,
            plane: Plane::Xy,
            view: None,
            grid: false,
            max_stretch: None,
            frames: true,
            monitor_plots: true,
        }
    }
}

/// What [`plot`] wrote.
#[derive(Debug, Clone, Default)]
pub struct PlotReport {
    /// Pictures written, with the time they show (`None`: monitor plots, the GIF).
    pub files: Vec<(PathBuf, Option<f64>)>,
    /// The field drawn and its colour range, with the unit.
    pub field: Option<(String, f64, f64, String)>,
    /// Seconds per frame: reading, drawing and writing.
    pub seconds_per_frame: f64,
    /// Notes for the user (e.g. no summary.json).
    pub notes: Vec<String>,
}

/// Writes an RGB buffer as a PNG (best compression: gallery pictures stay small).
pub fn write_png(path: &Path, rgb: &[u8], size: (u32, u32)) -> Result<(), PlotError> {
    use image::ImageEncoder;
    let err = |reason: String| PlotError::Write { file: path.to_path_buf(), reason };
    let file = std::fs::File::create(path).map_err(|e| err(e.to_string()))?;
    let encoder = image::codecs::png::PngEncoder::new_with_quality(
        std::io::BufWriter::new(file),
        image::codecs::png::CompressionType::Best,
        image::codecs::png::FilterType::Adaptive,
    );
    encoder.write_image(rgb, size.0, size.1, image::ColorType::Rgb8).map_err(|e| err(e.to_string()))
}

/// Plots the results in `dir`.
pub fn plot(dir: &Path, options: &PlotOptions) -> Result<PlotReport, PlotError> {
    if let Some((min, max)) = options.range.filter(|(min, max)| min >= max) {
        return Err(PlotError::BadInput(format!("--range {min},{max}: MIN must be below MAX")));
    }
    if let Some(v) = options.view.filter(|v| v[0] >= v[1] || v[2] >= v[3]) {
        return Err(PlotError::BadInput(format!(
            "--view {},{},{},{}: expected XMIN < XMAX and YMIN < YMAX",
            v[0], v[1], v[2], v[3]
        )));
    }
    if !dir.is_dir() {
        return Err(PlotError::NoDirectory(dir.to_path_buf()));
    }
    let series: Vec<Series> = results::find_series(dir)?
        .into_iter()
        .filter(|s| !s.steps.is_empty() && (options.grid || !s.is_grid))
        .collect();
    let monitors_csv = dir.join("monitors.csv");
    let fit_csv = dir.join("fit.csv");
    if series.is_empty() && !monitors_csv.is_file() && fit_csv.is_file() {
        // the output of `loam fit`: measured points and fitted lines per test
        let out = options.out.clone().unwrap_or_else(|| dir.join("plots"));
        std::fs::create_dir_all(&out).map_err(|e| PlotError::Write { file: out.clone(), reason: e.to_string() })?;
        let files = fit::plot_fit(&fit_csv, &out, options.size)?;
        return Ok(PlotReport { files: files.into_iter().map(|f| (f, None)).collect(), ..Default::default() });
    }
    if series.is_empty() && !monitors_csv.is_file() {
        return Err(PlotError::NoResults(dir.to_path_buf()));
    }
    let summary = RunSummary::read(dir).ok();
    let out = options.out.clone().unwrap_or_else(|| dir.join("plots"));
    std::fs::create_dir_all(&out).map_err(|e| PlotError::Write { file: out.clone(), reason: e.to_string() })?;
    let mut report = PlotReport::default();
    if options.frames && !series.is_empty() {
        plot_frames(dir, &series, summary.as_ref(), &out, options, &mut report)?;
    }
    if options.monitor_plots && monitors_csv.is_file() {
        plot_monitors(&monitors_csv, summary.as_ref(), &out, options, &mut report)?;
    } else if options.x.is_some() || options.monitors.is_some() {
        return Err(PlotError::BadInput(format!("{}: no monitors.csv", dir.display())));
    }
    Ok(report)
}

/// Indices into `times` of the selected outputs.
fn select(times: &[f64], selection: &TimeSelection) -> Vec<usize> {
    let n = times.len();
    match selection {
        TimeSelection::All => (0..n).collect(),
        TimeSelection::Last => vec![n - 1],
        TimeSelection::Every(k) => {
            let mut v: Vec<usize> = (0..n).step_by((*k).max(1)).collect();
            if v.last() != Some(&(n - 1)) {
                v.push(n - 1);
            }
            v
        }
        TimeSelection::Times(ts) => {
            let mut v: Vec<usize> = ts.iter().map(|&t| nearest(times, t)).collect();
            v.dedup();
            v
        }
    }
}

/// Index of the time nearest to `t`.
fn nearest(times: &[f64], t: f64) -> usize {
    (0..times.len()).min_by(|&a, &b| (times[a] - t).abs().total_cmp(&(times[b] - t).abs())).unwrap_or(0)
}

/// One series at one frame: its name, kind and file content (shared between frames that
/// show the same file).
type FramePiece = (String, SeriesKind, Rc<Piece>);

/// Whether a series shows a body (material points or a mesh), which a field colours.
fn is_body(kind: SeriesKind) -> bool {
    matches!(kind, SeriesKind::MaterialPoints | SeriesKind::Mesh)
}

/// The model's geometry from `summary.json`; without it, plane with unit thickness (3D if a
/// point lies off z = 0).
fn geometry(
    summary: Option<&RunSummary>,
    first: &[FramePiece],
    options: &PlotOptions,
    notes: &mut Vec<String>,
) -> Geometry {
    let (plane, max_stretch) = (options.plane, options.max_stretch);
    match summary {
        Some(s) => {
            let kind = match s.formulation.as_str() {
                "axisymmetric" => ModelKind::Axisymmetric,
                "3d" => ModelKind::ThreeD,
                _ => ModelKind::Plane,
            };
            Geometry { formulation: kind, thickness: s.thickness, plane, max_stretch }
        }
        None => {
            let three_d = first.iter().any(|(_, _, p)| p.points.iter().any(|x| x[2] != 0.0));
            notes.push(format!(
                "no summary.json: drawn as a {} model{}",
                if three_d { "3D" } else { "plane" },
                if three_d { "" } else { " of unit thickness" }
            ));
            Geometry {
                formulation: if three_d { ModelKind::ThreeD } else { ModelKind::Plane },
                thickness: 1.0,
                plane,
                max_stretch,
            }
        }
    }
}

/// The fields of the bodies (material points and meshes), with their kind, for messages.
fn available_fields(pieces: &[FramePiece]) -> String {
    let mut names: BTreeMap<String, usize> = BTreeMap::new();
    for (_, _, p) in pieces.iter().filter(|(_, k, _)| is_body(*k)) {
        for f in p.point_fields.iter().chain(&p.cell_fields) {
            names.insert(f.name.clone(), f.components);
        }
    }
    names
        .into_iter()
        .map(|(n, c)| match c {
            3 => format!("{n}:x|y|z|magnitude"),
            9 => format!("{n}:xx|yy|zz|xy|yz|xz"),
            _ => n,
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The pieces of every series at each selected output (`frames` index `times`), each file
/// read once.
fn read_frames(series: &[Series], times: &[f64], frames: &[usize]) -> Result<Vec<Vec<FramePiece>>, PlotError> {
    let mut cache: HashMap<PathBuf, Rc<Piece>> = HashMap::new();
    let mut pieces_at = Vec::with_capacity(frames.len());
    for &f in frames {
        let mut pieces = Vec::with_capacity(series.len());
        for s in series {
            let step_times: Vec<f64> = s.steps.iter().map(|x| x.0).collect();
            let path = &s.steps[nearest(&step_times, times[f])].1;
            let piece = match cache.get(path) {
                Some(p) => p.clone(),
                None => {
                    let p = Rc::new(results::read_vtu(path)?);
                    cache.insert(path.clone(), p.clone());
                    p
                }
            };
            pieces.push((s.name.clone(), piece.kind(s.is_grid), piece));
        }
        pieces_at.push(pieces);
    }
    Ok(pieces_at)
}

/// The field to colour by (`--field`, default `displacement`), checked against the bodies
/// of the first frame; a vector without a component is its magnitude.
fn resolve_field(dir: &Path, field: Option<&str>, first: &[FramePiece]) -> Result<FieldSelection, PlotError> {
    let mut selection = FieldSelection::parse(field.unwrap_or("displacement"));
    let found = first.iter().filter(|(_, k, _)| is_body(*k)).find_map(|(_, _, p)| p.field(&selection.name));
    let Some((field, _)) = found else {
        return Err(PlotError::UnknownField {
            field: selection.name.clone(),
            dir: dir.to_path_buf(),
            available: available_fields(first),
        });
    };
    selection.component(field.components).map_err(PlotError::BadInput)?;
    if field.components == 3 && selection.component.is_none() {
        selection.component = Some("magnitude".into());
    }
    Ok(selection)
}

/// Penalty walls as lines from the case file that `summary.json` names (2D); none, with a
/// note, where it cannot be read (their penalty points are drawn instead).
fn case_walls(summary: Option<&RunSummary>, geometry: &Geometry, notes: &mut Vec<String>) -> Vec<walls::WallLine> {
    match summary.and_then(|s| s.case_file.clone()) {
        Some(case) if geometry.formulation != ModelKind::ThreeD => walls::walls_of_case(&case).unwrap_or_else(|e| {
            notes.push(format!("walls drawn as their penalty points: case file {e}"));
            Vec::new()
        }),
        _ => Vec::new(),
    }
}

/// The view holding every frame and reference curve (`--view` if given), at equal scales.
fn common_view(scenes: &[Scene], overlays: &[Overlay], options: &PlotOptions) -> Result<View, PlotError> {
    if let Some(v) = options.view {
        return fit_view(v, 0.0, options.size);
    }
    let empty = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
    let union = |a: [f64; 4], b: [f64; 4]| [a[0].min(b[0]), a[1].max(b[1]), a[2].min(b[2]), a[3].max(b[3])];
    let curves = overlays.iter().map(|o| o.points.iter().fold(empty, |b, p| union(b, [p[0], p[0], p[1], p[1]])));
    let b = scenes.iter().filter_map(Scene::bounds).chain(curves).fold(empty, union);
    fit_view(if b[0] <= b[1] { b } else { [0.0, 1.0, 0.0, 1.0] }, 0.03, options.size)
}

/// The colour range: `--range`, or the values' range over all frames.
fn common_range(scenes: &[Scene], options: &PlotOptions) -> (f64, f64) {
    let (min, max) = options.range.unwrap_or_else(|| {
        scenes
            .iter()
            .filter_map(Scene::value_range)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (c, d)| (a.min(c), b.max(d)))
    });
    if min <= max {
        (min, max)
    } else {
        (0.0, 1.0)
    }
}

/// The frames: read the selected outputs, turn them into scenes, fix one view and one
/// colour range for all, draw and write each (and the GIF).
fn plot_frames(
    dir: &Path,
    series: &[Series],
    summary: Option<&RunSummary>,
    out: &Path,
    options: &PlotOptions,
    report: &mut PlotReport,
) -> Result<(), PlotError> {
    let start = Instant::now();
    // the timeline: the series with the most outputs (all are written at the same steps)
    let timeline = series.iter().filter(|s| !s.is_grid).max_by_key(|s| s.steps.len()).unwrap_or(&series[0]);
    let times: Vec<f64> = timeline.steps.iter().map(|s| s.0).collect();
    let frames = select(&times, &options.times);
    let pieces_at = read_frames(series, &times, &frames)?;
    let geometry = geometry(summary, &pieces_at[0], options, &mut report.notes);
    let selection = resolve_field(dir, options.field.as_deref(), &pieces_at[0])?;
    let walls = case_walls(summary, &geometry, &mut report.notes);
    let mut scenes = Vec::with_capacity(frames.len());
    for (pieces, &f) in pieces_at.iter().zip(&frames) {
        let mut scene = Scene { time: times[f], ..Scene::default() };
        for (name, kind, piece) in pieces {
            let drawn_as_line = walls.iter().any(|w| w.name.as_deref() == Some(name.as_str()));
            if !(*kind == SeriesKind::WallPoints && drawn_as_line) {
                add_piece(&mut scene, piece, *kind, &selection, &geometry).map_err(PlotError::BadInput)?;
            }
        }
        scene.walls = walls.iter().map(|w| w.at(scene.time)).collect();
        scenes.push(scene);
    }
    let overlays: Vec<Overlay> = options
        .overlays
        .iter()
        .map(|spec| {
            let (path, label) = overlay::parse_spec(spec);
            overlay::read_overlay(&path, label)
        })
        .collect::<Result<_, _>>()?;
    let (min, max) = common_range(&scenes, options);
    let scale = ColorScale::new(options.colormap, min, max);
    let unit = field::unit(&selection.name).unwrap_or("");
    let display = DisplayUnit::for_range(unit, scale.min.abs().max(scale.max.abs()));
    let (h, v) = geometry.axis_names();
    let projection = match geometry.formulation {
        ModelKind::ThreeD => format!(" ({})", geometry.plane.describe()),
        _ => String::new(),
    };
    let case =
        summary.map_or_else(|| dir.file_name().unwrap_or_default().to_string_lossy().into_owned(), |s| s.case.clone());
    let style = FrameStyle {
        size: options.size,
        title: format!("{case}: {}{projection}", selection.label()),
        axes: (h.to_string(), v.to_string()),
        scale,
        label: display.label(&selection.label()),
        unit: display,
        view: common_view(&scenes, &overlays, options)?,
    };
    let slug = selection.slug();
    let mut buffer = vec![255u8; 3 * options.size.0 as usize * options.size.1 as usize];
    for (scene, &f) in scenes.iter().zip(&frames) {
        {
            let root = BitMapBackend::with_buffer(&mut buffer, options.size).into_drawing_area();
            draw_frame(&root, scene, &style, &overlays)?;
            root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
        }
        let path = out.join(format!("{slug}_{f:04}.png"));
        write_png(&path, &buffer, options.size)?;
        report.files.push((path, Some(scene.time)));
    }
    report.seconds_per_frame = start.elapsed().as_secs_f64() / scenes.len().max(1) as f64;
    report.field = Some((selection.label(), style.scale.min, style.scale.max, unit.to_string()));
    if options.gif {
        let path = out.join(format!("{slug}.gif"));
        animation::write_gif(&path, &scenes, &style, &overlays, options.delay_ms)?;
        report.files.push((path, None));
    }
    Ok(())
}

fn plot_monitors(
    csv: &Path,
    summary: Option<&RunSummary>,
    out: &Path,
    options: &PlotOptions,
    report: &mut PlotReport,
) -> Result<(), PlotError> {
    let table = MonitorTable::read(csv)?;
    if table.rows.is_empty() || table.names.len() < 2 {
        return Ok(());
    }
    let unknown = |name: &str| PlotError::UnknownMonitor {
        name: name.to_string(),
        file: csv.to_path_buf(),
        available: table.names[1..].join(", "),
    };
    let x = match &options.x {
        Some(name) => table.column(name).ok_or_else(|| unknown(name))?,
        None => 0,
    };
    let ys: Vec<usize> = match &options.monitors {
        Some(names) => names
            .iter()
            .map(|n| table.column(n).filter(|&k| k > 0).ok_or_else(|| unknown(n)))
            .collect::<Result<_, _>>()?,
        None => (1..table.names.len()).filter(|&k| k != x).collect(),
    };
    let unit_of = |name: &str| -> Option<String> {
        if name == "time" {
            return Some("s".into());
        }
        summary.and_then(|s| s.monitor_units.get(name).cloned())
    };
    let case = summary.map_or_else(
        || csv.parent().and_then(Path::file_name).unwrap_or_default().to_string_lossy().into_owned(),
        |s| s.case.clone(),
    );
    for (unit, members) in monitors::groups(&table, &ys, &unit_of) {
        let path = monitors::file_name(out, &table, &unit, &members, x);
        let what = if x == 0 { "against time".to_string() } else { format!("against {}", table.names[x]) };
        let plot = MonitorPlot {
            table: &table,
            x,
            x_unit: unit_of(&table.names[x]),
            ys: members,
            y_unit: unit.clone(),
            title: format!("{case}: monitors {what}"),
        };
        plot.write(&path, options.size)?;
        report.files.push((path, None));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_selection() {
        let times = [0.0, 0.5, 1.0, 1.5, 2.0];
        assert_eq!(select(&times, &TimeSelection::All), vec![0, 1, 2, 3, 4]);
        assert_eq!(select(&times, &TimeSelection::Last), vec![4]);
        assert_eq!(select(&times, &TimeSelection::Every(3)), vec![0, 3, 4]);
        assert_eq!(select(&times, &TimeSelection::Times(vec![0.6, 0.4, 1.9])), vec![1, 4]);
    }
}
