//! Reference curves drawn on top of a frame (`--overlay FILE.csv[:LABEL]`): an experiment's
//! free surface, a failure line. The file holds one point per line, x and y in metres in
//! its first two columns, comma-separated; a first line that is not numeric is a header.

use std::path::{Path, PathBuf};

use super::PlotError;

/// A reference curve: its legend label and points (m).
#[derive(Debug, Clone, PartialEq)]
pub struct Overlay {
    /// Legend label (the file stem unless given).
    pub label: String,
    /// Points in order.
    pub points: Vec<[f64; 2]>,
}

/// Parses `FILE.csv[:LABEL]`.
pub fn parse_spec(spec: &str) -> (PathBuf, Option<String>) {
    match spec.rsplit_once(':') {
        Some((file, label)) if !label.is_empty() && !label.contains('/') => {
            (PathBuf::from(file), Some(label.to_string()))
        }
        _ => (PathBuf::from(spec), None),
    }
}

/// Reads a curve from `path`.
pub fn read_overlay(path: &Path, label: Option<String>) -> Result<Overlay, PlotError> {
    let bad = |reason: String| PlotError::BadInput(format!("--overlay {}: {reason}", path.display()));
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let mut points = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut cols = line.split(',').map(|c| c.trim().parse::<f64>());
        match (cols.next(), cols.next()) {
            (Some(Ok(x)), Some(Ok(y))) => points.push([x, y]),
            _ if k == 0 => {} // header
            _ => return Err(bad(format!("line {}: expected two numbers x,y (m), got `{line}`", k + 1))),
        }
    }
    if points.len() < 2 {
        return Err(bad("fewer than two points".into()));
    }
    let label = label.unwrap_or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default());
    Ok(Overlay { label, points })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_points() {
        let dir = std::env::temp_dir().join(format!("loam-overlay-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("surface.csv");
        std::fs::write(&path, "x_m,y_m\n0,0.1\n0.2,0.05\n").unwrap();
        let o = read_overlay(&path, None).unwrap();
        assert_eq!((o.label.as_str(), o.points.clone()), ("surface", vec![[0.0, 0.1], [0.2, 0.05]]));
        std::fs::write(&path, "x_m,y_m\n0,0.1\nzero,1\n").unwrap();
        let e = read_overlay(&path, None).unwrap_err().to_string();
        assert!(e.contains("line 3: expected two numbers"), "{e}");
        assert_eq!(parse_spec("a/b.csv:experiment"), (PathBuf::from("a/b.csv"), Some("experiment".into())));
        assert_eq!(parse_spec("a/b.csv"), (PathBuf::from("a/b.csv"), None));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
