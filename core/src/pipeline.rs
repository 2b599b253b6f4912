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
use crate::machine::{MotionControl, QueueFull};
use crate::motion::{Command, PEN_FULL};
use crate::motion::{Move, Path, StepPos};
use crate::planner::{AxisConfig, PlanError, Planner, PlannerConfig, Shape, PLANNER_BLOCKS};
use crate::settings::{AccelProfile, Interpolation, Settings};
use crate::stepper::prep::{HoldState, Prep, PrepConfig};
use crate::stepper::{CmdSink, StepCmd, MAX_WAIT};
use heapless::Deque;

/// The interrupt side, as the pipeline sees it.
pub trait StepSide {
    type Sink: CmdSink;
    /// Where prepared step commands go (the SPSC producer on the board).
    fn sink(&mut self) -> &mut Self::Sink;
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
/// Longest wait at rest for more moves before the first starts, in calls of
/// [`Pipeline::fill`] (milliseconds in the firmware): it waits while the planner holds
/// no more moves than [`MIN_AHEAD`] (each has a step at least), so the steps prepared
/// at the start never reach the end of what is queued. Measured on the zigzag
/// benchmark: without it the first moves stop at their ends (the planner had nothing
/// behind them yet).
const START_GATHER_MS: u8 = 8;

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
        // turn_ms * k / n, exactly, in 32 bits (a very slow servo turns for hours:
        // turn_ms * k would overflow; a u64 division costs the image 866 bytes).
        let (q, r) = (self.turn_ms / n, self.turn_ms % n);
        let at = |k: u32| q * k + r * k / n;
        let (from, to) = (i32::from(self.from), i32::from(self.to));
        let level = from + (to - from) * (k as i32 + 1) / n as i32;
        Some((level as u16, at(k + 1) - at(k)))
    }
}

/// Where a Z pen's trip for a hold is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ZStage {
    /// Going up to $205.
    Rising,
    /// Up, waiting for the resume.
    Up,
    /// Going back down to where the hold found it.
    Falling,
}

/// A Z pen's trip up for a hold and back down on resume: raw Z steps straight into
/// the step queue, beside the held block (the planner and the preparation never see
/// them, so the job resumes from exactly the same step count).
#[derive(Clone, Copy, Debug, PartialEq)]
struct ZTrip {
    /// Z where the hold found it: the way back ends here.
    back: i32,
    /// Steps of the way under way queued so far (16 bits: the trip fits in the
    /// pipeline's spare word of RAM; a pen further than 65,535 steps from $205 is not
    /// lifted).
    sent: u16,
    stage: ZStage,
}

