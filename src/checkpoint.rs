//! Checkpoints: the complete state of a run in one file, from which `loam run --resume`
//! continues to exactly the results of an uninterrupted run (same thread count).
//!
//! A checkpoint holds the committed nodal state, every domain's state (material points with
//! their law histories, FEM law histories, penalty walls, the sparsity pattern an MPM grid
//! keeps and what the linear solver learnt about it), the simulation's counters and step
//! control (adaptive step, rest criterion, input values) and the result writer's state
//! (`monitors.csv` length, the `.pvd` series). Monitors need none: they are evaluated on the
//! state.
//!
//! File layout (little endian):
//!
//! ```text
//! b"LOAMCKPT"  magic
//! u32          format version (FORMAT_VERSION)
//! u32          CRC-32 of the payload
//! u64          payload length
//! payload      bincode of `Checkpoint`
//! ```
//!
//! Files are written to a temporary name, synced, then renamed over the target, so a crash
//! during a write leaves the previous checkpoint intact. A checkpoint is refused (one line,
//! exit 2) if it is not one, is truncated or corrupt (length, CRC), comes from another format
//! version, or from another case: the case's fingerprint is the CRC-32 of its JSON with
//! `analysis.end_time`, `analysis.checkpoint` and the output settings that do not touch the
//! steps (`output.vtk`, `interval`, `time_interval`, `grid`; not `times`, which shortens
//! steps) removed, so a run can be resumed with a later end time, other checkpoint settings or
//! other VTK output (e.g. switched on to look at the steps before a failure), nothing else.
//! Checkpoints of builds whose fingerprint kept the output settings are still read.

use std::io::Write;
use std::path::{Path, PathBuf};

use bincode::Options;
use loam_fem::model::ModelState;
use serde::{Deserialize, Serialize};

use crate::output::results::WriterState;
use crate::simulation::SimulationState;

/// Version of the checkpoint format; a file of another version is refused. 2 (6 December
/// 2026): the linear solver's memory gained the `L B Lᵀ` back-off state.
pub const FORMAT_VERSION: u32 = 2;

const MAGIC: &[u8; 8] = b"LOAMCKPT";
const HEADER: usize = 8 + 4 + 4 + 8;

/// The state of a run.
#[derive(Serialize, Deserialize)]
pub struct Checkpoint {
    /// Loam's version that wrote it (reported, not checked: the format version is).
    pub loam_version: String,
    /// Name of the case (file stem).
    pub case_name: String,
    /// [`fingerprint`] of the case.
    pub case_fingerprint: u32,
    /// The simulation's counters and step control.
    pub simulation: SimulationState,
    /// The model with its domains.
    pub model: ModelState,
    /// The result writer's state, if the run wrote results.
    pub writer: Option<WriterState>,
}

/// Why a checkpoint cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file could not be read or written.
    #[error("{file}: {reason}")]
    Io {
        /// The file.
        file: PathBuf,
        /// What failed.
        reason: String,
    },
    /// Not a checkpoint, truncated, corrupt, of another version or of another case.
    #[error("{file}: {reason}")]
    Refused {
        /// The file.
        file: PathBuf,
        /// Why.
        reason: String,
    },
}

/// Output settings that change what is written, not the steps (left out of the fingerprint).
const OUTPUT_ONLY_KEYS: [&str; 4] = ["vtk", "interval", "time_interval", "grid"];

/// The fingerprints a case file's text accepts a checkpoint of: CRC-32 of its JSON without
/// `analysis.end_time`, `analysis.checkpoint` and the output-only settings
/// (`output.vtk`, `interval`, `time_interval`, `grid`; an `output` left empty is dropped),
/// keys in sorted order (whitespace and key order do not matter); then the same with the
/// output settings kept, as builds before 5 December 2026 wrote it. The first is written.
pub fn fingerprints(text: &str) -> [u32; 2] {
    let Ok(mut value) = serde_json::from_str::<serde_json::Value>(text) else {
        let crc = crc32fast::hash(text.as_bytes());
        return [crc, crc];
    };
    if let Some(analysis) = value.get_mut("analysis").and_then(|a| a.as_object_mut()) {
        analysis.remove("end_time");
        analysis.remove("checkpoint");
    }
    let legacy = crc32fast::hash(value.to_string().as_bytes());
    if let Some(case) = value.as_object_mut() {
        if let Some(output) = case.get_mut("output").and_then(|o| o.as_object_mut()) {
            OUTPUT_ONLY_KEYS.iter().for_each(|k| _ = output.remove(*k));
            if output.is_empty() {
                case.remove("output");
            }
        }
    }
    [crc32fast::hash(value.to_string().as_bytes()), legacy]
}

/// The fingerprint written into checkpoints: the first of [`fingerprints`].
pub fn fingerprint(text: &str) -> u32 {
    fingerprints(text)[0]
}

