//! Drawing one frame: the scene in metres with equal axis scales, a colour bar with the
//! field's name and unit, and the time in the title.
//!
//! ```text
//! ┌──────────────── case: field, t = 0.68 s ────────────────┐
//! │ y (m)                                              ┌─┐  │
//! │  ┤   ▪▪▪▪▪▪▪▪▪▪▪▪                                  │ │ 1│
//! │  ┤   ▪▪▪▪▪▪▪▪▪▪▪▪▪▪▪▪▪▪▪                           │ │  │ field (unit)
//! │  └──┬──────┬──────┬──────┬── x (m)                 └─┘ 0│
//! └──────────────────────────────────────────────────────────┘
//! ```
//!
//! Draw order: background grid, mesh cells, material points, walls, reference curves.
//! Nothing is anti-aliased, so the pixel at a point's centre has exactly the colour map's
//! colour of its value.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::colormap::ColorScale;
use super::field::{axis_tick, tick, DisplayUnit};
use super::overlay::Overlay;
use super::scene::Scene;
use super::PlotError;

/// Height of the title band (px).
const TITLE: u32 = 34;
/// Width of the colour-bar band (px).
const COLORBAR: u32 = 120;
/// Font family registered from the embedded DejaVu Sans.
pub const FONT: &str = "sans-serif";

/// The extent of the picture in metres: `[xmin, xmax, ymin, ymax]`.
pub type View = [f64; 4];

/// Colours of the overlay curves, in turn.
const OVERLAY_COLORS: [RGBColor; 4] =
    [RGBColor(0, 0, 0), RGBColor(214, 39, 40), RGBColor(31, 119, 180), RGBColor(255, 127, 14)];

/// What is the same on every frame of a series of pictures.
#[derive(Debug, Clone)]
pub struct FrameStyle {
    /// Picture size (px).
    pub size: (u32, u32),
    /// Title before the time (`case: field`).
    pub title: String,
    /// Axis names (`x`, `y`; `r`, `z`).
    pub axes: (String, String),
    /// Colours of the values.
    pub scale: ColorScale,
    /// How colour-bar values are shown.
    pub unit: DisplayUnit,
    /// Label of the colour bar (with the unit).
    pub label: String,
    /// The extent drawn, with equal scales (from [`fit_view`]).
    pub view: View,
}

type Chart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Registers the embedded font once (no system font is used).
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // a font that does not parse would be a build defect of the dejavu crate
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

fn draw_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// The chart area of a frame (left of the colour bar, below the title).
fn chart_area<'b>(root: &DrawingArea<BitMapBackend<'b>, Shift>) -> DrawingArea<BitMapBackend<'b>, Shift> {
    let (w, _) = root.dim_in_pixel();
    let (_, body) = root.split_vertically(TITLE);
    let (main, _) = body.split_horizontally(w.saturating_sub(COLORBAR));
    main
}

fn build_chart<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    view: &View,
) -> Result<Chart<'a, 'b>, PlotError> {
    ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(62)
        .build_cartesian_2d(view[0]..view[1], view[2]..view[3])
        .map_err(draw_err)
}

/// Size in pixels of the plotting area of a picture of `size`.
pub fn plot_area(size: (u32, u32)) -> Result<(u32, u32), PlotError> {
    let mut buffer = vec![0u8; 3 * size.0 as usize * size.1 as usize];
    let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
    let area = chart_area(&root);
    let chart = build_chart(&area, &[0.0, 1.0, 0.0, 1.0])?;
    Ok(chart.plotting_area().dim_in_pixel())
}

/// The view holding `bounds` (`[xmin, xmax, ymin, ymax]`) with a margin of `pad` of its
/// size, widened in one direction so that a metre is as long across as up (equal scales) in
/// a picture of `size`.
pub fn fit_view(bounds: [f64; 4], pad: f64, size: (u32, u32)) -> Result<View, PlotError> {
    let (pw, ph) = plot_area(size)?;
    let (pw, ph) = (f64::from(pw.max(1)), f64::from(ph.max(1)));
    let span = |a: f64, b: f64| if b > a { b - a } else { a.abs().max(1.0) * 1e-3 };
    let (w, h) = (span(bounds[0], bounds[1]) * (1.0 + 2.0 * pad), span(bounds[2], bounds[3]) * (1.0 + 2.0 * pad));
    let scale = (w / pw).max(h / ph);
    let (cx, cy) = (0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]));
    Ok([cx - 0.5 * scale * pw, cx + 0.5 * scale * pw, cy - 0.5 * scale * ph, cy + 0.5 * scale * ph])
}

