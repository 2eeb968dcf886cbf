//! Monitor plots from `monitors.csv`: one picture per group of monitors of one unit
//! against time, or against another monitor (`--x NAME`, e.g. force against settlement).

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::field::{axis_tick, DisplayUnit};
use super::frame::{register_font, FONT};
use super::PlotError;

/// The columns of `monitors.csv`: `time` first, then one per monitor.
#[derive(Debug, Clone, PartialEq)]
pub struct MonitorTable {
    /// Column names (`time` first).
    pub names: Vec<String>,
    /// Rows of values, one per step.
    pub rows: Vec<Vec<f64>>,
}

impl MonitorTable {
    /// Reads `path`.
    pub fn read(path: &Path) -> Result<Self, PlotError> {
        let bad = |reason: String| PlotError::Read { file: path.to_path_buf(), reason };
        let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
        let mut lines = text.lines();
        let names: Vec<String> = lines.next().unwrap_or("").split(',').map(|s| s.trim().to_string()).collect();
        if names.first().map(String::as_str) != Some("time") {
            return Err(bad("the first column is not `time`".into()));
        }
        let mut rows = Vec::new();
        for (k, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
            let row = line
                .split(',')
                .map(|v| v.trim().parse::<f64>())
                .collect::<Result<Vec<f64>, _>>()
                .map_err(|e| bad(format!("line {}: {e}", k + 2)))?;
            if row.len() != names.len() {
                return Err(bad(format!("line {}: {} values for {} columns", k + 2, row.len(), names.len())));
            }
            rows.push(row);
        }
        Ok(Self { names, rows })
    }

    /// Index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// The values of column `k`.
    pub fn values(&self, k: usize) -> Vec<f64> {
        self.rows.iter().map(|r| r[k]).collect()
    }
}

/// The quantity a unit measures, for file names and axis labels.
pub fn quantity(unit: &str) -> &str {
    match unit {
        "m" => "length",
        "m/s" => "velocity",
        "m/s2" | "m/s²" => "acceleration",
        "N" => "force",
        "Pa" => "stress",
        "J" => "energy",
        "kg" => "mass",
        "m3" | "m³" => "volume",
        "1" => "ratio",
        _ => "value",
    }
}

/// Monitors grouped by unit, in order of first appearance: (unit, column indices). Without
/// known units (`unit_of` gives `None`), every monitor is a group of its own.
pub fn groups(
    table: &MonitorTable,
    columns: &[usize],
    unit_of: &dyn Fn(&str) -> Option<String>,
) -> Vec<(Option<String>, Vec<usize>)> {
    let mut out: Vec<(Option<String>, Vec<usize>)> = Vec::new();
    for &k in columns {
        let unit = unit_of(&table.names[k]);
        match out.iter_mut().find(|(u, _)| u.is_some() && *u == unit) {
            Some((_, members)) => members.push(k),
            None => out.push((unit, vec![k])),
        }
    }
    out
}

/// Colours of the lines, in turn (matplotlib's tab10).
pub(crate) const LINE_COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// One monitor plot: the columns `ys` against column `x` (`x_unit` its unit).
pub struct MonitorPlot<'a> {
    /// The table.
    pub table: &'a MonitorTable,
    /// Column on the horizontal axis (0: time).
    pub x: usize,
    /// Unit of `x`.
    pub x_unit: Option<String>,
    /// Columns drawn.
    pub ys: Vec<usize>,
    /// Their common unit.
    pub y_unit: Option<String>,
    /// Title.
    pub title: String,
}

fn draw_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Draw(e.to_string())
}

pub(crate) fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (a, b) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if a > b {
        (0.0, 1.0)
    } else if a == b {
        let pad = if a == 0.0 { 1.0 } else { 0.05 * a.abs() };
        (a - pad, b + pad)
    } else {
        let pad = 0.04 * (b - a);
        (a - pad, b + pad)
    }
}

/// The chart a line plot draws its series on.
pub(crate) type LineChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// The axes of a line plot: caption, ranges and axis titles.
pub(crate) struct Axes<'a> {
    pub caption: &'a str,
    pub x: (f64, f64),
    pub y: (f64, f64),
    pub x_desc: String,
    pub y_desc: String,
}

