//! Look-ahead planner: a queue of blocks whose entry speeds are re-planned every time
//! a move is added, so the machine only slows where the path needs it.
//!
//! Owns: the block queue, junction speeds, the reverse/forward planning passes and the
//! feed and rapid overrides. It knows nothing about time slices or steps; the step
//! engine pops the oldest block, reports how fast it runs and how much of it is left
//! ([`Planner::head_runs`]: the planner decides what that allows the next block), and
//! asks [`Planner::exit_speed`] how fast it may leave.
//!
//! Semantics follow Grbl's documented behaviour (settings $110.. max rate in mm/min,
//! $120.. acceleration in mm/s^2, $11 junction deviation), written from the maths:
//! - along direction u, path acceleration is min_i a_i/|u_i|, speed min_i v_i/|u_i|;
//! - at a junction with angle theta between the incoming and outgoing directions, the
//!   speed is limited to v^2 = a_j * delta * sin(theta/2) / (1 - sin(theta/2)), where
//!   a_j is the per-axis acceleration limit along the change of direction;
//! - a start speed below which motors may start and stop at once replaces zero;
//! - curves (arcs, ellipses, sines) are single blocks, limited by their centripetal
//!   acceleration, so they never slow down at chord joints.
//!
//! Planning uses the profile shape's effective acceleration, so S-curves plan right.

pub mod geometry;
pub mod profile;

use crate::interpolation::Method;
use crate::motion::{Feed, Move, StepPos, AXES, POS_LIMIT};
use heapless::Deque;
pub use profile::{Profile, Shape};

/// Look-ahead depth.
pub const PLANNER_BLOCKS: usize = 24;

/// Limits of one axis, in Grbl's units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisConfig {
    /// $100..: steps per mm.
    pub steps_per_mm: f32,
    /// $110..: maximum rate, mm/min.
    pub max_rate: f32,
    /// $120..: acceleration, mm/s^2.
    pub accel: f32,
}

/// Everything the planner and step engine need from the settings.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlannerConfig {
    pub axes: [AxisConfig; AXES],
    /// $11: junction deviation, mm.
    pub junction_deviation: f32,
    /// Path speed (mm/s) below which the motors start and stop without a ramp.
    pub start_speed: f32,
    /// Ramp shape: trapezoid or cosine S-curve.
    pub shape: Shape,
    /// Interpolation method.
    pub method: Method,
    /// Step events per second no block may exceed: the step pipeline's cap, or less
    /// where the step pulse (`$0`) needs longer periods
    /// ([`crate::stepper::event_rate_for_pulse`]).
    pub max_event_rate: f32,
}

impl Default for PlannerConfig {
    /// The reference settings of the benchmark programs: 80 steps/mm, 5000 mm/min,
    /// 500 mm/s^2 on X and Y, junction deviation 0.01 mm, no start speed.
    fn default() -> Self {
        let xy = AxisConfig {
            steps_per_mm: 80.0,
            max_rate: 5000.0,
            accel: 500.0,
        };
        let z = AxisConfig {
            steps_per_mm: 80.0,
            max_rate: 1000.0,
            accel: 200.0,
        };
        PlannerConfig {
            axes: [xy, xy, z],
            junction_deviation: 0.01,
            start_speed: 0.0,
            shape: Shape::Trapezoid,
            method: Method::Dda,
            max_event_rate: crate::stepper::MAX_STEP_RATE,
        }
    }
}

/// One planned move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    /// The move (its start is where the previous block ended).
    pub mv: Move,
    /// Path length, mm.
    pub length: f32,
    /// Path acceleration limit (peak), mm/s^2.
    pub accel: f32,
    /// Requested speed before overrides, mm/s.
    pub nominal: f32,
    /// Axis and curvature speed limit, mm/s.
    pub limit: f32,
    /// Junction limit on the entry speed, mm/s.
    pub max_entry: f32,
    /// Planned entry speed squared, mm^2/s^2 (the passes work in squares: no root
    /// per block; [`Block::entry`] takes it).
    entry_sq: f32,
    /// What the planning passes last computed for this block (see [`Planner::replan`]).
    passes: Passes,
}

