//! inkstep firmware: thin RTIC wiring between the Blue Pill's peripherals (`board`) and
//! the hardware-free core (`inkstep-core`). Every decision is the core's: the tasks
//! here only move bytes, pins and time between the hardware and the same `Controller`
//! and `Pipeline` that the simulator drives (docs/architecture.md: the data flow and
//! the lock map).
//!
//! Priorities (higher preempts lower; docs/architecture.md has the lock map):
//!   7  e-stop and limit switches (EXTI0, EXTI1, EXTI3): outputs off at once; the 1 ms
//!      tick (SysTick, above every lock so that no millisecond is lost): the clock and
//!      the start of the periodic tasks below
//!   6  step timer (TIM2): the core's `Executor`, integer work only
//!   5  USB (endpoint <-> byte queues; a packet with a real-time byte is handed to
//!      the controller at once, so a `?` is answered before the preparation's next
//!      run) and segment preparation (`Pipeline::fill`, every tick)
//!   4  protocol / G-code / machine state (`Controller::service`, every tick while
//!      it has work; at idle only when bytes, an input edge or a key wake it),
//!      feed-hold and cycle-start inputs
//!   3  keypad scan (one column every 5 ms), buzzer, the watchdog
//!   1  LCD refresh (every 100 ms; its bytes go out by DMA, a buffer per transfer, and
//!      each transfer's end starts the task again for the next): everything preempts it
//!   0  idle: WFI
//!
//! Every task is an interrupt handler: the periodic ones run on interrupts that the
//! tick pends (I2C1_EV, SPI1, USART3, otherwise unused, and the LCD's DMA channel),
//! so the image carries no async executor and no timer queue. No task waits.
#![no_std]
// Every unsafe block says why it is sound (a `SAFETY:` comment).
#![deny(clippy::undocumented_unsafe_blocks)]
#![no_main]

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use defmt_rtt as _;
use inkstep::board;
use inkstep::steps::{self, BoardSide, StepOutput, HALT};
use inkstep_core::controller::{
    is_realtime, HOST_RX_RING, HOST_TX_RING, KEYPAD_SCAN_MS, LCD_REFRESH_MS,
};
use inkstep_core::pipeline::StepSide;
use inkstep_core::ring::{ByteRing, ByteRx, ByteTx};
use inkstep_core::stepper::exec::Executor;
use inkstep_core::stepper::output::OutputConfig;
use inkstep_core::stepper::queue::StepCmdQueue;
use inkstep_core::stepper::MAX_RELOAD;

/// The priority of `usb_lp`, the one task that uses the USB device (RTIC's attribute
/// takes a literal: keep the two equal). The USB driver's sections mask only the
/// interrupts at or below it (`board::init`).
const USB_PRIORITY: u8 = 5;

/// 4-phase outputs (`$200=1`): the motors are released by turning the coils off too.
static FOUR_PHASE: AtomicBool = AtomicBool::new(false);
/// The host has the serial port open (CDC's DTR), as the USB task last saw it.
static PORT_OPEN: AtomicBool = AtomicBool::new(false);
/// Something the protocol task must see happened since it last looked (bytes from the
/// host, the port opened or closed, an input pin's edge, a key): it runs at once, not
/// at the next tick, and again if this came while it ran (see `wake_protocol`).
static PROTOCOL_WAKE: AtomicBool = AtomicBool::new(false);
/// The protocol task has periodic work (a line, motion to follow, a timer): the tick
/// starts it every millisecond. Otherwise it sleeps until `wake_protocol`.
static PROTOCOL_BUSY: AtomicBool = AtomicBool::new(true);

/// Run the protocol task now: what just happened (bytes, an input, a key) is
/// answered at once, and a sleeping protocol task wakes up.
fn wake_protocol() {
    PROTOCOL_WAKE.store(true, Ordering::Relaxed);
    rtic::pend(stm32f1xx_hal::pac::Interrupt::SPI1);
}

