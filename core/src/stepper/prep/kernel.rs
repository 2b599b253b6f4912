//! Integer timing kernels of the preparation: the per-step arithmetic that turns a run of
//! ticks into timer counts without floating point, and the queueing of the result. It
//! owns [`Segment`] (a run of ticks and how they are timed), [`Timing`] (a cubic in the
//! tick count by forward differences, or an exact constant-acceleration [`RampTiming`]), the
//! Q fixed-point unit and the split of a long wait into pure waits. Nothing here knows
//! of blocks or profiles: [`super::profile`] decides each segment's coefficients, this
//! module only executes them, so that the inner loop stays a few integer additions per
//! tick.
//!
//! A segment as this module sees it (time since `base` against the tick index):
//!
//! ```text
//!   time (timer counts since Segment.base)
//!    ^                                       Timing::Poly: acc += d1; d1 += d2; d2 += d3
//!    |                                 *     Timing::Ramp: W += dw1 (+dw2, dw3),
//!    |                          *                          R = floor(sqrt W),
//!    |                   *                                 time = r0 -/+ R
//!    |            *
//!    |     *   <- Segment.at: the last queued tick's time
//!    +--*--+------+------+------+------+--> tick index, Segment.left ticks to go
//!     base
//! ```

use super::super::{CmdSink, StepCmd, MAX_STEP_RATE, MAX_WAIT};
use crate::interpolation::StepEvent;

/// Distance unit of path positions: 2^-32 mm.
pub(super) const Q: f32 = 4_294_967_296.0;
/// Longest segment whose time is not linear in the tick count, ticks.
pub(super) const MAX_SEGMENT: u32 = 256;
/// Longest segment whose time is linear in the tick count, ticks.
pub(super) const MAX_LINEAR: u32 = 2048;
/// Ticks timed per pass of the inner loop (a stack buffer of ticks and commands).
pub(super) const BATCH: usize = 32;
/// Longest segment, timer counts (its time since the segment start stays in i64 with 32
/// fractional bits).
pub(super) const MAX_SEGMENT_COUNTS: f32 = 1.0e9;

/// The ticks of one segment and how they are timed; `base` is the timer count of the
/// segment's start and `at` the last queued tick's time since it (a segment lasts less
/// than 2^30 timer counts, so 32 bits hold it).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Segment {
    pub(super) left: u32,
    pub(super) timing: Timing,
    pub(super) base: u64,
    pub(super) at: u32,
}

/// How a segment's ticks get their times.
#[derive(Clone, Copy, Debug)]
pub(super) enum Timing {
    /// A polynomial in the tick count: `acc` is the time since the segment's start and
    /// `d1..d3` its forward differences, in timer counts with 32 fractional bits;
    /// `linear` when d2 = d3 = 0.
    Poly {
        acc: u64,
        d1: u64,
        d2: u64,
        d3: u64,
        linear: bool,
    },
    /// A constant acceleration along a line, exact: see [`RampTiming`].
    Ramp(RampTiming),
}

impl Default for Timing {
    fn default() -> Self {
        Timing::Poly {
            acc: 0,
            d1: 0,
            d2: 0,
            d3: 0,
            linear: true,
        }
    }
}

/// Step event times under constant acceleration, in integers. With R = v / a in timer counts
/// (the time the speed would take to reach 0), R^2 = W grows or falls by 2 ds / a
/// (ticks^2) per tick of length ds, and the tick's time is a fixed tick plus or minus R
/// (the ramp's anchor: its start, or the profile's end for the last ramp). Each tick
/// updates W by one addition and takes R = floor(sqrt W) from the last two differences
/// of R (quadratic extrapolation) and one Newton correction with a 32-bit division, then
/// checks it exactly (one 32x32 multiply each way). Near rest the guess can be far off:
/// the exact digit-by-digit root there. Every time is the exact one rounded down to the
/// timer count (up to f32 rounding of W's start and step).
#[derive(Clone, Copy, Debug)]
pub(super) struct RampTiming {
    /// W and its forward differences per tick (wrapping: the differences may be
    /// negative). A line's ticks are equal, so W moves by a constant; along a curve the
    /// path position is a cubic in the tick count (within the error bound), so W is too.
    pub(super) w: u64,
    pub(super) dw1: u64,
    pub(super) dw2: u64,
    pub(super) dw3: u64,
    /// The tick's time since the segment's start is r0 + R (rising) or r0 - R.
    pub(super) rising_t: bool,
    pub(super) r0: u32,
    pub(super) r: u32,
    pub(super) dr: i32,
    pub(super) ddr: i32,
}

