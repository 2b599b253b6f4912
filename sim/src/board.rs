//! The virtual board: the firmware's tasks run in virtual time.
//!
//! Owns only scheduling, the way RTIC runs the firmware (src/main.rs): the step-timer
//! interrupt (the core's executor on the same step queue, with the same maximum reload,
//! reversal guard and tail period) fires at the times it asks for; every millisecond
//! tick runs segment preparation and then the protocol tick (the core's
//! [`Controller::service`], with the host's bytes crossing the same byte rings as the
//! USB task's), every 5 ms one keypad column scan of the simulated matrix, every
//! 100 ms the LCD. Settings persist through the core's store on a flash in memory.
//! The e-stop and limit inputs trip the core's halt latch at once, as their interrupts
//! do on the board ([`Board::set_pins`]), and the protocol task releases it by the
//! same rule. Nothing here decides anything about motion, G-code, menus, halts or
//! persistence.

use crate::flash::PAGE_ERASE_NS;
use inkstep_core::controller::{
    Controller, HostLink, HOST_RX_RING, HOST_TX_RING, KEYPAD_SCAN_MS, LCD_REFRESH_MS,
    SERVICE_PERIOD_MS,
};
use inkstep_core::halt::HaltLatch;
use inkstep_core::keypad::{Key, KEYMAP};
use inkstep_core::machine::{MotionControl, PinLevels};
use inkstep_core::motion::StepPos;
use inkstep_core::pipeline::{Pipeline, StepSide, START_LEAD_MS};
use inkstep_core::protocol::RX_BUFFER_SIZE;
use inkstep_core::ring::ByteRing;
use inkstep_core::screens::framebuffer::FrameBuffer;
use inkstep_core::screens::Screens;
use inkstep_core::settings::Settings;
use inkstep_core::settings_store::SettingsStore;
use inkstep_core::stepper::exec::Executor;
use inkstep_core::stepper::output::OutputConfig;
use inkstep_core::stepper::prep::PrepConfig;
use inkstep_core::stepper::queue::StepCmdQueue;
use inkstep_core::stepper::{tail_period, MAX_RELOAD, TIMER_HZ};

use crate::flash::{RamFlash, STORE_RANGE};
use std::rc::Rc;

/// The step timer's clock: the board's.
pub const TICK_HZ: u64 = TIMER_HZ as u64;
/// The CPU time a settings save takes on the board beyond the flash's own stall (the
/// store's search, encoding and verification around the programming), µs. It runs in
/// the protocol task under the core's lock: the tick's count goes on (SysTick is above
/// every lock), the tasks wait for it. The motion after a save starts at the end of
/// the pipeline's resume wait, which covers it on both boards.
const SAVE_CPU_US: u64 = 2_000;

/// The input pins at rest with the board's wiring: switches closed (low), the
/// feed-hold and cycle-start inputs released (high), no Z limit pin.
pub const PINS_AT_REST: PinLevels = PinLevels {
    estop: false,
    limits: [Some(false), Some(false), None],
    feed_hold: true,
    cycle_start: true,
};

/// The LCD task's state: the core's retained screens and frame buffer.
pub struct Lcd {
    pub screens: Screens,
    pub fb: FrameBuffer,
}

/// The executor and its queue: what the step-timer interrupt owns on the board.
pub struct SimSide {
    pub exec: Executor,
    pub queue: StepCmdQueue,
    /// The halt latch, shared with the board's input interrupts and protocol task.
    pub halt: Rc<HaltLatch>,
    /// A start from rest queued its lead ([`StepSide::start_now`]): the motion
    /// begins when the lead ends (the job's time counts from there, as Grbl's from
    /// the stepper's start).
    pub lead_queued: bool,
}

impl StepSide for SimSide {
    type Queue = StepCmdQueue;
    fn sink(&mut self) -> &mut Self::Queue {
        &mut self.queue
    }
    fn position(&self) -> StepPos {
        self.exec.position()
    }
    fn is_running(&self) -> bool {
        self.exec.is_running() || self.queue.queued() > 0
    }
    fn queued(&self) -> usize {
        self.queue.queued()
    }
    fn flush(&mut self) {
        self.exec.halt();
        self.queue.clear();
        self.halt.flushed();
    }
    fn set_position(&mut self, p: StepPos) {
        self.exec.set_position(p);
    }
    fn start_now(&mut self, _now_ms: u32) {
        // The board starts the timer at the end of the tick's tasks (no time passes
        // in them here).
        self.lead_queued = true;
    }
}

