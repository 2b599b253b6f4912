//! Relink when the memory layout changes. The linker finds our `memory.x` in the
//! package root (its working directory) before any dependency's copy on the -L path
//! (st7920's used to carry one); CI checks the linked symbols to prove it.
fn main() {
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
}
