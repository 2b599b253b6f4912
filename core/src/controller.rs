//! The controller: the glue the firmware's tasks and the simulator share, so that
//! neither carries its own copy of it.
//!
//! It ties the Grbl [`Protocol`] (and through it the [`Machine`](crate::machine::Machine))
//! to the keypad scanner and the standalone [`Hmi`], all driving one planner through
//! the [`MotionControl`] trait. Its methods are the entry points of the firmware's
//! tasks: bytes from USB ([`Controller::usb_rx`]), bytes to USB ([`Controller::usb_tx`]),
//! one keypad column scan ([`Controller::key_scan`]), and the periodic background work
//! ([`Controller::poll`]). The HMI's [`Action`]s are carried out here, in order, through
//! the machine state so that keypad motion obeys the same rules as G-code.
//!
//! Owned by the simulator's issue; kept small on purpose: no decision of the protocol,
//! the planner or the HMI is made here, only their wiring.

use crate::decimal::{put_int, Sink};
use crate::hmi::{self, Action, Beep, Hmi, MachineState};
use crate::keypad::{KeyEvent, Keypad, KeypadConfig};
use crate::machine::{MotionControl, RunState};
use crate::motion::Command;
use crate::motion::{X, Y, Z};
use crate::protocol::Protocol;
use crate::settings::Settings;
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use heapless::Vec;

/// Jog moves run this far (mm) unless stopped; key release stops them.
const JOG_REACH_MM: i32 = 1000;

/// Outputs of the controller that the firmware drives (buzzer, busy LED).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    pub busy_led: bool,
    /// The latest beep to play, taken by the buzzer task.
    pub beep: Option<Beep>,
}

pub struct Controller {
    protocol: Protocol,
    keypad: Keypad,
    hmi: Hmi,
    outputs: Outputs,
    /// Latest step direction on X and Y (-1, 0, +1), for the teaching view.
    dir: [i8; 2],
}

/// The HMI's view of the machine's configuration, from the settings.
pub fn hmi_config(s: &Settings) -> hmi::Config {
    hmi::Config {
        steps_per_mm: [s.steps_per_mm(X), s.steps_per_mm(Y), s.steps_per_mm(Z)],
        pen_up_mm: s.pen_z_up(),
        pen_down_mm: s.pen_z_down(),
        ..hmi::Config::default()
    }
}

impl Controller {
    pub fn new(settings: Settings, now_ms: u32) -> Controller {
        crate::in_place::build(|slot| Controller::init_in(slot, &settings, now_ms))
    }

