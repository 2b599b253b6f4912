//! The homing cycle (`$H`) as a state machine driven by switch levels, time and the
//! planner running empty: for each axis with a switch (Z first so the pen is clear,
//! then X, then Y), seek the switch fast ($25), back off, locate it slowly ($24),
//! pull off ($27); each trigger stops motion at once and waits the debounce time ($26).
//!
//! It only decides what to queue next and when it has failed; the machine state owns
//! the planner, the alarms and the position it sets at the end.

use super::MotionControl;
use crate::gcode::units::mm_to_steps;
use crate::motion::Command;
use crate::motion::{Feed, Move, Path, StepPos, AXES};
use crate::settings::Settings;

/// How far the seek may go, as a multiple of the axis travel.
const SEEK_TRAVEL_FACTOR: f32 = 1.5;
/// How far the slow locate may go, as a multiple of the pull-off distance.
const LOCATE_FACTOR: f32 = 5.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Fast move toward the switch until it triggers.
    Seek,
    /// Switch seen: wait for the debounce time to pass.
    Debounce { until_ms: u32, next: After },
    /// Move off the switch by the pull-off distance; the switch must release.
    Backoff,
    /// Slow move toward the switch.
    Locate,
    /// Final move off the switch.
    PullOff,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum After {
    Backoff,
    PullOff,
}

/// Why homing failed (mapped to alarms 8 and 9 by the machine).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HomingError {
    /// The switch did not release after pulling off.
    PullOff,
    /// The switch was not found within the search distance.
    NotFound,
}

/// Progress of a homing cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    Running,
    /// All axes found; the position to set (steps).
    Done(StepPos),
    Failed(HomingError),
}

/// A running homing cycle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Homing {
    /// Axes to home (X = bit 0), and those not homed yet.
    axes: u8,
    left: u8,
    stage: Stage,
    /// A move of the current phase has been queued.
    issued: bool,
}

impl Homing {
    /// Start a cycle over the axes that have switches ($214). `None` if there are none.
    pub fn start(s: &Settings) -> Option<Homing> {
        let axes = s.switch_mask() & 7;
        (axes != 0).then_some(Homing {
            axes,
            left: axes,
            stage: Stage::Seek,
            issued: false,
        })
    }

    /// Axis being homed: Z first, then X, then Y.
    pub fn axis(&self) -> usize {
        if self.left & 4 != 0 {
            2
        } else if self.left & 1 != 0 {
            0
        } else {
            1
        }
    }

    /// Advance with the current switch levels (`limits[axis]`, true = pressed).
    pub fn step<M: MotionControl>(
        &mut self,
        s: &Settings,
        limits: [bool; AXES],
        m: &mut M,
        now_ms: u32,
    ) -> Progress {
        let axis = self.axis();
        let pressed = limits.get(axis).copied().unwrap_or(false);
        // Toward the switch: negative when the $23 bit is set.
        let toward: f32 = if s.homing_dir_mask() & (1 << axis) != 0 {
            -1.0
        } else {
            1.0
        };
        match self.stage {
            Stage::Seek | Stage::Locate => {
                let seeking = matches!(self.stage, Stage::Seek);
                if pressed {
                    m.clear();
                    let next = if seeking {
                        After::Backoff
                    } else {
                        After::PullOff
                    };
                    self.stage = Stage::Debounce {
                        until_ms: now_ms.wrapping_add(s.homing_debounce_ms()),
                        next,
                    };
                    self.issued = false;
                } else if !self.issued {
                    let (dist, rate) = if seeking {
                        (
                            SEEK_TRAVEL_FACTOR * s.max_travel(axis).max(s.homing_pulloff()),
                            s.homing_seek(),
                        )
                    } else {
                        (LOCATE_FACTOR * s.homing_pulloff().max(0.1), s.homing_feed())
                    };
                    if !self.queue(s, m, axis, toward * dist, rate) {
                        return Progress::Running;
                    }
                } else if m.is_idle() {
                    return Progress::Failed(HomingError::NotFound);
                }
            }
            Stage::Debounce { until_ms, next } => {
                if now_ms.wrapping_sub(until_ms) as i32 >= 0 {
                    self.stage = match next {
                        After::Backoff => Stage::Backoff,
                        After::PullOff => Stage::PullOff,
                    };
                    self.issued = false;
                }
            }
            Stage::Backoff | Stage::PullOff => {
                let backing_off = matches!(self.stage, Stage::Backoff);
                if !self.issued {
                    let rate = if backing_off {
                        s.homing_seek()
                    } else {
                        s.homing_feed()
                    };
                    self.queue(s, m, axis, -toward * s.homing_pulloff(), rate);
                } else if m.is_idle() {
                    if pressed {
                        return Progress::Failed(HomingError::PullOff);
                    }
                    if backing_off {
                        self.stage = Stage::Locate;
                        self.issued = false;
                    } else {
                        self.left &= !(1 << axis);
                        self.stage = Stage::Seek;
                        self.issued = false;
                        if self.left == 0 {
                            return Progress::Done(self.home_position(s, m.position()));
                        }
                    }
                }
            }
        }
        Progress::Running
    }

    /// Queue a relative move of `mm` on `axis`; false if the queue was full.
    fn queue<M: MotionControl>(
        &mut self,
        s: &Settings,
        m: &mut M,
        axis: usize,
        mm: f32,
        rate: f32,
    ) -> bool {
        let mut target = m.position();
        if let Some(t) = target.get_mut(axis) {
            *t = t.saturating_add(mm_to_steps(mm, s.steps_per_mm(axis)));
        }
        let mv = Move {
            target,
            path: Path::Line,
            feed: Feed::MmPerMin(rate),
            line: 0,
        };
        self.issued = m.push(Command::Move(mv)).is_ok();
        self.issued
    }

    /// Position after homing: homed axes sit at the pull-off distance inside their
    /// travel (+pull-off when homing toward -, -pull-off when toward +).
    fn home_position(&self, s: &Settings, mut pos: StepPos) -> StepPos {
        for axis in 0..AXES as u8 {
            if self.axes & (1 << axis) == 0 {
                continue;
            }
            let a = usize::from(axis);
            let off = mm_to_steps(s.homing_pulloff(), s.steps_per_mm(a));
            if let Some(p) = pos.get_mut(a) {
                // Rounding is symmetric, so negating the rounded value is exact.
                *p = if s.homing_dir_mask() & (1 << axis) != 0 {
                    off
                } else {
                    -off
                };
            }
        }
        pos
    }
}
