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
//! The first data set (and a resumed series) writes the whole file, to a temporary file then
//! renamed over the old one; each later data set overwrites only the closing tags with its
//! line and the closing tags (one write of a line's length at a known offset), so a run of
//! `n` outputs writes O(n) bytes of `.pvd` in all, not O(n²), and a run that stops between
//! outputs leaves a valid series of the steps written so far.

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
    /// Byte offset of the closing tags in the file as written (`None`: not written yet).
    closing_at: Option<u64>,
}

/// The header of a `.pvd` document, up to the first data set.
const HEADER: &str =
    "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
/// The closing tags of a `.pvd` document.
const CLOSING: &str = "  </Collection>\n</VTKFile>\n";

impl PvdSeries {
    /// A series to be written to `path` (e.g. `results/soil.pvd`). Nothing is written until
    /// the first [`add`](Self::add).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self { path: path.into(), steps: Vec::new(), closing_at: None }
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
        let written = match self.closing_at {
            Some(offset) => self.append(offset),
            None => self.write(),
        };
        if let Err(e) = written {
            self.steps.pop();
            return Err(e);
        }
        Ok(())
    }

    /// A series to be written to `path` that already holds `steps` (a resumed run); the
    /// `.pvd` is rewritten with them.
    pub fn resume(path: impl Into<PathBuf>, steps: Vec<DataSet>) -> Result<Self, OutputError> {
        let mut series = Self { path: path.into(), steps, closing_at: None };
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
        let mut xml = String::from(HEADER);
        for step in &self.steps {
            xml += &data_set_line(step);
        }
        xml += CLOSING;
        xml
    }

    fn write_error(&self, e: std::io::Error) -> OutputError {
        OutputError::Write { file: self.path.clone(), reason: e.to_string() }
    }

    /// Writes the whole document (temporary file renamed over the old one).
    fn write(&mut self) -> Result<(), OutputError> {
        let mut tmp = self.path.clone().into_os_string();
        tmp.push(".tmp");
        let document = self.document();
        std::fs::write(&tmp, &document).map_err(|e| self.write_error(e))?;
        std::fs::rename(&tmp, &self.path).map_err(|e| self.write_error(e))?;
        self.closing_at = Some((document.len() - CLOSING.len()) as u64);
        Ok(())
    }

    /// Writes the last data set's line and the closing tags over the closing tags at
    /// `offset`.
    fn append(&mut self, offset: u64) -> Result<(), OutputError> {
        use std::io::{Seek, SeekFrom, Write};
        let line = data_set_line(self.steps.last().expect("a data set to append"));
        let appended = (|| {
            let mut file = std::fs::OpenOptions::new().write(true).open(&self.path)?;
            file.seek(SeekFrom::Start(offset))?;
            file.write_all(format!("{line}{CLOSING}").as_bytes())
        })();
        appended.map_err(|e| self.write_error(e))?;
        self.closing_at = Some(offset + line.len() as u64);
        Ok(())
    }
}

/// The `<DataSet …/>` line of one data set.
fn data_set_line((time, file, part): &DataSet) -> String {
    format!("    <DataSet timestep=\"{time}\" group=\"\" part=\"{part}\" file=\"{}\"/>\n", escape(file))
}

/// Escape the five XML special characters for an attribute value.
pub(super) fn escape(s: &str) -> String {
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
        // the appended file is the whole document, and stays so after a resume and more steps
        assert_eq!(three, series.document());
        let mut resumed = PvdSeries::resume(&path, series.steps()[..2].to_vec()).unwrap();
        resumed.add_part(2.0, "soil_000002.vtu", 1).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), resumed.document());
        assert_eq!(resumed.steps().len(), 3);
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
