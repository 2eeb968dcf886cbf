//! Empty: cargo resolves a package's build-dependencies only when it has a build script
//! (see Cargo.toml for why this crate has them).
fn main() {}
