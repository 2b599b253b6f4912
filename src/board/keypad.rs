//! The 4x4 keypad matrix: four open-drain columns driven low one at a time, four
//! pull-up rows.

use stm32f1xx_hal::gpio::{ErasedPin, Input, OpenDrain, Output, PinState, PullUp};

/// The 4x4 keypad: rows PB6-PB9 (pull-up inputs), columns PB10, PB11, PA15, PC14 (open
/// drain, released high).
pub struct KeypadMatrix {
    pub(super) columns: [ErasedPin<Output<OpenDrain>>; 4],
    pub(super) rows: [ErasedPin<Input<PullUp>>; 4],
}

impl KeypadMatrix {
    pub const COLUMNS: usize = 4;

    /// Drive column `col` low and release the others. The rows settle within a few us,
    /// which is why the scan task reads them on its next tick rather than busy-waiting.
    pub fn select_column(&mut self, col: usize) {
        for (i, pin) in self.columns.iter_mut().enumerate() {
            pin.set_state(if i == col {
                PinState::Low
            } else {
                PinState::High
            });
        }
    }

    /// Row bits of the selected column: bit r set = key in row r pressed (active low).
    pub fn read_rows(&self) -> u8 {
        self.rows
            .iter()
            .enumerate()
            .fold(0, |bits, (r, pin)| bits | (u8::from(pin.is_low()) << r))
    }
}
