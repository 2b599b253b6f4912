//! The motion pipeline (planner -> segment preparation -> step queue): implements the
//! machine's [`MotionControl`] over the look-ahead [`Planner`], the segment preparation
//! ([`Prep`]) and whatever executes the prepared step commands (the step-timer interrupt on the board, a virtual timer in the
//! simulator), so that the G-code interpreter, the protocol and the keypad modes drive
//! the real planner the same way everywhere.
//!
//! It owns only what the trait asks beyond the planner: commands that are not moves
//! (G4 dwells, servo pen lifts) wait in order behind the moves before them and run as
//! pure-wait step commands, so their timing comes from the same timer as the steps;
//! hold/resume/clear map onto the preparation and the planner (a hold lifts the pen
//! once XY is at rest: the servo's level, or a Z pen's trip to $205 and back made of
//! raw Z steps beside the held block, so the job's own steps are untouched); the
//! position is the executor's count. The firmware (its preparation task, `inkstep::steps::BoardSide`)
//! and the simulator (`SimSide`) each give it their interrupt side through the same
//! [`StepSide`] trait.

use crate::interpolation::StepEvent;
use crate::machine::{MotionControl, MotionState, QueueFull};
use crate::motion::{Command, PEN_FULL};
use crate::motion::{Move, Path, StepPos};
use crate::planner::{AxisConfig, PlanError, Planner, PlannerConfig, Shape, PLANNER_BLOCKS};
use crate::settings::{AccelProfile, Interpolation, Settings};
use crate::stepper::prep::{HoldState, Prep, PrepConfig};
use crate::stepper::{CmdSink, StepCmd, MAX_WAIT};
use heapless::Deque;

mod hold;
use hold::ZTrip;

/// The interrupt side, as the pipeline sees it.
pub trait StepSide {
    /// The step queue's producing end (the SPSC producer on the board).
    type Queue: CmdSink;
    /// Where prepared step commands go.
    fn sink(&mut self) -> &mut Self::Queue;
    /// Position after every step emitted so far.
    fn position(&self) -> StepPos;
    /// Steps are still to come: the timer runs or commands wait in the queue.
    fn is_running(&self) -> bool;
    /// Step commands waiting for the interrupt.
    fn queued(&self) -> usize;
    /// Stop at once (no further step) and drop every queued command; the position
    /// stays what was emitted.
    fn flush(&mut self);
    /// Redefine the position (at rest).
    fn set_position(&mut self, p: StepPos);
    /// What is queued may run from now: the first command of a start from rest (its
    /// lead, [`START_LEAD_MS`]) is queued, and the rest follow while it runs. The
    /// firmware starts its step timer at once, on the schedule of the service tick
    /// `now_ms`; the simulator, whose preparation takes no time, at the end of the
    /// call as always.
    fn start_now(&mut self, _now_ms: u32) {}
}

