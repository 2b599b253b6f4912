//! Profile evaluation of the preparation: where the block's velocity profile stands at
//! a path position ([`Cursor`]) and how long the next segment may be so that its timing
//! polynomial stays within the error bound. It owns the methods of [`Active`] that read
//! the profile (phase lookup, phase-local time, speed, the path's rate) and choose a
//! segment's [`Timing`]; it changes no block state but the cursor and the segment.
//! Kept apart from the block flow so that the numerics can be read (and tested) on
//! their own, and apart from the kernels so that no float reaches the per-tick loop.
//!
//! The profile of one block as it is evaluated here (`Active.prof`, phases
//! [`Phase::Up`], [`Phase::Cruise`], [`Phase::Down`]):
//!
//! ```text
//!   speed
//!    ^            Phase::Cruise
//!    |         +----------------------+          Cursor.v: speed at Cursor.s
//!    |        /                        \
//!    |       /  Phase::Up    Phase::Down\
//!    |      /                            \
//!    | v0  /                              \  v1 (exit speed)
//!    +----+----------+---------------+-----+----> path position, Q units
//!        0       ends_q[0]       ends_q[1]  ends_q[2] (= profile length)
//!     anchors[0]  anchors[1]                anchors[2]  (timer counts: the
//!     start of Up start of Cruise           profile's end; Down is timed back from it)
//! ```

use super::super::MAX_WAIT;
use super::kernel::*;
use super::Active;

/// The longest path a curve's tick can cover, in run units: a step of a DDA curve moves
/// one or both axes by one step, so its length is at most sqrt(2) (1.4142...) run units.
/// Rounded up so that the speed bound below (v^2 - 2 a s at the segment's end) never
/// overestimates the slowest speed of a segment slowing down.
const LONGEST_TICK: f32 = 1.415;

/// A ramp segment's ticks as [`RampTiming`] takes them: `n` ticks, W at the first and its
/// forward differences per tick, and where the segment ends (path position `s1`, Q units,
/// and the run's rate there, run units per tick).
struct RampRun {
    n: u32,
    w: u64,
    dw: [u64; 3],
    s1: u64,
    rate1: f32,
}
use crate::planner::profile::{Near, Phase};

/// Where the profile stands at the last timed tick (the end of the present segment).
#[derive(Clone, Copy, Debug)]
pub(super) struct Cursor {
    /// Path position, Q units from the profile's start.
    pub(super) s: u64,
    /// Its phase, the phase-local time there (see [`Profile::phase_time`]), seconds,
    /// and the timer count it falls on.
    pub(super) phase: Phase,
    pub(super) t: f32,
    pub(super) at: u64,
    /// Speed there, mm/s.
    pub(super) v: f32,
    /// The run's rate there, run units per tick.
    pub(super) rate: f32,
}

impl Active {
    /// Path position, speed and time of the present point: the cursor between
    /// segments (it may lie a little off the last queued tick's time after a circle's
    /// change of coordinate, see [`crate::interpolation::Interpolator::entry_shift`]),
    /// else the last queued tick (`t_last`).
    pub(super) fn now(&self, t_last: u64) -> (u64, f32, u64) {
        if self.seg.left == 0 {
            return (self.at.s, self.at.v, self.at.at);
        }
        let ahead = match self.line_tick_q {
            Some(q) => q.wrapping_mul(u64::from(self.seg.left)),
            None => to_q(self.interp.path_ahead(self.seg.left).0 * self.scale),
        };
        let s = self.at.s.saturating_sub(ahead);
        let p = self.phase_of(s).unwrap_or(Phase::Down);
        let (_, v) = self.prof.phase_time(p, self.local(p, s), self.near(p));
        (s, v, t_last)
    }