/// One step event: virtual time in timer counts, axes stepped, position after it, and
/// whether the servo pen was down (always false with a Z-axis pen).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepEvent {
    pub t: u64,
    pub step: u8,
    pub pos: StepPos,
    pub servo_down: bool,
}

pub struct Board {
    pub ctl: Controller,
    pub pipeline: Pipeline<SimSide>,
    /// The settings store on the virtual flash.
    pub store: SettingsStore<RamFlash>,
    /// Host -> board and board -> host bytes (the USB task's rings).
    host_rx: ByteRing<HOST_RX_RING>,
    host_tx: ByteRing<HOST_TX_RING>,
    /// The input pins' levels (change them through [`Board::set_pins`]).
    pins: PinLevels,
    /// The halt latch (the pipeline's side holds the same).
    halt: Rc<HaltLatch>,
    /// The host has the port open (CDC's DTR).
    port_open: bool,
    /// The step outputs' configuration, as the step interrupt applies it.
    outputs: OutputConfig,
    /// The pen servo's pulse width, as the protocol tick last set it.
    pub servo_pulse_us: Option<u32>,
    now: u64,
    /// Milliseconds since boot: the tick count.
    ms: u32,
    next_irq: Option<u64>,
    /// When the step timer first started (the trace's time origin).
    pub first_motion: Option<u64>,
    /// Keys held on the simulated matrix.
    pub held: Vec<Key>,
    /// The LCD, when the session shows it (off for plain G-code runs).
    pub lcd: Option<Lcd>,
    /// The flash's stall counter (ns), and how far it had got at the last look.
    flash_busy: std::rc::Rc<std::cell::Cell<u64>>,
    flash_busy_seen: u64,
    /// The flash's page erases, and how many had been seen at the last look.
    flash_erases: std::rc::Rc<std::cell::Cell<u64>>,
    flash_erases_seen: u64,
    /// The CPU stalls on flash programming until this tick (a settings save).
    stall_until: u64,
    /// The tasks wait for a save's CPU work until this tick (the tick count goes on).
    tasks_from: u64,
    /// Ticks the millisecond grid runs ahead of the tick count: SysTick interrupts
    /// lost while the CPU stalled on the flash (one pending tick is taken when the
    /// stall ends, the others are lost, as on the chip and in the emulator).
    lag: u64,
}

impl Board {
    /// A board whose flash holds `settings` (and nothing else), just powered up.
    pub fn new(settings: Settings) -> Board {
        let mut store = SettingsStore::new(RamFlash::default(), STORE_RANGE).expect("store range");
        // A fresh flash with these settings: the firmware saves them the same way.
        if settings != Settings::default() {
            store
                .save_settings(&settings)
                .expect("settings into a fresh flash");
        }
        Board::boot(store)
    }

    /// Power-up from `store`, as the firmware's init does.
    pub fn boot(store: SettingsStore<RamFlash>) -> Board {
        // The store again over the same flash, to keep a handle on its stall counter.
        let flash = store.into_flash();
        let flash_busy = flash.busy_ns.clone();
        let flash_erases = flash.erases.clone();
        let mut store = SettingsStore::new(flash, STORE_RANGE).expect("store range");
        let ctl = inkstep_core::in_place::build(|slot| Controller::boot_in(slot, &mut store, 0));
        let settings = ctl.protocol().machine().settings();
        let halt = Rc::new(HaltLatch::new());
        let side = SimSide {
            exec: Executor::new([0; 3], MAX_RELOAD),
            queue: StepCmdQueue::new(),
            halt: halt.clone(),
            lead_queued: false,
        };
        let prep = PrepConfig {
            timer_hz: TIMER_HZ,
            ..PrepConfig::default()
        };
        let pipeline = Pipeline::new(settings, prep, side);
        let outputs = OutputConfig::from(settings);
        halt.arm_hard_limits(outputs.hard_limit_axes);
        Board {
            ctl,
            pipeline,
            store,
            host_rx: ByteRing::new(),
            host_tx: ByteRing::new(),
            pins: PINS_AT_REST,
            halt,
            port_open: true,
            outputs,
            servo_pulse_us: None,
            now: 0,
            ms: 0,
            next_irq: None,
            first_motion: None,
            held: Vec::new(),
            lcd: None,
            flash_busy_seen: flash_busy.get(),
            flash_busy,
            flash_erases_seen: flash_erases.get(),
            flash_erases,
            stall_until: 0,
            tasks_from: 0,
            lag: 0,
        }
    }