/// The pixel of the point `(x, y)` (m) in a picture of `size` showing `view`.
pub fn pixel_of(size: (u32, u32), view: &View, x: f64, y: f64) -> Result<(i32, i32), PlotError> {
    let mut buffer = vec![0u8; 3 * size.0 as usize * size.1 as usize];
    let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
    let area = chart_area(&root);
    let chart = build_chart(&area, view)?;
    Ok(chart.backend_coord(&(x, y)))
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Draws `scene` with `style` and the reference curves `overlays` on `root` (the whole
/// picture).
pub fn draw_frame(
    root: &DrawingArea<BitMapBackend, Shift>,
    scene: &Scene,
    style: &FrameStyle,
    overlays: &[Overlay],
) -> Result<(), PlotError> {
    register_font();
    root.fill(&WHITE).map_err(draw_err)?;
    let (w, _) = root.dim_in_pixel();
    let (title_area, body) = root.split_vertically(TITLE);
    let (main, bar) = body.split_horizontally(w.saturating_sub(COLORBAR));
    let title = format!("{}   t = {} s", style.title, tick_time(scene.time));
    title_area
        .draw(&Text::new(title, ((w / 2) as i32, 10), TextStyle::from((FONT, 17).into_font()).pos(text_center())))
        .map_err(draw_err)?;

    let mut chart = build_chart(&main, &style.view)?;
    let span = style.view[1] - style.view[0];
    chart
        .configure_mesh()
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(232, 232, 232))
        .x_desc(format!("{} (m)", style.axes.0))
        .y_desc(format!("{} (m)", style.axes.1))
        .x_label_formatter(&|v| axis_tick(*v, span))
        .y_label_formatter(&|v| axis_tick(*v, span))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(draw_err)?;
    let grey = RGBColor(200, 200, 200);
    chart.draw_series(scene.grid.iter().map(|cell| closed(cell, grey.stroke_width(1)))).map_err(draw_err)?;
    // mesh edges where cells are at least 6 px across
    let (pw, _) = chart.plotting_area().dim_in_pixel();
    let metre = f64::from(pw) / (style.view[1] - style.view[0]);
    let edges = scene.polygons.first().is_some_and(|p| {
        let (a, b) = (p.vertices[0], p.vertices[p.vertices.len() / 2]);
        ((a[0] - b[0]).hypot(a[1] - b[1]) * metre) >= 6.0
    });
    for p in &scene.polygons {
        let points: Vec<(f64, f64)> = p.vertices.iter().map(|v| (v[0], v[1])).collect();
        chart
            .draw_series(std::iter::once(Polygon::new(points, rgb(style.scale.color(p.value)).filled())))
            .map_err(draw_err)?;
        if edges {
            chart
                .draw_series(std::iter::once(closed(&p.vertices, RGBColor(60, 60, 60).stroke_width(1))))
                .map_err(draw_err)?;
        }
    }
    // half a pixel more on each side: squares that touch cover the pixels between them
    let half_pixel = 0.5 / metre;
    chart
        .draw_series(scene.squares.iter().map(|s| {
            let ([x, y], h) = (s.centre, s.half + half_pixel);
            Rectangle::new([(x - h, y + h), (x + h, y - h)], rgb(style.scale.color(s.value)).filled())
        }))
        .map_err(draw_err)?;
    chart
        .draw_series(
            scene.walls.iter().map(|wall| {
                PathElement::new(wall.iter().map(|v| (v[0], v[1])).collect::<Vec<_>>(), BLACK.stroke_width(3))
            }),
        )
        .map_err(draw_err)?;
    chart
        .draw_series(scene.wall_points.iter().map(|p| Circle::new((p[0], p[1]), 1, BLACK.filled())))
        .map_err(draw_err)?;
    for (k, o) in overlays.iter().enumerate() {
        let color = OVERLAY_COLORS[k % OVERLAY_COLORS.len()];
        chart
            .draw_series(LineSeries::new(o.points.iter().map(|p| (p[0], p[1])), color.stroke_width(2)))
            .map_err(draw_err)?
            .label(o.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    if !overlays.is_empty() {
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(draw_err)?;
    }
    draw_colorbar(&bar, style)
}

/// A closed outline through `vertices`.
fn closed(vertices: &[[f64; 2]], style: ShapeStyle) -> PathElement<(f64, f64)> {
    let mut points: Vec<(f64, f64)> = vertices.iter().map(|v| (v[0], v[1])).collect();
    if let Some(&first) = points.first() {
        points.push(first);
    }
    PathElement::new(points, style)
}

fn text_center() -> Pos {
    Pos::new(HPos::Center, VPos::Top)
}

/// A time for a title: at least the digits that tell output times apart.
fn tick_time(t: f64) -> String {
    let s = format!("{t:.4}");
    let s = s.trim_end_matches('0');
    let s = s.strip_suffix('.').map_or_else(|| s.to_string(), |s| format!("{s}.0"));
    s
}

/// About `n` round tick values in `[min, max]`.
pub fn nice_ticks(min: f64, max: f64, n: usize) -> Vec<f64> {
    let span = max - min;
    if span.is_nan() || span <= 0.0 || span.is_infinite() {
        return vec![min];
    }
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0].iter().map(|f| f * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag);
    let first = (min / step).ceil() as i64;
    let last = (max / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// The colour bar: the map from bottom (min) to top (max), ticks on its right, the label
/// turned along it.
fn draw_colorbar(area: &DrawingArea<BitMapBackend, Shift>, style: &FrameStyle) -> Result<(), PlotError> {
    let (_, h) = area.dim_in_pixel();
    let (x0, x1) = (8, 28);
    let (top, bottom) = (22, h as i32 - 54);
    if bottom <= top {
        return Ok(());
    }
    let s = &style.scale;
    for py in top..=bottom {
        let t = f64::from(bottom - py) / f64::from(bottom - top);
        let c = s.map.at(t);
        area.draw(&PathElement::new(vec![(x0, py), (x1, py)], rgb(c))).map_err(draw_err)?;
    }
    area.draw(&Rectangle::new([(x0, top), (x1, bottom)], BLACK.stroke_width(1))).map_err(draw_err)?;
    let f = style.unit.factor;
    for v in nice_ticks(s.min / f, s.max / f, 6) {
        let t = (v * f - s.min) / (s.max - s.min);
        let py = bottom - (t * f64::from(bottom - top)).round() as i32;
        area.draw(&PathElement::new(vec![(x1, py), (x1 + 4, py)], BLACK)).map_err(draw_err)?;
        area.draw(&Text::new(
            tick(v),
            (x1 + 7, py),
            TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Left, VPos::Center)),
        ))
        .map_err(draw_err)?;
    }
    let label_style = TextStyle::from((FONT, 14).into_font().transform(FontTransform::Rotate270))
        .pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new(style.label.clone(), (100, (top + bottom) / 2), label_style)).map_err(draw_err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_have_equal_scales() {
        let size = (800, 500);
        let (pw, ph) = plot_area(size).unwrap();
        let v = fit_view([0.0, 0.5, 0.0, 0.1], 0.0, size).unwrap();
        let (sx, sy) = ((v[1] - v[0]) / f64::from(pw), (v[3] - v[2]) / f64::from(ph));
        assert!((sx - sy).abs() < 1e-12 * sx, "{sx} {sy}");
        assert!(v[0] <= 0.0 && v[1] >= 0.5 && v[2] <= 0.0 && v[3] >= 0.1);
        // the wide body fills the width
        assert!((v[1] - v[0] - 0.5).abs() < 1e-12);
        let (x0, y0) = pixel_of(size, &v, 0.0, 0.05).unwrap();
        let (x1, y1) = pixel_of(size, &v, 0.5, 0.05).unwrap();
        assert!(y0 == y1 && (x1 - x0 - pw as i32).abs() <= 1, "{x0} {x1} {pw}");
    }

    #[test]
    fn ticks_are_round() {
        let labels = |t: Vec<f64>| t.into_iter().map(tick).collect::<Vec<_>>();
        assert_eq!(labels(nice_ticks(0.0, 1.0, 5)), ["0", "0.2", "0.4", "0.6", "0.8", "1"]);
        assert_eq!(labels(nice_ticks(-3.0, 7.0, 4)), ["-2.5", "0", "2.5", "5"]);
        assert_eq!(nice_ticks(2.0, 2.0, 4), vec![2.0]);
        assert_eq!(tick_time(0.68), "0.68");
        assert_eq!(tick_time(2.0), "2.0");
    }
}
