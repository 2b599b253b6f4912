//! inkstep firmware: thin RTIC wiring between the Blue Pill's peripherals (`board`) and
//! the hardware-free core (`inkstep-core`). Every decision is the core's: the tasks
//! here only move bytes, pins and time between the hardware and the same `Controller`
//! and `Pipeline` that the simulator drives.
//!
//! Priorities (higher preempts lower), as in DESIGN.md:
//!   7  e-stop and limit switches (EXTI0, EXTI1, EXTI3): outputs off at once; the 1 ms
//!      tick (SysTick, above every lock so that no millisecond is lost): the clock and
//!      the start of the periodic tasks below
//!   6  step timer (TIM2): the core's `Executor`, integer work only
//!   5  USB (endpoint <-> byte queues) and segment preparation (`Pipeline::fill`, every
//!      tick)
//!   4  protocol / G-code / machine state (every tick), feed-hold and cycle-start inputs
//!   3  keypad scan (one column every 5 ms), buzzer, the watchdog
//!   1  LCD refresh (every 100 ms): the only task that waits (on its SPI); everything
//!      preempts it
//!   0  idle: WFI
//!
//! Every task is an interrupt handler: the periodic ones run on interrupts that the
//! tick pends (I2C1_EV, SPI1, USART3, USART2, otherwise unused), so the image carries
//! no async executor and no timer queue.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use defmt_rtt as _;
use inkstep::board;
use inkstep::steps::{self, BoardSide, StepCmdQueue, StepOutput, PULSE_TICKS};
use inkstep_core::pipeline::StepSide;
use inkstep_core::ring::{ByteRing, ByteRx, ByteTx};
use inkstep_core::stepper::exec::Executor;

/// USB byte queues (`inkstep_core::ring`), relays between the USB interrupt and the
/// protocol task, which trade up to one 64-byte packet each way every millisecond
/// (64 KB/s, far above what Grbl's protocol needs). RX holds Grbl's whole 128-byte character-counting window
/// (two packets); the window itself is the protocol's receive buffer (`Bf:`), and a
/// full ring only NAKs the host (back-pressure, nothing is dropped). TX holds two
/// packets; the responses wait in the protocol's output buffer (`OUT_CAP`), which only
/// hands out what this ring has room for.
const USB_RX: usize = 128;
const USB_TX: usize = 128;

