//! The bring-up image: checks the wiring of a new machine, one peripheral at a time,
//! with the same board module, step interrupt and core pieces as the product image.
//!
//! - LCD: a status page (keys, inputs, position, USB bytes) redrawn at 10 Hz through
//!   the core's frame buffer and ST7920 flush.
//! - Keypad: the core's debounced scanner; the eight keys around 5 jog X/Y at
//!   1 kHz while held (step commands through the core executor and the TIM2 interrupt),
//!   5 toggles the pen servo, every press beeps.
//! - Inputs: e-stop (outputs off at once, latched until reset), limits, feed hold and
//!   cycle start shown live; busy LED and busy output while stepping.
//! - USB: a CDC-ACM serial port that greets and echoes every byte back.
//! - The watchdog is fed by the keypad task.
#![no_std]
// Every unsafe block says why it is sound (a `SAFETY:` comment).
#![deny(clippy::undocumented_unsafe_blocks)]
#![no_main]

use defmt_rtt as _;
use inkstep::board;

/// A fault or panic must leave every motor driver disabled (see `inkstep::fault`).
#[cortex_m_rt::exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    inkstep::fault::on_hard_fault()
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    inkstep::fault::on_panic(info)
}

/// The priority of `usb_lp`, the one task that uses the USB device (RTIC's attribute
/// takes a literal: keep the two equal). The USB driver's sections mask only the
/// interrupts at or below it (`board::init`).
const USB_PRIORITY: u8 = 5;

#[rtic::app(device = stm32f1xx_hal::pac, peripherals = true, dispatchers = [USART1, USART2, USART3])]
mod app {
    use super::board;
    use core::fmt::Write as _;
    use embedded_graphics::{
        mono_font::{ascii::FONT_6X10, MonoTextStyle},
        pixelcolor::BinaryColor,
        prelude::*,
        text::{Baseline, Text},
    };
    use inkstep::steps::{self, StepOutput, StepTx};
    use inkstep_core::interpolation::StepEvent;
    use inkstep_core::keypad::{KeyKind, Keypad, KeypadConfig};
    use inkstep_core::ring::ByteRing;
    use inkstep_core::screens::{framebuffer::FrameBuffer, st7920};
    use inkstep_core::stepper::exec::Executor;
    use inkstep_core::stepper::queue::StepCmdQueue;
    use inkstep_core::stepper::StepCmd;
    use inkstep_core::stepper::MAX_RELOAD;
    use rtic_monotonics::systick::prelude::*;

    systick_monotonic!(Mono, 1_000);

    /// Jog rate: one step per millisecond on each moving axis.
    const JOG_WAIT_COUNTS: u32 = board::STEP_TIMER_HZ / 1_000;

    #[shared]
    struct Shared {
        usb: &'static mut board::Usb,
        serial: &'static mut board::UsbSerial,
        /// Held jog direction (signs of X, Y), or none.
        jog: Option<[i8; 2]>,
        last_key: &'static str,
        usb_bytes: u32,
    }

    #[local]
    struct Local {
        step_out: StepOutput,
        steps_tx: StepTx,
        keypad: board::KeypadMatrix,
        indicators: board::Indicators,
        busy: board::BusyOutputs,
        servo: board::PenServo,
        lcd_spi: board::LcdSpi,
        watchdog: board::Watchdog,
    }

