//! Finds PETSc (and the MPI it is built on) with pkg-config and runs bindgen over
//! `petscksp.h`, limited to the functions, types and variables Loam calls.

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=wrapper.h");
    println!("cargo:rerun-if-changed=build.rs");
    let petsc = pkg_config::Config::new().probe("petsc").unwrap_or_else(|e| {
        panic!(
            "PETSc not found by pkg-config ({e}); install it with scripts/install_petsc.sh \
             (Debian's petsc-dev, libopenmpi-dev, libclang-dev)"
        )
    });
    // petsc.h includes mpi.h, and PETSc's communicators are Open MPI globals: the MPI
    // include path and library come from Open MPI's pkg-config file (Debian: ompi-c)
    let mpi = ["ompi-c", "mpi", "ompi"]
        .iter()
        .find_map(|name| pkg_config::Config::new().probe(name).ok())
        .expect("MPI (Open MPI's pkg-config file ompi-c) not found: install libopenmpi-dev");
    let mut builder = bindgen::Builder::default()
        .header("wrapper.h")
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
        .allowlist_function(
            "Petsc(InitializeNoArguments|Initialized|Finalize|Finalized|OptionsSetValue|OptionsClearValue|PushErrorHandler|PopErrorHandler|ReturnErrorHandler|ErrorMessage)",
        )
        .allowlist_function(
            "Mat(Create|SetSizes|SetType|SeqAIJSetPreallocationCSR|MPIAIJSetPreallocationCSR|SeqAIJGetArray|SeqAIJRestoreArray|ZeroEntries|SetValues|AssemblyBegin|AssemblyEnd|SetBlockSize|Destroy|CreateVecs|SetOption)",
        )
        .allowlist_function(
            "Vec(GetArray|RestoreArray|GetArrayRead|RestoreArrayRead|Destroy|GetSize|GetLocalSize|Duplicate|CreateMPI|ZeroEntries|SetValues|AssemblyBegin|AssemblyEnd|ScatterCreateToAll|ScatterBegin|ScatterEnd|ScatterDestroy)",
        )
        .allowlist_function("MatNullSpace(Create|Destroy)|MatSetNearNullSpace")
        .allowlist_function(
            "KSP(Create|SetOperators|SetType|GetType|GetPC|SetTolerances|SetFromOptions|SetOptionsPrefix|Solve|GetIterationNumber|GetConvergedReason|GetResidualNorm|Destroy|GMRESSetRestart|SetNormType|SetPCSide|SetInitialGuessNonzero|SetUp)",
        )
        .allowlist_function("PC(SetType|GetType|FactorSetMatSolverType)")
        .allowlist_function("MPI_(Init_thread|Initialized|Finalize|Finalized)")
        .allowlist_var("PETSC_COMM_WORLD")
        .allowlist_var("MPI_THREAD_.*")
        .allowlist_type("KSPConvergedReason|KSPNormType|PCSide|MatAssemblyType|MatOption|PetscBool|InsertMode|ScatterMode")
        .rustified_enum("KSPNormType|PCSide|MatAssemblyType|MatOption|PetscBool|InsertMode|ScatterMode")
        .derive_debug(true)
        .layout_tests(false)
        .generate_comments(false);
    for path in petsc.include_paths.iter().chain(&mpi.include_paths) {
        builder = builder.clang_arg(format!("-I{}", path.display()));
    }
    let bindings = builder.generate().expect("bindgen over petscksp.h");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    bindings.write_to_file(out.join("bindings.rs")).expect("bindings written");
}
