//! `cargo emu test`: the on-target tests (tests/on_target.rs, defmt-test) on the
//! emulated board, as `cargo test` runs them on a real one through probe-rs: the test
//! image built with `cargo test --release --no-run`, flashed over a blank flash, run
//! with the HardFault vector catch set, its defmt log decoded as it comes. defmt-test
//! ends with a semihosting exit (status 0 when every test passed); a failed test
//! panics, and panic-probe ends in HardFault, where the probe (here: the run) stops.

use crate::clock::{T_PER_MS, T_PER_S};
use crate::machine::Stop;
use crate::session::{repo_root, Session};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Virtual time after which a test run that has not ended fails.
pub const LIMIT: u64 = 60 * T_PER_S;

/// Build the on-target test image; returns its path.
pub fn build() -> Result<PathBuf, String> {
    let out = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args([
            "test",
            "--release",
            "--no-run",
            "--test",
            "on_target",
            "--message-format=json-render-diagnostics",
        ])
        .current_dir(repo_root())
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| format!("cargo test --no-run: {e}"))?;
    if !out.status.success() {
        return Err("cargo test --release --no-run failed".into());
    }
    // The artifact line of the test target names its executable.
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.contains("\"reason\":\"compiler-artifact\"") && l.contains("\"on_target\""))
        .find_map(|l| {
            let at = l.find("\"executable\":\"")? + "\"executable\":\"".len();
            let end = l[at..].find('"')?;
            Some(PathBuf::from(&l[at..at + end]))
        })
        .ok_or_else(|| "cargo did not name the on_target test executable".into())
}

/// How a test run ended.
pub struct Outcome {
    /// The semihosting exit status (0: every test passed), or None when the run
    /// ended otherwise (a failed test's HardFault, a stop, the time limit).
    pub status: Option<i32>,
    /// Why it ended, in words.
    pub end: String,
    /// Virtual time at the end.
    pub t: u64,
    pub log: Vec<String>,
}

impl Outcome {
    pub fn passed(&self) -> bool {
        self.status == Some(0)
    }
}

/// Run the test image `elf` until it exits (or `limit`); the log is echoed to stderr
/// when `echo` is set.
pub fn run(elf: &Path, echo: bool, limit: u64) -> Result<Outcome, String> {
    let mut s = Session::new(elf, None)?;
    s.m.state_mut().echo_log = echo;
    s.m.state_mut().catch_hardfault = true;
    let stop = loop {
        if let Some(stop) = s.m.run_until(s.now() + 10 * T_PER_MS) {
            break Some(stop);
        }
        if s.now() >= limit {
            break None;
        }
    };
    let (status, end) = match stop {
        Some(Stop::Exit(code)) => (Some(code), format!("semihosting exit, status {code}")),
        Some(Stop::HardFault { pc }) => (
            None,
            format!("HardFault at PC 0x{pc:08X} (a failed test panics into it)"),
        ),
        Some(other) => (None, s.stopped(other)),
        None => (
            None,
            format!(
                "no exit within {} s of virtual time",
                limit as f64 / T_PER_S as f64
            ),
        ),
    };
    let log =
        s.m.state()
            .log
            .as_ref()
            .map(|l| l.lines.clone())
            .unwrap_or_default();
    Ok(Outcome {
        status,
        end,
        t: s.now(),
        log,
    })
}
