//! Records the cargo features this build of `loam` was compiled with, for `loam --version`.

fn main() {
    let mut features: Vec<String> = std::env::vars()
        .filter_map(|(k, _)| k.strip_prefix("CARGO_FEATURE_").map(|f| f.to_lowercase().replace('_', "-")))
        .collect();
    features.sort();
    let list = if features.is_empty() { "none".to_string() } else { features.join(", ") };
    println!("cargo:rustc-env=LOAM_BUILD_FEATURES={list}");
    println!("cargo:rerun-if-changed=build.rs");
}
