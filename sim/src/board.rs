//! The virtual board: the firmware's tasks run in virtual time.
//!
//! Owns only scheduling, the way RTIC runs the firmware: the step-timer interrupt
//! (the core's executor) fires at the times it asks for, and between interrupts the
//! lower-priority work runs to completion: USB bytes into the protocol, the protocol's
//! lines, the HMI's timers, segment preparation (the core's [`Controller`] and [`Pipeline`]),
//! and every 5 ms one keypad column scan of the simulated matrix. Nothing here decides
//! anything about motion, G-code or menus.

use heapless::spsc::Queue;
use inkstep_core::controller::Controller;
use inkstep_core::keypad::{Key, KEYMAP};
use inkstep_core::motion::StepPos;
use inkstep_core::pipeline::{Pipeline, StepSide};
use inkstep_core::screens::framebuffer::FrameBuffer;
use inkstep_core::screens::Screens;
use inkstep_core::settings::Settings;
use inkstep_core::stepper::drive::STEP_QUEUE;
use inkstep_core::stepper::exec::Executor;
use inkstep_core::stepper::prep::PrepConfig;
use inkstep_core::stepper::StepCmd;

/// The step timer's clock (the firmware's timer runs at the 72 MHz core clock).
pub const TICK_HZ: u64 = 72_000_000;
/// Keypad scan period: one column per tick.
pub const SCAN_MS: u64 = 5;
/// Longest stretch of virtual time without running the background tasks.
const POLL_MS: u64 = 1;
/// LCD refresh period (the firmware's lowest-priority task).
pub const LCD_MS: u64 = 100;

/// The LCD task's state: the core's retained screens and frame buffer.
pub struct Lcd {
    pub screens: Screens,
    pub fb: FrameBuffer,
    next: u64,
}

/// The executor and its queue: what the step-timer interrupt owns on the board.
pub struct SimSide {
    pub exec: Executor,
    pub queue: Queue<StepCmd, STEP_QUEUE>,
}

impl StepSide for SimSide {
    type Sink = Queue<StepCmd, STEP_QUEUE>;
    fn sink(&mut self) -> &mut Self::Sink {
        &mut self.queue
    }
    fn position(&self) -> StepPos {
        self.exec.position()
    }
    fn is_running(&self) -> bool {
        self.exec.is_running() || !self.queue.is_empty()
    }
    fn queued(&self) -> usize {
        self.queue.len()
    }
    fn flush(&mut self) {
        self.exec.halt();
        while self.queue.dequeue().is_some() {}
        self.exec.reset();
    }
    fn set_position(&mut self, p: StepPos) {
        self.exec.set_position(p);
    }
}

/// One step event: virtual time in timer ticks, axes stepped, position after it, and
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
    now: u64,
    next_irq: Option<u64>,
    next_scan: u64,
    /// When the step timer first started (the trace's time origin).
    pub first_motion: Option<u64>,
    /// Keys held on the simulated matrix.
    pub held: Vec<Key>,
    dir: [i8; 2],
    /// The LCD, when the session shows it (off for plain G-code runs).
    pub lcd: Option<Lcd>,
}

impl Board {
    pub fn new(settings: Settings) -> Board {
        let side = SimSide {
            exec: Executor::new([0; 3], 0xFFFF),
            queue: Queue::new(),
        };
        let prep = PrepConfig {
            timer_hz: TICK_HZ as u32,
            ..PrepConfig::default()
        };
        let pipeline = Pipeline::new(&settings, prep, side);
        Board {
            ctl: Controller::new(settings, 0),
            pipeline,
            now: 0,
            next_irq: None,
            next_scan: 0,
            first_motion: None,
            held: Vec::new(),
            dir: [0, 0],
            lcd: None,
        }
    }

    /// Turns the LCD task on.
    pub fn with_lcd(mut self) -> Board {
        self.lcd = Some(Lcd {
            screens: Screens::new(),
            fb: FrameBuffer::new(),
            next: 0,
        });
        self
    }

