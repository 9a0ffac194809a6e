//! The paper's large-bending example (section 4.2), in release mode:
//! `cargo test --release --test bending`.
//!
//! cases/bending/study.toml runs the two-layer plane-strain cantilever (Hex27, frictional
//! dissimilar interface, external pressure then a large end rotation) with one pass, two passes
//! and the conforming mesh (matching meshes, tied). Passing: over the whole bending, the tip
//! deflection of one pass and of two passes stays within 0.5 % of the conforming mesh's (the
//! paper: the final tip displacements within 0.5 %); every run converges; the plot exists.

mod common;

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test bending"
)]
fn one_and_two_passes_bend_like_the_conforming_mesh() {
    let (out, status) = common::run_shipped("study", "bending", "study.toml", "bending_study", &[]);
    assert!(status.success(), "the bending study failed");
    assert!(out.join("curves.png").is_file() && out.join("curves.svg").is_file());
    let s = common::summary(&out);
    for variant in ["onepass", "twopass"] {
        let key = format!("tip_rel_diff_{variant}");
        let d = s["metrics"][&key]
            .as_f64()
            .unwrap_or_else(|| panic!("no metric {key}"));
        assert!(d < 0.005, "{variant}: tip {d} from the conforming mesh");
    }
}
