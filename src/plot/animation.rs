//! `--gif`: the frames as one animated GIF (plotters' GIF backend; the same drawing as the
//! PNG frames).

use std::path::Path;

use plotters::prelude::*;

use super::frame::{draw_frame, FrameStyle};
use super::overlay::Overlay;
use super::scene::Scene;
use super::PlotError;

/// Writes `scenes` as an animation to `path`, `delay_ms` between frames.
pub fn write_gif(
    path: &Path,
    scenes: &[Scene],
    style: &FrameStyle,
    overlays: &[Overlay],
    delay_ms: u32,
) -> Result<(), PlotError> {
    let backend = BitMapBackend::gif(path, style.size, delay_ms)
        .map_err(|e| PlotError::Write { file: path.to_path_buf(), reason: e.to_string() })?;
    let root = backend.into_drawing_area();
    for scene in scenes {
        draw_frame(&root, scene, style, overlays)?;
        root.present().map_err(|e| PlotError::Write { file: path.to_path_buf(), reason: e.to_string() })?;
    }
    Ok(())
}
