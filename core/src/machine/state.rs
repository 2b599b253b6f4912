//! The machine state: what the machine is doing (idle, running, holding, jogging,
//! homing, alarm, check mode), the safety rules around it, and the execution of
//! G-code, jog and `$` actions against the planner.
//!
//! It owns the settings and the G-code interpreter so that every path into motion
//! (protocol, keypad modes) goes through the same checks. It never formats text:
//! it reports through a small queue of [`Event`]s that the protocol prints.
//! Time comes in as milliseconds from the caller (`now_ms`), so tests run in virtual time.

use super::homing::{Homing, HomingError, Progress};
use super::safety::{Alarm, Inputs};
use super::MotionControl;
use crate::gcode::interpreter::Jog;
use crate::gcode::units::{to_mm, to_nm};
use crate::gcode::{ErrorCode, Interpreter, Outcome, Reject, Stop};
use crate::motion::Command;
use crate::motion::{Move, AXES};
use crate::pending::Work;
use crate::settings::{PenMode, Settings};
use core::mem::MaybeUninit;
use heapless::Deque;

mod lines;

pub use super::tell::{Event, Message, Prompt, RunState, MESSAGE_LEN};

/// A line the machine took, and when its `ok` may go out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Taken {
    /// Answer it now.
    Now,
    /// Answer once the queue has run empty: a G4's `ok` comes after its dwell, as in
    /// Grbl, so that senders can wait for the motion before it with `G4 P0.01`.
    WhenIdle,
}

/// A pen change (M6) under way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PenChange {
    tool: u8,
    /// Commands of the line still to queue from this index, once at rest.
    split: u8,
    /// At rest, waiting for cycle start (the rest is queued).
    waiting: bool,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct JobRecord {
    running: bool,
    start_ms: u32,
    moves: u32,
    /// M2/M30 seen: finish when the queue has run empty.
    ending: bool,
}

/// The machine.
pub struct Machine {
    settings: Settings,
    interpreter: Interpreter,
    /// In the alarm state (G-code locked out until `$X`, `$H` or a cleared alarm).
    locked: bool,
    /// The alarm that caused the lock, if any (the power-up lock has none).
    alarm: Option<Alarm>,
    /// A critical alarm happened and no soft reset since.
    needs_reset: bool,
    check_mode: bool,
    /// `$SLP` ran: motors released, everything refused until a soft reset.
    sleeping: bool,
    /// The board refuses to run at all (the chip is not the one the image needs):
    /// why, said with the welcome and to every command that would unlock. Nothing
    /// clears it.
    refusal: Option<&'static str>,
    jogging: bool,
    jog_cancel: bool,
    homing: Option<Homing>,
    homed: bool,
    /// Safety door requested (0x84), until cycle start.
    door: bool,
    /// The hold came from the feed-hold pin and ends when it is released.
    hold_by_pin: bool,
    /// M0 ran: held at rest until cycle start (the lines after it queue meanwhile).
    paused: bool,
    /// An M6 pen change under way: `split` of the line's commands (the lift, the way
    /// to the pen-change place) run first; once at rest it pauses like M0 and queues
    /// the rest (back, drop). Lines wait until then (they come after the way back).
    pen_change: Option<PenChange>,
    /// The last `(MSG, ...)` text, for the LCD's prompts.
    message: Message,
    /// `message` is new: the LCD shows it once.
    message_new: bool,
    /// Soft-limit alarm: bring motion to rest, then drop the queue.
    stop_then_clear: bool,
    feed_ovr: u8,
    rapid_ovr: u8,
    ovr_changed: bool,
    inputs: Inputs,
    job: JobRecord,
    events: Deque<Event, 8>,
    settings_dirty: bool,
    coords_dirty: bool,
    /// The outcome of the last line interpreted (kept here, not on the stack of
    /// [`Machine::execute`], so that it can wait without a copy).
    outcome: Outcome,
    /// `outcome`'s commands wait for planner room: the line being taken is
    /// interpreted already (see [`Machine::execute`]).
    waiting: bool,
    /// The line being taken is a sync point that waits for the machine to come to
    /// rest before it is interpreted again.
    sync_waiting: bool,
    /// The last [`Machine::execute`] interpreted a curve and left its planning to the
    /// next call ([`Machine::take_yielded`]).
    yielded: bool,
}