    /// Redraws the LCD now (as its task would), so the frame buffer is current.
    pub fn refresh_lcd(&mut self) {
        let now = self.now_ms();
        let st = self.ctl.status(&self.pipeline);
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

    /// USB bytes from the host; returns how many the board took.
    pub fn usb_write(&mut self, bytes: &[u8]) -> usize {
        let now = self.now_ms();
        let n = self.ctl.usb_rx(bytes, &mut self.pipeline, now);
        self.background();
        n
    }

    /// USB bytes to the host.
    pub fn usb_read(&mut self) -> Vec<u8> {
        let mut out = Vec::new();
        let mut buf = [0u8; 256];
        loop {
            let n = self.ctl.usb_tx(&mut buf);
            if n == 0 {
                self.background();
                let n = self.ctl.usb_tx(&mut buf);
                if n == 0 {
                    return out;
                }
                out.extend_from_slice(&buf[..n]);
                continue;
            }
            out.extend_from_slice(&buf[..n]);
        }
    }

    /// Nothing moving, nothing queued.
    pub fn is_idle(&self) -> bool {
        use inkstep_core::machine::MotionControl;
        self.next_irq.is_none() && self.pipeline.is_idle()
    }

    /// The lower-priority tasks, run to completion: protocol and HMI, settings
    /// changes, segment preparation, and starting the step timer when it is idle.
    fn background(&mut self) {
        let now = self.now_ms();
        self.ctl.poll(&mut self.pipeline, now);
        // The planner took the new settings when they changed (MotionControl::configure).
        if self.ctl.protocol_mut().machine_mut().take_settings_dirty() {
            self.ctl.settings_changed();
        }
        self.pipeline.fill();
        if self.next_irq.is_none() {
            let side = self.pipeline.side_mut();
            if let Some(o) = side.exec.start(&mut side.queue) {
                self.first_motion.get_or_insert(self.now);
                self.next_irq = Some(self.now + u64::from(o.reload.max(1)));
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
    }

    /// Runs virtual time up to `until` ticks, calling `on_step` for every step.
    pub fn run_until(&mut self, until: u64, on_step: &mut impl FnMut(StepEvent)) {
        let poll_ticks = Self::ms_to_ticks(POLL_MS);
        let scan_ticks = Self::ms_to_ticks(SCAN_MS);
        loop {
            self.background();
            let next_poll = self.now + poll_ticks;
            let next_lcd = self.lcd.as_ref().map(|l| l.next);
            let t = [
                self.next_irq,
                Some(self.next_scan),
                Some(next_poll),
                next_lcd,
            ]
            .into_iter()
            .flatten()
            .min()
            .unwrap_or(next_poll);
            if t > until {
                self.now = until;
                return;
            }
            self.now = t;
            if self.next_irq == Some(t) {
                let side = self.pipeline.side_mut();
                let o = side.exec.on_interrupt(&mut side.queue);
                if o.step != 0 {
                    let pos = side.exec.position();
                    let servo_down = self.pipeline.pen_down();
                    on_step(StepEvent {
                        t,
                        step: o.step,
                        pos,
                        servo_down,
                    });
                    for (a, d) in self.dir.iter_mut().enumerate() {
                        if o.step & (1 << a) != 0 {
                            *d = if o.dir & (1 << a) != 0 { -1 } else { 1 };
                        }
                    }
                    self.ctl.note_direction(self.dir);
                }
                self.next_irq = if o.reload == 0 {
                    None
                } else {
                    Some(t + u64::from(o.reload))
                };
            }
            if self.next_scan == t {
                self.scan();
                self.next_scan = t + scan_ticks;
            }
            if next_lcd == Some(t) {
                self.refresh_lcd();
                if let Some(l) = self.lcd.as_mut() {
                    l.next = t + Self::ms_to_ticks(LCD_MS);
                }
            }
        }
    }

    /// Runs until the machine is idle (or `limit` ticks from now have passed).
    pub fn run_to_idle(&mut self, limit: u64, on_step: &mut impl FnMut(StepEvent)) -> bool {
        let end = self.now + limit;
        let step = Self::ms_to_ticks(10);
        while self.now < end {
            self.background();
            if self.is_idle() {
                return true;
            }
            let until = (self.now + step).min(end);
            self.run_until(until, on_step);
        }
        self.is_idle()
    }
}