/// Most Z steps of a hold's trip queued per [`Pipeline::fill`] (each costs a square
/// root): 32 a millisecond is far above a Z axis' rate.
const Z_STEPS_PER_FILL: u32 = 32;

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
    held: bool,
    /// Calls of [`Pipeline::fill`] spent waiting at rest for a second move.
    gather: u8,
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
            held = false,
            gather = 0,
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

    /// ms * timer_hz / 1000 (floored) with 32-bit divisions only (a u64 division pulls
    /// in an 866-byte runtime routine): split ms into seconds and the rest, hz likewise.
    fn ms_ticks(&self, ms: u32) -> u64 {
        let hz = self.timer_hz;
        let (sec, rest) = (u64::from(ms / 1000), ms % 1000);
        sec * u64::from(hz)
            + u64::from(rest) * u64::from(hz / 1000)
            + u64::from(rest * (hz % 1000) / 1000)
    }

    /// The segment-preparation task: fill the step queue, run dwells and pen commands
    /// in order once the moves before them have been prepared.
    pub fn fill(&mut self) {
        if self.held && self.prep.hold_state() == HoldState::Running {
            // Hold asked between blocks: start nothing new until resumed, but let a
            // wait under way (a pen move, a dwell) end, so that the machine comes to
            // rest (and the pen up).
            self.run_waits();
            self.run_z();
            self.lift_when_stopped();
            self.run_z();
            return;
        }
        if self.held {
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
        let horizon = self.timer_hz / 1000 * HORIZON_MS;
        let queued = self.side.queued();
        if queued == 0
            && self.prep.is_idle_block()
            && (1..=MIN_AHEAD).contains(&self.planner.len())
            && self.pending.is_empty()
        {
            // At rest with a move or two planned: the next ones of a stream are
            // usually a millisecond or two behind. Waiting that long for them (at most
            // START_GATHER_MS) lets the first moves run into the next instead of
            // stopping at their ends; the job still starts with its first step.
            if self.gather < START_GATHER_MS {
                self.gather += 1;
                return;
            }
        }
        self.gather = 0;
        if queued > 0 && 2 * queued >= self.prep.commands_for(horizon).max(MIN_AHEAD) {
            // More than half the horizon is still queued: refill later, in one go.
            return;
        }
        loop {
            let ahead = self.prep.commands_for(horizon).max(MIN_AHEAD);
            let left = ahead.saturating_sub(self.side.queued());
            if self.pen_move.is_some() && !self.run_waits() {
                // The pen goes down again after a hold before anything moves (its
                // waits first in the step queue); a pen move from the queue is
                // only started with nothing prepared, so it is the same there.
                return;
            }
            self.prep.fill(&mut self.planner, self.side.sink(), left);
            if !self.run_waits() {
                return;
            }
            // The path before the head of `pending` is fully prepared: start it.
            if !self.prep.is_idle(&self.planner) {
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

    /// A hold has brought XY to rest (nothing runs, no pen move is under way): the
    /// pen lifts (a servo at once: nothing waits for it; a Z pen on its own trip to
    /// $205 if it stands below it), and remembers where it was.
    // Out of line: its frame stays off the preparation's deepest stack path.
    #[inline(never)]
    fn lift_when_stopped(&mut self) {
        if !self.at_rest() {
            return;
        }
        if self.shown > 0 {
            self.lifted = Some(self.shown);
            self.shown = 0;
        }
        if let Some(z) = self.z_to_lift() {
            self.z_trip = Some(ZTrip {
                back: z,
                sent: 0,
                stage: ZStage::Rising,
            });
        }
    }

    /// Nothing runs and no pen move is under way (a hold may lift the pen).
    fn at_rest(&self) -> bool {
        self.prep.hold_state() != HoldState::Holding
            && !self.side.is_running()
            && self.pen_move.is_none()
            && self.wait_left == 0
            && !self.waiting
            && self.z_trip.is_none()
    }

    /// A Z pen on the paper's side of its up place (or between the two): where Z
    /// stands.
    fn z_to_lift(&self) -> Option<i32> {
        let (up, down) = (self.pen_timing.z_up, self.z_down);
        let z = self.side.position()[2];
        (down != 0 && (z - up).signum() == i32::from(down) && z.abs_diff(up) <= u32::from(u16::MAX))
            .then_some(z)
    }

    /// A held machine at rest whose Z pen is still to be lifted (at the next
    /// [`Pipeline::fill`]): it is not at rest yet.
    fn z_lift_due(&self) -> bool {
        self.held && self.at_rest() && self.z_to_lift().is_some()
    }

    /// Queue the Z pen's trip under way; true when no Z move of a hold is under way
    /// (none, or up and held). Up and no longer held: the way back starts; the trip
    /// ends once Z stands where the hold found it.
    // Out of line: its frame stays off the preparation's deepest stack path.
    #[inline(never)]
    fn run_z(&mut self) -> bool {
        let Some(mut t) = self.z_trip else {
            return true;
        };
        let up = self.pen_timing.z_up;
        loop {
            let (from, to) = match t.stage {
                ZStage::Up if self.held => {
                    self.z_trip = Some(t);
                    return true;
                }
                ZStage::Up => {
                    t.stage = ZStage::Falling;
                    t.sent = 0;
                    continue;
                }
                ZStage::Rising => (t.back, up),
                ZStage::Falling => (up, t.back),
            };
            let n = from.abs_diff(to);
            let tick = StepEvent::from_deltas([0, 0, if to > from { 1 } else { -1 }]);
            let mut budget = Z_STEPS_PER_FILL;
            while u32::from(t.sent) < n && budget > 0 && self.side.sink().room() > 0 {
                let wait = self.z_wait(u32::from(t.sent), n);
                self.side.sink().push_slice(&[StepCmd::new(tick, wait)]);
                t.sent += 1;
                budget -= 1;
            }
            if u32::from(t.sent) < n || self.side.is_running() {
                self.z_trip = Some(t);
                return false;
            }
            match t.stage {
                ZStage::Rising => t.stage = ZStage::Up,
                _ => {
                    self.z_trip = None;
                    return true;
                }
            }
        }
    }

    /// The wait after step `k` of a Z way of `n` steps, timer counts: Z's own
    /// acceleration ($122) from rest and to rest, capped at its rate ($112).
    fn z_wait(&self, k: u32, n: u32) -> u32 {
        let z = &self.planner.config().axes[2];
        let max = z.max_rate / 60.0 * z.steps_per_mm;
        let accel = z.accel * z.steps_per_mm;
        // Steps from the nearer end, to the step's middle.
        let d = k.min(n - 1 - k) as f32 + 0.5;
        let v = crate::fmath::sqrt(2.0 * accel * d).min(max).max(1.0);
        crate::decimal::to_u32(self.timer_hz as f32 / v)
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
        !self.prep.is_idle(&self.planner)
            || self.side.is_running()
            || self.wait_left > 0
            || self.waiting
            || self.pen_move.is_some()
            || self.z_moving()
    }

    /// A Z pen's trip for a hold is under way (or due: up and resumed).
    fn z_moving(&self) -> bool {
        self.z_trip
            .is_some_and(|t| t.stage != ZStage::Up || !self.held)
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
        self.held = true;
        self.prep.hold();
        // Already at rest (M0, `!` at rest): the pen lifts now, before the shell
        // reads the servo's level and may sleep until the next event.
        self.lift_when_stopped();
    }

    fn resume(&mut self) {
        self.held = false;
        self.prep.resume(&mut self.planner);
        if let Some(level) = self.lifted.take() {
            // Down again where it was lifted, the drop time waited, before XY goes on.
            self.pen_move = Some(PenMove::new(0, level, &self.pen_timing));
        }
    }

    fn is_holding(&self) -> bool {
        self.held || self.prep.hold_state() != HoldState::Running
    }

    fn is_moving(&self) -> bool {
        if self.prep.hold_state() == HoldState::Held {
            return self.side.is_running() || self.z_moving() || self.z_lift_due();
        }
        if self.held
            && self.prep.hold_state() == HoldState::Running
            && self.wait_left == 0
            && !self.waiting
        {
            // Hold asked between blocks: nothing is in execution, the queue waits.
            return self.side.is_running() || self.z_moving() || self.z_lift_due();
        }
        self.executing()
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
        self.held = false;
        // An abort or an alarm leaves the pen up.
        self.pen = 0;
        self.shown = 0;
        self.pen_move = None;
        self.lifted = None;
        // A Z pen stays where the stop found it (its steps end with the rest).
        self.z_trip = None;
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
    fn dwelling(&self) -> bool {
        // The wait under way is a dwell's, and nothing is behind it. (A dwell that
        // has just been queued starts at the next preparation, within a millisecond.)
        self.dwell && (self.wait_left > 0 || self.waiting) && self.pending.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{Feed, X, Y};
    use crate::stepper::queue::StepQueue;
    use crate::stepper::{CmdSource, TIMER_HZ};

    /// A side whose "interrupt" is the test: it drains the queue by hand.
    struct TestSide {
        queue: StepQueue<256>,
        pos: StepPos,
        /// Ticks left of the command the "timer" runs now ([`run_timed`]).
        busy: u64,
    }

    impl StepSide for TestSide {
        type Sink = StepQueue<256>;
        fn sink(&mut self) -> &mut Self::Sink {
            &mut self.queue
        }
        fn position(&self) -> StepPos {
            self.pos
        }
        fn is_running(&self) -> bool {
            self.queue.queued() > 0 || self.busy > 0
        }
        fn queued(&self) -> usize {
            self.queue.queued()
        }
        fn flush(&mut self) {
            self.queue.clear();
            self.busy = 0;
        }
        fn set_position(&mut self, p: StepPos) {
            self.pos = p;
        }
    }

    /// Runs everything queued; returns the shortest wait between two steps of `axis`
    /// (timer counts), i.e. the cruise speed.
    fn run(pipeline: &mut Pipeline<TestSide>, axis: usize) -> u32 {
        let mut fastest = u32::MAX;
        for _ in 0..1_000_000 {
            pipeline.fill();
            if MotionControl::queued(pipeline) == 0 {
                break;
            }
            let side = pipeline.side_mut();
            while let Some(c) = side.queue.pop() {
                c.tick().apply(&mut side.pos);
                if c.tick().steps() & (1 << axis) != 0 {
                    fastest = fastest.min(c.wait());
                }
            }
        }
        fastest
    }

    fn mv(target: StepPos, feed: Feed) -> Command {
        Command::Move(Move {
            target,
            path: Path::Line,
            feed,
            line: 0,
        })
    }

    /// A dwell alone is reported as dwelling (the machine shows Idle, as Grbl does);
    /// a move, or a pen lift's wait, is not.
    #[test]
    fn a_dwell_alone_is_dwelling_and_nothing_else_is() {
        let mut s = Settings::default();
        s.set(201, 1.0).unwrap(); // servo pen: its lift is a timed wait too
        let mut pipeline = test_pipeline(&s);
        pipeline.push(Command::Dwell { ms: 50 }).unwrap();
        pipeline.fill();
        assert!(pipeline.dwelling() && pipeline.is_moving(), "running");
        run(&mut pipeline, X);
        assert!(pipeline.is_idle());

        pipeline
            .push(mv([800, 0, 0], Feed::MmPerMin(600.0)))
            .unwrap();
        pipeline.push(Command::Dwell { ms: 50 }).unwrap();
        pipeline.fill();
        assert!(!pipeline.dwelling(), "a move runs first");
        pipeline.push(Command::Pen { level: PEN_FULL }).unwrap();
        run(&mut pipeline, X);
        pipeline.push(Command::Pen { level: 0 }).unwrap();
        pipeline.fill();
        assert!(pipeline.is_moving() && !pipeline.dwelling(), "a pen lift");
    }

    /// A pipeline on the default preparation, its steps into a test queue.
    fn test_pipeline(s: &Settings) -> Pipeline<TestSide> {
        Pipeline::new(
            s,
            PrepConfig::default(),
            TestSide {
                queue: StepQueue::new(),
                pos: [0; 3],
                busy: 0,
            },
        )
    }

    /// Runs the step queue for `ms` milliseconds of timer time (the preparation every
    /// millisecond, as the firmware's task).
    fn run_for(pipeline: &mut Pipeline<TestSide>, ms: u32) {
        let per_ms = u64::from(TIMER_HZ / 1000);
        for _ in 0..ms {
            pipeline.fill();
            let mut t = 0u64;
            let side = pipeline.side_mut();
            while t < per_ms {
                let Some(c) = side.queue.pop() else { break };
                c.tick().apply(&mut side.pos);
                t += u64::from(c.wait());
            }
        }
    }

    /// `FS:` is the feed the machine runs at: within 1 % at cruise (long moves run in
    /// segments, which once left the start rate showing), the ramp in between, 0 at rest.
    #[test]
    fn the_reported_speed_is_the_real_feed_at_cruise_and_zero_at_rest() {
        let s = Settings::default();
        let mut pipeline = test_pipeline(&s);
        assert_eq!(pipeline.speed(), 0.0);
        for (target, feed) in [(4800, 1500.0), (12800, 3000.0), (0, 600.0)] {
            pipeline
                .push(mv([target, 0, 0], Feed::MmPerMin(feed)))
                .unwrap();
            // Mid-move: the ramps (at most 3000 / 60 / 200 = 0.25 s) are over.
            run_for(&mut pipeline, 400);
            let v = pipeline.speed();
            assert!((v - feed).abs() <= feed * 0.01, "F{feed}: FS {v} mid-move");
            run(&mut pipeline, X);
            assert_eq!(pipeline.position()[X], target);
            assert_eq!(pipeline.speed(), 0.0, "at rest");
        }
    }

    #[test]
    fn overrides_survive_a_setting_change() {
        let mut s = Settings::default();
        let mut pipeline = test_pipeline(&s);
        pipeline.set_overrides(150, 50);
        // A setting changes at rest (the machine still reports Ov:150,50).
        s.set(120, 300.0).unwrap();
        pipeline.configure(&s);
        assert_eq!(pipeline.planner().feed_override(), 150);
        assert_eq!(pipeline.planner().config().axes[X].accel, 300.0);

        // 100 mm at F1000 with 150 %: 25 mm/s = 2000 steps/s = 36,000 timer counts.
        pipeline
            .push(mv([8000, 0, 0], Feed::MmPerMin(1000.0)))
            .unwrap();
        let wait = run(&mut pipeline, X);
        assert!(
            (35_900..=36_100).contains(&wait),
            "feed: {wait} ticks per step"
        );
        // Rapid at 50 % of 3000 mm/min: 25 mm/s again.
        pipeline.push(mv([8000, 8000, 0], Feed::Rapid)).unwrap();
        let wait = run(&mut pipeline, Y);
        assert!(
            (35_900..=36_100).contains(&wait),
            "rapid: {wait} ticks per step"
        );
        assert_eq!(pipeline.position(), [8000, 8000, 0]);
    }

    /// Runs `ms` milliseconds of timer time exactly (a command steps, then waits its
    /// ticks), the preparation every millisecond; logs each millisecond's end: the pen
    /// level shown and the position.
    fn run_timed(pipeline: &mut Pipeline<TestSide>, ms: u32, log: &mut Vec<(u16, StepPos)>) {
        let per_ms = u64::from(TIMER_HZ / 1000);
        for _ in 0..ms {
            pipeline.fill();
            let mut budget = per_ms;
            let side = pipeline.side_mut();
            while budget > 0 {
                if side.busy == 0 {
                    let Some(c) = side.queue.pop() else { break };
                    c.tick().apply(&mut side.pos);
                    side.busy = u64::from(c.wait());
                }
                let take = side.busy.min(budget);
                side.busy -= take;
                budget -= take;
            }
            log.push((pipeline.pen_level(), pipeline.position()));
        }
    }

    /// A servo pen at 90 deg up / 30 deg down with 100 ms lift ($204) and 300 ms drop
    /// ($207) times.
    fn servo_settings(speed: f32) -> Settings {
        let mut s = Settings::default();
        for (n, v) in [
            (201, 1.0),
            (202, 90.0),
            (203, 30.0),
            (204, 100.0),
            (207, 300.0),
        ] {
            s.set(n, v).unwrap();
        }
        s.set(208, speed).unwrap();
        s
    }

    /// Milliseconds until the pipeline is at rest.
    fn ms_to_rest(pipeline: &mut Pipeline<TestSide>, log: &mut Vec<(u16, StepPos)>) -> usize {
        let from = log.len();
        while pipeline.is_moving() || MotionControl::queued(pipeline) > 0 {
            run_timed(pipeline, 1, log);
            assert!(log.len() - from < 100_000, "never at rest");
        }
        log.len() - from
    }

    /// The drop waits $207, the lift $204; with a speed ($208) the servo is told the
    /// way frame by frame (20 ms) and the wait grows by the turn's time: 60 deg at 600
    /// deg/s = 100 ms. Default settings: one wait of 150 ms each way, as before.
    #[test]
    fn lift_and_drop_wait_their_own_times_and_the_turn_at_the_servo_speed() {
        let mut log = Vec::new();
        let mut p = test_pipeline(&servo_settings(0.0));
        p.push(Command::Pen { level: PEN_FULL }).unwrap();
        let drop = ms_to_rest(&mut p, &mut log);
        assert!((300..=301).contains(&drop), "drop {drop} ms");
        assert_eq!(p.pen_level(), PEN_FULL);
        p.push(Command::Pen { level: 0 }).unwrap();
        let lift = ms_to_rest(&mut p, &mut log);
        assert!((100..=101).contains(&lift), "lift {lift} ms");
        assert_eq!(p.pen_level(), 0);

        let mut p = test_pipeline(&servo_settings(600.0));
        log.clear();
        p.push(Command::Pen { level: PEN_FULL }).unwrap();
        let drop = ms_to_rest(&mut p, &mut log);
        // 100 ms turn + 300 ms drop; at most a millisecond between frames.
        assert!((400..=406).contains(&drop), "slow drop {drop} ms");
        let levels: Vec<u16> = log.iter().map(|e| e.0).collect();
        let mut seen = levels.clone();
        seen.dedup();
        assert_eq!(seen, [200, 400, 600, 800, 1000], "told frame by frame");
        let at_full = levels.iter().position(|&l| l == PEN_FULL).unwrap();
        assert!(
            (80..=85).contains(&at_full),
            "fully down after {at_full} ms"
        );
        // Half a turn back (M3 S500): 50 ms, then the lift time.
        p.push(Command::Pen { level: 500 }).unwrap();
        let half = ms_to_rest(&mut p, &mut log);
        assert!((150..=154).contains(&half), "half lift {half} ms");
        assert_eq!(p.pen_level(), 500);

        let mut servo = Settings::default();
        servo.set(201, 1.0).unwrap();
        let mut p = test_pipeline(&servo);
        p.push(Command::Pen { level: PEN_FULL }).unwrap();
        assert!(
            (150..=151).contains(&ms_to_rest(&mut p, &mut log)),
            "default drop"
        );
        p.push(Command::Pen { level: 0 }).unwrap();
        assert!(
            (150..=151).contains(&ms_to_rest(&mut p, &mut log)),
            "default lift"
        );
    }

    /// A hold in the middle of a stroke: once XY is at rest the pen lifts; on resume
    /// it goes down where it was, waits the drop time with XY still, and the stroke
    /// goes on to its exact end. A clear (abort, alarm) leaves it up.
    #[test]
    fn a_hold_lifts_the_pen_at_rest_and_resume_drops_it_before_xy_moves_on() {
        let mut log = Vec::new();
        let mut p = test_pipeline(&servo_settings(0.0));
        p.push(Command::Pen { level: PEN_FULL }).unwrap();
        p.push(mv([8000, 0, 0], Feed::MmPerMin(600.0))).unwrap();
        p.push(Command::Pen { level: 0 }).unwrap();
        run_timed(&mut p, 800, &mut log);
        assert_eq!(p.pen_level(), PEN_FULL, "drawing");
        assert!(p.position()[X] > 0);
        p.hold();
        while p.is_moving() {
            run_timed(&mut p, 1, &mut log);
            assert_eq!(p.pen_level(), PEN_FULL, "down while XY brakes");
        }
        run_timed(&mut p, 1, &mut log);
        assert_eq!(p.pen_level(), 0, "lifted at rest");
        let held = p.position();
        run_timed(&mut p, 500, &mut log);
        assert_eq!((p.pen_level(), p.position()), (0, held), "up while held");
        p.resume();
        log.clear();
        run_timed(&mut p, 320, &mut log);
        let first_step = log.iter().position(|e| e.1 != held).unwrap();
        assert!(
            (300..=302).contains(&first_step),
            "XY waited {first_step} ms"
        );
        assert!(
            log.iter().all(|e| e.0 == PEN_FULL),
            "down from the resume on"
        );
        ms_to_rest(&mut p, &mut log);
        assert_eq!((p.position(), p.pen_level()), ([8000, 0, 0], 0));

        p.push(Command::Pen { level: PEN_FULL }).unwrap();
        p.push(mv([0, 0, 0], Feed::MmPerMin(600.0))).unwrap();
        run_timed(&mut p, 500, &mut log);
        assert_eq!(p.pen_level(), PEN_FULL);
        p.clear();
        assert_eq!(p.pen_level(), 0, "an abort leaves the pen up");
    }

    /// The slowest servo speed the settings allow: a turn of hours, told in the most
    /// frames a pen move has, with no overflow on the way.
    #[test]
    fn a_very_slow_servo_turn_is_computed_without_overflow() {
        let t = PenTiming::from(&servo_settings(0.001));
        let mut m = PenMove::new(0, PEN_FULL, &t);
        // 60 deg at 0.001 deg/s: 6e7 ms (to f32's precision).
        assert!(m.turn_ms.abs_diff(60_000_000) < 10, "{}", m.turn_ms);
        let turn = u64::from(m.turn_ms);
        let (mut levels, mut total) = (0u32, 0u64);
        while let Some((level, ms)) = m.next() {
            levels += 1;
            total += u64::from(ms);
            assert!(level <= PEN_FULL);
        }
        assert_eq!(levels, u32::from(u16::MAX));
        assert_eq!(total, turn + 300, "the turn, then the drop time");
    }

    /// A hold during a pen drop: the drop ends, the machine comes to rest (not stuck
    /// braking), the pen lifts; resume drops it again before the stroke.
    #[test]
    fn a_hold_during_a_pen_drop_comes_to_rest_with_the_pen_up() {
        let mut log = Vec::new();
        let mut p = test_pipeline(&servo_settings(0.0));
        p.push(Command::Pen { level: PEN_FULL }).unwrap();
        p.push(mv([800, 0, 0], Feed::MmPerMin(600.0))).unwrap();
        run_timed(&mut p, 100, &mut log);
        p.hold();
        run_timed(&mut p, 250, &mut log);
        assert!(!p.is_moving(), "at rest");
        assert_eq!((p.pen_level(), p.position()), (0, [0, 0, 0]));
        p.resume();
        log.clear();
        ms_to_rest(&mut p, &mut log);
        let first_step = log.iter().position(|e| e.1 != [0, 0, 0]).unwrap();
        assert!(
            (300..=302).contains(&first_step),
            "dropped again: {first_step} ms"
        );
        assert_eq!(p.position(), [800, 0, 0]);
    }

    /// Runs one step command at a time until at rest or `until` says stop; logs the
    /// position after each.
    fn run_steps(
        p: &mut Pipeline<TestSide>,
        log: &mut Vec<StepPos>,
        mut until: impl FnMut(&Pipeline<TestSide>) -> bool,
    ) {
        for _ in 0..10_000_000 {
            if until(p) {
                return;
            }
            p.fill();
            let side = p.side_mut();
            match side.queue.pop() {
                Some(c) => {
                    c.tick().apply(&mut side.pos);
                    log.push(side.pos);
                }
                None if !p.is_moving() && MotionControl::queued(p) == 0 => return,
                None => {}
            }
        }
        panic!("never at rest");
    }

    /// A Z pen ($201=0): a hold mid-stroke lifts Z to $205 once XY is at rest (XY
    /// still, Hold:0 only once Z is up), resume brings it back to the same step before
    /// XY moves on, and the steps drawn with the pen down are exactly those of the
    /// uninterrupted job. An abort leaves Z where it stands.
    #[test]
    fn a_z_pen_goes_up_for_a_hold_and_back_down_before_the_stroke_goes_on() {
        let s = Settings::default();
        let spm = s.steps_per_mm(2);
        let (up, down) = (
            crate::fmath::round(s.pen_z_up() * spm) as i32,
            crate::fmath::round(s.pen_z_down() * spm) as i32,
        );
        assert!(down < up, "default: down below up");
        let job = |p: &mut Pipeline<TestSide>| {
            for target in [[0, 0, down], [8000, 3000, down], [8000, 3000, up]] {
                p.push(mv(target, Feed::MmPerMin(600.0))).unwrap();
            }
        };
        let drawn = |log: &[StepPos]| -> Vec<[i32; 2]> {
            let mut d: Vec<[i32; 2]> = log
                .iter()
                .filter(|q| q[2] == down)
                .map(|q| [q[0], q[1]])
                .collect();
            d.dedup();
            d
        };
        let mut whole = Vec::new();
        let mut p = test_pipeline(&s);
        job(&mut p);
        run_steps(&mut p, &mut whole, |_| false);
        assert_eq!(p.position(), [8000, 3000, up]);

        let mut log = Vec::new();
        let mut p = test_pipeline(&s);
        job(&mut p);
        run_steps(&mut p, &mut log, |p| p.position()[X] >= 4000);
        p.hold();
        let held_at = log.len();
        run_steps(&mut p, &mut log, |p| !p.is_moving());
        let rest = p.position();
        assert_eq!(rest[2], up, "Z up once at rest");
        let xy_stop = held_at + log[held_at..].iter().position(|q| q[2] != down).unwrap();
        assert!(
            log[xy_stop..]
                .iter()
                .all(|q| [q[0], q[1]] == [rest[0], rest[1]]),
            "XY still while Z rises"
        );
        // Held: nothing moves.
        for _ in 0..100 {
            p.fill();
        }
        assert!(p.side().queue.queued() == 0 && p.position() == rest);
        p.resume();
        let from = log.len();
        run_steps(&mut p, &mut log, |_| false);
        let back = log[from..].iter().position(|q| q[2] == down).unwrap();
        assert!(
            log[from..from + back]
                .iter()
                .all(|q| [q[0], q[1]] == [rest[0], rest[1]]),
            "XY still until Z is back down"
        );
        assert_eq!(p.position(), [8000, 3000, up], "nothing lost");
        assert_eq!(drawn(&log), drawn(&whole), "the same strokes");

        let mut p = test_pipeline(&s);
        job(&mut p);
        run_steps(&mut p, &mut log, |p| p.position()[X] >= 4000);
        p.hold();
        run_steps(&mut p, &mut log, |p| {
            p.position()[2] > down && p.position()[2] < up
        });
        let stop = p.position();
        p.clear();
        for _ in 0..10 {
            p.fill();
        }
        assert_eq!(p.position(), stop, "an abort leaves Z where it stands");
        assert!(p.is_idle());
    }
}
