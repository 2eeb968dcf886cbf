//! The pictures of a fit (`loam plot DIR` on the output of `loam fit`): from `fit.csv`, one
//! picture per pair of measured quantities (e.g. q against axial strain), each test in its
//! colour, the measured points as circles and the fitted curve as a line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::monitors::{legend_line, line_chart, range, Axes, LINE_COLORS};
use super::PlotError;

/// The rows of `fit.csv` of one picture: per test (in file order), `(x, measured, fitted)`.
type Group = Vec<(String, Vec<(f64, f64, f64)>)>;

/// A picture's key: `(x_quantity, x_unit, y_quantity, y_unit)`.
type Key = (String, String, String, String);

/// Reads `fit.csv`: the groups by [`Key`].
fn read(path: &Path) -> Result<BTreeMap<Key, Group>, PlotError> {
    let bad = |reason: String| PlotError::Read { file: path.to_path_buf(), reason };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("");
    if header != "test,x_quantity,x_unit,x,y_quantity,y_unit,measured,fitted" {
        return Err(bad("not a fit.csv of `loam fit` (header)".into()));
    }
    let mut groups: BTreeMap<_, Group> = BTreeMap::new();
    for (k, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |s: &str| s.trim().parse::<f64>().map_err(|e| bad(format!("line {}: {e}", k + 2)));
        if f.len() != 8 {
            return Err(bad(format!("line {}: {} values for 8 columns", k + 2, f.len())));
        }
        let key = (f[1].to_string(), f[2].to_string(), f[4].to_string(), f[5].to_string());
        let group = groups.entry(key).or_default();
        let point = (num(f[3])?, num(f[6])?, num(f[7])?);
        match group.iter_mut().find(|(t, _)| t == f[0]) {
            Some((_, points)) => points.push(point),
            None => group.push((f[0].to_string(), vec![point])),
        }
    }
    Ok(groups)
}

fn draw_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Draw(e.to_string())
}

fn label(quantity: &str, unit: &str) -> String {
    if unit == "1" {
        quantity.to_string()
    } else {
        format!("{quantity} ({unit})")
    }
}

/// Draws the pictures of `fit_csv` into `out`: `fit_<y>_vs_<x>.png`. Returns the files.
pub fn plot_fit(fit_csv: &Path, out: &Path, size: (u32, u32)) -> Result<Vec<PathBuf>, PlotError> {
    let mut files = Vec::new();
    for ((xq, xu, yq, yu), tests) in read(fit_csv)? {
        let all = || tests.iter().flat_map(|(_, p)| p.iter());
        let caption = format!("{yq} against {xq}: measured (points) and fitted (lines)");
        let axes = Axes {
            caption: &caption,
            x: range(all().map(|p| p.0)),
            y: range(all().flat_map(|p| [p.1, p.2])),
            x_desc: label(&xq, &xu),
            y_desc: label(&yq, &yu),
        };
        let buffer = line_chart(size, &axes, |chart, drawn| {
            for (i, (name, points)) in tests.iter().enumerate() {
                let color = LINE_COLORS[i % LINE_COLORS.len()];
                let mut sorted = points.clone();
                sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
                chart
                    .draw_series(sorted.iter().map(|p| Circle::new((p.0, p.1), 3, color.stroke_width(1))))
                    .map_err(draw_err)?;
                let line: Vec<(f64, f64)> = sorted.iter().map(|p| (p.0, p.2)).collect();
                drawn.extend(sorted.iter().map(|p| (p.0, p.1)));
                drawn.extend_from_slice(&line);
                chart
                    .draw_series(LineSeries::new(line, color.stroke_width(2)))
                    .map_err(draw_err)?
                    .label(name.clone())
                    .legend(legend_line(color));
            }
            Ok(())
        })?;
        let name: String = format!("fit_{yq}_vs_{xq}")
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' { c } else { '_' })
            .collect();
        let file = out.join(format!("{name}.png"));
        super::write_png(&file, &buffer, size)?;
        files.push(file);
    }
    Ok(files)
}