/// Non-move commands waiting behind moves, and moves behind them.
const PENDING: usize = 32;
/// How far ahead of the interrupt steps are prepared, in 1/1000 of the timer's
/// frequency (milliseconds). Prepared steps are committed: what a block arriving later
/// changes only applies to steps not yet prepared. Measured on the sine benchmark
/// streamed line by line: 3.375 s with the whole 256-step queue prepared, 3.271 s at
/// 20 ms, 3.231 s at 10 ms, 3.220 s at 5 ms (Grbl 3.224 s). 5 ms leaves the firmware's
/// 1 ms preparation task a 5x margin (the queue's length caps it at high step rates).
const HORIZON_MS: u32 = 5;
/// Fewest steps kept prepared (starting from rest, and at low speed, where the horizon
/// holds less than this): the step in progress and the next, so the interrupt never
/// waits for one. No more: at low speed a step is milliseconds long, and every step
/// prepared beyond the horizon is committed before the moves streaming in behind it
/// can shape it. Measured on programs of tiny moves streamed line by line (bench/
/// zigzag.nc, 4 steps a move): 16 made the second and third moves stop at their ends
/// (12.4717 s); 2 runs them at their junction speeds (12.4619 s, the time-optimal
/// bound of the planner's limits).
const MIN_AHEAD: usize = 2;
/// How long work that arrives at rest waits before it starts, in service ticks (ms):
/// counted from the rest's start if it arrives within that time, else from its
/// arrival. Two things come of it:
/// - A job's first moves run into the next instead of stopping at their ends: the
///   next lines of a stream are usually a millisecond or two behind the first
///   (measured on the zigzag benchmark, 4 steps a move: without a wait the first
///   moves stop at their ends, the planner has nothing behind them yet).
/// - The lines after a sync point (G4, G92, a settings save: the sender's next line
///   comes after the `ok` that waited for rest) start at the same tick however long
///   the link and the CPU took to bring them, so a job's timing depends on neither,
///   and the simulator runs it as the board does. 20 ms covers a settings save (5.8 ms
///   of flash programming and the store's CPU work under the pessimistic cycle model)
///   and the lines around it (`.ci/emu-random`: step times equal on both boards).
///
/// Work that was already waiting when the motion came to rest (a pen move behind the
/// last steps, a held block) goes on at once.
pub const RESUME_MS: u8 = 20;
/// A move that starts from rest (a job's first, the next after a sync point, a
/// resume after a hold) begins with a wait this long, ms, on every board: the
/// firmware starts its step timer on it at once, and prepares the move's first steps
/// while it runs. So its first step comes when the step timeline says, however long
/// that preparation takes (an arc's start under the S-curve took 2.0 ms under the
/// pessimistic cycle model, and may follow a protocol lock section of up to 1 ms):
/// without it such a start came up to 0.5 ms late on the board, and the simulator
/// could not say when (`.ci/emu-random`).
pub const START_LEAD_MS: u32 = 4;
/// How far the step timeline must be past the last command's end for a service tick
/// to see the machine at rest, µs: longer than a last pulse's tail (the pulse, `$0`
/// up to 255 µs, and the direction hold) and the firmware's call latency, so that
/// every board sees the rest at the same tick.
const REST_GUARD_US: u32 = 400;
/// [`Pipeline::rest_ms`]: the machine is not at rest.
const MOVING: u8 = u8::MAX;
/// [`Pipeline::rest_ms`]: at rest for [`RESUME_MS`] or longer, with nothing to start.
const IDLE: u8 = u8::MAX - 1;
/// [`Pipeline::rest_ms`]: the work that was waiting when the motion came to rest (a
/// pen move or a dwell behind the last steps, the moves behind them, a stream that
/// ran dry) goes on at once, without a lead: this is the motion going on, not a
/// start.
const GOING_ON: u8 = RESUME_MS + 1;

/// The planner's configuration from the machine settings.
pub fn planner_config(s: &Settings) -> PlannerConfig {
    let axis = |i| AxisConfig {
        steps_per_mm: s.steps_per_mm(i),
        max_rate: s.max_rate(i),
        accel: s.acceleration(i),
    };
    PlannerConfig {
        axes: [axis(0), axis(1), axis(2)],
        junction_deviation: s.junction_deviation(),
        start_speed: s.start_rate() / 60.0,
        shape: match s.accel_profile() {
            AccelProfile::Trapezoid => Shape::Trapezoid,
            AccelProfile::SCurve => Shape::Cosine,
        },
        method: match s.interpolation() {
            Interpolation::PointByPoint => crate::interpolation::Method::Classic,
            Interpolation::Dda => crate::interpolation::Method::Dda,
        },
        max_event_rate: crate::stepper::event_rate_for_pulse(s.step_pulse_us()),
    }
}

/// The servo's frame, ms: a slow pen move ($208) is told to the servo in steps of
/// this length (a 50 Hz servo takes a new position once per frame anyway).
const PEN_FRAME_MS: u32 = 20;

/// What a pen move takes, from the settings ($202/$203 angles, $204 lift and $207
/// drop waits, $208 speed).
#[derive(Clone, Copy, Debug, PartialEq)]
struct PenTiming {
    lift_ms: u32,
    drop_ms: u32,
    /// Degrees between up and down.
    span_deg: f32,
    /// deg/s; 0 = a jump.
    speed: f32,
    /// A Z-axis pen's up place ($205) in steps, as the interpreter rounds it.
    z_up: i32,
}

