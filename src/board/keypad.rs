//! The 4x4 keypad matrix: four open-drain columns driven low one at a time, four
//! pull-up rows read together.

use super::pins::{bsrr, idr, pin_word};
use stm32f1xx_hal::pac;

/// The 4x4 keypad: rows PB6-PB9 (pull-up inputs), columns PB10, PB11, PA15, PC14 (open drain).
pub struct KeypadMatrix {
    pub(super) _owned: (),
}

impl KeypadMatrix {
    pub const COLUMNS: usize = 4;

    /// Drive column `col` low (all others released). The rows settle within a few µs,
    /// which is why the scan task reads them on its next tick rather than busy-waiting.
    pub fn select_column(&mut self, col: usize) {
        // One BSRR word per port: the selected column low, the others released high
        // (a pin is never named in both halves, where setting would win).
        let (b, a, c) = match col {
            0 => (pin_word(10, false) | pin_word(11, true), 1 << 15, 1 << 14),
            1 => (pin_word(10, true) | pin_word(11, false), 1 << 15, 1 << 14),
            2 => (3 << 10, pin_word(15, false), 1 << 14),
            _ => (3 << 10, 1 << 15, pin_word(14, false)),
        };
        bsrr(pac::GPIOB::ptr(), b);
        bsrr(pac::GPIOA::ptr(), a);
        bsrr(pac::GPIOC::ptr(), c);
    }

    /// Row bits of the selected column: bit r set = key in row r pressed (active low).
    pub fn read_rows(&self) -> u8 {
        (!(idr(pac::GPIOB::ptr()) >> 6) & 0x0F) as u8
    }
}
