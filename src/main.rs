//! inkstep firmware: thin RTIC wiring between the Blue Pill's peripherals (`board`) and
//! the hardware-free core (`inkstep-core`).
//!
//! Priorities (higher preempts lower), as in DESIGN.md:
//!   7  e-stop and limit switches (EXTI0, EXTI1, EXTI3)
//!   6  step timer (TIM2): executes prepared step events, integer work only
//!   5  USB (moves bytes between the endpoint and the SPSC queues), segment preparation
//!      (planner blocks -> timed step commands in the SPSC step queue)
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
    use core::sync::atomic::{AtomicBool, Ordering};
    use heapless::spsc::{Consumer, Producer, Queue};
    use inkstep::board;
    use inkstep_core::planner::{Planner, PlannerConfig};
    use inkstep_core::stepper::drive::STEP_QUEUE;
    use inkstep_core::stepper::exec::{Executor, IsrOut};
    use inkstep_core::stepper::prep::{Prep, PrepConfig};
    use inkstep_core::stepper::StepCmd;
    use rtic_monotonics::systick::prelude::*;
    use stm32f1xx_hal::usb::UsbBusType;
    use usb_device::bus::UsbBusAllocator;

    systick_monotonic!(Mono, 1_000);

    /// Latched by the e-stop input (priority 7); the step interrupt checks it before
    /// every pulse and halts the executor, so no step follows it.
    static ESTOP: AtomicBool = AtomicBool::new(false);
    /// Feed hold / cycle start requests for the segment preparation.
    static HOLD_REQ: AtomicBool = AtomicBool::new(false);
    static RESUME_REQ: AtomicBool = AtomicBool::new(false);

    /// Step pulse width: 2 us at the 2 MHz step-timer clock (A4988/DRV8825 need 1-2 us).
    const PULSE_TICKS: u16 = 4;
    const STEP_ALL: u8 = (board::STEP_MASK_X | board::STEP_MASK_Y | board::STEP_MASK_Z) as u8;

    /// The step interrupt's state: the executor runs one event ahead of the hardware,
    /// because TIM2's ARR is preloaded (a period written now applies after the next
    /// update). `next` holds the step to pulse at the next update.
    pub struct StepIsr {
        exec: Executor,
        rx: Consumer<'static, StepCmd>,
        next: IsrOut,
        /// Direction pins for the step after the present one, written when its pulse ends.
        dir_after: u8,
    }

    #[shared]
    struct Shared {
        /// The look-ahead planner: the protocol and keypad tasks push moves, the segment
        /// preparation pops blocks.
        planner: Planner,
        /// The step interrupt's state. Only TIM2 (the ceiling) writes it, lock-free;
        /// lower tasks lock it briefly to read the machine position (`exec.position()`).
        step_isr: StepIsr,
        usb: board::Usb,
        serial: board::UsbSerial,
        indicators: board::Indicators,
    }

    #[local]
    struct Local {
        step_port: board::StepPort,
        step_timer: board::StepTimer,
        prep: Prep,
        steps_tx: Producer<'static, StepCmd>,
        servo: board::PenServo,
        keypad: board::KeypadMatrix,
        inputs: board::Inputs,
        lcd: board::Lcd,
        watchdog: stm32f1xx_hal::watchdog::IndependentWatchdog,
    }

    #[init(local = [
        usb_bus: Option<UsbBusAllocator<UsbBusType>> = None,
        steps: Queue<StepCmd, STEP_QUEUE> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut b = board::init(cx.device, cx.local.usb_bus);
        b.step_timer.set_pulse_ticks(PULSE_TICKS);
        let (steps_tx, steps_rx) = cx.local.steps.split();
        let cfg = PlannerConfig::default();
        let prep_cfg = PrepConfig {
            timer_hz: board::STEP_TIMER_HZ,
            ..PrepConfig::default()
        };
        let step_isr = StepIsr {
            exec: Executor::new([0; 3], 0x1_0000),
            rx: steps_rx,
            next: IsrOut::default(),
            dir_after: 0,
        };
        Mono::start(cx.core.SYST, b.sysclk_hz);
        defmt::info!(
            "inkstep {} up, sysclk {} Hz",
            env!("CARGO_PKG_VERSION"),
            b.sysclk_hz
        );
        keypad_scan::spawn().ok();
        lcd_refresh::spawn().ok();
        segment_prep::spawn().ok();
        (
            Shared {
                planner: Planner::new(cfg, [0; 3]),
                step_isr,
                usb: b.usb,
                serial: b.serial,
                indicators: b.indicators,
            },
            Local {
                step_port: b.step_port,
                step_timer: b.step_timer,
                prep: Prep::new(prep_cfg, [0; 3]),
                steps_tx,
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

    /// Emergency stop: highest priority. Outputs off first, then latch the stop that
    /// the step interrupt honours before its next pulse.
    #[task(binds = EXTI0, priority = 7)]
    fn estop(_: estop::Context) {
        if board::exti_take_pending(0) {
            board::emergency_outputs_off();
            ESTOP.store(true, Ordering::SeqCst);
            rtic::pend(stm32f1xx_hal::pac::Interrupt::TIM2);
            defmt::warn!("e-stop");
        }
    }

    /// The step timer. Update event: pulse the step pins of the pending event and
    /// program the period after the next one. Compare event (pulse width later): step
    /// pins low and the direction for the next step. A software pend starts an idle
    /// timer. Integer work only (inkstep_core::stepper::exec).
    #[task(binds = TIM2, priority = 6, local = [step_port, step_timer], shared = [step_isr])]
    fn step(mut cx: step::Context) {
        let step::LocalResources {
            step_port: port,
            step_timer: timer,
            ..
        } = cx.local;
        // Priority 6 is this resource's ceiling: the lock costs nothing.
        cx.shared.step_isr.lock(|s| step_isr_work(s, port, timer));
    }

    #[inline(always)]
    fn step_isr_work(s: &mut StepIsr, port: &mut board::StepPort, timer: &mut board::StepTimer) {
        let (update, compare) = timer.take_events();
        if ESTOP.load(Ordering::SeqCst) {
            s.exec.halt();
            timer.stop();
            port.write(0, STEP_ALL);
            return;
        }
        if compare {
            let d = s.dir_after & 0b111;
            port.write(
                d << board::DIR_SHIFT,
                STEP_ALL | ((!d & 0b111) << board::DIR_SHIFT),
            );
        }
        if update && timer.is_running() {
            let now = s.next;
            if now.step != 0 {
                port.write(now.step, 0);
            }
            s.dir_after = now.dir;
            if now.reload == 0 {
                timer.stop();
                return;
            }
            // Fetch the event after this one; its period starts at the next update.
            s.next = s.exec.on_interrupt(&mut s.rx);
            if s.next.reload != 0 {
                timer.set_period(s.next.reload);
            }
        } else if !timer.is_running() {
            // Start: the first event's wait runs now, the one after it is preloaded.
            if let Some(first) = s.exec.start(&mut s.rx) {
                let d = first.dir & 0b111;
                port.write(d << board::DIR_SHIFT, (!d & 0b111) << board::DIR_SHIFT);
                timer.start_with_period(first.reload);
                s.next = s.exec.on_interrupt(&mut s.rx);
                if s.next.reload != 0 {
                    timer.set_period(s.next.reload);
                }
            }
        }
    }

    /// Segment preparation: keeps the step queue full from the planner, every
    /// millisecond, and applies feed hold / cycle start requests.
    #[task(priority = 5, shared = [planner, indicators], local = [prep, steps_tx])]
    async fn segment_prep(mut cx: segment_prep::Context) {
        loop {
            let prep = &mut *cx.local.prep;
            let tx = &mut *cx.local.steps_tx;
            let busy = cx.shared.planner.lock(|planner| {
                if HOLD_REQ.swap(false, Ordering::AcqRel) {
                    prep.hold();
                }
                if RESUME_REQ.swap(false, Ordering::AcqRel) {
                    prep.resume(planner);
                }
                prep.fill(planner, tx);
                !prep.is_idle(planner)
            });
            // Busy output / LED follows motion (queued steps count as motion).
            let busy = busy || !tx.is_empty();
            cx.shared.indicators.lock(|ind| ind.set_busy(busy));
            if !tx.is_empty() {
                // Starts the timer if it is idle (the interrupt ignores it otherwise).
                rtic::pend(stm32f1xx_hal::pac::Interrupt::TIM2);
            }
            Mono::delay(1.millis()).await;
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

    /// Feed-hold input (the seed's SYNC: pause while low): hold on low, resume on high.
    #[task(binds = EXTI4, priority = 4, local = [inputs])]
    fn control_inputs(cx: control_inputs::Context) {
        if board::exti_take_pending(4) {
            let low = cx.local.inputs.feed_hold_low();
            if low {
                HOLD_REQ.store(true, Ordering::Release);
            } else {
                RESUME_REQ.store(true, Ordering::Release);
            }
            defmt::info!("feed hold input low: {}", low);
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
