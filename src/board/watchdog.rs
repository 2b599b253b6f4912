//! The independent watchdog (IWDG).

use stm32f1xx_hal::pac;

/// Watchdog timeout: long enough for the slowest task period, short enough to matter.
pub const WATCHDOG_MS: u32 = 500;

/// The independent watchdog (IWDG, 40 kHz LSI), started by [`init`](super::init) with a
/// [`WATCHDOG_MS`] timeout; the keypad task feeds it.
///
/// Register writes instead of the HAL's `IndependentWatchdog`, whose prescaler search
/// runs (with its panics) at boot: here it is done at compile time, with the same
/// result (prescaler /8, reload 2500 for 500 ms).
pub struct Watchdog {
    iwdg: pac::IWDG,
}

impl Watchdog {
    const KR_ACCESS: u16 = 0x5555;
    const KR_RELOAD: u16 = 0xAAAA;
    const KR_START: u16 = 0xCCCC;
    /// Prescaler code and reload for `ms`: the smallest divider (4 << pr) whose longest
    /// period (4096 ticks) reaches `ms`, the reload scaled to it.
    const fn period_ms(pr: u32) -> u32 {
        4096 * (4 << pr) / 40
    }
    const fn timing(ms: u32) -> (u16, u16) {
        let mut pr = 0;
        while pr < 6 && Self::period_ms(pr) < ms {
            pr += 1;
        }
        let rl = ms * 0xFFF / Self::period_ms(pr);
        // Both fit 16 bits: pr <= 6, rl <= 0xFFF.
        (pr as u16, if rl > 0xFFF { 0xFFF } else { rl as u16 })
    }
    const TIMING: (u16, u16) = Self::timing(WATCHDOG_MS);

    pub(super) fn start(iwdg: pac::IWDG) -> Self {
        let (pr, rl) = Self::TIMING;
        // SAFETY: IWDG key, prescaler and reload registers take any of these values.
        unsafe {
            iwdg.kr().write(|w| w.bits(Self::KR_ACCESS));
            iwdg.pr().write(|w| w.bits(pr));
            iwdg.rlr().write(|w| w.bits(rl));
            iwdg.kr().write(|w| w.bits(Self::KR_RELOAD));
            iwdg.kr().write(|w| w.bits(Self::KR_START));
        }
        Self { iwdg }
    }

    /// Reload the counter.
    pub fn feed(&mut self) {
        // SAFETY: writing the reload key only restarts the countdown.
        unsafe { self.iwdg.kr().write(|w| w.bits(Self::KR_RELOAD)) };
    }
}

// The HAL's search gives prescaler /8, reload 2500 for 500 ms.
const _: () = assert!(matches!(Watchdog::timing(500), (1, 2500)));
