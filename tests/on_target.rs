//! On-target tests (defmt-test): run on a Blue Pill with `cargo test` through probe-rs.
//!
//! They check what only the real chip can show: the clock tree, the step timer's pulse
//! count and width on the real pins, the emergency path's enable level for both `$4`
//! polarities, the keypad matrix at rest, and the settings flash.
#![no_std]
#![no_main]
#![deny(clippy::undocumented_unsafe_blocks)]

use defmt_rtt as _;
use panic_probe as _;

#[defmt_test::tests]
mod tests {
    use inkstep::board::{self, Board};
    use stm32f1xx_hal::pac;

    #[init]
    fn init() -> Board {
        let dp = pac::Peripherals::take().unwrap_or_else(|| defmt::panic!("peripherals taken"));
        let usb = cortex_m::singleton!(: board::UsbCells = board::UsbCells::new())
            .unwrap_or_else(|| defmt::panic!("singleton"));
        let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| defmt::panic!("core taken"));
        cp.DCB.enable_trace();
        cp.DWT.enable_cycle_counter();
        // No task here: the USB driver keeps its upstream sections (every interrupt
        // masked), which a priority above every level asks for.
        board::init(dp, usb, u8::MAX)
    }

    #[test]
    fn exception_entry_keeps_the_stack_8_byte_aligned(_b: &mut Board) {
        // CCR.STKALIGN: off at reset on this chip's Cortex-M3 r1p1; board::init sets
        // it, or handlers entered at SP = 4 mod 8 misaddress their locals.
        // SAFETY: a read-only register read.
        let ccr = unsafe { (*cortex_m::peripheral::SCB::PTR).ccr.read() };
        defmt::assert!(ccr & (1 << 9) != 0, "CCR.STKALIGN is clear: {=u32:#x}", ccr);
    }

    #[test]
    fn clocks_are_72mhz_from_hse_pll(b: &mut Board) {
        defmt::assert_eq!(b.sysclk_hz, 72_000_000);
        // SAFETY: read-only register reads.
        let rcc = unsafe { &*pac::RCC::ptr() };
        let cfgr = rcc.cfgr().read();
        defmt::assert!(rcc.cr().read().hserdy().bit_is_set(), "HSE not ready");
        defmt::assert_eq!(cfgr.sws().bits(), 0b10, "system clock is not the PLL");
        defmt::assert!(cfgr.pllsrc().bit_is_set(), "PLL not fed from HSE");
        defmt::assert_eq!(cfgr.pllmul().bits(), 0b0111, "PLL multiplier is not x9");
        defmt::assert_eq!(cfgr.ppre1().bits(), 0b100, "APB1 is not HCLK/2");
        defmt::assert!(!cfgr.usbpre().bit_is_set(), "USB clock is not PLL/1.5");
        // DWT counts core cycles: `delay(n)` is n + 1 turns of a two-instruction loop
        // (`subs; bne`, aligned to the flash's 64-bit prefetch line). A turn is three
        // cycles on zero-wait-state memory (cortex-m's documentation), and at most
        // seven from flash with its two wait states after the taken branch (the
        // emulator's pessimistic cycle model, emu/README.md; six in its typical one):
        // between ~216_000 and ~504_000 cycles.
        let start = cortex_m::peripheral::DWT::cycle_count();
        cortex_m::asm::delay(72_000);
        let spent = cortex_m::peripheral::DWT::cycle_count().wrapping_sub(start);
        defmt::assert!((216_000..504_200).contains(&spent), "cycles {}", spent);
    }

    #[test]
    fn step_timer_draws_n_pulses_of_the_set_width(b: &mut Board) {
        const N: u32 = 200;
        const PERIOD: u32 = 7_200; // ticks at 72 MHz: 10 kHz
        const WIDTH: u16 = 720; // ticks: 10 µs
        let x = board::STEP_MASK_X as u8;
        // Step/dir mode: the timer drives PA0-PA2 and draws the pulses itself.
        b.step_timer.configure_outputs(true, 0);
        b.step_timer.set_pulse_ticks(WIDTH);
        b.step_timer.arm_pulses(x); // the first pulse, when the first period ends
                                    // Interrupts stay masked in the NVIC: the test polls the update flag the step
                                    // interrupt would see, arms X for the next N - 1 periods and then nothing,
                                    // restarts the timer (one-pulse mode: it stops at every update event) on its
                                    // schedule, and samples the pin to time every pulse with the cycle counter.
                                    // SAFETY: read-only register reads (the input data register).
        let gpioa = unsafe { &*pac::GPIOA::ptr() };
        let pin_high = || gpioa.idr().read().bits() & board::STEP_MASK_X != 0;
        let (mut armed, mut rises, mut widths_ok) = (1u32, 0u32, true);
        let (mut high_since, mut first_rise, mut last_rise) = (None, 0u32, 0u32);
        let start = cortex_m::peripheral::DWT::cycle_count();
        let late_before = board::late_step_armings();
        b.step_timer.start(PERIOD, 0, true);
        // N + 3 periods: room to see that no pulse follows the N-th.
        let span = (N + 3) * PERIOD * (board::SYSCLK_HZ / board::STEP_TIMER_HZ);
        loop {
            let now = cortex_m::peripheral::DWT::cycle_count();
            if now.wrapping_sub(start) > span {
                break;
            }
            if b.step_timer.take_update() {
                b.step_timer.arm_pulses(if armed < N { x } else { 0 });
                armed += 1;
                b.step_timer.restart(PERIOD);
            }
            match (pin_high(), high_since) {
                (true, None) => {
                    high_since = Some(now);
                    if rises == 0 {
                        first_rise = now;
                    }
                    last_rise = now;
                    rises += 1;
                }
                (false, Some(t0)) => {
                    let width = now.wrapping_sub(t0);
                    // Sampling granularity: one loop pass, well under 60 cycles.
                    widths_ok &= (u32::from(WIDTH) - 60..u32::from(WIDTH) + 60).contains(&width);
                    high_since = None;
                }
                _ => {}
            }
        }
        b.step_timer.stop();
        b.step_timer.arm_pulses(0);
        defmt::assert_eq!(rises, N, "pulses drawn");
        defmt::assert!(widths_ok, "a pulse had the wrong width");
        defmt::assert_eq!(board::late_step_armings(), late_before, "no late arming");
        // N - 1 periods between the first and the last rise.
        let spent = last_rise.wrapping_sub(first_rise);
        let expected = (N - 1) * PERIOD * (board::SYSCLK_HZ / board::STEP_TIMER_HZ);
        defmt::assert!(
            spent + 120 >= expected && spent <= expected + 120,
            "{} cycles between the first and the last of {} pulses, expected {}",
            spent,
            N,
            expected
        );
    }

    /// The panic and e-stop path turns the drivers off with either enable polarity
    /// (`$4`): PA9 high for an active-low /EN, low for an active-high enable.
    #[test]
    fn a_late_restart_delays_the_step_and_never_repeats_it(b: &mut Board) {
        // Issue 20: the step interrupt held back three periods at the 10th update (as
        // a long masked section would): the pulse armed for that update fires once,
        // the timer waits, the next one comes a short rest after the late restart,
        // the late arming is counted, and every period after it is on the new schedule.
        const N: u32 = 20;
        const PERIOD: u32 = 7_200;
        const LATE_AT: u32 = 10;
        let x = board::STEP_MASK_X as u8;
        b.step_timer.configure_outputs(true, 0);
        b.step_timer.set_pulse_ticks(720);
        b.step_timer.arm_pulses(x);
        // SAFETY: read-only register reads (the input data register).
        let gpioa = unsafe { &*pac::GPIOA::ptr() };
        let pin_high = || gpioa.idr().read().bits() & board::STEP_MASK_X != 0;
        let (mut updates, mut rises, mut was_high) = (0u32, 0u32, false);
        let mut rise_at = [0u32; N as usize];
        // The update flag the last test's final period left.
        b.step_timer.take_update();
        let late_before = board::late_step_armings();
        let start = cortex_m::peripheral::DWT::cycle_count();
        b.step_timer.start(PERIOD, 0, true);
        let span = (N + 8) * PERIOD;
        loop {
            let now = cortex_m::peripheral::DWT::cycle_count();
            if now.wrapping_sub(start) > span {
                break;
            }
            if b.step_timer.take_update() {
                updates += 1;
                if updates == LATE_AT {
                    // Three periods late: sample the pin meanwhile (no pulse may come).
                    let t0 = cortex_m::peripheral::DWT::cycle_count();
                    loop {
                        let t = cortex_m::peripheral::DWT::cycle_count();
                        if t.wrapping_sub(t0) >= 3 * PERIOD {
                            break;
                        }
                        let high = pin_high();
                        if high && !was_high {
                            if let Some(slot) = rise_at.get_mut(rises as usize) {
                                *slot = t;
                            }
                            rises += 1;
                        }
                        was_high = high;
                    }
                }
                b.step_timer.arm_pulses(if updates < N { x } else { 0 });
                b.step_timer.restart(PERIOD);
                if updates == LATE_AT {
                    // The short rest after the late restart is 1 µs of low level,
                    // less than a pass of this loop: watch the pin closely for it.
                    let t0 = cortex_m::peripheral::DWT::cycle_count();
                    while pin_high() {}
                    loop {
                        let t = cortex_m::peripheral::DWT::cycle_count();
                        if pin_high() {
                            if let Some(slot) = rise_at.get_mut(rises as usize) {
                                *slot = t;
                            }
                            rises += 1;
                            was_high = true;
                            break;
                        }
                        if t.wrapping_sub(t0) > PERIOD {
                            break;
                        }
                    }
                }
            }
            let high = pin_high();
            if high && !was_high {
                if let Some(slot) = rise_at.get_mut(rises as usize) {
                    *slot = now;
                }
                rises += 1;
            }
            was_high = high;
        }
        b.step_timer.stop();
        b.step_timer.arm_pulses(0);
        defmt::assert_eq!(rises, N, "pulses drawn: each armed one once");
        defmt::assert_eq!(
            board::late_step_armings(),
            late_before + 1,
            "one late arming"
        );
        // Before the late one and after it, the periods are exact; across it, longer.
        let gap = |i: usize| rise_at[i + 1].wrapping_sub(rise_at[i]);
        let on_time = |g: u32| g + 120 >= PERIOD && g <= PERIOD + 120;
        let late = LATE_AT as usize - 1;
        for i in 0..N as usize - 1 {
            if i == late {
                // The three late periods plus the short rest after the restart.
                let g = gap(i);
                defmt::assert!(
                    g > 3 * PERIOD && g < 3 * PERIOD + PERIOD / 2,
                    "delayed: {}",
                    g
                );
            } else {
                defmt::assert!(on_time(gap(i)), "period {}: {} cycles", i, gap(i));
            }
        }
    }

    #[test]
    fn emergency_off_follows_the_enable_polarity(b: &mut Board) {
        // SAFETY: read-only register read.
        let pa9 = || unsafe { (*pac::GPIOA::ptr()).odr().read().bits() } & (1 << 9) != 0;
        for active_low in [true, false] {
            b.step_port.set_drivers_enabled(true, active_low);
            defmt::assert_eq!(pa9(), !active_low, "enabled");
            board::emergency_outputs_off();
            defmt::assert_eq!(pa9(), active_low, "off after the emergency path");
        }
        b.step_port.set_drivers_enabled(true, true);
    }

    #[test]
    fn keypad_matrix_reads_no_key_at_rest(b: &mut Board) {
        for col in 0..board::KeypadMatrix::COLUMNS {
            b.keypad.select_column(col);
            cortex_m::asm::delay(72 * 20);
            defmt::assert_eq!(b.keypad.read_rows(), 0, "column {} reads a key", col);
        }
    }

    #[test]
    fn settings_flash_round_trip(b: &mut Board) {
        use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};
        let page = board::settings_pages().end - board::FLASH_PAGE_SIZE;
        defmt::unwrap!(b.flash.erase(page, page + board::FLASH_PAGE_SIZE));
        let mut buf = [0u8; 16];
        defmt::unwrap!(b.flash.read(page, &mut buf));
        defmt::assert!(buf.iter().all(|&x| x == 0xFF), "erased page is not blank");
        let data = *b"inkstep settings";
        defmt::unwrap!(b.flash.write(page, &data));
        defmt::unwrap!(b.flash.read(page, &mut buf));
        defmt::assert_eq!(buf, data);
        // The program can never be overwritten through this driver.
        defmt::assert!(b.flash.write(0, &data).is_err());
        defmt::assert!(b.flash.erase(0, board::FLASH_PAGE_SIZE).is_err());
    }

    #[test]
    fn settings_store_round_trip(b: &mut Board) {
        use inkstep_core::settings::Settings;
        use inkstep_core::settings_store::{LoadStatus, SettingsStore};
        {
            let mut store =
                defmt::unwrap!(SettingsStore::new(&mut b.flash, board::settings_pages()).ok());
            let mut s = Settings::default();
            defmt::unwrap!(s.set(110, 4321.0).ok());
            defmt::unwrap!(store.save_settings(&s).ok());
        }
        // A fresh store over the same pages (as after a reset) loads what was saved.
        let mut store =
            defmt::unwrap!(SettingsStore::new(&mut b.flash, board::settings_pages()).ok());
        let mut loaded = Settings::default();
        let status = store.load_settings(&mut loaded);
        defmt::assert!(status == LoadStatus::Loaded);
        defmt::assert!(loaded.max_rate(0) == 4321.0);
    }
}