/// Draws a line plot of `size` pixels into an RGB buffer: the axes, then the series that
/// `series` draws (pushing every point it drew into its second argument), then the legend in
/// the emptiest corner ([`legend_corner`]). Monitor and fit pictures share it.
pub(crate) fn line_chart(
    size: (u32, u32),
    axes: &Axes<'_>,
    series: impl FnOnce(&mut LineChart<'_, '_>, &mut Vec<(f64, f64)>) -> Result<(), PlotError>,
) -> Result<Vec<u8>, PlotError> {
    register_font();
    let mut buffer = vec![255u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let ((x0, x1), (y0, y1)) = (axes.x, axes.y);
        let mut chart = ChartBuilder::on(&root)
            .caption(axes.caption, (FONT, 17))
            .margin(14)
            .x_label_area_size(42)
            .y_label_area_size(72)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(225, 225, 225))
            .x_desc(axes.x_desc.as_str())
            .y_desc(axes.y_desc.as_str())
            .x_label_formatter(&|v| axis_tick(*v, x1 - x0))
            .y_label_formatter(&|v| axis_tick(*v, y1 - y0))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .draw()
            .map_err(draw_err)?;
        let mut drawn = Vec::new();
        series(&mut chart, &mut drawn)?;
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(legend_corner(&drawn, (x0, x1), (y0, y1)))
            .draw()
            .map_err(draw_err)?;
        root.present().map_err(draw_err)?;
    }
    Ok(buffer)
}

/// A series' legend entry: a short line in its colour.
pub(crate) fn legend_line(color: RGBColor) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
}

impl MonitorPlot<'_> {
    /// Writes the plot as a PNG of `size` to `path`.
    pub fn write(&self, path: &Path, size: (u32, u32)) -> Result<(), PlotError> {
        let t = self.table;
        let xs = t.values(self.x);
        let x_unit = DisplayUnit::for_range(
            self.x_unit.as_deref().unwrap_or(""),
            xs.iter().fold(0.0, |m, v| f64::max(m, v.abs())),
        );
        let largest =
            self.ys.iter().flat_map(|&k| t.values(k)).filter(|v| v.is_finite()).fold(0.0, |m, v| f64::max(m, v.abs()));
        let y_unit = DisplayUnit::for_range(self.y_unit.as_deref().unwrap_or(""), largest);
        let x_name = if self.x == 0 { "time".to_string() } else { t.names[self.x].clone() };
        let y_name = match &self.y_unit {
            Some(u) => quantity(u).to_string(),
            None => t.names[self.ys[0]].clone(),
        };
        let axes = Axes {
            caption: &self.title,
            x: range(xs.iter().map(|v| v / x_unit.factor)),
            y: range(self.ys.iter().flat_map(|&k| t.values(k)).map(|v| v / y_unit.factor)),
            x_desc: x_unit.label(&x_name),
            y_desc: y_unit.label(&y_name),
        };
        let buffer = line_chart(size, &axes, |chart, drawn| {
            for (i, &k) in self.ys.iter().enumerate() {
                let color = LINE_COLORS[i % LINE_COLORS.len()];
                let points: Vec<(f64, f64)> = t
                    .rows
                    .iter()
                    .map(|r| (r[self.x] / x_unit.factor, r[k] / y_unit.factor))
                    .filter(|(a, b)| a.is_finite() && b.is_finite())
                    .collect();
                drawn.extend_from_slice(&points);
                chart
                    .draw_series(LineSeries::new(points, color.stroke_width(2)))
                    .map_err(draw_err)?
                    .label(t.names[k].clone())
                    .legend(legend_line(color));
            }
            Ok(())
        })?;
        super::write_png(path, &buffer, size)
    }
}

/// Share of the axes' width and height that the legend's corner box spans (a legend of one
/// to three monitors takes about that).
const LEGEND_BOX: (f64, f64) = (0.35, 0.3);

