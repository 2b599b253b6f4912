//! Relink when the memory layout changes (memory.x at the package root, where the
//! linker finds it).
fn main() {
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
}
