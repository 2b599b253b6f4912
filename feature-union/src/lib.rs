//! No code: this crate only names dependencies with the features the whole
//! workspace's test build gives them (Cargo.toml says why).
#![no_std]
