//! inkstep firmware: thin RTIC wiring between the Blue Pill's peripherals (`board`) and
//! the hardware-free core (`inkstep-core`).
//!
//! Priorities (higher preempts lower), as in DESIGN.md:
//!   7  e-stop and limit switches (EXTI0, EXTI1, EXTI3)
//!   6  step timer (TIM2): executes prepared step events, integer work only
//!   5  USB (moves bytes between the endpoint and the SPSC queues), segment preparation
//!   4  protocol / G-code, feed-hold and cycle-start inputs
//!   3  keypad scan (every 5 ms) and the watchdog
//!   1  LCD refresh: the only task that waits (on its SPI); everything preempts it
//!   0  idle: WFI
#![no_std]
#![no_main]

use inkstep::board;

use defmt_rtt as _;

/// A fault must leave every motor driver disabled, whatever caused it.
#[cortex_m_rt::exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    board::emergency_outputs_off();
    loop {
        cortex_m::asm::bkpt();
    }
}

/// The panic handler: drivers off before anything else, then what panic-probe does
/// (print over defmt, then fault so that probe-rs stops and shows the backtrace).
/// panic-probe itself offers no hook to run first, hence this copy of its behaviour.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    board::emergency_outputs_off();
    cortex_m::interrupt::disable();
    defmt::error!("panic: {}", defmt::Display2Format(info));
    // Escalate the undefined instruction to HardFault (it disables the outputs again).
    // SAFETY: SHCSR is the System Handler Control and State Register; clearing
    // USGFAULTENA only changes which fault handler runs.
    unsafe {
        const SHCSR: *mut u32 = 0xE000_ED24_usize as *mut u32;
        core::ptr::write_volatile(SHCSR, core::ptr::read_volatile(SHCSR) & !(1 << 18));
    }
    cortex_m::asm::udf()
}

#[rtic::app(device = stm32f1xx_hal::pac, peripherals = true, dispatchers = [USART1, USART2, USART3, SPI1, I2C1_EV])]
mod app {
    use inkstep::board;
    use rtic_monotonics::systick::prelude::*;
    use stm32f1xx_hal::usb::UsbBusType;
    use usb_device::bus::UsbBusAllocator;

    systick_monotonic!(Mono, 1_000);

    #[shared]
    struct Shared {
        usb: board::Usb,
        serial: board::UsbSerial,
        indicators: board::Indicators,
    }

    #[local]
    struct Local {
        step_port: board::StepPort,
        step_timer: board::StepTimer,
        servo: board::PenServo,
        keypad: board::KeypadMatrix,
        inputs: board::Inputs,
        lcd: board::Lcd,
        watchdog: stm32f1xx_hal::watchdog::IndependentWatchdog,
    }

    #[init(local = [usb_bus: Option<UsbBusAllocator<UsbBusType>> = None])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let b = board::init(cx.device, cx.local.usb_bus);
        Mono::start(cx.core.SYST, b.sysclk_hz);
        defmt::info!(
            "inkstep {} up, sysclk {} Hz",
            env!("CARGO_PKG_VERSION"),
            b.sysclk_hz
        );
        keypad_scan::spawn().ok();
        lcd_refresh::spawn().ok();
        (
            Shared {
                usb: b.usb,
                serial: b.serial,
                indicators: b.indicators,
            },
            Local {
                step_port: b.step_port,
                step_timer: b.step_timer,
                servo: b.servo,
                keypad: b.keypad,
                inputs: b.inputs,
                lcd: b.lcd,
                watchdog: b.watchdog,
            },
        )
    }

    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// Emergency stop: highest priority. Outputs off first, then tell the core.
    #[task(binds = EXTI0, priority = 7)]
    fn estop(_: estop::Context) {
        if board::exti_take_pending(0) {
            board::emergency_outputs_off();
            defmt::warn!("e-stop");
        }
    }

    #[task(binds = TIM2, priority = 6, local = [step_port, step_timer])]
    fn step(cx: step::Context) {
        let (_update, compare) = cx.local.step_timer.take_events();
        if compare {
            cx.local.step_port.write(
                0,
                (board::STEP_MASK_X | board::STEP_MASK_Y | board::STEP_MASK_Z) as u8,
            );
        }
    }

    #[task(binds = USB_LP_CAN_RX0, priority = 5, shared = [usb, serial])]
    fn usb_rx(cx: usb_rx::Context) {
        (cx.shared.usb, cx.shared.serial).lock(|usb, serial| {
            if usb.poll(&mut [serial]) {
                let mut buf = [0u8; 64];
                if let Ok(n) = serial.read(&mut buf) {
                    let _ = serial.write(buf.get(..n).unwrap_or(&[]));
                }
            }
        });
    }

    #[task(binds = EXTI4, priority = 4, local = [inputs])]
    fn control_inputs(cx: control_inputs::Context) {
        if board::exti_take_pending(4) {
            defmt::info!("feed hold input low: {}", cx.local.inputs.feed_hold_low());
        }
    }

    #[task(priority = 3, local = [keypad, watchdog])]
    async fn keypad_scan(cx: keypad_scan::Context) {
        let mut col = 0usize;
        loop {
            cx.local.keypad.select_column(col);
            Mono::delay(5.millis()).await;
            let rows = cx.local.keypad.read_rows();
            if rows != 0 {
                defmt::debug!("key col {} rows {:04b}", col, rows);
            }
            col = (col + 1) % board::KeypadMatrix::COLUMNS;
            cx.local.watchdog.feed();
        }
    }

    #[task(priority = 1, local = [lcd, servo])]
    async fn lcd_refresh(cx: lcd_refresh::Context) {
        let mut delay = board::SpinDelay;
        if cx.local.lcd.init(&mut delay).is_err() {
            defmt::warn!("LCD init failed");
        }
        cx.local.servo.set_pulse_us(1000);
        loop {
            let _ = cx.local.lcd.flush(&mut delay);
            Mono::delay(100.millis()).await;
        }
    }
}