impl PenTiming {
    fn from(s: &Settings) -> Self {
        PenTiming {
            lift_ms: s.pen_lift_ms(),
            drop_ms: s.pen_drop_ms(),
            span_deg: (s.pen_down_angle() - s.pen_up_angle()).abs(),
            speed: s.pen_speed(),
            z_up: z_steps(s, s.pen_z_up()).unwrap_or(0),
        }
    }
    /// The turn from level `from` to `to`, ms (0 without a speed limit).
    fn turn_ms(&self, from: u16, to: u16) -> u32 {
        if self.speed <= 0.0 {
            return 0;
        }
        let deg = self.span_deg * f32::from(from.abs_diff(to)) / f32::from(PEN_FULL);
        crate::decimal::to_u32(deg * 1000.0 / self.speed + 0.5)
    }
}

/// A Z place in steps, as the interpreter rounds it.
fn z_steps(s: &Settings, mm: f32) -> Option<i32> {
    crate::gcode::units::nm_to_steps(crate::gcode::units::mm_to_nm(mm), s.steps_per_mm(2))
}

/// A Z-axis pen ($201=0): which way from its up place ($205) down ($206) is, -1 or
/// 1; 0: a servo pen (or both places the same). Kept beside the pipeline's flags,
/// not in [`PenTiming`], where it would cost a word of RAM.
fn z_down_side(s: &Settings) -> i8 {
    match (
        s.pen_mode(),
        z_steps(s, s.pen_z_up()),
        z_steps(s, s.pen_z_down()),
    ) {
        (crate::settings::PenMode::ZAxis, Some(u), Some(d)) => (d - u).signum() as i8,
        _ => 0,
    }
}

/// A pen move under way: the turn told to the servo frame by frame, then the settle
/// wait (lift or drop time).
#[derive(Clone, Copy, Debug, PartialEq)]
struct PenMove {
    from: u16,
    to: u16,
    /// Frames told so far; `frames + 1` once the settle wait has started.
    frame: u16,
    frames: u16,
    turn_ms: u32,
    settle_ms: u32,
}

impl PenMove {
    fn new(from: u16, to: u16, t: &PenTiming) -> Self {
        let turn_ms = t.turn_ms(from, to);
        PenMove {
            from,
            to,
            frame: 0,
            frames: turn_ms.div_ceil(PEN_FRAME_MS).min(u32::from(u16::MAX - 1)) as u16,
            turn_ms,
            settle_ms: if to < from { t.lift_ms } else { t.drop_ms },
        }
    }
    /// The next stage: the level to tell the servo and the ms to wait; `None` when
    /// the move is over.
    fn next(&mut self) -> Option<(u16, u32)> {
        let n = u32::from(self.frames);
        let k = u32::from(self.frame);
        if k > n {
            return None;
        }
        self.frame += 1;
        if k == n {
            return Some((self.to, self.settle_ms));
        }
        // turn_ms * k / n in 64 bits: a very slow servo turns for hours, and
        // turn_ms * k would overflow 32.
        let at = |k: u32| (u64::from(self.turn_ms) * u64::from(k) / u64::from(n)) as u32;
        let (from, to) = (i32::from(self.from), i32::from(self.to));
        let level = from + (to - from) * (k as i32 + 1) / n as i32;
        Some((level as u16, at(k + 1) - at(k)))
    }
}