    #[init(local = [
        usb_cells: board::UsbCells = board::UsbCells::new(),
        steps: StepCmdQueue = StepCmdQueue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let b = board::init(cx.device, cx.local.usb_cells, super::USB_PRIORITY);
        Mono::start(cx.core.SYST, b.sysclk_hz);
        let (steps_tx, steps_rx) = cx.local.steps.split();
        let mut port = b.step_port;
        let mut timer = b.step_timer;
        timer.set_pulse_ticks(10 * (board::STEP_TIMER_HZ / 1_000_000) as u16);
        port.set_drivers_enabled(true, true);
        let step_out = steps::install(Executor::new([0; 3], MAX_RELOAD), steps_rx, port, timer);
        defmt::info!("inkstep bring-up, sysclk {} Hz", b.sysclk_hz);
        jogger::spawn().ok();
        keypad_scan::spawn().ok();
        lcd_refresh::spawn().ok();
        (
            Shared {
                usb: b.usb,
                serial: b.serial,
                jog: None,
                last_key: "-",
                usb_bytes: 0,
            },
            Local {
                step_out,
                steps_tx,
                keypad: b.keypad,
                indicators: b.indicators,
                busy: b.busy,
                servo: b.servo,
                lcd_spi: b.lcd_spi,
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

    #[task(binds = EXTI0, priority = 7)]
    fn estop(_: estop::Context) {
        if board::exti_take_pending(0) {
            board::emergency_outputs_off();
            steps::HALT.trip_estop();
            steps::halt();
        }
    }

    #[task(binds = TIM2, priority = 6, local = [step_out])]
    fn step(cx: step::Context) {
        cx.local.step_out.on_interrupt();
    }

    /// Echo every byte (what the output ring has no room for is dropped); greet on
    /// the first.
    #[task(binds = USB_LP_CAN_RX0, priority = 5, shared = [usb, serial, usb_bytes], local = [
        echo: ByteRing<128> = ByteRing::new(),
    ])]
    fn usb_lp(cx: usb_lp::Context) {
        let (mut out, mut queued) = cx.local.echo.split();
        (cx.shared.usb, cx.shared.serial, cx.shared.usb_bytes).lock(|usb, serial, count| {
            if usb.poll(&mut [serial.class()]) {
                let mut buf = [0u8; board::USB_PACKET];
                let n = serial.read_packet(&mut buf);
                if n > 0 {
                    if *count == 0 {
                        out.push(b"inkstep bring-up: echo\r\n");
                    }
                    *count = count.wrapping_add(n as u32);
                    out.push(buf.get(..n).unwrap_or(&[]));
                }
            }
            serial.send(&mut queued);
        });
    }

    /// Keeps a few 1 ms jog steps queued while a jog key is held.
    #[task(priority = 5, shared = [jog], local = [steps_tx])]
    async fn jogger(mut cx: jogger::Context) {
        loop {
            if let Some([dx, dy]) = cx.shared.jog.lock(|j| *j) {
                let tx = &mut *cx.local.steps_tx;
                while tx.len() < 4 && !tx.is_full() {
                    let step = u8::from(dx != 0) | (u8::from(dy != 0) << 1);
                    let neg = u8::from(dx < 0) | (u8::from(dy < 0) << 1);
                    tx.push(StepCmd::new(StepEvent(step | (neg << 3)), JOG_WAIT_COUNTS));
                }
                steps::kick();
            }
            Mono::delay(2.millis()).await;
        }
    }

    #[task(priority = 3, shared = [jog, last_key], local = [keypad, watchdog, indicators, busy, servo])]
    async fn keypad_scan(mut cx: keypad_scan::Context) {
        let mut scanner = Keypad::new(KeypadConfig::default());
        let mut pen_down = false;
        let mut beep_ms = 0u32;
        loop {
            cx.local.keypad.select_column(scanner.column());
            Mono::delay(5.millis()).await;
            let rows = cx.local.keypad.read_rows();
            for ev in scanner.feed(rows, Mono::now().ticks()) {
                let label = ev.key.label();
                match ev.kind {
                    KeyKind::Press => {
                        beep_ms = 60;
                        cx.shared.last_key.lock(|k| *k = label);
                        if let Some(dir) = ev.key.jog_dir() {
                            cx.shared.jog.lock(|j| *j = Some(dir));
                        } else if ev.key == inkstep_core::keypad::Key::Digit(5) {
                            pen_down = !pen_down;
                            cx.local
                                .servo
                                .set_pulse_us(if pen_down { 1200 } else { 2000 });
                        }
                    }
                    KeyKind::Release => {
                        if ev.key.jog_dir().is_some() {
                            cx.shared.jog.lock(|j| *j = None);
                        }
                    }
                    KeyKind::Repeat => {}
                }
            }
            let moving = cx.shared.jog.lock(|j| j.is_some());
            cx.local.busy.set(moving, moving);
            cx.local.indicators.set_buzzer(beep_ms > 0);
            beep_ms = beep_ms.saturating_sub(5);
            if !moving {
                // E-stop released and no key held: re-arm (the drivers come back on).
                // No machine here to see the trip and flush the queue: both done here.
                let _ = steps::HALT.take_tripped();
                steps::HALT.flushed();
                steps::release_halt(|| !board::Inputs::levels().estop);
            }
            cx.local.watchdog.feed();
        }
    }

    #[task(priority = 1, shared = [last_key, usb_bytes], local = [lcd_spi])]
    async fn lcd_refresh(mut cx: lcd_refresh::Context) {
        let spi = cx.local.lcd_spi;
        board::lcd_init(spi);
        let mut fb = FrameBuffer::new();
        fb.mark_all_dirty();
        let style = MonoTextStyle::new(&FONT_6X10, BinaryColor::On);
        loop {
            let key = cx.shared.last_key.lock(|k| *k);
            let bytes = cx.shared.usb_bytes.lock(|b| *b);
            let inputs = board::Inputs::levels();
            let pos = steps::position();
            let mut lines: [heapless::String<22>; 5] = Default::default();
            let _ = write!(lines[0], "inkstep bring-up");
            let _ = write!(lines[1], "key {} usb {}", key, bytes);
            let _ = write!(lines[2], "X{} Y{}", pos[0], pos[1]);
            let _ = write!(
                lines[3],
                "E{} X{} Y{} H{} S{}",
                u8::from(inputs.estop),
                u8::from(inputs.limits[0] == Some(true)),
                u8::from(inputs.limits[1] == Some(true)),
                u8::from(!inputs.feed_hold),
                u8::from(!inputs.cycle_start)
            );
            let _ = write!(
                lines[4],
                "{}",
                if steps::is_halted() {
                    "E-STOP"
                } else {
                    "ready"
                }
            );
            let _ = fb.clear(BinaryColor::Off);
            for (i, l) in lines.iter().enumerate() {
                let _ =
                    Text::with_baseline(l, Point::new(1, 1 + 12 * i as i32), style, Baseline::Top)
                        .draw(&mut fb);
            }
            let _ = st7920::flush(&mut fb, |b| {
                spi.write_blocking(b);
                Ok::<(), core::convert::Infallible>(())
            });
            Mono::delay(100.millis()).await;
        }
    }
}