/// The planning passes' results for one block, kept so that a pass stops where
/// nothing changes. All of them are squared speeds (mm^2/s^2): a pass then costs one
/// soft-float addition and an integer comparison per block, where speeds cost a
/// square, an addition and often a root (with speeds, the protocol task took 28,500
/// instructions a line on bench/dashes.nc, whose every new move raises the whole
/// queue; now 22,500: `cargo emu run bench/dashes.nc --profile 10`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Passes {
    /// `2 a L`: the change of squared speed this block allows (its planning
    /// acceleration a, its length L).
    reach: f32,
    /// The entry limit squared: junction limit and maximum speed with the overrides.
    limit_sq: f32,
    /// Reverse pass: the square of the fastest entry from which the rest of the queue
    /// can still stop. It depends only on this block and those after it.
    reverse_sq: f32,
    /// Forward pass: the square of the fastest exit reachable from the entry (its
    /// exact bits); NaN until computed. (Exact bits because these passes must give
    /// exactly what full passes give: the simulator's figures and golden tests depend
    /// on them.)
    exit_sq: f32,
}

/// How much of the reverse pass a replan needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Reverse {
    /// A block was added at the tail: from there back only as far as results can
    /// change (see [`Planner::replan`]).
    FromTail,
    /// Speed limits of every block changed (an override).
    All,
    /// Nothing after the executing block changed (a new head cap).
    None,
}

impl Block {
    /// Planned entry speed, mm/s.
    pub fn entry(&self) -> f32 {
        crate::fmath::sqrt(self.entry_sq)
    }

    pub fn is_rapid(&self) -> bool {
        self.mv.feed == Feed::Rapid
    }

    /// [`Planner::max_speed`] with these overrides (fractions of 1).
    fn max_speed(&self, feed_override: f32, rapid_override: f32) -> f32 {
        if self.is_rapid() {
            self.limit * rapid_override
        } else {
            (self.nominal * feed_override).min(self.limit)
        }
    }
}

/// Why a move was not queued.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanError {
    /// The queue is full: try again after the step engine took a block.
    Full,
    /// The move's geometry is invalid.
    Invalid,
}

/// The look-ahead planner.
#[derive(Debug)]
pub struct Planner {
    cfg: PlannerConfig,
    blocks: Deque<Block, PLANNER_BLOCKS>,
    /// Where the next queued move starts.
    next_start: StepPos,
    /// Direction and speed limit at the end of the last queued move, if the machine
    /// will still be moving when it ends (None after a stop).
    prev: Option<([f32; AXES], f32)>,
    feed_override: f32,
    rapid_override: f32,
    /// Highest exit speed the block in execution can still reach (mm/s).
    head_cap: f32,
    /// Leading blocks whose entry the last forward pass set to its cap.
    capped: usize,
    /// Leading blocks whose stored reverse result is only a lower bound (at most
    /// `capped`; see [`Planner::replan`]).
    stale: usize,
    generation: u32,
}

impl Planner {
    pub fn new(cfg: PlannerConfig, position: StepPos) -> Self {
        crate::in_place::build(|slot| Planner::init_in(slot, cfg, position))
    }

    /// [`Planner::new`] built in `slot` (the firmware's static pipeline cell, through
    /// [`Pipeline::init_in`](crate::pipeline::Pipeline::init_in)): field by field, so that the
    /// block buffer is not built on the stack and copied.
    #[allow(unsafe_code)]
    pub fn init_in(
        slot: &mut core::mem::MaybeUninit<Planner>,
        cfg: PlannerConfig,
        position: StepPos,
    ) -> &mut Planner {
        crate::init_fields!(slot => Planner {
            cfg = cfg,
            blocks = Deque::new(),
            next_start = position,
            prev = None,
            feed_override = 1.0,
            rapid_override = 1.0,
            head_cap = cfg.start_speed,
            capped = 0,
            stale = 0,
            generation = 0,
        })
    }