pub struct Pipeline<S: StepSide> {
    planner: Planner,
    prep: Prep,
    side: S,
    timer_hz: u32,
    /// Commands behind a dwell or pen command, in order.
    pending: Deque<Command, PENDING>,
    /// Timer counts of the running dwell still to queue.
    wait_left: u64,
    /// The running dwell / pen command has been fully queued; it ends when the side
    /// has run it.
    waiting: bool,
    /// The pen level the program has reached (0 up .. [`PEN_FULL`] down), as far as
    /// the queue has run.
    pen: u16,
    /// The level the servo is told now: `pen`, the way there during a pen move, 0
    /// while lifted for a hold.
    shown: u16,
    /// The pen move under way, frame by frame.
    pen_move: Option<PenMove>,
    /// The pen was lifted for a hold at this level: it goes down again on resume,
    /// before XY moves on.
    lifted: Option<u16>,
    /// A Z pen lifted for a hold (or on its way up or back).
    z_trip: Option<ZTrip>,
    /// The wait in `wait_left` / `waiting` is a G4 dwell (not a pen lift's).
    dwell: bool,
    pen_timing: PenTiming,
    /// [`z_down_side`]: a Z pen's down side, 0 for a servo pen.
    z_down: i8,
    /// At rest: service ticks since the rest began (since the step timeline passed
    /// the end of the last queued command), or since work arrived after a long rest,
    /// up to [`RESUME_MS`] (work starts there); [`IDLE`], [`MOVING`].
    rest_ms: u8,
    /// The step timeline ([`Pipeline::fill_at`]): the service tick (ms) of the last
    /// call, and where on the timeline that tick was (timer counts, wrapping: what is
    /// compared on it is less than a second apart).
    clock: (u32, u32),
    /// Where on the step timeline the last queued command ends.
    queue_end: u32,
}

impl<S: StepSide> Pipeline<S> {
    pub fn new(s: &Settings, prep: PrepConfig, side: S) -> Self {
        crate::in_place::build(|slot| Pipeline::init_in(slot, s, prep, side))
    }

