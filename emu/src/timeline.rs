//! CPU load over time while a job runs (`cargo emu run --timeline MS`): per window of
//! virtual time, each task's share of the CPU and the step events put out. Shaped for
//! the questions a whole-run average hides: which part of a job a task falls behind
//! in (a curve whose events cost more than the rest), and whether the tasks below it
//! still get to run. Read from the cycle model's busy time per exception, as the
//! bench's load tables are.

use crate::bench::{rtic_tasks, task_name};
use crate::clock::{T_PER_MS, T_PER_S};
use crate::session::Session;
use std::fmt::Write as _;

/// Snapshots taken every `window` of virtual time.
pub struct Timeline {
    window: u64,
    next: u64,
    /// (time, busy time per exception, step events so far).
    rows: Vec<(u64, Vec<u64>, usize)>,
}

impl Timeline {
    /// A timeline of `window_ms` windows from now.
    pub fn new(s: &mut Session, window_ms: u64) -> Timeline {
        let mut t = Timeline {
            window: window_ms.max(1) * T_PER_MS,
            next: 0,
            rows: Vec::new(),
        };
        t.take(s);
        t
    }

    fn take(&mut self, s: &mut Session) {
        let now = s.now();
        let events = s.m.state().board.steps.len();
        let busy = s.m.state_mut().profile_now().busy.clone();
        self.rows.push((now, busy, events));
        self.next = now + self.window;
    }

    /// Take a snapshot if a window has passed (call it often: each sender step).
    pub fn poll(&mut self, s: &mut Session) {
        if s.now() >= self.next {
            self.take(s);
        }
    }

    /// Exception `e`'s share of the CPU in each window so far (0..1).
    pub fn shares(&self, e: usize) -> Vec<f64> {
        self.rows
            .windows(2)
            .map(|w| {
                let span = (w[1].0 - w[0].0).max(1) as f64;
                w[1].1
                    .get(e)
                    .zip(w[0].1.get(e))
                    .map_or(0.0, |(b, a)| (b - a) as f64)
                    / span
            })
            .collect()
    }

    /// The table: a row per window, a column per task that was busy at all (the six
    /// busiest over the whole run), then the step events per second.
    pub fn report(&self) -> String {
        let names = rtic_tasks();
        let (Some(first), Some(last)) = (self.rows.first(), self.rows.last()) else {
            return String::new();
        };
        let mut total: Vec<(usize, u64)> = (0..first.1.len())
            .map(|e| (e, last.1[e] - first.1[e]))
            .filter(|&(_, b)| b > 0)
            .collect();
        total.sort_by_key(|&(_, b)| std::cmp::Reverse(b));
        total.truncate(6);
        let mut out = String::from("\nCPU per window of virtual time:\n\n| from ms |");
        for &(e, _) in &total {
            let _ = write!(out, " {} |", task_name(e, &names));
        }
        out.push_str(" step events/s |\n|---:|");
        for _ in &total {
            out.push_str("---:|");
        }
        out.push_str("---:|\n");
        for w in self.rows.windows(2) {
            let span = (w[1].0 - w[0].0).max(1) as f64;
            let _ = write!(out, "| {:.0} |", w[0].0 as f64 / T_PER_MS as f64);
            for &(e, _) in &total {
                let _ = write!(
                    out,
                    " {:.1} % |",
                    100.0 * (w[1].1[e] - w[0].1[e]) as f64 / span
                );
            }
            let rate = (w[1].2 - w[0].2) as f64 * T_PER_S as f64 / span;
            let _ = writeln!(out, " {rate:.0} |");
        }
        out
    }
}