/// Hard limits stop stepping at once only when `$21` is on.
static HARD_LIMITS_ARMED: AtomicBool = AtomicBool::new(false);

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
    use inkstep_core::controller::Controller;
    use inkstep_core::gcode::STARTUP_LINES;
    use inkstep_core::hmi::buzzer::Buzzer;
    use inkstep_core::machine::Inputs;
    use inkstep_core::pipeline::Pipeline;
    use inkstep_core::screens::{framebuffer::FrameBuffer, st7920, Screens};
    use inkstep_core::settings::{OutputMode, PenMode, Settings};
    use inkstep_core::settings_store::{BlockingFlash, SettingsStore};
    use inkstep_core::stepper::prep::PrepConfig;
    use stm32f1xx_hal::pac::Interrupt;

    /// Milliseconds since boot, the core's clock: counted by the tick (its only
    /// writer), read by every task.
    static NOW_MS: AtomicU32 = AtomicU32::new(0);

    fn now_ms() -> u32 {
        NOW_MS.load(Ordering::Relaxed)
    }

    /// One keypad column per scan; the buzzer pattern advances by the same period.
    const KEYPAD_MS: u32 = 5;
    /// The LCD refresh period.
    const LCD_MS: u32 = 100;

    type Store = SettingsStore<BlockingFlash<board::SettingsFlash>>;

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
        inputs: board::Inputs,
        indicators: board::Indicators,
        lcd_spi: board::LcdSpi,
        screens: &'static mut Screens,
        fb: &'static mut FrameBuffer,
        watchdog: board::Watchdog,
        store: Store,
        usb_rx_in: ByteTx<'static, USB_RX>,
        usb_rx_out: ByteRx<'static, USB_RX>,
        usb_tx_in: ByteTx<'static, USB_TX>,
        usb_tx_out: ByteRx<'static, USB_TX>,
    }

    #[init(local = [
        usb_cells: board::UsbCells = board::UsbCells::new(),
        steps: StepCmdQueue = StepCmdQueue::new(),
        usb_rxq: ByteRing<USB_RX> = ByteRing::new(),
        usb_txq: ByteRing<USB_TX> = ByteRing::new(),
        ctl_cell: MaybeUninit<Controller> = MaybeUninit::uninit(),
        screens_cell: MaybeUninit<Screens> = MaybeUninit::uninit(),
        fb_cell: MaybeUninit<FrameBuffer> = MaybeUninit::uninit(),
        pipeline_cell: MaybeUninit<Pipeline<BoardSide>> = MaybeUninit::uninit(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let b = board::init(cx.device, cx.local.usb_cells);
        // The 1 ms tick from the core clock.
        let mut syst = cx.core.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(b.sysclk_hz / 1_000 - 1);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();

        // This image uses 128 KB of flash: on a chip that promises less (a C8's 64 KB)
        // it refuses to run rather than fault later; the panic leaves the drivers off.
        let flash_kb = board::flash_size_kb();
        if flash_kb < board::FLASH_SIZE / 1024 {
            defmt::panic!(
                "this image needs a 128 KB STM32F103CB; this chip has {} KB of flash",
                flash_kb
            );
        }
        // Settings from flash.
        let mut store = match SettingsStore::new(BlockingFlash(b.flash), board::settings_pages()) {
            Ok(s) => s,
            // memory.x places the pages inside the chip's flash; this cannot happen.
            Err(_) => defmt::panic!("settings flash range"),
        };
        let (steps_tx, steps_rx) = cx.local.steps.split();
        let (ctl, pipeline) = boot_core(
            &mut store,
            cx.local.ctl_cell,
            cx.local.pipeline_cell,
            BoardSide { tx: steps_tx },
        );
        let settings = ctl.protocol().machine().settings();
        let (usb_rx_in, usb_rx_out) = cx.local.usb_rxq.split();
        let (usb_tx_in, usb_tx_out) = cx.local.usb_txq.split();

        let mut step_port = b.step_port;
        let mut step_timer = b.step_timer;
        apply_output_settings(settings, &mut step_port, &mut step_timer);
        let step_out = steps::install(
            Executor::new([0; 3], 0x1_0000),
            steps_rx,
            step_port,
            step_timer,
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
        rtic::pend(Interrupt::USART2);
        (
            Shared {
                core: Core { ctl, pipeline },
            },
            Local {
                usb: b.usb,
                serial: b.serial,
                step_out,
                servo: b.servo,
                keypad,
                inputs: b.inputs,
                indicators: b.indicators,
                lcd_spi: b.lcd_spi,
                // The LCD task's retained state: the screens and the 1 KB frame buffer
                // (entirely dirty from the start: the first flush sends the whole
                // screen), built here in .bss rather than on that task's stack.
                screens: boot_screens(cx.local.screens_cell),
                fb: boot_frame_buffer(cx.local.fb_cell),
                watchdog: b.watchdog,
                store,
                usb_rx_in,
                usb_rx_out,
                usb_tx_in,
                usb_tx_out,
            },
        )
    }

    /// The settings, offsets and startup lines from flash, and the controller and the
    /// pipeline built in place in their static cells from them (inlined: out of line it
    /// saves no stack and costs ~500 bytes of flash).
    #[inline(always)]
    fn boot_core(
        store: &mut Store,
        ctl_cell: &'static mut MaybeUninit<Controller>,
        pipeline_cell: &'static mut MaybeUninit<Pipeline<BoardSide>>,
        side: BoardSide,
    ) -> (&'static mut Controller, &'static mut Pipeline<BoardSide>) {
        // A corrupt store falls back to defaults and says so.
        let (settings, load) = store.load_settings();
        let ctl = Controller::init_in(ctl_cell, &settings, 0);
        if let Some(msg) = load.message() {
            defmt::warn!("settings: {}", msg);
            ctl.protocol_mut().notify(msg);
        }
        let (coords, _) = store.load_coords();
        ctl.protocol_mut().machine_mut().set_coords(coords);
        for i in 0..STARTUP_LINES {
            let (line, _) = store.load_startup(i);
            ctl.protocol_mut().set_startup_line(i, line.as_str());
        }
        let prep = PrepConfig {
            timer_hz: board::STEP_TIMER_HZ,
            ..PrepConfig::default()
        };
        let pipeline = Pipeline::init_in(
            pipeline_cell,
            ctl.protocol().machine().settings(),
            prep,
            side,
        );
        (ctl, pipeline)
    }

    // The LCD task's retained state, built out of line: their temporaries (the frame
    // buffer's 1 KB) are then gone before the rest of init runs instead of adding to
    // init's frame.

    /// The LCD task's screens, in .bss rather than on that task's stack.
    #[inline(never)]
    fn boot_screens(cell: &'static mut MaybeUninit<Screens>) -> &'static mut Screens {
        cell.write(Screens::new())
    }

    /// The 1 KB frame buffer, entirely dirty from the start: the first flush sends the
    /// whole screen.
    #[inline(never)]
    fn boot_frame_buffer(cell: &'static mut MaybeUninit<FrameBuffer>) -> &'static mut FrameBuffer {
        cell.write(FrameBuffer::new())
    }

    /// The controller and the motion pipeline, one resource: every task that uses the
    /// controller also drives the pipeline, so one lock (at the tick's priority, where
    /// the segment preparation runs) covers both.
    pub struct Core {
        ctl: &'static mut Controller,
        pipeline: &'static mut Pipeline<BoardSide>,
    }

    impl Core {
        fn parts(&mut self) -> (&mut Controller, &mut Pipeline<BoardSide>) {
            (&mut *self.ctl, &mut *self.pipeline)
        }
    }

    /// What waits to be written to flash (at rest).
    pub struct Saves {
        settings: bool,
        coords: bool,
        startup: bool,
    }

    impl Saves {
        const fn new() -> Self {
            Self {
                settings: false,
                coords: false,
                startup: false,
            }
        }
    }

    /// Received bytes the protocol has not taken yet (it takes only what it can use:
    /// back-pressure toward the USB queue and the host).
    pub struct Carry {
        buf: [u8; 64],
        len: usize,
    }

    impl Carry {
        const fn new() -> Self {
            Self {
                buf: [0; 64],
                len: 0,
            }
        }

        /// Top up from the USB receive queue.
        fn fill(&mut self, rx: &mut ByteRx<'static, USB_RX>) {
            if let Some(free) = self.buf.get_mut(self.len..) {
                self.len += rx.pop(free);
            }
        }

        fn bytes(&self) -> &[u8] {
            self.buf.get(..self.len).unwrap_or(&[])
        }

        /// Drop the first `n` bytes (the ones the protocol took).
        fn consume(&mut self, n: usize) {
            let len = self.len.min(self.buf.len());
            let n = n.min(len);
            self.buf.copy_within(n..len, 0);
            self.len = len - n;
        }
    }

    /// Output polarity, mode and pulse width for the step interrupt, and the hard-limit
    /// arming, from the settings (at boot and whenever they change).
    fn publish_output_settings(s: &Settings) {
        steps::set_output_config(
            s.step_invert_mask(),
            s.dir_invert_mask(),
            s.output_mode() == OutputMode::FourPhase,
        );
        HARD_LIMITS_ARMED.store(s.hard_limits(), Ordering::Relaxed);
        // `$4` at once: the enable pin is rewritten with the new polarity unless an
        // e-stop holds the drivers off.
        board::set_enable_polarity(!s.invert_enable());
        steps::drivers_on_unless_halted();
        let ticks = u32::from(s.step_pulse_us()) * (board::STEP_TIMER_HZ / 1_000_000);
        PULSE_TICKS.store(ticks.min(0xFFFF), Ordering::Relaxed);
    }

    /// Output polarity, mode, pulse width and driver enable from the settings (at boot;
    /// later changes go through `publish_output_settings`).
    fn apply_output_settings(
        s: &Settings,
        port: &mut board::StepPort,
        timer: &mut board::StepTimer,
    ) {
        publish_output_settings(s);
        timer.set_pulse_ticks(PULSE_TICKS.load(Ordering::Relaxed) as u16);
        port.set_drivers_enabled(true, !s.invert_enable());
    }

    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// Emergency stop: highest priority. Drivers off and steps halted before anything
    /// else; the protocol task raises the alarm when it next reads the inputs (<= 1 ms).
    #[task(binds = EXTI0, priority = 7)]
    fn estop(_: estop::Context) {
        if board::exti_take_pending(0) {
            board::emergency_outputs_off();
            steps::halt();
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

    /// A limit switch on EXTI line `line` changed (one body for both axes).
    #[inline(never)]
    fn limit_switch(line: u8) {
        if board::exti_take_pending(line) && HARD_LIMITS_ARMED.load(Ordering::Relaxed) {
            steps::halt();
        }
    }

    /// The step timer: the core's executor, see `inkstep::steps`.
    #[task(binds = TIM2, priority = 6, local = [step_out])]
    fn step(cx: step::Context) {
        cx.local.step_out.on_interrupt();
    }

    /// USB: poll the device, take bytes from the endpoint only while the RX queue has
    /// room (so a full queue NAKs the host instead of dropping), send queued output.
    #[task(binds = USB_LP_CAN_RX0, priority = 5, local = [usb, serial, usb_rx_in, usb_tx_out])]
    fn usb_lp(cx: usb_lp::Context) {
        let rx = cx.local.usb_rx_in;
        let tx = cx.local.usb_tx_out;
        let serial = &mut **cx.local.serial;
        cx.local.usb.poll(&mut [&mut *serial]);
        let mut buf = [0u8; 64];
        if rx.free() >= buf.len() {
            if let Ok(n) = serial.read(&mut buf) {
                rx.push(buf.get(..n).unwrap_or(&[]));
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
        let n = tx.pop(&mut buf);
        if n > 0 {
            // The CDC class buffers what the endpoint cannot take yet; bytes it refuses
            // are dropped only if the host stopped reading.
            let _ = serial.write(buf.get(..n).unwrap_or(&[]));
        }
    }

    /// The 1 ms tick: the clock, and the periodic tasks started at their periods
    /// (segment preparation and the protocol every tick, the keypad scan, the LCD).
    /// Above every lock ceiling, so that a long critical section delays the tasks but
    /// not the clock.
    #[task(binds = SysTick, priority = 7)]
    fn tick(_: tick::Context) {
        let now = NOW_MS.load(Ordering::Relaxed).wrapping_add(1);
        NOW_MS.store(now, Ordering::Relaxed);
        rtic::pend(Interrupt::I2C1_EV);
        rtic::pend(Interrupt::SPI1);
        if now.is_multiple_of(KEYPAD_MS) {
            rtic::pend(Interrupt::USART3);
        }
        if now.is_multiple_of(LCD_MS) {
            rtic::pend(Interrupt::USART2);
        }
    }

    /// Segment preparation, every tick: keep a few ms of step commands queued ahead of
    /// the interrupt and start the timer when it is idle and commands wait.
    #[task(binds = I2C1_EV, priority = 5, shared = [core])]
    fn prepare(mut cx: prepare::Context) {
        let kick = cx.shared.core.lock(|c| {
            let pipeline = &mut *c.pipeline;
            pipeline.fill();
            pipeline.side().queued() > 0
        });
        if kick {
            steps::kick();
        }
    }

    /// The protocol, the machine state and the G-code interpreter, every millisecond:
    /// inputs, received bytes (only those the protocol takes: back-pressure), the
    /// periodic work, replies, the busy LED, the pen servo and settings persistence.
    #[task(binds = SPI1, priority = 4, shared = [core], local = [usb_rx_out, usb_tx_in, inputs, servo, store, carry: Carry = Carry::new(), saves: Saves = Saves::new(), pen: Option<bool> = None])]
    fn protocol(mut cx: protocol::Context) {
        let now = now_ms();
        let pins = &mut *cx.local.inputs;
        let carry = &mut *cx.local.carry;
        carry.fill(cx.local.usb_rx_out);
        let tx = &mut *cx.local.usb_tx_in;
        let (busy, settings_changed, pen_down, pen_pulse, alarmed, estop_inverted) =
            cx.shared.core.lock(|c| {
                let (ctl, pipeline) = c.parts();
                let s = ctl.protocol().machine().settings();
                let inputs = Inputs {
                    estop: pins.estop_open() != s.invert_inputs(),
                    limits: [
                        pins.limit_x_open() != s.invert_limits(),
                        pins.limit_y_open() != s.invert_limits(),
                        false,
                    ],
                    feed_hold: pins.feed_hold_low(),
                    cycle_start: pins.cycle_start_low(),
                };
                ctl.protocol_mut().set_inputs(inputs, pipeline, now);
                let taken = ctl.usb_rx(carry.bytes(), pipeline, now);
                carry.consume(taken);
                ctl.poll(pipeline, now);
                let mut out = [0u8; 64];
                let room = tx.free().min(out.len());
                let n = out.get_mut(..room).map_or(0, |b| ctl.usb_tx(b));
                tx.push(out.get(..n).unwrap_or(&[]));
                // The planner took new settings when they changed (at rest, before
                // the next line); what is left is the HMI, the outputs and the save.
                let changed = ctl.protocol_mut().machine_mut().take_settings_dirty();
                if changed {
                    ctl.settings_changed();
                }
                let busy = ctl.take_outputs().busy_led;
                let pen_down = pipeline.pen_down();
                // Only what the outputs need is read here; the settings stay in place.
                let s = ctl.protocol().machine().settings();
                if changed {
                    publish_output_settings(s);
                }
                let pen_pulse =
                    (s.pen_mode() == PenMode::Servo).then(|| s.pen_servo_pulse_us(pen_down));
                let alarmed = ctl.protocol().machine().alarm().is_some();
                (
                    busy,
                    changed,
                    pen_down,
                    pen_pulse,
                    alarmed,
                    s.invert_inputs(),
                )
            });
        // SAFETY: RTIC's locks use BASEPRI, not NVIC masks; unmasking only undoes the
        // USB task's own back-pressure mask (see `usb_lp`).
        unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::USB_LP_CAN_RX0) };
        rtic::pend(Interrupt::USB_LP_CAN_RX0);
        // A reset from the alarm (soft reset / $X) releases the latched halt, only while
        // the e-stop input is released now: an e-stop pressed after the alarm was read
        // above must not be undone.
        steps::release_halt(|| !alarmed && pins.estop_open() == estop_inverted);
        if settings_changed {
            cx.local.saves.settings = true;
        }
        if let Some(us) = pen_pulse.filter(|_| *cx.local.pen != Some(pen_down)) {
            cx.local.servo.set_pulse_us(us);
            *cx.local.pen = Some(pen_down);
        }
        // Flash writes stall the CPU (instruction fetch waits), so only at rest.
        let saves = &mut *cx.local.saves;
        let store = &mut *cx.local.store;
        cx.shared.core.lock(|c| persist(c.ctl, saves, store, busy));
        // A tick that came while this ran is dropped: the next run starts at the next
        // tick, so the tasks below always get a turn between two runs.
        cortex_m::peripheral::NVIC::unpend(Interrupt::SPI1);
    }

    /// What changed goes to flash, at rest. Out of line: the images it stages (the
    /// settings' 184 bytes, the offsets', a startup line) would otherwise sit in the
    /// protocol task's frame under its deepest path (a setting change reconfiguring
    /// the planner).
    #[inline(never)]
    fn persist(ctl: &mut Controller, saves: &mut Saves, store: &mut Store, busy: bool) {
        saves.coords |= ctl.protocol_mut().machine_mut().take_coords_dirty();
        saves.startup |= ctl.protocol_mut().take_startup_dirty();
        if busy {
            return;
        }
        if core::mem::take(&mut saves.settings)
            && store
                .save_settings(ctl.protocol().machine().settings())
                .is_err()
        {
            defmt::warn!("settings save failed");
        }
        if core::mem::take(&mut saves.coords)
            && store
                .save_coords(ctl.protocol().machine().interp().coords())
                .is_err()
        {
            defmt::warn!("offsets save failed");
        }
        if core::mem::take(&mut saves.startup) {
            for i in 0..STARTUP_LINES {
                let line = ctl.protocol().startup_line(i).unwrap_or("");
                if store.save_startup(i, line).is_err() {
                    defmt::warn!("startup line save failed");
                }
            }
        }
    }

    /// Feed hold / SYNC and cycle start act at once, like `!` and `~`.
    #[task(binds = EXTI4, priority = 4, shared = [core])]
    fn feed_hold(mut cx: feed_hold::Context) {
        if board::exti_take_pending(4) {
            let now = now_ms();
            cx.shared.core.lock(|c| input_edge(c, now, false));
        }
    }

    #[task(binds = EXTI9_5, priority = 4, shared = [core])]
    fn cycle_start(mut cx: cycle_start::Context) {
        if board::exti_take_pending(5) {
            let now = now_ms();
            cx.shared.core.lock(|c| input_edge(c, now, true));
        }
    }

    /// The feed-hold (`cycle_start` false) or cycle-start input's new level into the
    /// machine (one body for both interrupts).
    #[inline(never)]
    fn input_edge(c: &mut Core, now: u32, cycle_start: bool) {
        let (ctl, pipeline) = c.parts();
        let mut i = ctl.protocol().machine().inputs();
        if cycle_start {
            i.cycle_start = board::Inputs::read_cycle_start_low();
        } else {
            i.feed_hold = board::Inputs::read_feed_hold_low();
        }
        ctl.protocol_mut().set_inputs(i, pipeline, now);
    }

    /// The keypad: drive the column the scanner asks for, read its rows one scan
    /// period later (no busy wait for the lines to settle), hand them to the core.
    /// Also plays the buzzer patterns and feeds the watchdog.
    #[task(binds = USART3, priority = 3, shared = [core], local = [keypad, watchdog, indicators, buzzer: Buzzer = Buzzer::new()])]
    fn keypad_scan(mut cx: keypad_scan::Context) {
        // The rows of the column selected one scan period ago.
        let rows = cx.local.keypad.read_rows();
        let now = now_ms();
        let (out, col) = cx.shared.core.lock(|c| {
            let (ctl, pipeline) = c.parts();
            ctl.key_scan(rows, pipeline, now);
            (ctl.take_outputs(), ctl.keypad().column())
        });
        cx.local.keypad.select_column(col);
        let buzzer = cx.local.buzzer;
        cx.local.indicators.set_busy(out.busy_led);
        if let Some(b) = out.beep {
            buzzer.play(b);
        }
        cx.local.indicators.set_buzzer(buzzer.tick(KEYPAD_MS));
        cx.local.watchdog.feed();
    }

    /// The LCD at 10 Hz, lowest priority: take a snapshot of the HMI and the status
    /// under a short lock, draw it into the frame buffer, send only the changed words.
    /// The SPI waits here are the only blocking waits in the firmware; every other
    /// task preempts them.
    #[task(binds = USART2, priority = 1, shared = [core], local = [
        lcd_spi,
        screens,
        fb,
        up: bool = false,
        last_pos: [i32; 3] = [0; 3],
    ])]
    fn lcd_refresh(mut cx: lcd_refresh::Context) {
        let spi = cx.local.lcd_spi;
        if !*cx.local.up {
            // The controller comes up in graphics mode; after that only the changed
            // bytes are sent (core::screens::st7920).
            if board::lcd_init(spi).is_err() {
                defmt::warn!("LCD init failed");
            }
            *cx.local.up = true;
        }
        let (screens, fb) = (&mut **cx.local.screens, &mut **cx.local.fb);
        let last_pos = cx.local.last_pos;
        let now = now_ms();
        // The teaching view's feed directions: which way each axis moved since the
        // last refresh (the step interrupt stays free of bookkeeping for it).
        let snap = cx.shared.core.lock(|c| {
            let (ctl, pipeline) = c.parts();
            let pos = pipeline.side().position();
            if pos != *last_pos {
                let sign = |a: usize| (pos[a] - last_pos[a]).signum() as i8;
                ctl.note_direction([sign(0), sign(1)]);
                *last_pos = pos;
            }
            (ctl.hmi().clone(), ctl.status(pipeline))
        });
        let _ = screens.render(&snap.0, &snap.1, now, fb);
        if st7920::flush(fb, |bytes| spi.write(bytes)).is_err() {
            defmt::warn!("LCD write failed");
        }
    }
}