    pub fn config(&self) -> &PlannerConfig {
        &self.cfg
    }
    /// Queued blocks (not counting the one in execution).
    pub fn len(&self) -> usize {
        self.blocks.len()
    }
    pub fn is_empty(&self) -> bool {
        self.blocks.is_empty()
    }
    pub fn is_full(&self) -> bool {
        self.blocks.is_full()
    }
    /// Free slots, for the protocol's `Bf:` report.
    pub fn free(&self) -> usize {
        PLANNER_BLOCKS - self.blocks.len()
    }
    /// Changes every time planned speeds may have changed; the step engine rebuilds
    /// its profile when it sees a new value.
    pub fn generation(&self) -> u32 {
        self.generation
    }
    /// Where the next move will start.
    pub fn end_position(&self) -> StepPos {
        self.next_start
    }

    /// Queues a move. Zero-length moves are accepted and dropped; a move that starts
    /// or ends outside +-[`POS_LIMIT`] steps is invalid.
    pub fn push(&mut self, mv: &Move) -> Result<(), PlanError> {
        if self.blocks.is_full() {
            return Err(PlanError::Full);
        }
        let ends = mv.target.iter().chain(self.next_start.iter());
        if ends.into_iter().any(|v| v.unsigned_abs() >= POS_LIMIT) {
            return Err(PlanError::Invalid);
        }
        let g = match geometry::of_move(&self.cfg, self.next_start, mv) {
            Ok(g) => g,
            Err(geometry::GeometryError::Empty) => return Ok(()),
            Err(geometry::GeometryError::Invalid) => return Err(PlanError::Invalid),
        };
        let nominal = match mv.feed {
            Feed::Rapid => f32::INFINITY,
            // NaN, zero, negative and infinite fail one of the two comparisons.
            Feed::MmPerMin(f) if f > 0.0 && f <= f32::MAX => f / 60.0,
            Feed::MmPerMin(_) => return Err(PlanError::Invalid),
        };
        let floor = self.cfg.start_speed;
        let max_entry = match self.prev {
            None => floor,
            Some((u_prev, prev_limit)) => {
                let v = junction_speed(&self.cfg, u_prev, g.unit_start, self.cfg.shape);
                v.min(prev_limit)
                    .min(g.speed_limit)
                    .min(nominal)
                    .max(floor.min(g.speed_limit))
            }
        };
        let accel = g.accel;
        let mut block = Block {
            mv: *mv,
            length: g.length,
            accel,
            nominal,
            limit: g.speed_limit,
            max_entry,
            entry_sq: floor * floor,
            passes: Passes {
                reach: 0.0,
                limit_sq: 0.0,
                reverse_sq: floor * floor,
                exit_sq: f32::NAN,
            },
        };
        block.passes.reach = 2.0 * self.plan_accel(&block) * block.length;
        block.passes.limit_sq = square(block.max_entry.min(self.max_speed(&block)));
        self.prev = Some((g.unit_end, g.speed_limit.min(nominal)));
        self.next_start = mv.target;
        // Cannot fail: checked for room above.
        let _ = self.blocks.push_back(block);
        self.replan(Reverse::FromTail);
        Ok(())
    }

    /// Takes the oldest block for execution.
    pub fn pop(&mut self) -> Option<Block> {
        let b = self.blocks.pop_front();
        if b.is_some() {
            self.capped = self.capped.saturating_sub(1);
            self.stale = self.stale.saturating_sub(1);
            self.generation = self.generation.wrapping_add(1);
        }
        b
    }

    /// The machine came to a stop with nothing queued: the next move starts from rest.
    pub fn note_stopped(&mut self) {
        if self.blocks.is_empty() {
            self.prev = None;
        }
    }

    /// Speed the block in execution should leave at: the next block's planned entry
    /// (or the start speed when nothing follows).
    pub fn exit_speed(&self) -> f32 {
        self.blocks
            .front()
            .map(Block::entry)
            .unwrap_or(self.cfg.start_speed)
    }

