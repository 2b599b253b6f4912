//! inkstep-emu: the unmodified firmware image on an emulated STM32F103CB board
//! (emu/README.md). The CPU is unicorn's Cortex-M3; everything around it (exceptions,
//! peripherals, the USB host, the outside of the board) is modelled here.

pub mod bench;
pub mod board;
pub mod clock;
pub mod count_trial;
pub mod cpu_model;
pub mod debug;
pub mod demo;
pub mod elf;
pub mod latency;
pub mod machine;
pub mod nvic;
pub mod periph;
pub mod pins;
pub mod profiler;
pub mod rtt;
pub mod session;
pub mod soak;
pub mod sram;
pub mod target_tests;
pub mod timeline;
pub mod usb_host;
