//! Step-trace analysis: job time, deviation of every step position from the ideal
//! path, and the end position, the figures the motion benchmark compares with Grbl.
//!
//! Owns only measurement; it is fed step events one at a time (from a run or a trace
//! file) and keeps O(1) state besides the ideal path it is given. Bench-only, so it
//! lives in the simulator, not in the firmware's core.

use inkstep_core::motion::{StepPos, AXES};

/// The ideal path, in mm.
#[derive(Clone, Copy, Debug)]
pub enum Ideal<'a> {
    /// A polyline through these points.
    Poly(&'a [[f64; 2]]),
    /// A circle.
    Circle { c: [f64; 2], r: f64 },
}

impl Ideal<'_> {
    /// Distance in mm from `p` (mm) to the path.
    pub fn distance(&self, p: [f64; 2]) -> f64 {
        match *self {
            Ideal::Circle { c, r } => (f64::hypot(p[0] - c[0], p[1] - c[1]) - r).abs(),
            Ideal::Poly(pts) => {
                let mut best = f64::INFINITY;
                if let [only] = pts {
                    return f64::hypot(p[0] - only[0], p[1] - only[1]);
                }
                for w in pts.windows(2) {
                    best = best.min(seg_distance(w[0], w[1], p));
                }
                best
            }
        }
    }
}

fn seg_distance(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    f64::hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)
}

/// Figures of one run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceStats {
    /// First step to last step, seconds.
    pub job_time: f64,
    /// Time of the last step, seconds (from the trace's time origin: the simulator's
    /// trace starts when the step timer first starts).
    pub last_step: f64,
    /// Largest and RMS distance of a step position from the ideal path, in steps.
    pub max_dev: f64,
    pub rms_dev: f64,
    /// Steps emitted per axis.
    pub steps: [u64; AXES],
    /// Position after the last step.
    pub end: StepPos,
    /// Step events seen.
    pub events: u64,
}

/// Accumulates [`TraceStats`] from step events.
#[derive(Clone, Debug)]
pub struct Analyzer<'a> {
    ideal: Ideal<'a>,
    steps_per_mm: [f64; 2],
    first_t: Option<f64>,
    last_t: f64,
    max_dev: f64,
    sum_sq: f64,
    steps: [u64; AXES],
    end: StepPos,
    events: u64,
}

impl<'a> Analyzer<'a> {
    /// `steps_per_mm` of X and Y (deviation is reported in steps of X).
    pub fn new(ideal: Ideal<'a>, steps_per_mm: [f64; 2], start: StepPos) -> Self {
        Analyzer {
            ideal,
            steps_per_mm,
            first_t: None,
            last_t: 0.0,
            max_dev: 0.0,
            sum_sq: 0.0,
            steps: [0; AXES],
            end: start,
            events: 0,
        }
    }

    /// One step event at time `t` seconds: `step` is the mask of axes that stepped and
    /// `pos` the position after it.
    pub fn step(&mut self, t: f64, step: u8, pos: StepPos) {
        if self.first_t.is_none() {
            self.first_t = Some(t);
        }
        self.last_t = t;
        for (i, n) in self.steps.iter_mut().enumerate() {
            if step & (1 << i) != 0 {
                *n += 1;
            }
        }
        self.end = pos;
        self.events += 1;
        let p = [
            f64::from(pos[0]) / self.steps_per_mm[0],
            f64::from(pos[1]) / self.steps_per_mm[1],
        ];
        let d = self.ideal.distance(p) * self.steps_per_mm[0];
        self.max_dev = self.max_dev.max(d);
        self.sum_sq += d * d;
    }

    pub fn finish(&self) -> TraceStats {
        TraceStats {
            job_time: self.last_t - self.first_t.unwrap_or(self.last_t),
            last_step: self.last_t,
            max_dev: self.max_dev,
            rms_dev: if self.events > 0 {
                f64::sqrt(self.sum_sq / self.events as f64)
            } else {
                0.0
            },
            steps: self.steps,
            end: self.end,
            events: self.events,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_to_polyline_and_circle() {
        let pts = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]];
        let poly = Ideal::Poly(&pts);
        assert!((poly.distance([5.0, 1.0]) - 1.0).abs() < 1e-12);
        assert!((poly.distance([12.0, 5.0]) - 2.0).abs() < 1e-12);
        assert!((poly.distance([-3.0, -4.0]) - 5.0).abs() < 1e-12);
        let c = Ideal::Circle {
            c: [1.0, 1.0],
            r: 2.0,
        };
        assert!((c.distance([1.0, 4.0]) - 1.0).abs() < 1e-12);
        assert!((c.distance([1.0, 1.0]) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn analyzer_counts_time_steps_and_deviation() {
        let pts = [[0.0, 0.0], [1.0, 0.0]];
        let mut a = Analyzer::new(Ideal::Poly(&pts), [10.0, 10.0], [0; 3]);
        a.step(0.5, 1, [1, 0, 0]);
        a.step(0.7, 3, [2, 1, 0]);
        a.step(1.0, 1, [3, 1, 0]);
        let s = a.finish();
        assert!((s.job_time - 0.5).abs() < 1e-12);
        assert!((s.last_step - 1.0).abs() < 1e-12);
        assert_eq!(s.steps, [3, 1, 0]);
        assert_eq!(s.end, [3, 1, 0]);
        // 0.1 mm off the line at 10 steps/mm: one step.
        assert!((s.max_dev - 1.0).abs() < 1e-9);
        assert!((s.rms_dev - (2.0f64 / 3.0).sqrt()).abs() < 1e-9);
    }
}