    /// Path position (Q units from the profile's start) and the run's rate `n` ticks
    /// ahead: a line's exact multiple; a curve's from the interpolator, and at the end
    /// of an arc's last run exactly the profile's end (the same point, without the
    /// rounding of the sum).
    pub(super) fn ahead(&self, n: u32) -> (u64, f32) {
        if let Some(q) = self.line_tick_q {
            return (self.at.s + q.wrapping_mul(u64::from(n)), 1.0);
        }
        let (d, r) = self.interp.path_ahead(n);
        if n == self.run_left && self.exact_end && self.interp.in_last_run() {
            return (self.rest_q.max(self.at.s), r);
        }
        (self.at.s + to_q(d * self.scale), r)
    }

    /// The phase a tick at path position `s` falls in (`None`: beyond the profile).
    pub(super) fn phase_of(&self, s: u64) -> Option<Phase> {
        if s <= self.ends_q[0] && self.ends_q[0] > 0 {
            Some(Phase::Up)
        } else if s <= self.ends_q[1] && self.ends_q[1] > self.ends_q[0] {
            Some(Phase::Cruise)
        } else if s <= self.ends_q[2] {
            Some(Phase::Down)
        } else {
            None
        }
    }

    /// The phase-local distance of position `s` (see [`Profile::phase_time`]).
    pub(super) fn local(&self, p: Phase, s: u64) -> f32 {
        match p {
            Phase::Up => from_q(s),
            Phase::Cruise => from_q(s.saturating_sub(self.ends_q[0])),
            Phase::Down => from_q(self.ends_q[2].saturating_sub(s)),
        }
    }

    /// The cursor as a known point of phase `p` (see [`Profile::phase_time`]), if it
    /// lies in that phase.
    fn near(&self, p: Phase) -> Option<Near> {
        (p == self.at.phase).then(|| Near {
            t: self.at.t,
            d: self.local(p, self.at.s),
            v: self.at.v,
        })
    }

    /// The exact time of position `s` in phase `p`: the cursor there.
    pub(super) fn exact(&self, p: Phase, s: u64, hz: f32) -> Cursor {
        let (t, v, ticks) = if p == Phase::Cruise {
            // The cruise's time is its distance over its speed: a product here (the
            // phase-local time, a hint for Newton's method elsewhere, is not needed).
            let ticks = self.local(p, s) * self.cruise_ticks_per_mm;
            (0.0, self.prof.phase_speeds(p).0, ticks)
        } else {
            let (t, v) = self.prof.phase_time(p, self.local(p, s), self.near(p));
            (t, v, t * hz)
        };
        let ticks = (ticks + 0.5) as u64;
        let at = match p {
            Phase::Up => self.anchors[0] + ticks,
            Phase::Cruise => self.anchors[1] + ticks,
            Phase::Down => self.anchors[2].saturating_sub(ticks),
        };
        Cursor {
            s,
            phase: p,
            t,
            at,
            v,
            rate: self.at.rate,
        }
    }

