//! What the emulator's tests share: the product image (built once with
//! `cargo build --release`, as the commands do) and a booted board.

#![allow(dead_code)] // each test file uses its own part of this

use inkstep_emu::session::{product_elf, Session};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The release product image, built once per test process (or the image named by
/// INKSTEP_EMU_ELF, to try the tests on another build).
pub fn elf() -> &'static Path {
    static ELF: OnceLock<PathBuf> = OnceLock::new();
    ELF.get_or_init(|| match std::env::var_os("INKSTEP_EMU_ELF") {
        Some(p) => PathBuf::from(p),
        None => product_elf().expect("cargo build --release"),
    })
}

/// A board with the product image, a blank flash (or `flash`), the USB port
/// enumerated and open.
pub fn booted(flash: Option<&Path>) -> Session<'static> {
    let mut s = Session::new(elf(), flash).expect("emulated board");
    s.boot().expect("boot");
    s
}

/// Steps per mm of X and Y at the default settings (`$100`, `$101`).
pub const STEPS_PER_MM: f64 = 80.0;
