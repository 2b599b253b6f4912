//! The 4x4 keypad matrix: four open-drain columns driven low one at a time, four
//! pull-up rows.

use stm32f1xx_hal::gpio::{Input, OpenDrain, Output, Pin, PinState, PullUp};

/// A column: open drain, released high, driven low to scan.
type Column<const P: char, const N: u8> = Pin<P, N, Output<OpenDrain>>;
/// A row: pulled up, low while a key of the driven column is pressed.
type Row<const N: u8> = Pin<'B', N, Input<PullUp>>;

/// The 4x4 keypad: rows PB6-PB9, columns PB10, PB11, PA15, PC14. Each pin keeps its
/// own type (not an array of erased pins): every access is then a fixed register bit,
/// with no run-time choice of port and pin and no bounds check on it.
pub struct KeypadMatrix {
    pub(super) columns: (
        Column<'B', 10>,
        Column<'B', 11>,
        Column<'A', 15>,
        Column<'C', 14>,
    ),
    pub(super) rows: (Row<6>, Row<7>, Row<8>, Row<9>),
}

impl KeypadMatrix {
    pub const COLUMNS: usize = 4;

    /// Drive column `col` low and release the others. The rows settle within a few us,
    /// which is why the scan task reads them on its next tick rather than busy-waiting.
    pub fn select_column(&mut self, col: usize) {
        let state = |i| {
            if i == col {
                PinState::Low
            } else {
                PinState::High
            }
        };
        let (c0, c1, c2, c3) = &mut self.columns;
        c0.set_state(state(0));
        c1.set_state(state(1));
        c2.set_state(state(2));
        c3.set_state(state(3));
    }

    /// Row bits of the selected column: bit r set = key in row r pressed (active low).
    pub fn read_rows(&self) -> u8 {
        let (r0, r1, r2, r3) = &self.rows;
        [r0.is_low(), r1.is_low(), r2.is_low(), r3.is_low()]
            .iter()
            .enumerate()
            .fold(0, |bits, (r, &low)| bits | (u8::from(low) << r))
    }
}