/// A fault or panic must leave every motor driver disabled (see `inkstep::fault`).
#[cortex_m_rt::exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    inkstep::fault::on_hard_fault()
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    inkstep::fault::on_panic(info)
}

#[rtic::app(device = stm32f1xx_hal::pac, peripherals = true)]
mod app {
    use super::*;
    use core::mem::MaybeUninit;
    use cortex_m::peripheral::syst::SystClkSource;
    use inkstep::service_tick::{now_ms, ticks_since_tick};
    use inkstep_core::controller::{Controller, HostLink};
    use inkstep_core::hmi::buzzer::Buzzer;
    use inkstep_core::pipeline::Pipeline;
    use inkstep_core::screens::{framebuffer::FrameBuffer, st7920, Screens};
    use inkstep_core::settings_store::SettingsStore;
    use inkstep_core::stepper::prep::PrepConfig;
    use stm32f1xx_hal::pac::Interrupt;

    /// While the LCD powers up: the millisecond its next step is due (0: none). The
    /// tick pends the LCD task then, so the power-up waits cost no CPU.
    static LCD_DUE_MS: AtomicU32 = AtomicU32::new(0);

    type Store = SettingsStore<board::SettingsFlash>;

    // The controller (2 KB) and the pipeline (4 KB, the planner's buffer) are built in
    // place in init's static cells and shared by reference: returned by value they
    // would be built on init's stack (more than the stack left beside the statics)
    // and copied. They are one resource (`Core`), locked together. The USB device and
    // its serial port, likewise built in place (`board::UsbCells`), belong to the USB
    // task alone.
    #[shared]
    struct Shared {
        core: Core,
    }

    #[local]
    struct Local {
        usb: &'static mut board::Usb,
        serial: &'static mut board::UsbSerial,
        step_out: StepOutput,
        servo: board::PenServo,
        keypad: board::KeypadMatrix,
        indicators: board::Indicators,
        busy: board::BusyOutputs,
        lcd_spi: board::LcdSpi,
        watchdog: board::Watchdog,
        store: Store,
        usb_rx_in: ByteTx<'static, HOST_RX_RING>,
        usb_tx_out: ByteRx<'static, HOST_TX_RING>,
    }

