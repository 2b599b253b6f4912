//! Where the simulator finds the reference programs: `shared/bench` beside the
//! repository root (CI clones the repository with shared/ next to it), else the copy
//! in the repository's own `bench/`.

use std::path::PathBuf;

/// The repository root (the workspace that holds `sim/`).
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `../shared` relative to the repository root, or `$INKSTEP_SHARED` when set.
pub fn shared_dir() -> PathBuf {
    match std::env::var_os("INKSTEP_SHARED") {
        Some(p) => PathBuf::from(p),
        None => repo_root().join("../shared"),
    }
}

/// The folder of the reference programs and Grbl's figures.
pub fn bench_dir() -> PathBuf {
    let shared = shared_dir().join("bench");
    if shared.join("README.md").exists() {
        shared
    } else {
        repo_root().join("bench")
    }
}

/// The markdown file with Grbl's figures in a bench folder (`README.md` in shared/,
/// `GRBL.md` in the repository's copy).
pub fn grbl_figures(bench: &std::path::Path) -> PathBuf {
    let readme = bench.join("README.md");
    if readme.exists() {
        readme
    } else {
        bench.join("GRBL.md")
    }
}