    /// Sets up the next segment of the present run: `false` if the next tick is to be
    /// timed on its own (it lies beyond the profile's end).
    pub(super) fn plan_segment(&mut self, eps: f32, hz: f32, t_last: u64) -> bool {
        let at = self.at;
        let step_q = match self.line_tick_q {
            Some(q) => q,
            None => to_q(at.rate * self.scale),
        };
        // The next tick's phase, from the rate (near the end exactly: a curve's last
        // tick lands on the profile's end).
        let near = self
            .phase_of(at.s + step_q)
            .or_else(|| self.phase_of(self.ahead(1).0));
        let Some(mut p) = near else {
            return false;
        };
        if let Some((seg, end)) = self.ramp_segment(p, eps, hz, t_last) {
            // The cursor moves to the segment's last tick (its exact time).
            self.seg = seg;
            self.at = end;
            return true;
        }
        let cap = self.run_left;
        let (mut n, linear) = if p != at.phase || at.v <= 0.0 || cap <= 1 {
            // The first tick of a phase (or from rest) is timed exactly on its own.
            (1, true)
        } else {
            self.segment_len(p, cap, eps, hz)
        };
        // The segment's end: within the phase.
        let (s1, rate1) = loop {
            let (s1, rate1) = self.ahead(n);
            let ds = s1 - at.s;
            let end = match p {
                Phase::Up => self.ends_q[0],
                Phase::Cruise => self.ends_q[1],
                Phase::Down => self.ends_q[2],
            };
            if s1 <= end {
                break (s1, rate1);
            }
            if n > 1 {
                let room = end.saturating_sub(at.s) as f32;
                n = ((n as f32 * room / ds as f32) as u32).max(1).min(n - 1);
                continue;
            }
            match self.phase_of(s1) {
                Some(next) if next != p => p = next,
                // Beyond the profile's end: timed on its own.
                _ => return false,
            }
        };
        let end = self.exact(p, s1, hz);
        let span = end.at.saturating_sub(at.at) as f32;
        let (d, longest) = if n == 1 {
            ([fixed(span), 0, 0], span)
        } else if linear {
            let d1 = span / n as f32;
            ([fixed(d1), 0, 0], d1)
        } else {
            // The slopes (timer counts per tick) at both ends.
            let per = self.scale * hz;
            let m0 = at.rate * per / at.v;
            let m1 = rate1 * per / end.v.max(1e-9);
            let d = hermite(n, span, m0, m1);
            (d.map(fixed), m0.max(m1).max(d[0]))
        };
        if longest > (MAX_WAIT / 2) as f32 {
            // A wait may exceed a command's 24 bits: this tick goes on its own.
            return false;
        }
        self.seg = Segment::poly(n, d, at.at, t_last);
        self.at = Cursor { rate: rate1, ..end };
        true
    }

