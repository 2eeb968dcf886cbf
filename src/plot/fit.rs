//! The pictures of a fit (`loam plot DIR` on the output of `loam fit`): from `fit.csv`, one
//! picture per pair of measured quantities (e.g. q against axial strain), each test in its
//! colour, the measured points as circles and the fitted curve as a line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::field::axis_tick;
use super::frame::{register_font, FONT};
use super::monitors::{legend_corner, range, LINE_COLORS};
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
        register_font();
        let mut buffer = vec![255u8; 3 * size.0 as usize * size.1 as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
            root.fill(&WHITE).map_err(draw_err)?;
            let all = || tests.iter().flat_map(|(_, p)| p.iter());
            let (x0, x1) = range(all().map(|p| p.0));
            let (y0, y1) = range(all().flat_map(|p| [p.1, p.2]));
            let mut chart = ChartBuilder::on(&root)
                .caption(format!("{yq} against {xq}: measured (points) and fitted (lines)"), (FONT, 17))
                .margin(14)
                .x_label_area_size(42)
                .y_label_area_size(72)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(draw_err)?;
            chart
                .configure_mesh()
                .light_line_style(TRANSPARENT)
                .bold_line_style(RGBColor(225, 225, 225))
                .x_desc(label(&xq, &xu))
                .y_desc(label(&yq, &yu))
                .x_label_formatter(&|v| axis_tick(*v, x1 - x0))
                .y_label_formatter(&|v| axis_tick(*v, y1 - y0))
                .label_style((FONT, 13))
                .axis_desc_style((FONT, 14))
                .draw()
                .map_err(draw_err)?;
            let mut drawn = Vec::new();
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
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
            }
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
