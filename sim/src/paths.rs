//! Where the simulator finds the repository's neighbours: `shared/` lives beside the
//! repository root (CI clones the repository with shared/ next to it).

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