impl Machine {
    /// Power-up state. With homing enabled, the machine starts locked in alarm until
    /// `$H` or `$X`, as Grbl does.
    pub fn new(settings: Settings) -> Machine {
        crate::in_place::build(|slot| Machine::init_in(slot, &settings))
    }

    /// [`Machine::new`] built in `slot` (the firmware's static cell, through
    /// [`Controller::init_in`](crate::controller::Controller::init_in)): field by field,
    /// so that no whole machine is built on the stack and copied.
    #[allow(unsafe_code)]
    pub fn init_in<'a>(slot: &'a mut MaybeUninit<Machine>, settings: &Settings) -> &'a mut Machine {
        let m = crate::init_fields!(slot => Machine {
            settings = settings.clone(),
            interpreter = Interpreter::new(),
            locked = false,
            alarm = None,
            needs_reset = false,
            check_mode = false,
            sleeping = false,
            refusal = None,
            jogging = false,
            jog_cancel = false,
            homing = None,
            homed = false,
            door = false,
            hold_by_pin = false,
            paused = false,
            pen_change = None,
            message = Message::new(),
            message_new = false,
            stop_then_clear = false,
            feed_ovr = 100,
            rapid_ovr = 100,
            ovr_changed = false,
            inputs = Inputs::default(),
            job = JobRecord::default(),
            events = Deque::new(),
            settings_dirty = false,
            coords_dirty = false,
            outcome = Outcome::default(),
            waiting = false,
            sync_waiting = false,
            yielded = false,
        });
        m.lock_if_unhomed();
        m
    }

    /// With homing enabled the machine starts (and resets) locked until `$H` or `$X`.
    fn lock_if_unhomed(&mut self) {
        if self.settings.homing_enabled() && !self.homed {
            self.locked = true;
        }
    }

    /// In alarm and `$H` or `$X` would unlock it (not while an e-stop is held): the
    /// welcome line is then followed by Grbl's `[MSG:'$H'|'$X' to unlock]`.
    pub fn needs_unlock(&self) -> bool {
        self.locked && !self.needs_reset && self.refusal.is_none()
    }

    /// Refuse to run for good (the shell found a chip the image cannot use): locked in
    /// alarm, the motors released, `why` said with every welcome and to every `$X`,
    /// `$H` or other `$` command that would change something.
    pub fn refuse_to_run(&mut self, why: &'static str) {
        self.refusal = Some(why);
        self.locked = true;
    }

    /// Why the board refuses to run, if it does.
    pub fn refusal(&self) -> Option<&'static str> {
        self.refusal
    }

    fn event(&mut self, e: Event) {
        // Oldest first; if the host is not reading, drop the oldest message.
        if self.events.is_full() {
            let _ = self.events.pop_front();
        }
        let _ = self.events.push_back(e);
    }

    /// Next message for the host.
    pub fn next_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }
    pub fn interpreter(&self) -> &Interpreter {
        &self.interpreter
    }
    /// Replace the coordinate data (loaded from flash at boot).
    pub fn set_coords(&mut self, c: crate::gcode::interpreter::Coords) {
        self.interpreter.set_coords(c);
    }
    /// The alarm that locked the machine, while locked.
    pub fn alarm(&self) -> Option<Alarm> {
        self.alarm.filter(|_| self.locked)
    }
    /// In the alarm state.
    pub fn is_locked(&self) -> bool {
        self.locked
    }
    pub fn overrides(&self) -> (u8, u8) {
        (self.feed_ovr, self.rapid_ovr)
    }
    pub fn inputs(&self) -> Inputs {
        self.inputs
    }
    /// Settings were changed and should be saved (cleared by reading).
    pub fn take_settings_dirty(&mut self) -> bool {
        core::mem::take(&mut self.settings_dirty)
    }
    /// Coordinate data changed and should be saved (cleared by reading).
    pub fn take_coords_dirty(&mut self) -> bool {
        core::mem::take(&mut self.coords_dirty)
    }
    /// Overrides changed since last asked (for the `Ov:` field).
    pub fn take_overrides_changed(&mut self) -> bool {
        core::mem::take(&mut self.ovr_changed)
    }

    /// The state for status reports.
    pub fn state<M: MotionControl>(&self, m: &M) -> RunState {
        if self.sleeping {
            RunState::Sleep
        } else if self.homing.is_some() {
            RunState::Home
        } else if self.locked {
            RunState::Alarm
        } else if self.door {
            RunState::Door {
                at_rest: !m.is_moving(),
            }
        } else if self.jogging {
            // Including the deceleration of a jog cancel, as Grbl reports it.
            RunState::Jog
        } else if self.paused || m.is_holding() {
            RunState::Hold {
                complete: !m.is_moving(),
            }
        } else if self.check_mode {
            RunState::Check
        } else if !m.is_idle() && !m.dwelling() {
            RunState::Run
        } else {
            // A G4 dwell with nothing queued behind it is Idle, as Grbl reports it
            // (its dwell is no motion).
            RunState::Idle
        }
    }

    /// `$SLP` (only at rest; the protocol checks): the motors are released
    /// ([`Machine::motors_released`]) and lines and `$` commands are refused until a
    /// soft reset, which wakes the machine in alarm (the motors may have moved while
    /// unpowered), as Grbl's sleep does.
    pub fn sleep(&mut self) {
        self.drop_activity();
        self.sleeping = true;
    }

    /// The motors must stay unpowered whatever the idle delay says (`$SLP`, a
    /// refused board).
    pub fn motors_released(&self) -> bool {
        self.sleeping || self.refusal.is_some()
    }

    /// The busy output: motion is under way or homing.
    pub fn busy<M: MotionControl>(&self, m: &M) -> bool {
        self.homing.is_some() || m.is_moving()
    }

    /// The first work the machine (with its motion) still holds: without any,
    /// nothing changes until an outside event (a byte, an input, a key), and
    /// [`Machine::poll`] has nothing to do.
    pub fn pending<M: MotionControl>(&self, m: &M) -> Option<Work> {
        let work = if !m.is_idle() {
            Work::Motion
        } else if self.homing.is_some() {
            Work::Homing
        } else if self.stop_then_clear {
            Work::StopThenClear
        } else if self.jog_cancel {
            Work::JogCancel
        } else if self.jogging {
            Work::Jogging
        } else if self.job.ending {
            Work::JobEnding
        } else if !self.events.is_empty() {
            Work::Events
        } else {
            return None;
        };
        Some(work)
    }

    /// Test support: hold `w` if it is the machine's own kind of work (`on`), or
    /// none of it; false for the other layers' kinds.
    #[cfg(test)]
    pub(crate) fn set_work(&mut self, w: Work, on: bool) -> bool {
        match w {
            Work::Homing => self.homing = on.then(|| Homing::start(&Settings::default())).flatten(),
            Work::StopThenClear => self.stop_then_clear = on,
            Work::JogCancel => self.jog_cancel = on,
            Work::Jogging => self.jogging = on,
            Work::JobEnding => self.job.ending = on,
            Work::Events if on => self.event(Event::Msg("test")),
            Work::Events => self.events.clear(),
            _ => return false,
        }
        true
    }

    /// G-code lines are taken only when this holds: during a stop that will drop the
    /// queue they wait until it is done (otherwise they would be answered `ok` and
    /// then dropped).
    pub fn can_accept(&self) -> bool {
        !self.stop_then_clear && !self.jog_cancel && self.pen_change.is_none_or(|pc| pc.waiting)
    }

    fn idle_or_alarm<M: MotionControl>(&self, m: &M) -> bool {
        matches!(
            self.state(m),
            RunState::Idle | RunState::Alarm | RunState::Check
        )
    }

    /// `$n=v`: only at rest (Grbl's error 8 otherwise).
    pub fn set_setting<M: MotionControl>(
        &mut self,
        n: u16,
        v: f32,
        m: &mut M,
    ) -> Result<(), ErrorCode> {
        if !self.idle_or_alarm(m) {
            return Err(ErrorCode::IdleError);
        }
        self.settings.set(n, v)?;
        self.settings_dirty = true;
        // The motion system takes the new limits now, before the next line is run.
        m.configure(&self.settings);
        // Steps per mm may have changed: the planner's step position is the truth.
        self.resync(m);
        Ok(())
    }

    /// `$RST=#`: zero the work offsets and stored positions.
    pub fn clear_coords(&mut self) {
        self.interpreter
            .set_coords(crate::gcode::interpreter::Coords::default());
        self.coords_dirty = true;
    }

    /// Replace all settings (`$RST=$` or a loaded image).
    pub fn replace_settings<M: MotionControl>(&mut self, s: Settings, m: &mut M) {
        self.settings = s;
        self.settings_dirty = true;
        m.configure(&self.settings);
        self.resync(m);
    }

    /// `$X`.
    pub fn unlock(&mut self) -> Result<(), ErrorCode> {
        if let Some(why) = self.refusal {
            self.event(Event::Msg(why));
            return Err(ErrorCode::SystemLocked);
        }
        if self.inputs.estop || self.needs_reset {
            self.event(Event::Msg("Reset to continue"));
            return Err(ErrorCode::SystemLocked);
        }
        if core::mem::take(&mut self.locked) {
            self.alarm = None;
            self.event(Event::Msg("Caution: Unlocked"));
        }
        Ok(())
    }

    /// `$H`.
    pub fn start_homing<M: MotionControl>(&mut self, m: &mut M) -> Result<(), ErrorCode> {
        if let Some(why) = self.refusal {
            self.event(Event::Msg(why));
            return Err(ErrorCode::SystemLocked);
        }
        if !self.settings.homing_enabled() {
            return Err(ErrorCode::HomingDisabled);
        }
        if self.inputs.estop || self.needs_reset {
            return Err(ErrorCode::SystemLocked);
        }
        if !matches!(self.state(m), RunState::Idle | RunState::Alarm) || !m.is_idle() {
            return Err(ErrorCode::IdleError);
        }
        match Homing::start(&self.settings) {
            Some(h) => {
                self.locked = false;
                self.alarm = None;
                self.homing = Some(h);
                Ok(())
            }
            None => Err(ErrorCode::HomingDisabled),
        }
    }

    /// `$C`: toggle check mode. Leaving it resets like Grbl does.
    pub fn toggle_check<M: MotionControl>(&mut self, m: &mut M) -> Result<(), ErrorCode> {
        if self.check_mode {
            self.soft_reset(m);
            self.event(Event::Msg("Disabled"));
            Ok(())
        } else if self.state(m) == RunState::Idle {
            self.check_mode = true;
            self.event(Event::Msg("Enabled"));
            Ok(())
        } else {
            Err(ErrorCode::IdleError)
        }
    }

    pub fn check_mode(&self) -> bool {
        self.check_mode
    }

    fn raise<M: MotionControl>(&mut self, a: Alarm, m: &mut M) {
        if a == Alarm::SoftLimit && !m.is_idle() {
            // Position stays exact: decelerate, then drop the rest.
            m.hold();
            self.stop_then_clear = true;
        } else {
            self.drop_queue(m);
        }
        if a.critical() {
            self.needs_reset = true;
        }
        self.drop_activity();
        self.locked = true;
        self.alarm = Some(a);
        self.event(Event::Alarm(a));
        if a.critical() {
            self.event(Event::Msg("Reset to continue"));
        }
    }

    /// Forget what the machine was doing (homing, jogging, holds, pauses, the job):
    /// both an alarm and a soft reset end all of it.
    fn drop_activity(&mut self) {
        self.homing = None;
        self.jogging = false;
        self.jog_cancel = false;
        self.release_holds();
        self.job = JobRecord::default();
    }

    /// A pen change that has reached its place (the machine at rest) waits there
    /// for cycle start, with the way back and the drop queued behind the pause.
    fn poll_pen_change<M: MotionControl>(&mut self, m: &mut M) {
        let Some(pc) = self.pen_change.as_mut() else {
            return;
        };
        if pc.waiting || !m.is_idle() {
            return;
        }
        pc.waiting = true;
        let (tool, from) = (pc.tool, usize::from(pc.split));
        self.paused = true;
        m.hold();
        let rest = self.outcome.cmds.get(from..).unwrap_or(&[]);
        for &cmd in rest {
            if m.push(cmd).is_err() {
                self.raise(Alarm::AbortCycle, m);
                return;
            }
        }
        self.event(Event::PenChange(tool));
    }

    /// What the machine waits for the user to do, if anything.
    pub fn prompt(&self) -> Option<Prompt> {
        match self.pen_change {
            Some(pc) if pc.waiting => Some(Prompt::PenChange(pc.tool)),
            Some(_) => None,
            None => self.paused.then_some(Prompt::Paused),
        }
    }

    /// The last `(MSG, ...)` text (at most [`MESSAGE_LEN`] bytes).
    pub fn message(&self) -> &[u8] {
        &self.message
    }

    /// A line's `(MSG, ...)` comment ran: keep its text for the LCD.
    pub fn set_message(&mut self, text: &[u8]) {
        self.message.clear();
        let n = text.len().min(MESSAGE_LEN);
        let _ = self.message.extend_from_slice(text.get(..n).unwrap_or(&[]));
        self.message_new = true;
    }

    /// A new `(MSG, ...)` came since the last call.
    pub fn take_message_new(&mut self) -> bool {
        core::mem::take(&mut self.message_new)
    }

    /// Forget every reason to hold (`!`, the pin, the door, M0, M6).
    fn release_holds(&mut self) {
        self.door = false;
        self.hold_by_pin = false;
        self.paused = false;
        self.pen_change = None;
    }

    /// Stop at once and drop everything queued; the interpreter continues from where
    /// the machine stopped.
    fn drop_queue<M: MotionControl>(&mut self, m: &mut M) {
        m.clear();
        if self.settings.pen_mode() == PenMode::Servo {
            // The pipeline leaves the servo pen up.
            self.interpreter.pen_lifted();
        }
        self.resync(m);
    }

    /// The interpreter continues from where the machine is. Commands still waiting
    /// for room were planned from the old position: they are dropped, and their line
    /// (if it is still to be answered) is interpreted again from the new one.
    fn resync<M: MotionControl>(&mut self, m: &M) {
        self.interpreter
            .sync_position(&m.position(), &self.settings);
        self.forget_line();
    }

    /// The line being taken is answered or dropped: nothing of it waits any more.
    fn forget_line(&mut self) {
        self.waiting = false;
        self.sync_waiting = false;
    }

    /// The keypad's "set origin": at rest, the current X/Y become zero and the G-code
    /// interpreter continues from there. Modal state, offsets, overrides and alarms are
    /// left as they are (a soft reset would reset the first and the third). Nothing
    /// happens if the machine is not at rest.
    pub fn zero_xy_here<M: MotionControl>(&mut self, m: &mut M) {
        if m.is_idle() {
            let p = m.position();
            m.set_position([0, 0, p[2]]);
            self.resync(m);
        }
    }

    /// 0x18: stop everything, keep position if it is known.
    pub fn soft_reset<M: MotionControl>(&mut self, m: &mut M) {
        // Position is lost if steps were cut off mid-move (a hold at rest keeps it).
        let held_at_rest = m.is_holding() && !m.is_moving();
        let lost = self.homing.is_some() || (!m.is_idle() && !held_at_rest);
        let was_homing = self.homing.is_some();
        m.clear();
        m.set_overrides(100, 100);
        self.resync(m);
        self.interpreter.reset_modal();
        self.drop_activity();
        self.stop_then_clear = false;
        self.check_mode = false;
        // Waking from sleep: where the unpowered motors are is not known.
        let woke = core::mem::take(&mut self.sleeping);
        self.feed_ovr = 100;
        self.rapid_ovr = 100;
        self.needs_reset = false;
        let alarm = if self.inputs.estop {
            Some(Alarm::EStop)
        } else if was_homing {
            Some(Alarm::HomingFailReset)
        } else if lost {
            Some(Alarm::AbortCycle)
        } else {
            None
        };
        if let Some(a) = alarm {
            if a != Alarm::EStop {
                self.homed = false;
            }
            self.needs_reset = a == Alarm::EStop;
            self.locked = true;
            self.alarm = Some(a);
            self.event(Event::Alarm(a));
        }
        if (woke || self.refusal.is_some()) && !self.locked {
            self.homed = false;
            self.locked = true;
        }
        self.lock_if_unhomed();
    }

    /// `!` or the feed-hold pin. At rest too, as in Grbl: the machine reports
    /// `Hold:0` and the next motion waits for cycle start.
    pub fn feed_hold<M: MotionControl>(&mut self, m: &mut M) {
        self.hold_motion(m);
    }

    /// [`Machine::feed_hold`]; true if the motion now holds for it (the pipeline
    /// keeps the hold until cycle start or a clear).
    fn hold_motion<M: MotionControl>(&mut self, m: &mut M) -> bool {
        if self.locked || self.homing.is_some() || self.check_mode || self.sleeping {
            return false;
        }
        if self.jogging {
            // A hold during a jog cancels it, as Grbl does.
            self.jog_cancel(m);
            return false;
        }
        m.hold();
        true
    }

    /// 0x84, the safety door: like a feed hold reported as `Door`; during homing it
    /// aborts with alarm 7, during a jog it cancels the jog.
    pub fn safety_door<M: MotionControl>(&mut self, m: &mut M) {
        if self.locked || self.check_mode || self.sleeping {
            return;
        }
        if self.homing.is_some() {
            self.raise(Alarm::HomingFailDoor, m);
            return;
        }
        self.door = true;
        self.feed_hold(m);
    }

    /// `~` or the cycle-start pin.
    pub fn cycle_start<M: MotionControl>(&mut self, m: &mut M) {
        // A stop that drops the queue cannot be resumed.
        if self.locked || self.homing.is_some() || self.stop_then_clear || self.jog_cancel {
            return;
        }
        if self.paused || self.door || m.is_holding() {
            self.release_holds();
            m.resume();
        }
    }

    /// Queue a command made outside G-code (the keypad's drawing modes). Refused in
    /// alarm, homing, jogging or check mode; a line target outside travel with soft
    /// limits on is refused with `error:15` semantics ([`ErrorCode::TravelExceeded`]);
    /// shapes check their own extent with [`crate::gcode::units::within_travel`].
    /// The interpreter continues from the command's end point.
    pub fn queue<M: MotionControl>(
        &mut self,
        cmd: Command,
        m: &mut M,
        now_ms: u32,
    ) -> Result<(), ErrorCode> {
        if self.locked || self.homing.is_some() {
            return Err(ErrorCode::SystemLocked);
        }
        if self.jogging || self.check_mode {
            return Err(ErrorCode::IdleError);
        }
        if self.waiting {
            // A G-code line came first and waits for room: no overtaking.
            return Err(ErrorCode::Overflow);
        }
        if let Command::Move(mv) = &cmd {
            let end = to_nm(&mv.target, &self.settings);
            if self.settings.soft_limits()
                && !crate::gcode::units::within_travel(&end, &self.settings)
            {
                return Err(ErrorCode::TravelExceeded);
            }
        }
        m.push(cmd).map_err(|_| ErrorCode::Overflow)?;
        if let Command::Move(mv) = cmd {
            self.interpreter.sync_position(&mv.target, &self.settings);
            self.count_move(now_ms);
        }
        Ok(())
    }

    /// A move was queued: the first one of a job starts it (and says so).
    fn count_move(&mut self, now_ms: u32) {
        if !self.job.running {
            self.job = JobRecord {
                running: true,
                start_ms: now_ms,
                moves: 0,
                ending: false,
            };
            self.event(Event::JobStarted);
        }
        self.job.moves = self.job.moves.wrapping_add(1);
    }

    /// Stop cleanly and forget the rest (the keypad's abort): decelerate to rest, then
    /// drop the queue; the position stays exact.
    pub fn stop_and_clear<M: MotionControl>(&mut self, m: &mut M) {
        self.release_holds();
        self.job = JobRecord::default();
        if m.is_idle() && !m.is_holding() {
            return;
        }
        if self.jogging {
            self.jog_cancel(m);
        } else {
            self.stop_then_clear = true;
            m.hold();
        }
    }

    /// 0x85: stop a jog (decelerate, then drop the rest of the jog queue).
    pub fn jog_cancel<M: MotionControl>(&mut self, m: &mut M) {
        if self.jogging && !self.jog_cancel {
            self.jog_cancel = true;
            m.hold();
        }
    }

    /// Feed/rapid override real-time commands 0x90-0x97.
    pub fn override_command<M: MotionControl>(&mut self, byte: u8, m: &mut M) {
        let f = i16::from(self.feed_ovr);
        let feed = match byte {
            0x90 => 100,
            0x91 => f + 10,
            0x92 => f - 10,
            0x93 => f + 1,
            0x94 => f - 1,
            _ => f,
        };
        let rapid = match byte {
            0x95 => 100,
            0x96 => 50,
            0x97 => 25,
            _ => self.rapid_ovr,
        };
        let feed = feed.clamp(10, 200) as u8;
        if feed != self.feed_ovr || rapid != self.rapid_ovr {
            self.feed_ovr = feed;
            self.rapid_ovr = rapid;
            self.ovr_changed = true;
            m.set_overrides(feed, rapid);
        }
    }

    /// New input levels. Call from the input interrupt path for the fastest reaction
    /// (the firmware stops the step engine itself on e-stop before calling this).
    pub fn set_inputs<M: MotionControl>(&mut self, inputs: Inputs, m: &mut M, now_ms: u32) {
        let before = self.inputs;
        self.inputs = inputs;
        if inputs.estop {
            if !(self.locked && self.alarm == Some(Alarm::EStop)) {
                self.raise(Alarm::EStop, m);
            } else {
                m.clear();
            }
            return;
        }
        if self.homing.is_some() {
            self.step_homing(m, now_ms);
            return;
        }
        // Only the axes that have a switch ($214): another axis's pin is not wired
        // to one (floating, or a stray switch) and must not stop the machine.
        let with_switch = self.settings.switch_mask();
        let newly_hit = inputs
            .limits
            .iter()
            .zip(before.limits.iter())
            .enumerate()
            .any(|(axis, (&now, &was))| now && !was && with_switch & (1 << axis) != 0);
        if newly_hit && self.settings.hard_limits() && !self.needs_reset {
            self.raise(Alarm::HardLimit, m);
            return;
        }
        if inputs.feed_hold && !before.feed_hold {
            self.hold_by_pin = self.hold_motion(m);
        } else if !inputs.feed_hold && before.feed_hold && self.hold_by_pin {
            self.cycle_start(m);
        }
        if inputs.cycle_start && !before.cycle_start {
            self.cycle_start(m);
        }
    }

    fn step_homing<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) {
        let Some(h) = self.homing.as_mut() else {
            return;
        };
        match h.step(&self.settings, self.inputs.limits, m, now_ms) {
            Progress::Running => {}
            Progress::Done(pos) => {
                self.homing = None;
                self.homed = true;
                m.set_position(pos);
                self.resync(m);
            }
            Progress::Failed(e) => {
                self.homing = None;
                let a = match e {
                    HomingError::PullOff => Alarm::HomingFailPullOff,
                    HomingError::NotFound => Alarm::HomingFailApproach,
                };
                self.raise(a, m);
            }
        }
    }

    /// Make progress: homing, job end, jog cancel, soft-limit stop.
    pub fn poll<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) {
        if self.homing.is_some() {
            self.step_homing(m, now_ms);
        }
        self.poll_pen_change(m);
        let at_rest = !m.is_moving();
        if self.stop_then_clear && at_rest {
            self.stop_then_clear = false;
            self.drop_queue(m);
        }
        if self.jog_cancel && at_rest {
            self.jog_cancel = false;
            self.drop_queue(m);
            self.jogging = false;
        }
        if self.jogging && m.is_idle() && !self.jog_cancel {
            self.jogging = false;
        }
        if self.job.ending && m.is_idle() {
            let ms = now_ms.wrapping_sub(self.job.start_ms);
            let moves = self.job.moves;
            self.job = JobRecord::default();
            self.event(Event::JobFinished { ms, moves });
        }
    }

    /// Machine position in mm from the planner's step position.
    pub fn machine_position<M: MotionControl>(&self, m: &M) -> [f32; AXES] {
        to_mm(&m.position(), &self.settings)
    }
}