    /// [`Controller::new`] built in `slot`, the firmware's static cell: field by field,
    /// so that no whole controller (2 KB), protocol or machine is built on init's stack
    /// and copied.
    #[allow(unsafe_code)]
    pub fn init_in<'a>(
        slot: &'a mut MaybeUninit<Controller>,
        settings: &Settings,
        now_ms: u32,
    ) -> &'a mut Controller {
        // Lists every field (no `..`): a new field fails to compile here until it is
        // written below too.
        const _: fn(&Controller) = |Controller {
                                        protocol: _,
                                        keypad: _,
                                        hmi: _,
                                        outputs: _,
                                        dir: _,
                                    }| {};
        let p = slot.as_mut_ptr();
        // SAFETY: `p` points to `slot`, valid for writes and properly aligned; each field
        // is written once through a raw field pointer (the protocol through its own
        // `init_in`, on its field viewed as `MaybeUninit`, which has the same layout)
        // and the list below names every field, so the controller is initialised when
        // `assume_init_mut` runs.
        unsafe {
            Protocol::init_in(
                &mut *addr_of_mut!((*p).protocol).cast::<MaybeUninit<Protocol>>(),
                settings,
            );
            addr_of_mut!((*p).keypad).write(Keypad::new(KeypadConfig::default()));
            addr_of_mut!((*p).hmi).write(Hmi::new(hmi_config(settings), now_ms));
            addr_of_mut!((*p).outputs).write(Outputs::default());
            addr_of_mut!((*p).dir).write([0, 0]);
            slot.assume_init_mut()
        }
    }

    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }
    pub fn protocol_mut(&mut self) -> &mut Protocol {
        &mut self.protocol
    }
    pub fn hmi(&self) -> &Hmi {
        &self.hmi
    }
    pub fn keypad(&self) -> &Keypad {
        &self.keypad
    }

    /// Takes the outputs: the beep is handed out once.
    pub fn take_outputs(&mut self) -> Outputs {
        let o = self.outputs;
        self.outputs.beep = None;
        o
    }

    /// The settings changed (the caller saw `take_settings_dirty`): the HMI takes the
    /// new steps/mm and pen heights, keeping the draw speed the user chose.
    pub fn settings_changed(&mut self) {
        let cfg = hmi::Config {
            draw_feed_mm_min: self.hmi.draw_feed(),
            ..hmi_config(self.protocol.machine().settings())
        };
        self.hmi.set_config(cfg);
    }

    /// Records the direction of the latest step (the step engine's direction bits).
    pub fn note_direction(&mut self, dir: [i8; 2]) {
        self.dir = dir;
    }

    /// USB bytes in; returns how many were taken (the rest stay in the endpoint).
    pub fn usb_rx<M: MotionControl>(&mut self, bytes: &[u8], m: &mut M, now_ms: u32) -> usize {
        self.protocol.receive(bytes, m, now_ms)
    }

    /// USB bytes out.
    pub fn usb_tx(&mut self, buf: &mut [u8]) -> usize {
        self.protocol.read_output(buf)
    }

    /// The machine as the HMI sees it.
    pub fn status<M: MotionControl>(&self, m: &M) -> hmi::Status {
        let state = match self.protocol.machine().state(m) {
            RunState::Idle | RunState::Check => MachineState::Idle,
            RunState::Run => MachineState::Run,
            RunState::Hold { .. } | RunState::Door { .. } => MachineState::Hold,
            RunState::Jog => MachineState::Jog,
            RunState::Home => MachineState::Homing,
            RunState::Alarm => {
                MachineState::Alarm(self.protocol.machine().alarm().map_or(0, |a| a.code()))
            }
        };
        hmi::Status {
            state,
            pos: m.position(),
            feed_mm_min: m.speed(),
            queue_empty: m.queued() == 0,
            dir: self.dir,
        }
    }

    /// One keypad column scan: `rows` read while [`Keypad::column`] was driven.
    pub fn key_scan<M: MotionControl>(&mut self, rows: u8, m: &mut M, now_ms: u32) {
        let events = self.keypad.feed(rows, now_ms);
        for ev in events {
            self.key_event(ev, m, now_ms);
        }
    }

    /// One key event through the HMI. Out of line, so that the HMI's working state and
    /// its actions live in this frame only while a key is handled, not in the caller's
    /// (the firmware's keypad task) beside everything else inlined there.
    #[inline(never)]
    fn key_event<M: MotionControl>(&mut self, ev: KeyEvent, m: &mut M, now_ms: u32) {
        let st = self.status(m);
        let actions = self.key_actions(ev, &st, now_ms);
        self.apply(&actions, m, now_ms);
    }

    /// The HMI's handling of one key alone, out of line like `tick_actions`: its
    /// working state is gone before the actions are applied.
    #[inline(never)]
    fn key_actions(&mut self, ev: KeyEvent, st: &hmi::Status, now_ms: u32) -> hmi::Actions {
        self.hmi.key(ev, st, now_ms)
    }

    /// Background work: the protocol's lines and messages, the HMI's timers, the
    /// completion of a keypad abort, the busy LED.
    pub fn poll<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) {
        self.protocol.poll(m, now_ms);
        self.hmi_tick(m, now_ms);
    }

    /// The HMI's timers. Out of line, so that its actions (a 440-byte list) are not
    /// part of the caller's frame (the firmware's protocol task) while the protocol
    /// runs, and the protocol's locals are gone while the actions are applied.
    #[inline(never)]
    fn hmi_tick<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) {
        let st = self.status(m);
        let actions = self.tick_actions(&st, now_ms);
        self.apply(&actions, m, now_ms);
    }

    /// The HMI's timer step alone, out of line too: its working state is gone before
    /// the actions are applied (through the machine and the planner, the deeper
    /// path).
    #[inline(never)]
    fn tick_actions(&mut self, st: &hmi::Status, now_ms: u32) -> hmi::Actions {
        self.hmi.tick(st, now_ms)
    }

    fn apply<M: MotionControl>(&mut self, actions: &[Action], m: &mut M, now_ms: u32) {
        for a in actions {
            self.apply_one(a, m, now_ms);
        }
    }

    fn apply_one<M: MotionControl>(&mut self, a: &Action, m: &mut M, now_ms: u32) {
        let machine = self.protocol.machine_mut();
        // A refused action is shown as an error beep.
        let refused = match *a {
            // Through the machine state: the same locks and soft limits as G-code, and
            // the interpreter continues from the move's end. The HMI only starts a job
            // that fits the queue.
            Action::Queue(mv) => machine.queue(Command::Move(mv), m, now_ms).is_err(),
            Action::JogStart { dir, feed_mm_min } => {
                // Whole numbers only, through the protocol's number writer.
                let mut body: Vec<u8, 64> = Vec::new();
                body.put(b"G91G21");
                for (d, name) in [(dir[X], b"X"), (dir[Y], b"Y")] {
                    if d != 0 {
                        body.put(name);
                        put_int(&mut body, i32::from(d) * JOG_REACH_MM);
                    }
                }
                body.put(b"F");
                put_int(&mut body, crate::fmath::round(feed_mm_min) as i32);
                machine.jog(&body, m).is_err()
            }
            Action::JogStop => {
                machine.jog_cancel(m);
                false
            }
            Action::FeedHold => {
                machine.feed_hold(m);
                false
            }
            Action::Resume => {
                machine.cycle_start(m);
                false
            }
            Action::Abort => {
                machine.stop_and_clear(m);
                false
            }
            Action::Home => machine.start_homing(m).is_err(),
            Action::SetOrigin => {
                machine.zero_xy_here(m);
                false
            }
            Action::Unlock => {
                let _ = machine.unlock();
                false
            }
            Action::Beep(b) => {
                self.outputs.beep = Some(b);
                false
            }
            Action::BusyLed(on) => {
                self.outputs.busy_led = on;
                false
            }
        };
        if refused {
            self.outputs.beep = Some(Beep::Error);
        }
    }
}
