//! A hold's pen lift for a Z-axis pen ($201=0): once a hold has brought XY to rest,
//! the pen goes up to its up place ($205) in raw Z steps queued straight into the step
//! queue beside the held block, and back down to where the hold found it on resume,
//! before XY moves on. The planner and the preparation never see these steps, so the
//! job resumes from exactly the same step count. A servo pen's lift is only a level
//! (see [`Pipeline::pen_level`](super::Pipeline)); it is decided here too, at the same
//! moment of rest.

use super::{Pipeline, StepSide};
use crate::interpolation::StepEvent;
use crate::stepper::prep::HoldState;
use crate::stepper::{CmdSink, StepCmd};

/// Where a Z pen's trip for a hold is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum ZStage {
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
pub(super) struct ZTrip {
    /// Z where the hold found it: the way back ends here.
    back: i32,
    /// Steps of the way under way queued so far (16 bits: the trip fits in the
    /// pipeline's spare word of RAM; a pen further than 65,535 steps from $205 is not
    /// lifted).
    sent: u16,
    stage: ZStage,
}

/// Most Z steps of a hold's trip queued per [`Pipeline::fill`] (each costs a square
/// root and two divisions, about 880 instructions): 32 a millisecond is far above a
/// Z axis' rate. Fewer where the horizon is reached first (see `run_z`).
const Z_STEPS_PER_FILL: u32 = 32;

impl<S: StepSide> Pipeline<S> {
    /// A hold has brought XY to rest (nothing runs, no pen move is under way): the
    /// pen lifts (a servo at once: nothing waits for it; a Z pen on its own trip to
    /// $205 if it stands below it), and remembers where it was.
    // Out of line: its frame stays off the preparation's deepest stack path.
    #[inline(never)]
    pub(super) fn lift_when_stopped(&mut self) {
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

    /// A feed hold is in effect (braking, or at rest until resumed).
    pub(super) fn held(&self) -> bool {
        self.prep.hold_state() != HoldState::Running
    }

    /// Nothing runs and no pen move is under way (a hold may lift the pen): at rest
    /// as the service tick saw it ([`Pipeline::fill_at`]), the same tick on every
    /// board.
    fn at_rest(&self) -> bool {
        self.rest_ms != super::MOVING && self.braked()
    }

    /// The hold has braked XY to its end and no pen move, wait or Z trip is under
    /// way (the rest itself may not be seen yet).
    fn braked(&self) -> bool {
        self.prep.hold_state() != HoldState::Holding
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
    pub(super) fn z_lift_due(&self) -> bool {
        self.held() && self.braked() && self.z_to_lift().is_some()
    }

    /// Queue the Z pen's trip under way; true when no Z move of a hold is under way
    /// (none, or up and held). Up and no longer held: the way back starts; the trip
    /// ends once Z stands where the hold found it.
    // Out of line: its frame stays off the preparation's deepest stack path.
    #[inline(never)]
    pub(super) fn run_z(&mut self) -> bool {
        let Some(mut t) = self.z_trip else {
            return true;
        };
        let up = self.pen_timing.z_up;
        loop {
            let (from, to) = match t.stage {
                ZStage::Up if self.held() => {
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
            // Up to the preparation's horizon past the timeline, as for XY: 32 steps
            // at once, when a hold at rest lifted the pen, took the call 1.6 ms under
            // the pessimistic cycle model before the step timer was started, past what
            // the trip's first 5 ms wait absorbs (`.ci/emu-random`, seed 456428396:
            // the lift 20 µs late on the image).
            while u32::from(t.sent) < n
                && budget > 0
                && self.side.sink().room() > 0
                && (self.side.queued() < super::MIN_AHEAD
                    || self.ahead_of(self.clock.1).0 < self.horizon())
            {
                let wait = self.z_wait(u32::from(t.sent), n);
                self.side.sink().push_slice(&[StepCmd::new(tick, wait)]);
                self.queue_end = self.queue_end.wrapping_add(wait);
                t.sent += 1;
                budget -= 1;
            }
            // Its last step is made once a service tick sees the machine at rest (the
            // step timeline past the trip's end: `fill_at`), not once the timer has
            // stopped: the firmware's call, a little after its tick, found the timer
            // stopped where the simulator's, at the tick, found the last pulse's tail
            // still running, and the moves after the trip started a tick earlier on
            // the image (seed 1729238220: a step 0.91 ms early).
            if u32::from(t.sent) < n || self.rest_ms == super::MOVING {
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

    /// A Z pen's trip for a hold is under way (or due: up and resumed).
    pub(super) fn z_moving(&self) -> bool {
        self.z_trip
            .is_some_and(|t| t.stage != ZStage::Up || !self.held())
    }
}
