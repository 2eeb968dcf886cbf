//! Helpers for the tests that drive the `loam` binary: the command, the repository root and
//! a fresh temporary folder per test.

use std::path::PathBuf;
use std::process::Command;

/// The `loam` binary built for this test run.
pub fn loam() -> Command {
    Command::new(env!("CARGO_BIN_EXE_loam"))
}

/// The repository root (bundled cases, docs, test data are below it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The temporary folder `name` of this test binary and process, not emptied.
pub fn temp_dir_path(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("loam-{}-{}-{name}", env!("CARGO_CRATE_NAME"), std::process::id()))
}

/// The temporary folder `name` of this test binary and process, created empty.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = temp_dir_path(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
