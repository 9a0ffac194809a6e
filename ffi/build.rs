//! Generates the raw PETSc bindings with bindgen against Debian's PETSc headers (found through
//! pkg-config) and compiles the C shim. See docs/guide.md, "System set-up",
//! for the PETSc this expects; the comments below say why each option is here.

use std::env;
use std::path::PathBuf;

fn main() {
    let petsc = pkg_config::Config::new()
        .cargo_metadata(true)
        .probe("PETSc")
        .expect("pkg-config cannot find PETSc: run ci/setup (libpetsc-real-dev)");
    if !petsc.version.starts_with("3.18") {
        panic!(
            "the bindings are written for PETSc 3.18 (Debian bookworm); pkg-config found {}",
            petsc.version
        );
    }
    let ompi = pkg_config::Config::new()
        .cargo_metadata(false)
        .probe("ompi-c")
        .expect("pkg-config cannot find ompi-c: run ci/setup (libopenmpi-dev)");
    let includes: Vec<PathBuf> = petsc
        .include_paths
        .iter()
        .chain(ompi.include_paths.iter())
        .cloned()
        .collect();

    let mut shim = cc::Build::new();
    shim.file("shim.c");
    for inc in &includes {
        shim.include(inc);
    }
    shim.compile("petsc_ffi_shim");

    let mut builder = bindgen::Builder::default()
        .header("wrapper.h")
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
        .default_macro_constant_type(bindgen::MacroTypeVariation::Signed)
        .default_enum_style(bindgen::EnumVariation::NewType {
            is_bitfield: false,
            is_global: false,
        })
        // MPI types come from mpi-sys so rsmpi's raw communicator is the type PETSc takes.
        .blocklist_type("MPI_.*")
        .blocklist_type("ompi_.*")
        .allowlist_function("(Petsc|Mat|Vec|KSP|SNES|PC|IS|ISLocalToGlobalMapping|VecScatter|PetscOptions|PetscLog).*")
        .allowlist_type("(Petsc|Mat|Vec|KSP|SNES|PC|IS|_p_).*")
        .allowlist_var("(PETSC|MAT|VEC|KSP|SNES|PC|INSERT|ADD|NORM|SCATTER).*")
        .layout_tests(false)
        .generate_comments(false);
    for inc in &includes {
        builder = builder.clang_arg(format!("-I{}", inc.display()));
    }
    let bindings = builder.generate().expect("bindgen failed on PETSc headers");
    let out = PathBuf::from(env::var("OUT_DIR").unwrap()).join("bindings.rs");
    bindings.write_to_file(out).expect("cannot write bindings");
    println!("cargo:rerun-if-changed=wrapper.h");
    println!("cargo:rerun-if-changed=shim.c");
}