    /// The step engine reports where the block in execution (`block`, popped from
    /// here) is: running at `v` with `rest` of its length ahead. The fastest exit it
    /// can still reach, accelerating all the way, caps the next block's entry: the
    /// forward pass starts from it (and replans if the cap binds).
    pub fn head_runs(&mut self, block: &Block, v: f32, rest: f32) {
        let ae = self.plan_accel(block);
        self.set_head_cap(crate::fmath::sqrt(v * v + 2.0 * ae * rest));
    }

    /// The fastest exit the block in execution can still reach; the forward pass
    /// starts from it.
    fn set_head_cap(&mut self, cap: f32) {
        if (cap - self.head_cap).abs() <= 1e-3 {
            return;
        }
        // The cap only matters if it binds the first block's entry now or did before
        // (compared as squares: no root).
        let entry_sq = self.blocks.front().map_or(0.0, |b| b.entry_sq);
        let was = (self.head_cap - 1e-3).max(0.0);
        let binds = entry_sq >= was * was || entry_sq > cap * cap;
        self.head_cap = cap;
        if binds {
            self.replan(Reverse::None);
        }
    }

    /// Maximum speed of `b` with the overrides applied (mm/s). A rapid's nominal speed
    /// is unbounded (as fast as the axes allow): its override scales the axis limit.
    pub fn max_speed(&self, b: &Block) -> f32 {
        b.max_speed(self.feed_override, self.rapid_override)
    }

    /// Feed and rapid overrides in percent (Grbl: feed 10..200, rapid 25, 50, 100),
    /// set together: one replan for both.
    pub fn set_overrides(&mut self, feed_percent: u16, rapid_percent: u16) {
        self.feed_override = f32::from(feed_percent.clamp(10, 200)) / 100.0;
        self.rapid_override = f32::from(rapid_percent.clamp(1, 100)) / 100.0;
        self.replan(Reverse::All);
    }
    pub fn feed_override(&self) -> u16 {
        (self.feed_override * 100.0 + 0.5) as u16
    }

    /// Effective (planning) acceleration of a block.
    pub fn plan_accel(&self, b: &Block) -> f32 {
        self.cfg.shape.effective_accel(b.accel)
    }

    /// New limits (settings change only at rest, with nothing queued): drops what is
    /// queued and restarts from `position` like [`Planner::clear`], but keeps the feed
    /// and rapid overrides, which the machine still reports. Configures in place: no
    /// second planner on the stack.
    pub fn reconfigure(&mut self, cfg: &PlannerConfig, position: StepPos) {
        self.cfg = *cfg;
        self.clear(position);
    }

    /// Drops every queued block (after a hold, for abort) and restarts from `position`.
    pub fn clear(&mut self, position: StepPos) {
        self.blocks.clear();
        self.next_start = position;
        self.prev = None;
        self.head_cap = self.cfg.start_speed;
        self.capped = 0;
        self.stale = 0;
        self.generation = self.generation.wrapping_add(1);
    }

    /// Reverse pass (every block must be able to slow to the next one's entry), then
    /// forward pass (and to reach it from the previous one's).
    ///
    /// The result is bit for bit that of full passes over the queue, at a fraction of
    /// the cost (two soft-float square roots per queued block were most of a G-code
    /// line's CPU time on the M3):
    /// - the reverse pass stops at the first block whose result comes out as before
    ///   (the blocks before it depend only on it and on themselves);
    /// - when a block was added and every result so far rose or stayed, it also stops
    ///   at the prefix of blocks whose entry the forward pass capped (reverse result
    ///   at or above the cap): their true reverse results can only have risen, so
    ///   those entries stay the cap. Their stored results are then lower bounds
    ///   (`stale`), brought up to date only when a forward pass needs them (a lower
    ///   head cap, after pops);
    /// - the forward pass reuses a block's exit speed while its entry is unchanged.
    ///
    /// Everything is in squared speeds, compared as integers ([`at_most`]): no root at
    /// all (the step engine takes one, of the first block's entry, [`Planner::exit_speed`]).
    fn replan(&mut self, reverse: Reverse) {
        if reverse != Reverse::None {
            self.reverse_pass(reverse == Reverse::FromTail);
        }
        if !self.forward_pass() {
            self.refresh_stale();
            let _ = self.forward_pass();
        }
        self.generation = self.generation.wrapping_add(1);
    }