    /// Ticks in a ramp of constant acceleration (trapezoid), timed exactly
    /// ([`RampTiming`]): a line's up to the ramp's end; a curve's as far as its path position
    /// stays within the error bound of a cubic in the tick count. `None` for anything
    /// else (or a ramp so long that its times leave 2^30 timer counts).
    pub(super) fn ramp_segment(
        &self,
        p: Phase,
        eps: f32,
        hz: f32,
        t_last: u64,
    ) -> Option<(Segment, Cursor)> {
        let [acc, jerk, _] = self.prof.derivative_bounds(p);
        if p == Phase::Cruise || !(acc > 0.0) || jerk != 0.0 {
            return None;
        }
        let at = self.at;
        let end = match p {
            Phase::Up => self.ends_q[0],
            _ => self.ends_q[2],
        };
        let (v0, v1) = self.prof.phase_speeds(p);
        let per_s = hz / acc; // R per mm/s, timer counts
        if v0.max(v1) * per_s >= (1u32 << 30) as f32 {
            return None;
        }
        let k = 2.0 * hz * per_s; // W per mm, ticks^2
        let square = |v: f32| {
            let r = (v * per_s + 0.5) as u64;
            (r * r, r as u32)
        };
        // W grows along the path in the first ramp (if it speeds up), falls otherwise.
        let grows = p == Phase::Up && v1 >= v0;
        let RampRun {
            n,
            w,
            dw: [dw1, dw2, dw3],
            s1,
            rate1,
        } = if let Some(q) = self.line_tick_q {
            // A line: whole ticks up to the ramp's end, W from whole ticks from its
            // anchor, so that a ramp to rest ends exactly at W = 0 (where time is most
            // sensitive to it).
            let n = (ticks_in(end.saturating_sub(at.s), q) as u32).min(self.run_left);
            let dw = (k * from_q(q)) as u64;
            let ticks = if p == Phase::Up {
                ticks_in(at.s, q)
            } else {
                u64::from(n)
            };
            let d = ticks.wrapping_mul(dw);
            let w = match p {
                Phase::Up if grows => square(v0).0 + d,
                Phase::Up => square(v0).0.saturating_sub(d),
                _ => square(v1).0 + d,
            };
            let s1 = at.s + q * u64::from(n);
            RampRun {
                n,
                w,
                dw: [if grows { dw } else { dw.wrapping_neg() }, 0, 0],
                s1,
                rate1: 1.0,
            }
        } else {
            // A curve: as many ticks as a cubic of the path position follows within
            // the bound (the time error is the position error over the speed).
            let to_end = from_q(end.saturating_sub(at.s)) / (at.rate * self.scale);
            let mut n = self
                .run_left
                .min(MAX_SEGMENT)
                .min(to_end.max(1.0) as u32)
                .max(1);
            let s4 = self.interp.run_bounds(n)[3] * self.scale;
            // Halving until the bound holds at the segment's slowest point (its start
            // when speeding up, its end when slowing down).
            loop {
                let nf = n as f32;
                let v2 = if grows {
                    at.v * at.v
                } else {
                    at.v * at.v - 2.0 * acc * nf * self.scale * LONGEST_TICK
                };
                let room = 384.0 * eps * crate::fmath::sqrt(v2.max(0.0));
                if n == 1 || s4 * nf * nf * nf * nf <= room {
                    break;
                }
                n /= 2;
            }
            let (s1, rate1) = loop {
                let (s1, r) = self.ahead(n);
                if s1 <= end || n == 1 {
                    break (s1, r);
                }
                n = (n / 2).max(1);
            };
            if s1 > end {
                return None;
            }
            let ds = from_q(s1 - at.s) / self.scale;
            // W at the segment's last tick (exactly the anchor's at the end of a ramp to
            // rest, where the time is most sensitive to it).
            let d1 = match p {
                Phase::Up => from_q(s1),
                _ => from_q(end.saturating_sub(s1)),
            };
            let w_end = match p {
                Phase::Up if grows => square(v0).0 as f32 + k * d1,
                Phase::Up => square(v0).0 as f32 - k * d1,
                _ => square(v1).0 as f32 + k * d1,
            };
            let w_end = if d1 == 0.0 {
                match p {
                    Phase::Up => square(v0).0,
                    _ => square(v1).0,
                }
            } else {
                w_end.max(0.0) as u64
            };
            // W along the segment: the Hermite cubic of the path position (run units),
            // scaled to W, as forward differences; the start is set back from the end
            // by their exact sum.
            let kk = if grows {
                k * self.scale
            } else {
                -k * self.scale
            };
            let [e1, e2, e3] = hermite(n, ds, at.rate, rate1).map(|d| (kk * d) as i64);
            // The sums of 1, k and k(k-1)/2 over the ticks: n <= MAX_SEGMENT, so they
            // fit in 32 bits (a 64-bit division would link a kilobyte of library code).
            let pairs = n * (n - 1) / 2;
            let triples = pairs * n.saturating_sub(2) / 3;
            let sum = i64::from(n) * e1 + i64::from(pairs) * e2 + i64::from(triples) * e3;
            RampRun {
                n,
                w: (w_end as i64).wrapping_sub(sum).max(0) as u64,
                dw: [e1 as u64, e2 as u64, e3 as u64],
                s1,
                rate1,
            }
        };
        if n == 0 || (dw1 as i64).unsigned_abs() > 1 << 46 {
            // None, or a first or last step slower than half a command's wait: that
            // one goes on its own.
            return None;
        }
        let (anchor, r_ref, rising_t) = match p {
            Phase::Up => (self.anchors[0], square(v0).1, grows),
            _ => (self.anchors[2], square(v1).1, false),
        };
        // The tick's time: anchor + (R - R_ref) (rising) or anchor - (R - R_ref).
        let off = if rising_t {
            anchor.wrapping_sub(u64::from(r_ref))
        } else {
            anchor.wrapping_add(u64::from(r_ref))
        };
        let r = RampTiming::root_near(w, (at.v * per_s) as u32);
        let dr = if r > 0 {
            (dw1 as i64 as f32 / (2 * r) as f32) as i32
        } else {
            0
        };
        let ramp = RampTiming {
            w,
            dw1,
            dw2,
            dw3,
            rising_t,
            r0: off.wrapping_sub(at.at) as u32,
            r,
            dr,
            ddr: 0,
        };
        let seg = Segment {
            left: n,
            timing: Timing::Ramp(ramp),
            base: at.at,
            at: t_last.wrapping_sub(at.at) as u32,
        };
        Some((
            seg,
            Cursor {
                rate: rate1,
                ..self.exact(p, s1, hz)
            },
        ))
    }

