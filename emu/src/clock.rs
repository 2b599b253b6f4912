//! Virtual time. One unit ("T") is 1/144 µs, half a cycle of the 72 MHz system clock,
//! so that a cycle is a whole number of units at 72 MHz (2 T), 36 MHz and the 8 MHz
//! reset clock (18 T). Everything the emulator reports
//! is derived from this counter, which only instructions and modelled hardware delays
//! advance: a run is the same every time.

/// Units per microsecond.
pub const T_PER_US: u64 = 144;
/// Units per millisecond.
pub const T_PER_MS: u64 = 1000 * T_PER_US;
/// Units per second.
pub const T_PER_S: u64 = 1000 * T_PER_MS;

/// Units per cycle of a clock of `hz` (every clock of the board divides 144 MHz evenly:
/// 72, 36, 8 MHz and the 40 kHz LSI; anything else is rounded up and flagged by RCC).
pub const fn t_per_cycle(hz: u32) -> u64 {
    T_PER_S.div_ceil(hz as u64)
}

/// Microseconds, for reports.
pub fn us(t: u64) -> f64 {
    t as f64 / T_PER_US as f64
}