    /// The square of the fastest entry into `b` from which it can still slow to an
    /// entry of `next_sq` into the next: min(limit^2, next^2 + 2 a L).
    fn reverse_of(b: &Block, next_sq: f32) -> f32 {
        min_sq(b.passes.limit_sq, next_sq + b.passes.reach)
    }

    /// Reverse results from the tail down; after a push (`added`) only as far as
    /// [`Planner::replan`] says they can change; `all` first brings every block's
    /// entry limit to the overrides.
    fn reverse_pass(&mut self, added: bool) {
        if !added {
            let (feed, rapid) = (self.feed_override, self.rapid_override);
            for i in 0..self.blocks.len() {
                if let Some(b) = self.blocks.get_mut(i) {
                    b.passes.limit_sq = square(b.max_entry.min(b.max_speed(feed, rapid)));
                }
            }
        }
        let mut next_sq = square(self.cfg.start_speed);
        let mut rising = added;
        let capped = self.capped;
        for i in (0..self.blocks.len()).rev() {
            if rising && i < capped {
                self.stale = self.stale.max(i + 1);
                return;
            }
            let Some(b) = self.blocks.get_mut(i) else {
                return;
            };
            let r = Planner::reverse_of(b, next_sq);
            let old = b.passes.reverse_sq;
            b.passes.reverse_sq = r;
            next_sq = r;
            if rising {
                if r.to_bits() == old.to_bits() {
                    return; // i >= capped >= stale: `old` was exact
                }
                rising = at_most(old, r);
            }
        }
        self.stale = 0;
    }

    /// Exact reverse results for the `stale` front blocks.
    fn refresh_stale(&mut self) {
        let stale = core::mem::take(&mut self.stale);
        let mut next_sq = match self.blocks.get(stale) {
            Some(b) => b.passes.reverse_sq,
            None => square(self.cfg.start_speed),
        };
        for i in (0..stale).rev() {
            if let Some(b) = self.blocks.get_mut(i) {
                next_sq = Planner::reverse_of(b, next_sq);
                b.passes.reverse_sq = next_sq;
            }
        }
    }

    /// Entries from the head cap forward; false (and to be run again after
    /// [`Planner::refresh_stale`]) when a stale reverse result would bind.
    fn forward_pass(&mut self) -> bool {
        // The cap on the next entry (squared): the head's, then the previous block's
        // exit.
        let mut cap_sq = square(self.head_cap.max(self.cfg.start_speed));
        let mut capped = 0;
        for i in 0..self.blocks.len() {
            let Some(b) = self.blocks.get_mut(i) else {
                break;
            };
            let r = b.passes.reverse_sq;
            // entry = min(r, cap); a reverse result at the cap counts as capped (its
            // entry stays the cap however far it rises).
            let at_cap = at_most(cap_sq, r);
            let entry_sq = if at_cap { cap_sq } else { r };
            if i < self.stale && !at_cap {
                return false;
            }
            if at_cap && capped == i {
                capped = i + 1;
            }
            if entry_sq.to_bits() != b.entry_sq.to_bits() || is_nan(b.passes.exit_sq) {
                b.entry_sq = entry_sq;
                b.passes.exit_sq = entry_sq + b.passes.reach;
            }
            cap_sq = b.passes.exit_sq;
        }
        self.capped = capped;
        true
    }
}

fn square(v: f32) -> f32 {
    v * v
}

/// `a <= b` for squared speeds (zero or positive, infinity included, never NaN): the
/// order of their bits, with no soft-float comparison.
fn at_most(a: f32, b: f32) -> bool {
    a.to_bits() <= b.to_bits()
}

/// The smaller of two squared speeds (see [`at_most`]).
fn min_sq(a: f32, b: f32) -> f32 {
    if at_most(a, b) {
        a
    } else {
        b
    }
}

/// NaN, by its bits (no soft-float comparison).
fn is_nan(x: f32) -> bool {
    x.to_bits() & 0x7FFF_FFFF > 0x7F80_0000
}