    /// [`Pipeline::new`] built in `slot` (the firmware's static cell): field by field, so
    /// that no whole pipeline (3.6 KB: the planner's block buffer) is built on init's stack
    /// and copied.
    #[allow(unsafe_code)]
    pub fn init_in<'a>(
        slot: &'a mut core::mem::MaybeUninit<Self>,
        s: &Settings,
        prep: PrepConfig,
        side: S,
    ) -> &'a mut Self {
        let pos = side.position();
        crate::init_fields!(slot => Self {
            planner in |cell| Planner::init_in(cell, planner_config(s), pos),
            prep = Prep::new(prep, pos),
            side = side,
            timer_hz = prep.timer_hz,
            pending = Deque::new(),
            wait_left = 0,
            waiting = false,
            pen = 0,
            shown = 0,
            pen_move = None,
            lifted = None,
            z_trip = None,
            dwell = false,
            pen_timing = PenTiming::from(s),
            z_down = z_down_side(s),
            rest_ms = IDLE,
            clock = (0, 0),
            queue_end = 0,
        })
    }

    pub fn side(&self) -> &S {
        &self.side
    }
    pub fn side_mut(&mut self) -> &mut S {
        &mut self.side
    }
    pub fn planner(&self) -> &Planner {
        &self.planner
    }
    /// Take new limits from the settings. Settings change only at rest (the machine
    /// refuses `$n=v` otherwise), when the planner is empty; it is reconfigured in
    /// place and keeps the feed and rapid overrides (the machine keeps reporting
    /// them). Called by the machine through [`MotionControl::configure`] as soon as a
    /// setting changes.
    fn reconfigure(&mut self, s: &Settings) {
        let pos = self.side.position();
        self.planner.reconfigure(&planner_config(s), pos);
        self.pen_timing = PenTiming::from(s);
        self.z_down = z_down_side(s);
    }
    /// A move is being prepared or waits in the planner (dwells and pen moves are not
    /// moves): the step queue running dry now would be a stall.
    pub fn in_move(&self) -> bool {
        !self.prep.is_idle(&self.planner)
    }
    /// Source line of the block in execution.
    pub fn line(&self) -> Option<u32> {
        self.prep.line()
    }

    /// How far the queue reaches past `now` on the step timeline (timer counts), and
    /// how many of the commands after `now` it holds, up to [`MIN_AHEAD`] (the last
    /// command's wait tells whether the one before it is after `now` too).
    fn ahead_of(&self, now: u32) -> (u32, usize) {
        // Signed distances on the wrapping timeline (a queue end behind `now`: the
        // interrupt has run it all).
        let to_end = self.queue_end.wrapping_sub(now) as i32;
        let before_last = to_end.saturating_sub_unsigned(self.prep.last_wait());
        let after = if to_end <= 0 {
            0
        } else if before_last <= 0 {
            1
        } else {
            MIN_AHEAD
        };
        (to_end.max(0) as u32, after)
    }

    /// How far ahead of the step timeline steps are prepared ([`HORIZON_MS`]), timer
    /// counts.
    fn horizon(&self) -> u32 {
        self.timer_hz / 1000 * HORIZON_MS
    }

    /// `ms` milliseconds in timer counts (floored).
    fn ms_ticks(&self, ms: u32) -> u64 {
        u64::from(ms) * u64::from(self.timer_hz) / 1000
    }

    /// [`Pipeline::fill_at`] one service tick after the last call (tests and benches
    /// that call it once per tick).
    pub fn fill(&mut self) {
        self.fill_at(self.clock.0.wrapping_add(1));
    }

    /// The segment-preparation task at service tick `now_ms`: fill the step queue, run
    /// dwells and pen commands in order once the moves before them have been prepared.
    ///
    /// How much to prepare is decided on the step timeline, not from how much of the
    /// queue the interrupt has taken by the time this runs: the timeline starts at the
    /// tick whose call queued the first command after rest (the board starts its step
    /// timer on that tick's schedule, the simulator at that instant) and runs on with
    /// the ticks, and the queue ends where the waits queued since add up to. So the
    /// firmware, whatever this call's latency, and the simulator prepare the same
    /// commands at the same ticks, and a feed hold, which brakes from the end of what
    /// is prepared, stops both at the same step.
    pub fn fill_at(&mut self, now_ms: u32) {
        let per_ms = self.timer_hz / 1000;
        let (ms, t) = self.clock;
        let on_timeline = t.wrapping_add(now_ms.wrapping_sub(ms).wrapping_mul(per_ms));
        // At rest once the side has stopped and the timeline is [`REST_GUARD_US`] past
        // the last command's end: a last step just before the tick leaves its pulse's
        // tail running at the tick on the simulator, and stopped by the time the
        // firmware's call (a little after its tick) looks; with the guard both see
        // the rest at the same tick.
        let guard = (self.timer_hz / 1000 * REST_GUARD_US / 1000) as i32;
        let ended = on_timeline.wrapping_sub(self.queue_end) as i32 >= guard;
        if ended && self.side.queued() == 0 && !self.side.is_running() {
            self.count_rest(now_ms, on_timeline);
        } else {
            self.rest_ms = MOVING;
            self.clock = (now_ms, on_timeline);
        }
        self.fill_queue();
    }

    /// At rest: true while work waits for [`RESUME_MS`] to end (nothing starts now);
    /// once it may start, a move gets its lead ([`START_LEAD_MS`]) first, running
    /// while the move is prepared. (Not inlined: the preparation task's own frame is on its
    /// deepest stack path.)
    #[inline(never)]
    fn wait_at_rest(&mut self) -> bool {
        if self.rest_ms < RESUME_MS {
            return self.has_work();
        }
        if self.rest_ms != RESUME_MS
            || self.side.queued() > 0
            || self.pen_move.is_some()
            || self.prep.hold_state() != HoldState::Running
            || (!self.prep.in_block() && self.planner.is_empty())
        {
            return false;
        }
        let lead = self.ms_ticks(START_LEAD_MS) as u32;
        self.side
            .sink()
            .push_slice(&[StepCmd::new(StepEvent(0), lead)]);
        self.queue_end = self.queue_end.wrapping_add(lead);
        self.rest_ms = MOVING;
        self.side.start_now(self.clock.0);
        false
    }

    /// Work to do: a block under way (held) or waiting, or a command behind it.
    fn has_work(&self) -> bool {
        self.prep.in_block() || !self.planner.is_empty() || !self.pending.is_empty()
    }

    /// A call at rest at the service tick `now_ms`, where the timeline would be at
    /// `on_timeline`: the timeline goes on from here, and [`Pipeline::rest_ms`]
    /// counts. (Not inlined: the preparation task's own frame is on its deepest
    /// stack path.)
    #[inline(never)]
    fn count_rest(&mut self, now_ms: u32, on_timeline: u32) {
        let elapsed = now_ms.wrapping_sub(self.clock.0);
        self.clock = (now_ms, self.queue_end);
        let resume = u32::from(RESUME_MS);
        let work = self.has_work();
        let rest = match self.rest_ms {
            // Work that was waiting for the motion to end goes on at once.
            MOVING if work => {
                self.rest_ms = GOING_ON;
                return;
            }
            GOING_ON if work => return,
            // The rest began where the timeline ended, not at the call that saw it
            // (the firmware's runs a little after its tick, and may see a last step's
            // end a tick before the simulator does): counted from there.
            MOVING => {
                let past = (on_timeline.wrapping_sub(self.queue_end) as i32).max(0) as u32;
                past / (self.timer_hz / 1000).max(1)
            }
            // Work after a long rest: it waits from its arrival.
            IDLE if work => 0,
            IDLE => return,
            GOING_ON => resume,
            r => u32::from(r).saturating_add(elapsed),
        };
        self.rest_ms = if rest >= resume && !work {
            IDLE
        } else {
            rest.min(resume) as u8
        };
    }

    fn fill_queue(&mut self) {
        if self.prep.hold_state() == HoldState::Held && !self.prep.in_block() {
            // Held between blocks: start nothing new until resumed, but let a
            // wait under way (a pen move, a dwell) end, so that the machine comes to
            // rest (and the pen up).
            self.run_waits();
            self.run_z();
            self.lift_when_stopped();
            self.run_z();
            return;
        }
        if self.held() {
            self.run_z();
            self.lift_when_stopped();
            if self.z_trip.is_some() {
                // The Z pen goes up (or waits up) beside the held block.
                self.run_z();
                return;
            }
        } else if !self.run_z() {
            // Back down after a hold before XY moves on.
            return;
        }
        let horizon = self.horizon();
        let queued = self.side.queued();
        let now = self.clock.1;
        if self.rest_ms != MOVING && self.wait_at_rest() {
            return;
        }
        let (ahead, after) = self.ahead_of(now);
        if queued > 0 && 2 * ahead >= horizon && after >= MIN_AHEAD {
            // More than half the horizon is still queued: refill later, in one go.
            return;
        }
        loop {
            let (ahead, after) = self.ahead_of(now);
            let budget = horizon.saturating_sub(ahead);
            let need = MIN_AHEAD - after;
            let left = self.prep.commands_for(budget).max(need);
            if self.pen_move.is_some() && !self.run_waits() {
                // The pen goes down again after a hold before anything moves (its
                // waits first in the step queue); a pen move from the queue is
                // only started with nothing prepared, so it is the same there.
                return;
            }
            // The count from the last wait is an estimate: short after a long wait,
            // long after a short one. Bounded in time at twice the horizon past the
            // timeline: a point-by-point circle's minor step 62 µs after a 580 µs
            // one made it 77 single ticks, 45 ms committed in one call (19 ms of this
            // task under the pessimistic cycle model). Not at the horizon itself: the
            // refill comes when half of it is left, and the estimate's slack is what
            // covers a block's start under load there (cut to the horizon, the step
            // queue of bench/polygon.nc ran dry twice under the pessimistic model).
            let before = self.prep.prepared_until();
            self.prep.fill_until(
                &mut self.planner,
                self.side.sink(),
                need,
                left,
                before + u64::from(budget + horizon),
            );
            let made = self.prep.prepared_until().wrapping_sub(before);
            self.queue_end = self.queue_end.wrapping_add(made as u32);
            if !self.run_waits() {
                return;
            }
            // The path before the head of `pending` is fully prepared: start it.
            if !self.prep.is_idle(&self.planner) {
                return;
            }
            if self.held() && !matches!(self.pending.front(), Some(Command::Move(_))) {
                // A hold that came to rest at the end of the planned path: a dwell or
                // a pen move behind it waits for the resume (moves are still planned,
                // into the held queue).
                return;
            }
            if matches!(self.pending.front(), Some(Command::Pen { .. })) && self.side.is_running() {
                // The pen moves only once the steps before it have been made.
                return;
            }
            let Some(cmd) = self.pending.pop_front() else {
                return;
            };
            match cmd {
                Command::Dwell { ms } => {
                    self.dwell = true;
                    self.wait_left = self.ms_ticks(ms).max(1);
                }
                Command::Pen { level } => {
                    self.dwell = false;
                    self.pen = level.min(PEN_FULL);
                    self.pen_move = Some(PenMove::new(self.shown, self.pen, &self.pen_timing));
                    if !self.run_waits() {
                        return;
                    }
                }
                Command::Move(mv) => {
                    if self.plan(&mv).is_err() {
                        let _ = self.pending.push_front(cmd);
                        return;
                    }
                    // Later moves go straight on, up to the next non-move command.
                    while let Some(Command::Move(next)) = self.pending.front().copied() {
                        if self.plan(&next).is_err() {
                            break;
                        }
                        self.pending.pop_front();
                    }
                }
            }
        }
    }

    /// Queue the wait under way (a dwell's, or the pen move's stages one after the
    /// other, each told to the servo as its wait starts); true once all of it has run.
    fn run_waits(&mut self) -> bool {
        loop {
            if self.wait_left > 0 {
                while self.wait_left > 0 && self.side.sink().room() > 0 {
                    let w = self.wait_left.min(u64::from(MAX_WAIT)) as u32;
                    self.side
                        .sink()
                        .push_slice(&[StepCmd::new(StepEvent(0), w)]);
                    self.wait_left -= u64::from(w);
                    self.queue_end = self.queue_end.wrapping_add(w);
                }
                if self.wait_left > 0 {
                    return false;
                }
                self.waiting = true;
            }
            if self.waiting {
                if self.side.is_running() {
                    return false;
                }
                self.waiting = false;
            }
            let Some(stage) = self.pen_move.as_mut().and_then(PenMove::next) else {
                self.pen_move = None;
                return true;
            };
            self.shown = stage.0;
            self.wait_left = self.ms_ticks(stage.1).max(1);
        }
    }

    /// Hands a move to the planner. A fine line or arc whose exact start is not where
    /// the machine will be (the interpreter's position went stale, e.g. after keypad
    /// moves) runs from where the machine really is: a plain line, or the arc around
    /// the same centre (rounded to a step).
    fn plan(&mut self, mv: &Move) -> Result<(), PlanError> {
        let start = self.planner.end_position();
        let round = |q: i32| q.saturating_add(128).div_euclid(256);
        let stale = |from: [i32; 2]| {
            (round(from[0]) - start[0]).abs() > 1 || (round(from[1]) - start[1]).abs() > 1
        };
        let mut mv = *mv;
        match mv.path {
            Path::LineFine { from, .. } if stale(from) => mv.path = Path::Line,
            Path::ArcFine {
                from,
                center,
                ccw,
                turns,
            } if stale(from) => {
                mv.path = Path::Arc {
                    center: [
                        round(center[0]).wrapping_sub(start[0]),
                        round(center[1]).wrapping_sub(start[1]),
                    ],
                    ccw,
                    turns,
                }
            }
            _ => {}
        }
        self.planner.push(&mv)
    }

    fn executing(&self) -> bool {
        // At rest only once a service tick has seen it (the rest then begins where
        // the timeline ended on every board, and work that comes after it, a sync
        // point's next line, waits for `RESUME_MS`).
        self.rest_ms == MOVING
            || !self.prep.is_idle(&self.planner)
            || self.side.is_running()
            || self.wait_left > 0
            || self.waiting
            || self.pen_move.is_some()
            || self.z_moving()
    }
}