    /// Turns the LCD task on.
    pub fn with_lcd(mut self) -> Board {
        self.lcd = Some(Lcd {
            screens: Screens::new(),
            fb: FrameBuffer::new(),
        });
        self
    }

    /// The host opens or closes the serial port (DTR on the board; `cargo sim serve`
    /// follows the pty's clients). A board starts with the port open, as a run
    /// without a pty has a host listening all along.
    pub fn set_port_open(&mut self, open: bool) {
        self.port_open = open;
    }

    /// Redraws the LCD now (as its task would), so the frame buffer is current.
    pub fn refresh_lcd(&mut self) {
        let now = self.now_ms();
        let st = self.ctl.refresh_view(&self.pipeline);
        if let Some(l) = self.lcd.as_mut() {
            // Drawing into the frame buffer cannot fail (it is plain memory).
            let _ = l.screens.render(self.ctl.hmi(), &st, now, &mut l.fb);
        }
    }

    pub fn now(&self) -> u64 {
        self.now
    }
    pub fn now_ms(&self) -> u32 {
        (self.now * 1000 / TICK_HZ) as u32
    }
    pub fn ms_to_ticks(ms: u64) -> u64 {
        ms * TICK_HZ / 1000
    }

    /// USB bytes from the host; returns how many the board took (the rest are NAKed:
    /// the host offers them again).
    pub fn usb_write(&mut self, bytes: &[u8]) -> usize {
        self.host_rx.split().0.push(bytes)
    }

    /// USB bytes to the host: what the board has sent so far.
    pub fn usb_read(&mut self) -> Vec<u8> {
        let mut out = Vec::new();
        let mut buf = [0u8; HOST_TX_RING];
        let (_, mut rx) = self.host_tx.split();
        loop {
            let n = rx.pop_into(&mut buf);
            if n == 0 {
                return out;
            }
            out.extend_from_slice(&buf[..n]);
        }
    }

    /// The input pins' levels.
    pub fn pins(&self) -> PinLevels {
        self.pins
    }

    /// New levels of the input pins, as their interrupts see them on the board: an
    /// e-stop edge, or a limit switch's on an axis with hard limits armed, trips the
    /// halt latch and stops the step output at once; every change wakes the protocol
    /// task (the feed-hold and cycle-start inputs also reach the machine at once).
    pub fn set_pins(&mut self, pins: PinLevels) {
        let was = core::mem::replace(&mut self.pins, pins);
        let mut halted = false;
        if pins.estop != was.estop {
            self.halt.trip_estop();
            halted = true;
        }
        for axis in 0..2 {
            if pins.limits[axis] != was.limits[axis] {
                halted |= self.halt.trip_limit(axis);
            }
        }
        if halted {
            // The firmware stops the timer and halts the executor in the interrupt.
            self.pipeline.side_mut().exec.halt();
            self.next_irq = None;
        }
        if pins.feed_hold != was.feed_hold || pins.cycle_start != was.cycle_start {
            let now = self.ms;
            self.ctl.set_pins(pins, &mut self.pipeline, now);
        }
        if pins != was {
            self.run_protocol();
        }
    }

    /// The step output is halted (the halt latch is set).
    pub fn is_halted(&self) -> bool {
        self.halt.is_halted()
    }

    /// Nothing moving, nothing queued, every byte from the host taken and framed.
    pub fn is_idle(&self) -> bool {
        self.next_irq.is_none()
            && self.pipeline.is_idle()
            && self.host_rx.is_empty()
            && self.ctl.protocol().rx_free() == RX_BUFFER_SIZE
    }