/// The corner of the axes `x × y` for the legend: the one whose box ([`LEGEND_BOX`]) holds
/// the fewest of the curves' `points` (ties in the order upper right, upper left, lower
/// right, lower left), so that the legend hides as little of the curves as it can (a
/// load–settlement curve ends in the upper right and leaves the lower right empty).
pub(crate) fn legend_corner(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let (w, h) = (x.1 - x.0, y.1 - y.0);
    let count = |right: bool, upper: bool| {
        points
            .iter()
            .filter(|(px, py)| {
                let (u, v) = ((px - x.0) / w, (py - y.0) / h);
                let in_x = if right { u >= 1.0 - LEGEND_BOX.0 } else { u <= LEGEND_BOX.0 };
                let in_y = if upper { v >= 1.0 - LEGEND_BOX.1 } else { v <= LEGEND_BOX.1 };
                in_x && in_y
            })
            .count()
    };
    [
        (SeriesLabelPosition::UpperRight, count(true, true)),
        (SeriesLabelPosition::UpperLeft, count(false, true)),
        (SeriesLabelPosition::LowerRight, count(true, false)),
        (SeriesLabelPosition::LowerLeft, count(false, false)),
    ]
    .into_iter()
    .min_by_key(|&(_, n)| n)
    .map(|(corner, _)| corner)
    .unwrap_or(SeriesLabelPosition::UpperRight)
}

/// A file name for a group: `monitors_<quantity>.png`, or `monitors_<name>.png` for a
/// monitor of unknown unit; `_vs_<x>` when not against time.
pub fn file_name(dir: &Path, table: &MonitorTable, unit: &Option<String>, ys: &[usize], x: usize) -> PathBuf {
    let what = match unit {
        Some(u) => quantity(u).to_string(),
        None => table.names[ys[0]].clone(),
    };
    let vs = if x == 0 { String::new() } else { format!("_vs_{}", table.names[x]) };
    let name: String = format!("monitors_{what}{vs}")
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' { c } else { '_' })
        .collect();
    dir.join(format!("{name}.png"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The legend goes to the emptiest corner: lower right for a curve that rises to a plateau
    /// (a footing's load), upper right for one that decays, upper right when all are empty.
    #[test]
    fn legend_takes_the_emptiest_corner() {
        let rising: Vec<(f64, f64)> = (0..=50).map(|i| (i as f64 / 50.0, 1.0 - (-(i as f64) / 8.0).exp())).collect();
        assert!(matches!(legend_corner(&rising, (0.0, 1.0), (0.0, 1.0)), SeriesLabelPosition::LowerRight));
        let decaying: Vec<(f64, f64)> = rising.iter().map(|&(x, y)| (x, 1.0 - y)).collect();
        assert!(matches!(legend_corner(&decaying, (0.0, 1.0), (0.0, 1.0)), SeriesLabelPosition::UpperRight));
        assert!(matches!(legend_corner(&[], (0.0, 1.0), (0.0, 1.0)), SeriesLabelPosition::UpperRight));
    }

    #[test]
    fn table_and_groups_by_unit() {
        let dir = std::env::temp_dir().join(format!("loam-monitors-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("monitors.csv");
        std::fs::write(&path, "time,a,f,b\n0,0,1,2\n0.5,1,NaN,3\n").unwrap();
        let t = MonitorTable::read(&path).unwrap();
        assert_eq!(t.names, ["time", "a", "f", "b"]);
        assert_eq!(t.values(3), vec![2.0, 3.0]);
        let unit = |n: &str| Some(if n == "f" { "N" } else { "m" }.to_string());
        assert_eq!(groups(&t, &[1, 2, 3], &unit), vec![(Some("m".into()), vec![1, 3]), (Some("N".into()), vec![2])]);
        assert_eq!(groups(&t, &[1, 3], &|_| None), vec![(None, vec![1]), (None, vec![3])]);
        assert_eq!(file_name(&dir, &t, &Some("N".into()), &[2], 1), dir.join("monitors_force_vs_a.png"));
        std::fs::write(&path, "t,a\n0,1\n").unwrap();
        assert!(MonitorTable::read(&path).unwrap_err().to_string().contains("not `time`"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