    /// The longest segment (at most `cap` ticks, and where the time is not linear in
    /// the tick count at most [`MAX_SEGMENT`], a power-of-two fraction of it) whose
    /// timing polynomial stays within `eps` seconds of the ideal: h^4/384 times a bound
    /// of the tick time's fourth derivative, from the phase's acceleration, jerk and
    /// its rate, the speed (its lowest in the segment) and the path's derivatives.
    pub(super) fn segment_len(&self, p: Phase, cap: u32, eps: f32, hz: f32) -> (u32, bool) {
        let at = self.at;
        let per_tick = at.rate * self.scale;
        // Ticks to the phase's end at the present rate, and a segment's longest span.
        let end = match p {
            Phase::Up => self.ends_q[0],
            Phase::Cruise => self.ends_q[1],
            Phase::Down => self.ends_q[2],
        };
        let to_end = from_q(end.saturating_sub(at.s)) / per_tick;
        let by_time = MAX_SEGMENT_COUNTS * at.v / (per_tick * hz);
        let mut n = cap
            .min(to_end.max(1.0) as u32)
            .min(by_time.max(1.0) as u32)
            .max(1);
        let [acc, jerk, djerk] = self.prof.derivative_bounds(p);
        let [r1, r2, r3, r4] = self.interp.run_bounds(n);
        let sc = self.scale;
        let (s1, s2, s3, s4) = (r1 * sc, r2 * sc, r3 * sc, r4 * sc);
        if acc == 0.0 && s2 == 0.0 {
            // Time is linear in the tick count; [`MAX_LINEAR`] bounds the f32 rounding
            // of the interval before the next exact time.
            return (n.min(MAX_LINEAR), true);
        }
        n = n.min(MAX_SEGMENT);
        // |d^4 t / dk^4| at speed v (in a cruise only the path's curvature counts).
        let bound = |v: f32| {
            if acc == 0.0 {
                return s4 / v;
            }
            let x = 1.0 / v;
            let x2 = x * x;
            let x4 = x2 * x2;
            let t2 = acc * x2 * x;
            let t3 = jerk * x4 + 3.0 * acc * acc * x4 * x;
            let t4 = x4 * x * (djerk + x * (10.0 * acc * jerk + 15.0 * acc * acc * acc * x));
            let s1sq = s1 * s1;
            t4 * s1sq * s1sq + 6.0 * t3 * s1sq * s2 + t2 * (3.0 * s2 * s2 + 4.0 * s1 * s3) + x * s4
        };
        let limit = 384.0 * eps;
        // The largest power-of-two fraction of n with bound * n^4 <= limit: one bound,
        // then a factor 16 per halving.
        let fits = |b: f32, n: u32| {
            let nf = n as f32;
            let mut x = b * nf * nf * nf * nf;
            let mut n = n;
            while n > 1 && !(x <= limit) {
                x *= 1.0 / 16.0;
                n /= 2;
            }
            n
        };
        let v = at.v;
        n = fits(bound(v), n);
        if !self.prof.phase_rises(p) {
            // Slowing down: the segment's lowest speed is at its end.
            while n > 1 {
                let v2 = v * v - 2.0 * acc * n as f32 * s1;
                let m = if v2 > 0.0 {
                    fits(bound(crate::fmath::sqrt(v2)), n)
                } else {
                    n / 2
                };
                if m == n {
                    break;
                }
                n = m;
            }
        }
        (n, false)
    }
}
