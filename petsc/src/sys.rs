//! The raw declarations bindgen generates from `petscksp.h` (allowlisted in `build.rs`).
#![allow(non_upper_case_globals, non_camel_case_types, non_snake_case, dead_code, missing_docs)]
#![allow(clippy::all)]

include!(concat!(env!("OUT_DIR"), "/bindings.rs"));