    /// Starts the step timer if it is stopped and commands wait (the preparation
    /// task's kick and the interrupt's pend in the firmware).
    fn kick(&mut self) {
        if self.next_irq.is_some() || self.pipeline.side().queued() == 0 || self.halt.is_halted() {
            return;
        }
        let side = self.pipeline.side_mut();
        side.exec.set_turn_guard(self.outputs.turn_guard_ticks());
        let lead = std::mem::take(&mut side.lead_queued);
        if let Some(o) = side.exec.start(&mut side.queue) {
            let lead_ticks = if lead {
                Self::ms_to_ticks(u64::from(START_LEAD_MS))
            } else {
                0
            };
            self.first_motion.get_or_insert(self.now + lead_ticks);
            self.next_irq = Some(self.now + u64::from(o.reload));
        }
    }

    /// The step-timer interrupt.
    fn step_interrupt(&mut self, t: u64, on_step: &mut impl FnMut(StepEvent)) {
        let side = self.pipeline.side_mut();
        let o = side.exec.on_interrupt(&mut side.queue);
        if o.step != 0 {
            let pos = side.exec.position();
            on_step(StepEvent {
                t,
                step: o.step,
                pos,
                servo_down: self.pipeline.pen_down(),
            });
        }
        self.next_irq = if o.reload != 0 {
            Some(t + u64::from(o.reload))
        } else if o.step != 0 {
            // The queue ran empty: one more short period so that the last pulse ends.
            Some(t + u64::from(tail_period(self.outputs.pulse_ticks)))
        } else {
            None
        };
    }

    /// The millisecond tick's tasks, in the firmware's priority order: segment
    /// preparation, the protocol tick, a keypad column every 5 ms, the LCD every
    /// 100 ms.
    fn tick(&mut self) {
        let now = self.ms;
        self.pipeline.fill_at(self.ms);
        self.kick();
        // As the firmware's protocol task: one line a call, called again while
        // another may run (the firmware stops at the next tick; here it costs no time).
        self.run_protocol();
        if now.is_multiple_of(KEYPAD_SCAN_MS) {
            self.scan();
        }
        if now.is_multiple_of(LCD_REFRESH_MS) && self.lcd.is_some() {
            self.refresh_lcd();
        }
    }

    /// Bytes arrived: the protocol task runs now, not at the next tick, as the
    /// firmware's USB task wakes it (a real-time byte such as `!` acts at once).
    pub fn wake_protocol(&mut self) {
        if self.now < self.tasks_from {
            // A save's CPU work holds the task: it runs at the tick after it.
            return;
        }
        self.run_protocol();
    }

    /// The protocol task: the controller's service, one line a call, until it has
    /// no more to do now.
    fn run_protocol(&mut self) {
        let now = self.ms;
        loop {
            // The firmware's task reads the pins again for the release (no time
            // passes here).
            let pins_now = self.pins;
            let (_, mut rx) = self.host_rx.split();
            let (mut tx, _) = self.host_tx.split();
            let host = HostLink {
                rx: &mut rx,
                tx: &mut tx,
                port_open: self.port_open,
            };
            let done = self.ctl.service(
                host,
                self.pins,
                &self.halt,
                &mut self.store,
                &mut self.pipeline,
                now,
            );
            if let Some(cfg) = done.outputs {
                self.outputs = cfg;
                self.halt.arm_hard_limits(cfg.hard_limit_axes);
            }
            if let Some(us) = done.servo_pulse_us {
                self.servo_pulse_us = Some(us);
            }
            self.halt.release(done.allows_release(pins_now));
            if !done.again(now, now) {
                break;
            }
        }
    }

    fn scan(&mut self) {
        let col = self.ctl.keypad().column();
        let mut rows = 0u8;
        for (r, row) in KEYMAP.iter().enumerate() {
            if self.held.contains(&row[col]) {
                rows |= 1 << r;
            }
        }
        let now = self.now_ms();
        self.ctl.key_scan(rows, &mut self.pipeline, now);
        // The keypad task takes the beep and the busy LED; the simulator has no
        // buzzer to play them on.
        let _ = self.ctl.take_outputs();
    }