/// Writes `checkpoint` to `path` atomically (temporary file, sync, rename).
pub fn write(path: &Path, checkpoint: &Checkpoint) -> Result<(), CheckpointError> {
    let io = |e: std::io::Error| CheckpointError::Io { file: path.to_path_buf(), reason: e.to_string() };
    let payload = bincode::serialize(checkpoint)
        .map_err(|e| CheckpointError::Io { file: path.to_path_buf(), reason: format!("encoding: {e}") })?;
    let mut bytes = Vec::with_capacity(HEADER + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&payload);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let mut file = std::fs::File::create(&tmp).map_err(io)?;
    file.write_all(&bytes).map_err(io)?;
    file.sync_all().map_err(io)?;
    drop(file);
    std::fs::rename(&tmp, path).map_err(io)
}

/// Reads and checks the checkpoint at `path` against the case of [`fingerprints`]
/// `case_fingerprints` (either one is accepted).
pub fn read(path: &Path, case_fingerprints: [u32; 2]) -> Result<Checkpoint, CheckpointError> {
    let refused = |reason: String| CheckpointError::Refused { file: path.to_path_buf(), reason };
    let meta =
        std::fs::metadata(path).map_err(|e| CheckpointError::Io { file: path.to_path_buf(), reason: e.to_string() })?;
    if !meta.is_file() {
        return Err(refused("not a regular file".into()));
    }
    let bytes =
        std::fs::read(path).map_err(|e| CheckpointError::Io { file: path.to_path_buf(), reason: e.to_string() })?;
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Err(refused("not a Loam checkpoint".into()));
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let version = word(8);
    if version != FORMAT_VERSION {
        return Err(refused(format!("checkpoint format version {version}, this Loam reads version {FORMAT_VERSION}")));
    }
    let crc = word(12);
    let length = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER..];
    if payload.len() as u64 != length {
        return Err(refused(format!(
            "truncated or extended: {} payload bytes, the header says {length}",
            payload.len()
        )));
    }
    if crc32fast::hash(payload) != crc {
        return Err(refused("corrupt (its checksum does not match)".into()));
    }
    // the encoding of `write` (bincode's fixed-width integers), allocating no more than the
    // payload can hold: a crafted length cannot ask for more memory than the file has
    let options =
        bincode::DefaultOptions::new().with_fixint_encoding().allow_trailing_bytes().with_limit(payload.len() as u64);
    let checkpoint: Checkpoint =
        options.deserialize(payload).map_err(|e| refused(format!("corrupt (cannot decode: {e})")))?;
    if !case_fingerprints.contains(&checkpoint.case_fingerprint) {
        return Err(refused(format!(
            "written for another case ('{}', or this case with other settings than end_time, checkpoint and the VTK output)",
            checkpoint.case_name
        )));
    }
    Ok(checkpoint)
}

/// The checkpoint directory of a results directory.
pub fn directory(out_dir: &Path) -> PathBuf {
    out_dir.join("checkpoints")
}

/// The file of the checkpoint after step `step` in `out_dir`.
pub fn path_of(out_dir: &Path, step: usize) -> PathBuf {
    directory(out_dir).join(format!("step_{step:09}.ckpt"))
}

/// The checkpoints in `out_dir`, newest (highest step) last.
pub fn list(out_dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(directory(out_dir)) else { return Vec::new() };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ckpt"))
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("step_")))
        .collect();
    files.sort();
    files
}

/// Deletes all but the newest `keep` checkpoints in `out_dir`.
pub fn prune(out_dir: &Path, keep: usize) {
    let files = list(out_dir);
    for old in files.iter().take(files.len().saturating_sub(keep)) {
        let _ = std::fs::remove_file(old);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fingerprint leaves out the end time, the checkpoint settings and the output-only
    /// settings (an `output` they leave empty counts as none), keeps `output.times` and the
    /// rest; the second fingerprint is the one of builds that kept the output settings.
    #[test]
    fn fingerprints_leave_out_what_does_not_touch_the_steps() {
        let base = r#"{"analysis": {"type": "static", "end_time": 1.0}, "domains": []}"#;
        let same = [
            r#"{"domains": [], "analysis": {"end_time": 2.0, "type": "static", "checkpoint": {"every_steps": 5}}}"#,
            r#"{"analysis": {"type": "static"}, "domains": [], "output": {"vtk": false, "interval": 3}}"#,
            r#"{"analysis": {"type": "static"}, "domains": [], "output": {"time_interval": 0.1, "grid": true}}"#,
        ];
        let [fp, legacy] = fingerprints(base);
        assert_eq!(fp, legacy, "a case without output settings has one fingerprint");
        for text in same {
            assert_eq!(fingerprint(text), fp, "{text}");
        }
        let other = [
            r#"{"analysis": {"type": "static"}, "domains": [], "output": {"times": [0.5]}}"#,
            r#"{"analysis": {"type": "dynamic"}, "domains": []}"#,
        ];
        for text in other {
            assert_ne!(fingerprint(text), fp, "{text}");
        }
        let with_vtk = r#"{"analysis": {"type": "static"}, "domains": [], "output": {"vtk": false}}"#;
        let [fp_vtk, legacy_vtk] = fingerprints(with_vtk);
        assert_eq!(fp_vtk, fp);
        assert_ne!(legacy_vtk, fp, "the old fingerprint kept the output settings");
    }
}
