//! ParaView data collections (`.pvd`): a time series of files, one per output step.
//!
//! ```xml
//! <VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
//!   <Collection>
//!     <DataSet timestep="0.5" group="" part="0" file="soil_000001.vtu"/>
//!   </Collection>
//! </VTKFile>
//! ```
//!
//! The whole file is rewritten after every step (to a temporary file, then renamed over the
//! old one), so a run that stops at any moment leaves a valid series of the steps written
//! so far.

use std::path::{Path, PathBuf};

use super::vtk::OutputError;

/// One data set of a series: time, file name relative to the `.pvd`, part.
pub type DataSet = (f64, String, usize);

/// A `.pvd` series being written: (time, file name relative to the `.pvd`, part) per data
/// set; a series of several parts lists every part of each step (ParaView shows them
/// together, e.g. the soil's points and the structure's mesh of a coupled case).
#[derive(Debug, Clone)]
pub struct PvdSeries {
    path: PathBuf,
    steps: Vec<DataSet>,
}

impl PvdSeries {
    /// A series to be written to `path` (e.g. `results/soil.pvd`). Nothing is written until
    /// the first [`add`](Self::add).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self { path: path.into(), steps: Vec::new() }
    }

    /// Record that `file` (a name relative to the `.pvd`'s directory, e.g. `soil_000003.vtu`)
    /// holds the state at `time`, and rewrite the `.pvd`.
    pub fn add(&mut self, time: f64, file: &str) -> Result<(), OutputError> {
        self.add_part(time, file, 0)
    }

    /// As [`add`](Self::add), for part `part` of a series of several parts.
    pub fn add_part(&mut self, time: f64, file: &str, part: usize) -> Result<(), OutputError> {
        let invalid = |reason: String| OutputError::InvalidData { file: self.path.clone(), reason };
        if !time.is_finite() {
            return Err(invalid(format!("time {time} of `{file}` is not finite")));
        }
        if file.is_empty() || Path::new(file).is_absolute() {
            return Err(invalid(format!("`{file}` is not a file name relative to the .pvd")));
        }
        self.steps.push((time, file.to_string(), part));
        if let Err(e) = self.write() {
            self.steps.pop();
            return Err(e);
        }
        Ok(())
    }

    /// A series to be written to `path` that already holds `steps` (a resumed run); the
    /// `.pvd` is rewritten with them.
    pub fn resume(path: impl Into<PathBuf>, steps: Vec<DataSet>) -> Result<Self, OutputError> {
        let series = Self { path: path.into(), steps };
        series.write()?;
        Ok(series)
    }

    /// Path of the `.pvd` file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The data sets recorded so far: (time, relative file name, part).
    pub fn steps(&self) -> &[DataSet] {
        &self.steps
    }

    /// The `.pvd` document of the steps so far.
    fn document(&self) -> String {
        let mut xml = String::from(
            "<?xml version=\"1.0\"?>\n\
             <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (time, file, part) in &self.steps {
            xml +=
                &format!("    <DataSet timestep=\"{time}\" group=\"\" part=\"{part}\" file=\"{}\"/>\n", escape(file));
        }
        xml += "  </Collection>\n</VTKFile>\n";
        xml
    }

    fn write(&self) -> Result<(), OutputError> {
        let write_err = |e: std::io::Error| OutputError::Write { file: self.path.clone(), reason: e.to_string() };
        let mut tmp = self.path.clone().into_os_string();
        tmp.push(".tmp");
        std::fs::write(&tmp, self.document()).map_err(write_err)?;
        std::fs::rename(&tmp, &self.path).map_err(write_err)
    }
}

/// Escape the five XML special characters for an attribute value.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("loam-pvd-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn series_is_valid_after_every_step() {
        let dir = temp_dir("series");
        let path = dir.join("soil.pvd");
        let mut series = PvdSeries::new(&path);
        assert!(!path.exists());
        series.add(0.0, "soil_000000.vtu").unwrap();
        let one = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            one,
            "<?xml version=\"1.0\"?>\n\
             <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
             \x20 <Collection>\n\
             \x20   <DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"soil_000000.vtu\"/>\n\
             \x20 </Collection>\n\
             </VTKFile>\n"
        );
        series.add(0.1, "soil_000001.vtu").unwrap();
        series.add(1.5e-7, "a&b <\"c\">.vtu").unwrap();
        let three = std::fs::read_to_string(&path).unwrap();
        assert!(three.starts_with(&one[..one.find("  </Collection>").unwrap()]));
        assert!(three.contains("timestep=\"0.1\" group=\"\" part=\"0\" file=\"soil_000001.vtu\""));
        assert!(
            three.contains("timestep=\"0.00000015\" group=\"\" part=\"0\" file=\"a&amp;b &lt;&quot;c&quot;&gt;.vtu\"")
        );
        assert!(three.ends_with("  </Collection>\n</VTKFile>\n"));
        assert_eq!(series.steps().len(), 3);
        assert_eq!(series.path(), path);
        // no temporary file left behind
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("soil.pvd")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_steps_and_unwritable_paths_are_errors() {
        let dir = temp_dir("errors");
        let mut series = PvdSeries::new(dir.join("s.pvd"));
        assert!(series.add(f64::NAN, "a.vtu").unwrap_err().to_string().contains("is not finite"));
        assert!(series.add(0.0, "/abs/a.vtu").unwrap_err().to_string().contains("not a file name relative"));
        assert!(series.steps().is_empty());

        let mut series = PvdSeries::new(dir.join("missing/s.pvd"));
        let err = series.add(0.0, "a.vtu").unwrap_err();
        assert!(err.to_string().starts_with(&format!("{}: cannot write: ", dir.join("missing/s.pvd").display())));
        assert!(series.steps().is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