/// Junction speed limit (mm/s) between direction `u1` (end of the previous move) and
/// `u2` (start of the next), from the junction deviation.
pub fn junction_speed(cfg: &PlannerConfig, u1: [f32; AXES], u2: [f32; AXES], shape: Shape) -> f32 {
    let dot: f32 = u1.iter().zip(u2.iter()).map(|(a, b)| a * b).sum();
    if dot > 0.999_999 {
        return f32::INFINITY; // straight on
    }
    if dot < -0.999_999 {
        return cfg.start_speed; // full reversal
    }
    // theta: angle between the reversed incoming and the outgoing direction.
    let sin_half = crate::fmath::sqrt(0.5 * (1.0 + dot));
    // The per-axis acceleration limit along the change of direction, as along a move.
    let change = core::array::from_fn(|k| u2[k] - u1[k]);
    let (a, _) = geometry::axis_limits(cfg, geometry::length_and_unit(change).1);
    let a = shape.effective_accel(a);
    crate::fmath::sqrt(a * cfg.junction_deviation * sin_half / (1.0 - sin_half))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Path;

    fn line(x: i32, y: i32, f: f32) -> Move {
        Move {
            target: [x, y, 0],
            path: Path::Line,
            feed: Feed::MmPerMin(f),
            line: 0,
        }
    }

    /// Entry speeds from full reverse and forward passes over the whole queue (what
    /// `replan` computed before it learnt to stop where nothing changes).
    /// Full passes over the queue, in squared speeds: the entries squared.
    fn full_passes(p: &Planner) -> std::vec::Vec<f32> {
        let floor = p.cfg.start_speed;
        let mut entries: std::vec::Vec<f32> = std::vec::Vec::new();
        let mut next = floor * floor;
        for b in p.blocks.iter().rev() {
            let limit = b.max_entry.min(p.max_speed(b));
            let reach = next + 2.0 * p.plan_accel(b) * b.length;
            next = if limit * limit <= reach {
                limit * limit
            } else {
                reach
            };
            entries.push(next);
        }
        entries.reverse();
        let head = p.head_cap.max(floor);
        let mut cap = head * head;
        for (e, b) in entries.iter_mut().zip(p.blocks.iter()) {
            if *e > cap {
                *e = cap;
            }
            cap = *e + 2.0 * p.plan_accel(b) * b.length;
        }
        entries
    }

    proptest::proptest! {
        /// Squared speeds compared by their bits order as f32 does (zero, positive,
        /// infinity).
        #[test]
        fn bit_order_is_the_order_of_squared_speeds(ab in 0u32..=0x7F80_0000, bb in 0u32..=0x7F80_0000) {
            let (a, b) = (f32::from_bits(ab), f32::from_bits(bb));
            proptest::prop_assert_eq!(at_most(a, b), a <= b);
            proptest::prop_assert_eq!(min_sq(a, b).to_bits(), if a <= b { ab } else { bb });
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]
        /// Incremental replanning gives bit for bit the squared entries of full passes
        /// whenever it replans, through pushes, pops, head caps and overrides.
        #[test]
        fn incremental_replan_equals_full_passes(
            ops in proptest::collection::vec((0u8..8, -400i32..400, -400i32..400, 1u16..200), 1..200),
            start_speed in proptest::prop_oneof![proptest::strategy::Just(0.0f32), 0.1f32..5.0],
            cosine: bool,
        ) {
            let cfg = PlannerConfig {
                start_speed,
                shape: if cosine { Shape::Cosine } else { Shape::Trapezoid },
                ..PlannerConfig::default()
            };
            let mut p = Planner::new(cfg, [0; 3]);
            let mut overrides = [100u16, 100];
            let mut at = [0i32; 2];
            let mut dir = [1i32, 0];
            for (op, dx, dy, k) in ops {
                let generation = p.generation();
                match op {
                    0..=3 => {
                        // Mostly short collinear runs (whose speeds the reverse pass
                        // raises all along the queue), some turns and long moves,
                        // some rapids.
                        if op == 3 {
                            dir = [dx.signum(), dy.signum()];
                        }
                        let len = if op == 2 { dx.abs() * 10 } else { dy.abs() % 8 + 1 };
                        at = [at[0] + dir[0] * len, at[1] + dir[1] * len];
                        let mv = Move {
                            // Some feeds below the start speed (entries then fall
                            // back along the queue).
                            feed: match k % 7 {
                                0 => Feed::Rapid,
                                1 => Feed::MmPerMin(f32::from(k % 16 + 1) * 10.0),
                                _ => Feed::MmPerMin(f32::from(k) * 25.0),
                            },
                            ..line(at[0], at[1], 1.0)
                        };
                        if p.push(&mv) == Err(PlanError::Full) {
                            p.pop();
                            continue;
                        }
                    }
                    // A pop replans nothing (the step engine's head cap follows).
                    4 => {
                        p.pop();
                        continue;
                    }
                    5 => p.set_head_cap(f32::from(k) / 4.0),
                    6 => {
                        overrides[0] = k;
                        p.set_overrides(overrides[0], overrides[1]);
                    }
                    _ => {
                        overrides[1] = k / 2;
                        p.set_overrides(overrides[0], overrides[1]);
                    }
                }
                if p.generation() == generation {
                    continue; // nothing replanned
                }
                let got: std::vec::Vec<u32> = p.blocks.iter().map(|b| b.entry_sq.to_bits()).collect();
                let want: std::vec::Vec<u32> = full_passes(&p).iter().map(|e| e.to_bits()).collect();
                proptest::prop_assert_eq!(got, want);
            }
        }
    }

    #[test]
    fn right_angle_junction_matches_the_deviation_rule() {
        let cfg = PlannerConfig::default();
        let v = junction_speed(&cfg, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], Shape::Trapezoid);
        // theta = 90 deg: sin(45) = 0.7071; a along (-1, 1)/sqrt2 = 500 * sqrt2.
        let s = 0.5f32.sqrt();
        let expect = (500.0 * 2f32.sqrt() * 0.01 * s / (1.0 - s)).sqrt();
        assert!((v - expect).abs() < 1e-3, "{v} vs {expect}");
        assert_eq!(
            junction_speed(&cfg, [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], Shape::Trapezoid),
            0.0
        );
        assert!(
            junction_speed(&cfg, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], Shape::Trapezoid).is_infinite()
        );
    }

    #[test]
    fn collinear_moves_keep_speed_and_the_queue_ends_at_rest() {
        let mut p = Planner::new(PlannerConfig::default(), [0; 3]);
        for i in 1..=10 {
            p.push(&line(800 * i, 0, 3000.0)).unwrap();
        }
        // Middle blocks enter at full speed (50 mm/s); the first from rest.
        assert_eq!(p.blocks.get(0).unwrap().entry(), 0.0);
        assert!((p.blocks.get(5).unwrap().entry() - 50.0).abs() < 1e-3);
        // The last block (10 mm) must be able to stop: entry <= sqrt(2 a d) = 100.
        let last = p.blocks.get(9).unwrap();
        assert!(last.entry() <= (2.0 * 500.0 * 10.0f32).sqrt() + 1e-3);
        // Every block can decelerate to its successor's entry.
        for i in 0..9 {
            let (a, b) = (p.blocks.get(i).unwrap(), p.blocks.get(i + 1).unwrap());
            assert!(
                b.entry() * b.entry() <= a.entry() * a.entry() + 2.0 * a.accel * a.length + 1e-2
            );
            assert!(
                a.entry() * a.entry() <= b.entry() * b.entry() + 2.0 * a.accel * a.length + 1e-2
            );
        }
    }

    #[test]
    fn look_ahead_spans_many_short_blocks() {
        // 20 collinear 0.5 mm moves: full speed needs more than one block to reach.
        let mut p = Planner::new(PlannerConfig::default(), [0; 3]);
        for i in 1..=20 {
            p.push(&line(40 * i, 0, 3000.0)).unwrap();
        }
        let entries: std::vec::Vec<f32> =
            (0..20).map(|i| p.blocks.get(i).unwrap().entry()).collect();
        // Symmetric triangle: rises then falls, peak sqrt(a * L) = sqrt(500*10) in the middle.
        assert!(entries[10] > 60.0 || (entries[10] - 50.0).abs() < 1e-3);
        assert!(entries[1] > entries[0] && entries[19] < entries[15]);
    }

    #[test]
    fn overrides_scale_feed_but_not_past_axis_limits() {
        let mut p = Planner::new(PlannerConfig::default(), [0; 3]);
        p.push(&line(8000, 0, 3000.0)).unwrap();
        let b = *p.blocks.front().unwrap();
        assert!((p.max_speed(&b) - 50.0).abs() < 1e-4);
        p.set_overrides(150, 100);
        assert!((p.max_speed(&b) - 75.0).abs() < 1e-4);
        p.set_overrides(200, 100);
        assert!((p.max_speed(&b) - 5000.0 / 60.0).abs() < 1e-3);
        p.set_overrides(10, 100);
        assert!((p.max_speed(&b) - 5.0).abs() < 1e-4);
        assert_eq!(p.feed_override(), 10);
        // A rapid runs at the axis limit (5000 mm/min); its override scales that.
        let mut p = Planner::new(PlannerConfig::default(), [0; 3]);
        p.push(&Move {
            feed: Feed::Rapid,
            ..line(8000, 0, 1.0)
        })
        .unwrap();
        let b = *p.blocks.front().unwrap();
        assert!((p.max_speed(&b) - 5000.0 / 60.0).abs() < 1e-3);
        p.set_overrides(100, 25);
        assert!((p.max_speed(&b) - 1250.0 / 60.0).abs() < 1e-3);
    }

    #[test]
    fn start_speed_replaces_zero_and_full_queue_pushes_back() {
        let cfg = PlannerConfig {
            start_speed: 2.0,
            ..PlannerConfig::default()
        };
        let mut p = Planner::new(cfg, [0; 3]);
        for i in 0..PLANNER_BLOCKS as i32 {
            let (x, y) = if i % 2 == 0 { (800, 0) } else { (0, 0) };
            p.push(&line(x, y, 3000.0)).unwrap();
        }
        assert_eq!(p.push(&line(5, 5, 3000.0)), Err(PlanError::Full));
        // Reversals: junction speed is the start speed.
        assert!(p.blocks.iter().all(|b| (b.entry() - 2.0).abs() < 1e-4));
        assert_eq!(p.exit_speed(), 2.0);
    }

    #[test]
    fn invalid_moves_are_rejected() {
        let mut p = Planner::new(PlannerConfig::default(), [0; 3]);
        let bad = Move {
            target: [0, 0, 5],
            path: Path::Arc {
                center: [10, 0],
                ccw: true,
                turns: 0,
            },
            feed: Feed::Rapid,
            line: 0,
        };
        assert_eq!(p.push(&bad), Err(PlanError::Invalid));
        assert_eq!(p.push(&line(10, 0, -5.0)), Err(PlanError::Invalid));
        assert_eq!(p.push(&line(0, 0, 100.0)), Ok(()));
        assert!(p.is_empty());
        // Endpoints must lie strictly inside +-2^30 steps (a line's travel then
        // fits the interpolators' u32 counters).
        let edge = (1 << 30) - 1;
        assert_eq!(p.push(&line(1 << 30, 0, 100.0)), Err(PlanError::Invalid));
        assert_eq!(p.push(&line(0, -(1 << 30), 100.0)), Err(PlanError::Invalid));
        assert_eq!(p.push(&line(0, i32::MIN, 100.0)), Err(PlanError::Invalid));
        assert!(p.is_empty());
        assert_eq!(p.push(&line(edge, -edge, 100.0)), Ok(()));
        assert_eq!(p.push(&line(-edge, edge, 100.0)), Ok(()));
        assert_eq!(p.len(), 2);
        // A start outside the range (a position set there) is refused as well.
        let mut p = Planner::new(PlannerConfig::default(), [1 << 30, 0, 0]);
        assert_eq!(p.push(&line(0, 0, 100.0)), Err(PlanError::Invalid));
        assert!(p.is_empty());
    }
}