impl RampTiming {
    /// floor(sqrt(w)) near the guess `g` (below 2^30): one Newton step from the guess
    /// with a 32-bit division, checked exactly; far from it (near rest), digit by digit.
    #[inline(always)]
    pub(super) fn root_near(w: u64, g: u32) -> u32 {
        if (w as i64) < 0 {
            // W fell below 0 (a curve's cubic just past rest): at rest.
            return 0;
        }
        let g = g.clamp(1, (1 << 30) - 1);
        let e = w as i64 - (u64::from(g) * u64::from(g)) as i64;
        if e.unsigned_abs() < 1 << 31 {
            let r = (g as i32 + (e as i32) / (2 * g as i32)).max(1) as u64;
            // r^2 <= w < (r + 1)^2, or one step either way.
            let sq = r * r;
            if sq <= w {
                if sq + 2 * r + 1 > w {
                    return r as u32;
                }
                if sq + 4 * r + 4 > w {
                    return r as u32 + 1;
                }
            } else if (r - 1) * (r - 1) <= w {
                return r as u32 - 1;
            }
        }
        crate::fmath::isqrt(w) as u32
    }

    /// The next tick's time since the segment's start (32 bits, wrapping).
    #[inline(always)]
    pub(super) fn next(&mut self) -> u32 {
        self.w = self.w.wrapping_add(self.dw1);
        self.dw1 = self.dw1.wrapping_add(self.dw2);
        self.dw2 = self.dw2.wrapping_add(self.dw3);
        let guess = (self.r as i32).wrapping_add(self.dr).wrapping_add(self.ddr);
        let r = Self::root_near(self.w, guess.max(1) as u32);
        let dr = r.wrapping_sub(self.r) as i32;
        self.ddr = dr.wrapping_sub(self.dr);
        self.dr = dr;
        self.r = r;
        if self.rising_t {
            self.r0.wrapping_add(r)
        } else {
            self.r0.wrapping_sub(r)
        }
    }
}

impl Segment {
    /// `n` ticks timed by a polynomial with the forward differences `d` (timer counts,
    /// see [`fixed`]) from the cursor's time `base`; `t_last` is the last queued tick's.
    pub(super) fn poly(n: u32, d: [i64; 3], base: u64, t_last: u64) -> Self {
        let [d1, d2, d3] = d.map(|d| d as u64);
        Segment {
            left: n,
            timing: Timing::Poly {
                acc: 0,
                d1,
                d2,
                d3,
                linear: d2 == 0 && d3 == 0,
            },
            base,
            at: t_last.wrapping_sub(base) as u32,
        }
    }

    /// Times `ticks` and packs them into `cmds` (the same length): per tick two
    /// (linear) or six (cubic) 32-bit additions, or a ramp's integer root, and the wait
    /// since the last one.
    #[inline(always)]
    pub(super) fn time(&mut self, ticks: &[StepEvent], cmds: &mut [StepCmd]) {
        let mut prev = self.at;
        let mut emit = |at: u32, tick: StepEvent, cmd: &mut StepCmd| {
            // At least 2 ticks apart (the executor's promise); the 24-bit bound holds
            // for every segment (a tick that may wait longer is timed on its own).
            let wait = at.wrapping_sub(prev).clamp(2, MAX_WAIT);
            prev = prev.wrapping_add(wait);
            *cmd = StepCmd((u32::from(tick.0) << 24) | wait);
        };
        match &mut self.timing {
            Timing::Poly {
                acc,
                d1,
                linear: true,
                ..
            } => {
                let (mut a, d) = (*acc, *d1);
                for (tick, cmd) in ticks.iter().zip(cmds.iter_mut()) {
                    a = a.wrapping_add(d);
                    emit((a >> 32) as u32, *tick, cmd);
                }
                *acc = a;
            }
            Timing::Poly {
                acc, d1, d2, d3, ..
            } => {
                let (mut a, mut b, mut c, d) = (*acc, *d1, *d2, *d3);
                for (tick, cmd) in ticks.iter().zip(cmds.iter_mut()) {
                    a = a.wrapping_add(b);
                    b = b.wrapping_add(c);
                    c = c.wrapping_add(d);
                    emit((a >> 32) as u32, *tick, cmd);
                }
                (*acc, *d1, *d2) = (a, b, c);
            }
            Timing::Ramp(ramp) => {
                for (tick, cmd) in ticks.iter().zip(cmds.iter_mut()) {
                    emit(ramp.next(), *tick, cmd);
                }
            }
        }
        self.at = prev;
        self.left -= ticks.len() as u32;
    }
}