    #[init(local = [
        usb_cells: board::UsbCells = board::UsbCells::new(),
        steps: StepCmdQueue = StepCmdQueue::new(),
        usb_rxq: ByteRing<HOST_RX_RING> = ByteRing::new(),
        usb_txq: ByteRing<HOST_TX_RING> = ByteRing::new(),
        ctl_cell: MaybeUninit<Controller> = MaybeUninit::uninit(),
        pipeline_cell: MaybeUninit<Pipeline<BoardSide>> = MaybeUninit::uninit(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let b = board::init(cx.device, cx.local.usb_cells, USB_PRIORITY);
        // The 1 ms tick from the core clock.
        let mut syst = cx.core.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(b.sysclk_hz / 1_000 - 1);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();

        // Settings, offsets and startup lines from flash; a corrupt store falls back to
        // defaults and the host is told.
        let mut store = match SettingsStore::new(b.flash, board::settings_pages()) {
            Ok(s) => s,
            // memory.x places the pages inside the chip's flash; this cannot happen.
            Err(_) => defmt::panic!("settings flash range"),
        };
        let ctl = Controller::boot_in(cx.local.ctl_cell, &mut store, 0);
        // This image uses 128 KB of flash: a chip that promises less (a C8's 64 KB)
        // does not run it, but stays visibly alive: the LED blinks a code, USB answers
        // with the alarm and the part needed, the motors stay off (the core decides).
        let flash_kb = board::flash_size_kb();
        ctl.check_chip(flash_kb);
        if ctl.protocol().machine().refusal().is_some() {
            defmt::error!(
                "this image needs a 128 KB STM32F103CB; this chip has {} KB of flash",
                flash_kb
            );
        }
        let settings = ctl.protocol().machine().settings();
        let (steps_tx, steps_rx) = cx.local.steps.split();
        let prep = PrepConfig {
            timer_hz: board::STEP_TIMER_HZ,
            ..PrepConfig::default()
        };
        let pipeline = Pipeline::init_in(
            cx.local.pipeline_cell,
            settings,
            prep,
            BoardSide { tx: steps_tx },
        );
        let (usb_rx_in, usb_rx_out) = cx.local.usb_rxq.split();
        let (usb_tx_in, usb_tx_out) = cx.local.usb_txq.split();

        apply_output_config(&OutputConfig::from(settings));
        let step_out = steps::install(
            Executor::new([0; 3], MAX_RELOAD),
            steps_rx,
            b.step_port,
            b.step_timer,
        );

        defmt::info!(
            "inkstep {} up, sysclk {} Hz",
            env!("CARGO_PKG_VERSION"),
            b.sysclk_hz
        );
        // The keypad's first column, read one scan period from now; the LCD comes up
        // at once (the tick starts the rest).
        let mut keypad = b.keypad;
        keypad.select_column(ctl.keypad().column());
        rtic::pend(Interrupt::DMA1_CHANNEL5);
        (
            Shared {
                core: Core {
                    ctl,
                    pipeline,
                    rx: usb_rx_out,
                    tx: usb_tx_in,
                },
            },
            Local {
                usb: b.usb,
                serial: b.serial,
                step_out,
                servo: b.servo,
                keypad,
                indicators: b.indicators,
                busy: b.busy,
                lcd_spi: b.lcd_spi,
                watchdog: b.watchdog,
                store,
                usb_rx_in,
                usb_tx_out,
            },
        )
    }

    /// The controller and the motion pipeline, one resource: every task that uses the
    /// controller also drives the pipeline, so one lock (at the tick's priority, where
    /// the segment preparation runs) covers both. With them the controller's ends of
    /// the host's byte rings (received bytes out, replies in), which the protocol task
    /// and the USB task (real-time bytes) both hand to it.
    pub struct Core {
        ctl: &'static mut Controller,
        pipeline: &'static mut Pipeline<BoardSide>,
        rx: ByteRx<'static, HOST_RX_RING>,
        tx: ByteTx<'static, HOST_TX_RING>,
    }

    impl Core {
        fn parts(&mut self) -> (&mut Controller, &mut Pipeline<BoardSide>) {
            (&mut *self.ctl, &mut *self.pipeline)
        }
    }

    /// The core's output configuration into the step interrupt, the hard-limit arming
    /// and the driver-enable polarity (at boot and whenever the settings change). `$4`
    /// acts within a millisecond: the preparation task rewrites the enable pin every
    /// tick with the polarity set here.
    fn apply_output_config(cfg: &OutputConfig) {
        steps::set_output_config(cfg);
        HALT.arm_hard_limits(cfg.hard_limit_axes);
        FOUR_PHASE.store(cfg.four_phase, Ordering::Relaxed);
        board::set_enable_polarity(cfg.enable_active_low);
    }

    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// Emergency stop: highest priority. Drivers off and steps halted before anything
    /// else; the protocol task raises the alarm when it next reads the inputs (<= 1 ms:
    /// the core's halt latch shows it the e-stop as pressed even if it was released
    /// again meanwhile).
    #[task(binds = EXTI0, priority = 7)]
    fn estop(_: estop::Context) {
        if board::exti_take_pending(0) {
            board::emergency_outputs_off();
            HALT.trip_estop();
            steps::halt();
            wake_protocol();
        }
    }

    /// Limit switches: with hard limits armed, stop stepping at once like the e-stop
    /// (drivers stay enabled so the position is held); the machine raises the alarm.
    #[task(binds = EXTI1, priority = 7)]
    fn limit_x(_: limit_x::Context) {
        limit_switch(1);
    }