impl<S: StepSide> MotionControl for Pipeline<S> {
    fn push(&mut self, cmd: Command) -> Result<(), QueueFull> {
        if let (Command::Move(mv), true) = (
            cmd,
            self.pending.is_empty() && self.wait_left == 0 && !self.waiting,
        ) {
            return match self.plan(&mv) {
                Ok(()) => Ok(()),
                Err(PlanError::Full) => Err(QueueFull),
                // Invalid geometry (e.g. a zero-length move) is dropped, like Grbl.
                Err(PlanError::Invalid) => Ok(()),
            };
        }
        self.pending.push_back(cmd).map_err(|_| QueueFull)
    }

    fn queued(&self) -> usize {
        self.planner.len() + self.pending.len() + usize::from(self.executing())
    }

    fn capacity(&self) -> usize {
        PLANNER_BLOCKS
    }

    fn hold(&mut self) {
        self.prep.hold();
        // Already at rest (M0, `!` at rest): the pen lifts now, before the shell
        // reads the servo's level and may sleep until the next event.
        self.lift_when_stopped();
    }

    fn resume(&mut self) {
        self.prep.resume(&mut self.planner);
        if self.rest_ms != MOVING {
            // Held at rest: the held path starts again, with its lead.
            self.rest_ms = RESUME_MS;
        }
        if let Some(level) = self.lifted.take() {
            // Down again where it was lifted, the drop time waited, before XY goes on.
            self.pen_move = Some(PenMove::new(0, level, &self.pen_timing));
        }
    }

