//! Prepares the reference programs for inclusion: drops the `G4 P0` padding lines.
//! Also writes the emulator's memory map: the harness is not bound by the chip's 64 KB.
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    for name in ["star", "circle", "sine", "spiral"] {
        let src = format!("../{name}.nc");
        println!("cargo:rerun-if-changed={src}");
        let text = fs::read_to_string(&src).expect("reference program");
        let kept: Vec<&str> = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("G4"))
            .collect();
        fs::write(out.join(format!("{name}.nc")), kept.join("\n") + "\n").expect("write");
    }
    fs::write(
        out.join("memory.x"),
        "MEMORY\n{\n  FLASH : ORIGIN = 0x08000000, LENGTH = 1024K\n  RAM : ORIGIN = 0x20000000, LENGTH = 256K\n}\n",
    )
    .expect("memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=build.rs");
}
