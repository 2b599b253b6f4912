//! On-target tests (defmt-test): run on a Blue Pill with `cargo test` through probe-rs.
//!
//! They check what only the real chip can show: the clock tree, the step timer's pulse
//! count and width on the real pins, the keypad matrix at rest, and the settings flash.
#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_probe as _;

#[defmt_test::tests]
mod tests {
    use inkstep::board::{self, Board};
    use stm32f1xx_hal::{pac, usb::UsbBusType};
    use usb_device::bus::UsbBusAllocator;

    #[init]
    fn init() -> Board {
        let dp = pac::Peripherals::take().unwrap_or_else(|| defmt::panic!("peripherals taken"));
        let bus = cortex_m::singleton!(: Option<UsbBusAllocator<UsbBusType>> = None)
            .unwrap_or_else(|| defmt::panic!("singleton"));
        let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| defmt::panic!("core taken"));
        cp.DCB.enable_trace();
        cp.DWT.enable_cycle_counter();
        board::init(dp, bus)
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
        // DWT counts core cycles: 1 ms of SysTick-free busy wait is ~72_000 cycles.
        let start = cortex_m::peripheral::DWT::cycle_count();
        cortex_m::asm::delay(72_000);
        let spent = cortex_m::peripheral::DWT::cycle_count().wrapping_sub(start);
        defmt::assert!((72_000..80_000).contains(&spent), "cycles {}", spent);
    }

    #[test]
    fn step_timer_emits_n_pulses_of_the_set_width(b: &mut Board) {
        const N: u32 = 200;
        const PERIOD: u32 = 100; // ticks: 20 kHz at 2 MHz
        const WIDTH: u16 = 20; // ticks: 10 µs
        b.step_timer.set_pulse_ticks(WIDTH);
        b.step_timer.set_period(PERIOD);
        // Interrupts stay masked in the NVIC: the test polls the flags the ISR would see.
        let gpioa = unsafe { &*pac::GPIOA::ptr() };
        let tim = unsafe { &*pac::TIM2::ptr() };
        let (mut rises, mut falls) = (0u32, 0u32);
        let mut widths_ok = true;
        let start = cortex_m::peripheral::DWT::cycle_count();
        b.step_timer.start();
        while falls < N {
            let (update, compare) = b.step_timer.take_events();
            if compare && rises > falls {
                let width = tim.cnt().read().bits();
                b.step_port.write(0, board::STEP_MASK_X as u8);
                widths_ok &= gpioa.odr().read().bits() & board::STEP_MASK_X == 0;
                widths_ok &= width >= u32::from(WIDTH) && width < u32::from(WIDTH) + 10;
                falls += 1;
            }
            if update && rises < N {
                b.step_port.write(board::STEP_MASK_X as u8, 0);
                widths_ok &= gpioa.odr().read().bits() & board::STEP_MASK_X != 0;
                rises += 1;
            }
        }
        b.step_timer.stop();
        let cycles = cortex_m::peripheral::DWT::cycle_count().wrapping_sub(start);
        defmt::assert_eq!(rises, N);
        defmt::assert!(widths_ok, "a pulse had the wrong width or pin level");
        // N periods of PERIOD ticks at 2 MHz = N * PERIOD * 36 cycles at 72 MHz.
        let expected = N * PERIOD * (board::SYSCLK_HZ / board::STEP_TIMER_HZ);
        defmt::assert!(
            cycles >= expected - expected / 50 && cycles <= expected + expected / 20,
            "{} cycles for {} pulses, expected {}",
            cycles,
            N,
            expected
        );
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
        let page = board::SETTINGS_OFFSET + board::SETTINGS_FLASH_SIZE - board::FLASH_PAGE_SIZE;
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
        use inkstep_core::settings_store::{BlockingFlash, LoadStatus, SettingsStore, STORE_RANGE};
        {
            let mut store =
                defmt::unwrap!(SettingsStore::new(BlockingFlash(&mut b.flash), STORE_RANGE).ok());
            let mut s = Settings::default();
            defmt::unwrap!(s.set(110, 4321.0).ok());
            defmt::unwrap!(store.save_settings(&s).ok());
        }
        // A fresh store over the same pages (as after a reset) loads what was saved.
        let mut store =
            defmt::unwrap!(SettingsStore::new(BlockingFlash(&mut b.flash), STORE_RANGE).ok());
        let (loaded, status) = store.load_settings();
        defmt::assert!(status == LoadStatus::Loaded);
        defmt::assert!(loaded.max_rate(0) == 4321.0);
    }
}