    fn motion(&self) -> MotionState {
        let hold = self.prep.hold_state();
        if hold != HoldState::Running {
            let waits = self.wait_left > 0 || self.waiting;
            let braking = if hold == HoldState::Held && (self.prep.in_block() || !waits) {
                // At rest in the block, or held between blocks with no wait under
                // way (nothing is in execution, the queue waits): only what runs
                // out of the step queue, and the Z pen's trip, still move.
                self.side.is_running() || self.z_moving() || self.z_lift_due()
            } else {
                self.executing()
            };
            return if braking {
                MotionState::Holding
            } else {
                MotionState::Held
            };
        }
        if !self.executing() {
            MotionState::Idle
        } else if self.dwell && (self.wait_left > 0 || self.waiting) && self.pending.is_empty() {
            // The wait under way is a dwell's, and nothing is behind it. (A dwell
            // that has just been queued starts at the next preparation, within a
            // millisecond.)
            MotionState::Dwelling
        } else {
            MotionState::Running
        }
    }

    fn clear(&mut self) {
        self.side.flush();
        let pos = self.side.position();
        self.prep.abort(pos);
        self.planner.clear(pos);
        self.pending.clear();
        self.wait_left = 0;
        self.waiting = false;
        self.dwell = false;
        // An abort or an alarm leaves the pen up.
        self.pen = 0;
        self.shown = 0;
        self.pen_move = None;
        self.lifted = None;
        // A Z pen stays where the stop found it (its steps end with the rest).
        self.z_trip = None;
        // At rest from now: nothing queued is left on the timeline either.
        self.rest_ms = 0;
        self.queue_end = self.clock.1;
    }

    fn set_overrides(&mut self, feed_percent: u8, rapid_percent: u8) {
        self.planner
            .set_overrides(u16::from(feed_percent), u16::from(rapid_percent));
    }

    fn position(&self) -> StepPos {
        self.side.position()
    }

    fn set_position(&mut self, pos: StepPos) {
        self.side.set_position(pos);
        self.prep.abort(pos);
        self.planner.clear(pos);
    }

    fn speed(&self) -> f32 {
        if self.side.is_running() && !self.waiting && self.wait_left == 0 {
            self.prep.speed() * 60.0
        } else {
            0.0
        }
    }
    fn configure(&mut self, s: &Settings) {
        self.reconfigure(s);
    }
    fn pen_level(&self) -> u16 {
        self.shown
    }
    fn line(&self) -> Option<u32> {
        self.prep.line()
    }
}

#[cfg(test)]
mod tests;