    #[task(binds = EXTI3, priority = 7)]
    fn limit_y(_: limit_y::Context) {
        limit_switch(3);
    }

    /// A limit switch on EXTI line `line` changed (one body for both axes): the core's
    /// halt latch decides whether it halts (hard limits armed on that axis).
    fn limit_switch(line: u8) {
        if board::exti_take_pending(line) {
            let axis = if line == 1 { 0 } else { 1 };
            if HALT.trip_limit(axis) {
                steps::halt();
            }
            // The machine reads the switch (alarm, homing, the `?` report's pins).
            wake_protocol();
        }
    }

    /// The step timer: the core's executor, see `inkstep::steps`.
    #[task(binds = TIM2, priority = 6, local = [step_out])]
    fn step(cx: step::Context) {
        cx.local.step_out.on_interrupt();
    }

    /// USB: poll the device, take bytes from the endpoint only while the RX queue has
    /// room (so a full queue NAKs the host instead of dropping), send queued output,
    /// and publish whether the host has the port open. A packet that brings a real-time
    /// byte goes to the controller at once (`Controller::take_realtime`): this task
    /// runs between two lock sections, before the segment preparation when both wait
    /// (same priority, lower interrupt number), so a `?`'s report waits for neither
    /// the preparation nor the protocol task's next run.
    #[task(binds = USB_LP_CAN_RX0, priority = 5, shared = [core], local = [usb, serial, usb_rx_in, usb_tx_out])]
    fn usb_lp(mut cx: usb_lp::Context) {
        let rx = cx.local.usb_rx_in;
        let tx = cx.local.usb_tx_out;
        let serial = &mut **cx.local.serial;
        cx.local.usb.poll(&mut [serial.class()]);
        let open = serial.dtr();
        let mut arrived = PORT_OPEN.swap(open, Ordering::Relaxed) != open;
        if rx.free() >= board::USB_PACKET {
            let mut buf = [0u8; board::USB_PACKET];
            let n = serial.read_packet(&mut buf);
            let packet = buf.get(..n).unwrap_or(&[]);
            arrived |= rx.push(packet) > 0;
            if packet.iter().any(|&b| is_realtime(b)) {
                let now = now_ms();
                cx.shared.core.lock(|c| {
                    let host = HostLink {
                        rx: &mut c.rx,
                        tx: &mut c.tx,
                        port_open: open,
                    };
                    c.ctl.take_realtime(host, &mut *c.pipeline, now);
                });
            }
        } else {
            // A packet left in the endpoint keeps the peripheral's transfer flag set,
            // and with it this interrupt: it would fire again at once, forever, and
            // starve the protocol task that empties the queue (the watchdog then
            // resets the board). Masked here, unmasked by the protocol task after each
            // run, so while the queue is full this task runs once per millisecond:
            // the host is NAKed (back-pressure) and output still flows.
            cortex_m::peripheral::NVIC::mask(Interrupt::USB_LP_CAN_RX0);
        }
        // Output waits in its ring until the endpoint takes it; with the port closed
        // nobody will read it (the protocol discards its own output then too), and a
        // host that opens the port later must see its session start, not stale lines.
        if !open {
            tx.clear();
        }
        serial.send(tx);
        if arrived {
            // Real-time bytes act when they arrive, not at the next tick.
            wake_protocol();
        }
    }

    /// The 1 ms tick: the clock, and the periodic tasks started at their periods
    /// (segment preparation and the protocol every tick, the keypad scan, the LCD).
    /// Above every lock ceiling, so that a long critical section delays the tasks but
    /// not the clock.
    #[task(binds = SysTick, priority = 7)]
    fn tick(_: tick::Context) {
        let now = inkstep::service_tick::count_tick();
        rtic::pend(Interrupt::I2C1_EV);
        if PROTOCOL_BUSY.load(Ordering::Relaxed) {
            rtic::pend(Interrupt::SPI1);
        }
        if now.is_multiple_of(KEYPAD_SCAN_MS) {
            rtic::pend(Interrupt::USART3);
        }
        let lcd_due = LCD_DUE_MS.load(Ordering::Relaxed);
        if now.is_multiple_of(LCD_REFRESH_MS) || (lcd_due != 0 && now == lcd_due) {
            rtic::pend(Interrupt::DMA1_CHANNEL5);
        }
    }

