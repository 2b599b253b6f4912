//! What a user sees when a tool can be had neither from the system nor from PyPI: the
//! set-up stops with one line that names the tool and the command that installs it,
//! before any build starts.

use std::fs;
use std::os::unix::fs::{symlink, PermissionsExt};
use std::path::Path;
use std::process::Command;

/// A PATH with rustc, cargo and rustup (so the target is found) and a stand-in
/// flip-link, but no cmake and no python3; no system packages (`INKSTEP_SETUP=user`).
fn bare_path(dir: &Path) {
    for tool in ["rustc", "cargo", "rustup"] {
        let real = which(tool).unwrap_or_else(|| panic!("{tool} is not on PATH"));
        symlink(real, dir.join(tool)).unwrap();
    }
    let flip = dir.join("flip-link");
    fs::write(&flip, "#!/bin/sh\nexit 0\n").unwrap();
    fs::set_permissions(&flip, fs::Permissions::from_mode(0o755)).unwrap();
}

fn which(tool: &str) -> Option<std::path::PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join(tool))
        .find(|p| p.is_file())
}

#[test]
fn a_tool_that_cannot_be_had_is_named_in_one_line_with_its_install_command() {
    let tmp = std::env::temp_dir().join(format!("inkstep-setup-missing-{}", std::process::id()));
    let bin = tmp.join("bin");
    fs::create_dir_all(&bin).unwrap();
    bare_path(&bin);
    let out = Command::new(env!("CARGO_BIN_EXE_inkstep-setup"))
        .env("PATH", &bin)
        .env("INKSTEP_SETUP", "user")
        .env("INKSTEP_TOOLS", tmp.join("tools"))
        .env_remove("LIBCLANG_PATH")
        .output()
        .unwrap();
    let _ = fs::remove_dir_all(&tmp);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one line, not {lines:?}");
    let line = lines[0];
    assert!(line.starts_with("inkstep setup: cmake"), "{line}");
    assert!(line.contains("python3 is not installed"), "{line}");
    assert!(line.contains("sudo apt-get install cmake"), "{line}");
    assert!(line.contains("pip install --user"), "{line}");
}