pub(super) fn to_q(mm: f32) -> u64 {
    if mm > 0.0 {
        (mm * Q + 0.5) as u64
    } else {
        0
    }
}

pub(super) fn from_q(q: u64) -> f32 {
    q as f32 * (1.0 / Q)
}

/// f32 timer counts (at most 2^31) in i64 with 32 fractional bits.
pub(super) fn fixed(ticks: f32) -> i64 {
    (ticks * Q) as i64
}

/// The forward differences of the cubic Hermite polynomial through (0, 0) and
/// (n, span) with the slopes `m0` and `m1` at its ends (per tick).
pub(super) fn hermite(n: u32, span: f32, m0: f32, m1: f32) -> [f32; 3] {
    let nf = n as f32;
    let inv = 1.0 / nf;
    let c3 = ((m0 + m1) * nf - 2.0 * span) * inv * inv * inv;
    let c2 = (3.0 * span - (2.0 * m0 + m1) * nf) * inv * inv;
    [c3 + c2 + m0, 6.0 * c3 + 2.0 * c2, 6.0 * c3]
}

/// The shortest wait between two step events, timer counts: one event period at the
/// configuration's cap `max_event_rate` (at most [`MAX_STEP_RATE`], 12.5 us; less for
/// long step pulses: the pulse plus the drivers' low time).
pub(super) fn min_wait(timer_hz: u32, max_event_rate: f32) -> u64 {
    let w = timer_hz as f32 / max_event_rate.min(MAX_STEP_RATE);
    (w as u64 + u64::from((w as u64 as f32) < w)).max(2)
}

/// Whole ticks of `q` in `len` (Q units): the division in f32, checked exactly.
pub(super) fn ticks_in(len: u64, q: u64) -> u64 {
    let q = q.max(1);
    let mut n = (len as f32 / q as f32) as u64;
    while n > 0 && n.wrapping_mul(q) > len {
        n -= 1;
    }
    while (n + 1).wrapping_mul(q) <= len {
        n += 1;
    }
    n
}

/// Pure waits before a step whose wait is longer than a command holds: each this long
/// (a power of two, so that counting them is a shift, not a 64-bit division).
pub(super) const PURE_WAIT: u64 = 1 << 23;

/// Pure waits a step `wait` ticks after the last one needs before its own command.
pub(super) fn pure_waits(wait: u64) -> u64 {
    if wait > u64::from(MAX_WAIT) {
        (wait - u64::from(MAX_WAIT) + PURE_WAIT - 1) >> 23
    } else {
        0
    }
}

/// Commands a step `wait` ticks after the last one takes.
pub(super) fn commands_for_wait(wait: u64) -> usize {
    1 + pure_waits(wait) as usize
}

/// Queues `tick` `wait` ticks after the last command (pure waits first for a long
/// one); the wait of its own command.
pub(super) fn push_waited(sink: &mut dyn CmdSink, tick: StepEvent, wait: u64) -> u32 {
    let n = pure_waits(wait);
    for _ in 0..n {
        sink.push_slice(&[StepCmd::new(StepEvent(0), PURE_WAIT as u32)]);
    }
    let last = wait.max(2) - n * PURE_WAIT;
    sink.push_slice(&[StepCmd::new(tick, last as u32)]);
    last as u32
}
