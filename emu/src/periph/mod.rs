//! The STM32F103's peripherals, each written from its chapter of RM0008 (reference
//! manual, rev. 21), register by register with the documented reset values and access
//! types. A register a model does not know is an error that stops the run; nothing
//! reads a silent zero.

pub mod dma;
pub mod flash;
pub mod gpio;
pub mod iwdg;
pub mod rcc;
pub mod spi;
pub mod st7920;
pub mod timer;
pub mod usb;

/// An access no model answers: the run stops with its address and PC.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusError(pub String);

pub type Access<T> = Result<T, BusError>;

/// The error for a register offset a peripheral does not have.
pub fn unknown(periph: &str, off: u32) -> BusError {
    BusError(format!("{periph}: no register at offset 0x{off:03X}"))
}