    /// The time of the next millisecond tick: on the millisecond grid, or when a
    /// flash stall ends if the grid's tick fell inside it.
    fn next_event(&self) -> u64 {
        let grid = Self::ms_to_ticks(u64::from(self.ms) + u64::from(SERVICE_PERIOD_MS)) + self.lag;
        grid.max(self.stall_until)
    }

    /// After a tick: what a settings save in it cost. The CPU stalls on the flash
    /// while it is programmed or erased (it fetches its code from there). A
    /// half-word's programming (52.5 µs) only delays the tick's interrupt; a page
    /// erase (20 ms) stalls it past many: the SysTick interrupts that fall in it
    /// collapse into one taken when it ends, and the grid goes on after it (as on the
    /// chip and in the emulator). Then the programming and the save's own CPU work
    /// ([`SAVE_CPU_US`]) hold the tasks, not the tick count (settings saves run at
    /// rest, so no step is due).
    fn flash_stall(&mut self, tick_at: u64) {
        let busy = self.flash_busy.get();
        let d_ns = busy - self.flash_busy_seen;
        self.flash_busy_seen = busy;
        let erases = self.flash_erases.get() - self.flash_erases_seen;
        self.flash_erases_seen = self.flash_erases.get();
        if d_ns == 0 {
            return;
        }
        let to_ticks = |ns: u64| (u128::from(ns) * u128::from(TICK_HZ) / 1_000_000_000) as u64;
        let erase_ns = erases * PAGE_ERASE_NS;
        let from = self.now.max(tick_at);
        self.stall_until = from + to_ticks(erase_ns);
        if erases > 0 {
            // One tick taken at the end of each erase: those before the last are
            // counted here (their tasks wait for the save), the last by the run.
            self.ms += (erases - 1) as u32 * SERVICE_PERIOD_MS;
            let period = Self::ms_to_ticks(u64::from(SERVICE_PERIOD_MS));
            let grid =
                Self::ms_to_ticks(u64::from(self.ms) + u64::from(SERVICE_PERIOD_MS)) + self.lag;
            if grid < self.stall_until {
                // The first grid tick after the stall's end follows the one taken at it.
                let next = grid + period * ((self.stall_until - grid) / period + 1);
                let lost = (next - grid) / period - 1;
                self.lag += lost * period;
            }
        }
        self.tasks_from = self.stall_until + to_ticks(d_ns - erase_ns + SAVE_CPU_US * 1000);
    }

    /// Runs virtual time up to `until` ticks, calling `on_step` for every step.
    pub fn run_until(&mut self, until: u64, on_step: &mut impl FnMut(StepEvent)) {
        self.run(until, false, on_step);
    }

    /// As [`Board::run_until`], but returns at the first step event's interrupt if
    /// one comes before `until` (a real-time byte timed from a step goes out at that
    /// step's time plus its offset, however long the wait before the step).
    pub fn run_until_a_step(&mut self, until: u64, on_step: &mut impl FnMut(StepEvent)) {
        self.run(until, true, on_step);
    }

    fn run(&mut self, until: u64, stop_at_step: bool, on_step: &mut impl FnMut(StepEvent)) {
        loop {
            let tick = self.next_event();
            let t = self.next_irq.map_or(tick, |irq| irq.min(tick));
            if t > until {
                self.now = until;
                return;
            }
            self.now = t;
            // The step interrupt preempts the tasks the tick starts at the same time.
            let mut stepped = false;
            if self.next_irq == Some(t) {
                self.step_interrupt(t, &mut |e| {
                    stepped = true;
                    on_step(e)
                });
            }
            if t == tick {
                self.ms += SERVICE_PERIOD_MS;
                if t >= self.tasks_from {
                    self.tick();
                    self.flash_stall(t);
                }
            }
            if stepped && stop_at_step {
                return;
            }
        }
    }

    /// Runs until the machine is idle (or `limit` ticks from now have passed).
    pub fn run_to_idle(&mut self, limit: u64, on_step: &mut impl FnMut(StepEvent)) -> bool {
        let end = self.now + limit;
        let step = Self::ms_to_ticks(10);
        while self.now < end {
            if self.is_idle() {
                return true;
            }
            let until = (self.now + step).min(end);
            self.run_until(until, on_step);
        }
        self.is_idle()
    }
}