    /// Segment preparation, every tick: keep a few ms of step commands queued ahead of
    /// the interrupt and start the timer when it is idle and commands wait. Then the
    /// outputs that follow the motion millisecond by millisecond, whatever the
    /// protocol task does (it sleeps at idle): the busy LED and output, and the
    /// motors' power (`$1`: released that long after the last motion; on again
    /// before the first step of the next).
    #[task(binds = I2C1_EV, priority = 5, shared = [core], local = [busy])]
    fn prepare(mut cx: prepare::Context) {
        let now = now_ms();
        let (kick, levels) = cx.shared.core.lock(|c| {
            let (ctl, pipeline) = c.parts();
            pipeline.fill_at(now);
            let levels = ctl.outputs_now(pipeline, now);
            (pipeline.side().queued() > 0, levels)
        });
        cx.local.busy.set(levels.led, levels.busy);
        if levels.motors {
            steps::drivers_on_unless_halted();
        } else {
            // At rest (no step queued or in flight: the motors needed no power for
            // `$1` ms), so the coils are free to write.
            board::drivers_enabled(false);
            if FOUR_PHASE.load(Ordering::Relaxed) {
                board::coils_off();
            }
        }
        if kick {
            steps::kick_since(ticks_since_tick(now));
        }
    }

    /// The protocol tick: the controller's `service` (inputs, host bytes, the
    /// protocol, the HMI's timers, replies, settings and their persistence at rest),
    /// then what it asks of the hardware: the output configuration, the pen servo and
    /// the release of a halt (each decided by the core).
    #[task(binds = SPI1, priority = 4, shared = [core], local = [servo, store])]
    fn protocol(mut cx: protocol::Context) {
        let started = now_ms();
        let quiet = loop {
            PROTOCOL_WAKE.store(false, Ordering::Relaxed);
            let now = now_ms();
            let pins = board::Inputs::levels();
            let port_open = PORT_OPEN.load(Ordering::Relaxed);
            let store = &mut *cx.local.store;
            let done = cx.shared.core.lock(|c| {
                let host = HostLink {
                    rx: &mut c.rx,
                    tx: &mut c.tx,
                    port_open,
                };
                let done = c
                    .ctl
                    .service(host, pins, &HALT, store, &mut *c.pipeline, now);
                // The replies out now, and the receive side open again: pended before
                // the lock is released, so that the USB task runs first (ahead of a
                // preparation the tick pended meanwhile: same priority, lower
                // interrupt number) and the sender's next line is not held up by it.
                // SAFETY: RTIC's locks use BASEPRI, not NVIC masks; unmasking only
                // undoes the USB task's own back-pressure mask (see `usb_lp`).
                unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::USB_LP_CAN_RX0) };
                rtic::pend(Interrupt::USB_LP_CAN_RX0);
                done
            });
            if let Some(cfg) = done.outputs {
                apply_output_config(&cfg);
            }
            if let Some(us) = done.servo_pulse_us {
                cx.local.servo.set_pulse_us(us);
            }
            // The core's release rule, with the e-stop pin read again now: an e-stop
            // pressed after the inputs were read above is not undone.
            steps::release_halt(|| done.allows_release(board::Inputs::levels()));
            // One line per run, the lock released in between (so the USB task and the
            // step preparation get in, and a `?` that arrives meanwhile is answered
            // before the next line); more lines until the next tick.
            if !done.again(started, now_ms()) {
                break done.quiet;
            }
        };
        // Quiet: no tick starts this task again until something wakes it.
        PROTOCOL_BUSY.store(!quiet, Ordering::Relaxed);
        // A tick that came while this ran is dropped, so the tasks below always get a
        // turn between two runs; a wake that came after the last look starts a new run.
        cortex_m::peripheral::NVIC::unpend(Interrupt::SPI1);
        if PROTOCOL_WAKE.load(Ordering::Relaxed) {
            rtic::pend(Interrupt::SPI1);
        }
    }

    /// Feed hold / SYNC and cycle start act at once, like `!` and `~`.
    #[task(binds = EXTI4, priority = 4, shared = [core])]
    fn feed_hold(mut cx: feed_hold::Context) {
        if board::exti_take_pending(4) {
            input_edge(&mut cx.shared.core);
            wake_protocol();
        }
    }

    #[task(binds = EXTI9_5, priority = 4, shared = [core])]
    fn cycle_start(mut cx: cycle_start::Context) {
        if board::exti_take_pending(5) {
            input_edge(&mut cx.shared.core);
            wake_protocol();
        }
    }

    /// An input pin changed: its level (with the others) into the controller.
    fn input_edge(core: &mut impl rtic::Mutex<T = Core>) {
        let now = now_ms();
        let pins = board::Inputs::levels();
        core.lock(|c| {
            let (ctl, pipeline) = c.parts();
            ctl.set_pins(pins, pipeline, now);
        });
    }

    /// The keypad: drive the column the scanner asks for, read its rows one scan
    /// period later (no busy wait for the lines to settle), hand them to the core.
    /// Also plays the buzzer patterns and feeds the watchdog.
    #[task(binds = USART3, priority = 3, shared = [core], local = [keypad, watchdog, indicators, buzzer: Buzzer = Buzzer::new()])]
    fn keypad_scan(mut cx: keypad_scan::Context) {
        // The rows of the column selected one scan period ago.
        let rows = cx.local.keypad.read_rows();
        let now = now_ms();
        let (out, col, keyed) = cx.shared.core.lock(|c| {
            let (ctl, pipeline) = c.parts();
            let keyed = ctl.key_scan(rows, pipeline, now);
            (ctl.take_outputs(), ctl.keypad().column(), keyed)
        });
        if keyed {
            // A key's job, jog or menu change: the protocol task follows it.
            wake_protocol();
        }
        cx.local.keypad.select_column(col);
        let buzzer = cx.local.buzzer;
        if let Some(b) = out.beep {
            buzzer.play(b);
        }
        cx.local.indicators.set_buzzer(buzzer.tick(KEYPAD_SCAN_MS));
        cx.local.watchdog.feed();
    }

    /// The LCD at 10 Hz, lowest priority: take a snapshot of the HMI and the status
    /// under a short lock, draw it into the frame buffer, and send only the changed
    /// words by DMA, a buffer at a time. Started by the tick (the refresh, the
    /// power-up's steps) and by the end of each DMA transfer (the next buffer of the
    /// refresh under way); it never waits. Also logs the step interrupt's late armings
    /// when their count has grown, once the queue is empty (from the task with time to
    /// spare).
    #[task(binds = DMA1_CHANNEL5, priority = 1, shared = [core], local = [
        lcd_spi,
        // The task's retained state, static: the screens, and the 1 KB frame buffer
        // (entirely dirty from the start: the first refresh sends the whole screen).
        screens: Screens = Screens::new(),
        fb: FrameBuffer = FrameBuffer::new(),
        // Power-up steps done (0: none; past `INIT_SEQUENCE.len() + 1`: up).
        init_step: usize = 0,
        init_due: u32 = 0,
        // Where the next buffer of the refresh under way starts (None: none under way).
        sending: Option<st7920::Cursor> = None,
        // The refresh period the last refresh belonged to (its first millisecond).
        drawn_ms: Option<u32> = None,
        late_seen: u32 = 0,
    ])]
    fn lcd_refresh(mut cx: lcd_refresh::Context) {
        let spi = cx.local.lcd_spi;
        // A transfer's end raised this interrupt (or the tick did): the line drops.
        spi.ack();
        let init = board::INIT_SEQUENCE;
        let step = *cx.local.init_step;
        if step <= init.len() + 1 {
            // The controller comes up in graphics mode, one instruction per wake-up at
            // the tick its wait ends (rounded up to whole milliseconds, plus one for
            // the tick's phase); after that only the changed bytes are sent
            // (core::screens::st7920).
            let now = now_ms();
            if step > 0 && (now.wrapping_sub(*cx.local.init_due) as i32) < 0 {
                return;
            }
            if step <= init.len() {
                let wait_ms = match step.checked_sub(1).and_then(|i| init.get(i)) {
                    None => board::POWER_UP_MS,
                    Some(&(cmd, wait_us)) => {
                        // Each wait is far longer than a frame: the link is free.
                        if !spi.command(cmd) {
                            defmt::warn!("LCD init: link busy");
                        }
                        wait_us.div_ceil(1000)
                    }
                };
                let due = now.wrapping_add(wait_ms + 1).max(1);
                *cx.local.init_due = due;
                LCD_DUE_MS.store(due, Ordering::Relaxed);
                *cx.local.init_step = step + 1;
                return;
            }
            // The last wait is over: draw from now on.
            LCD_DUE_MS.store(0, Ordering::Relaxed);
            *cx.local.init_step = step + 1;
        }
        let fb = cx.local.fb;
        if let Some(at) = *cx.local.sending {
            // The next buffer of the refresh under way.
            *cx.local.sending = send_chunk(spi, fb, at);
            return;
        }
        // A new refresh once per period, once the last one is sent: a tick that found
        // a refresh still under way is served when its last transfer ends.
        let now = now_ms();
        let period = now - now % LCD_REFRESH_MS;
        if *cx.local.drawn_ms == Some(period) || !spi.sent() {
            return;
        }
        *cx.local.drawn_ms = Some(period);
        let screens = cx.local.screens;
        // Bound by reference: the snapshot stays where the lock returned it, rather
        // than being moved again into locals of this task's stack.
        let (ref hmi, ref status) = cx.shared.core.lock(|c| {
            let (ctl, pipeline) = c.parts();
            let status = ctl.refresh_view(pipeline);
            (ctl.hmi().clone(), status)
        });
        // The late step armings, logged at rest only: a defmt frame masks every
        // interrupt while it is written (critical-section), for about 35 µs under the
        // emulator's pessimistic cycle model, which is itself enough to make the next
        // step arming late.
        let late = board::late_step_armings();
        if late != *cx.local.late_seen && status.queue_empty {
            *cx.local.late_seen = late;
            defmt::warn!(
                "step interrupt late {} times since power-up: steps delayed, none lost",
                late
            );
        }
        let _ = screens.render(hmi, status, now, fb);
        if !fb.is_dirty() {
            return;
        }
        // The last refresh's last bytes leave SPI2 two frames (57 µs) after its
        // transfer ended, less than a render takes: this task, the lowest, may wait
        // out what is left of them.
        while !spi.idle() {}
        *cx.local.sending = send_chunk(spi, fb, st7920::Cursor::START);
    }

    /// The refresh's bytes from `at` on: as many as fill the LCD's buffer, sent by
    /// DMA once the last transfer is done. Returns where the next buffer starts (None:
    /// the refresh is all sent, and the frame buffer is marked clean).
    fn send_chunk(
        spi: &mut board::LcdSpi,
        fb: &mut FrameBuffer,
        at: st7920::Cursor,
    ) -> Option<st7920::Cursor> {
        let Some(buf) = spi.buffer() else {
            // A transfer still reads the buffer; its end starts the task again.
            return Some(at);
        };
        let (n, next) = st7920::encode_chunk(fb, at, buf);
        spi.send(n);
        if next.is_none() {
            fb.mark_clean();
        }
        next
    }
}
