//! Where the simulator finds the reference programs: the repository's `bench/` (the
//! programs, their ideal paths and Grbl's figures in `GRBL.md`), unless `--dir` names
//! another folder of the same shape.

use std::path::PathBuf;

/// The repository root (the workspace that holds `sim/`).
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The repository's folder of reference programs and Grbl's figures.
pub fn bench_dir() -> PathBuf {
    repo_root().join("bench")
}

/// The markdown file with Grbl's figures in a bench folder: `GRBL.md`, or a
/// `README.md` holding the same table.
pub fn grbl_figures(bench: &std::path::Path) -> PathBuf {
    let grbl = bench.join("GRBL.md");
    if grbl.exists() {
        grbl
    } else {
        bench.join("README.md")
    }
}
