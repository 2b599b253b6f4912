//! The whole motion chain (planner -> preparation -> queue -> interrupt) run in
//! virtual time, exactly as the firmware runs it but with the timer simulated. Used
//! by the simulator and by tests that need a step trace; it holds no logic of its own
//! beyond calling the same functions the firmware tasks call.

use super::exec::Executor;
use super::prep::{HoldState, Prep, PrepConfig};
use super::StepCmd;
use crate::motion::{Move, StepPos};
use crate::planner::{PlanError, Planner, PlannerConfig};
use heapless::spsc::Queue;

/// Step queue depth used by the firmware and the virtual machine.
pub const STEP_QUEUE: usize = 256;

/// One step event: time in timer ticks since the machine was created, the axes that
/// stepped and the position after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepEvent {
    pub t: u64,
    pub step: u8,
    pub pos: StepPos,
}

/// The motion chain in virtual time.
pub struct VirtualMachine {
    pub planner: Planner,
    pub prep: Prep,
    pub exec: Executor,
    queue: Queue<StepCmd, STEP_QUEUE>,
    now: u64,
    next_irq: Option<u64>,
    /// Interrupts taken (with and without a step).
    pub interrupts: u64,
}

impl VirtualMachine {
    pub fn new(cfg: PlannerConfig, prep: PrepConfig, position: StepPos) -> Self {
        VirtualMachine {
            planner: Planner::new(cfg, position),
            prep: Prep::new(prep, position),
            exec: Executor::new(position, 0xFFFF),
            queue: Queue::new(),
            now: 0,
            next_irq: None,
            interrupts: 0,
        }
    }

    /// Present virtual time in timer ticks.
    pub fn now(&self) -> u64 {
        self.now
    }

    /// Queues a move (the G-code / keypad side).
    pub fn push(&mut self, mv: &Move) -> Result<(), PlanError> {
        self.planner.push(mv)
    }

    /// Everything executed and nothing left to do (or held at rest).
    pub fn is_idle(&self) -> bool {
        self.next_irq.is_none()
            && self.queue.is_empty()
            && (self.prep.is_idle(&self.planner) || self.prep.hold_state() == HoldState::Held)
    }

    /// Runs until virtual time `until` or until idle; calls `on_step` for each step.
    pub fn run_until(&mut self, until: u64, on_step: &mut impl FnMut(StepEvent)) {
        loop {
            if self.queue.len() < STEP_QUEUE / 2 {
                self.prep.fill(&mut self.planner, &mut self.queue, STEP_QUEUE);
            }
            if self.next_irq.is_none() {
                match self.exec.start(&mut self.queue) {
                    Some(o) => self.next_irq = Some(self.now + u64::from(o.reload)),
                    None => {
                        if self.is_idle() || self.exec.is_halted() {
                            return;
                        }
                    }
                }
            }
            let Some(t) = self.next_irq else { continue };
            if t > until {
                self.now = until;
                return;
            }
            self.now = t;
            self.interrupts += 1;
            let o = self.exec.on_interrupt(&mut self.queue);
            if o.step != 0 {
                on_step(StepEvent {
                    t,
                    step: o.step,
                    pos: self.exec.position(),
                });
            }
            self.next_irq = if o.reload == 0 {
                None
            } else {
                Some(t + u64::from(o.reload))
            };
        }
    }

    /// Runs everything queued to the end.
    pub fn run_to_idle(&mut self, on_step: &mut impl FnMut(StepEvent)) {
        self.run_until(u64::MAX, on_step);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{Feed, Path};
    use crate::planner::Shape;
    use std::vec::Vec;

    const HZ: f64 = 72_000_000.0;

    fn line(x: i32, y: i32, f: f32) -> Move {
        Move {
            target: [x, y, 0],
            path: Path::Line,
            feed: Feed::MmPerMin(f),
            line: 0,
        }
    }

    fn run(vm: &mut VirtualMachine) -> Vec<StepEvent> {
        let mut ev = Vec::new();
        vm.run_to_idle(&mut |e| ev.push(e));
        ev
    }

    /// Steps per second of axis X in [t0, t1) seconds.
    fn rate(ev: &[StepEvent], t0: f64, t1: f64) -> f64 {
        let n = ev
            .iter()
            .filter(|e| e.step & 1 != 0 && (e.t as f64 / HZ) >= t0 && (e.t as f64 / HZ) < t1)
            .count();
        n as f64 / (t1 - t0)
    }

    #[test]
    fn straight_line_runs_the_trapezoid() {
        let mut vm = VirtualMachine::new(PlannerConfig::default(), PrepConfig::default(), [0; 3]);
        vm.push(&line(8000, 0, 3000.0)).unwrap();
        let ev = run(&mut vm);
        assert_eq!(ev.len(), 8000);
        assert_eq!(ev.last().unwrap().pos, [8000, 0, 0]);
        // 100 mm at 50 mm/s with 0.1 s ramps: 2.1 s.
        let t_end = ev.last().unwrap().t as f64 / HZ;
        assert!((t_end - 2.1).abs() < 1e-3, "{t_end}");
        // Cruise: 50 mm/s * 80 steps/mm.
        let r = rate(&ev, 1.0, 1.2);
        assert!((r - 4000.0).abs() <= 10.0, "{r}");
    }

    #[test]
    fn thesis_s_curve_example_reaches_20_khz_at_two_seconds() {
        // 200 pulses/rev, "mm" = rev: 100 rev/s cruise, 1 s cosine ramp, 500 rev.
        let mut cfg = PlannerConfig::default();
        cfg.axes[0] = crate::planner::AxisConfig {
            steps_per_mm: 200.0,
            max_rate: 6000.0,
            accel: core::f32::consts::PI * 100.0 / 2.0,
        };
        cfg.shape = Shape::Cosine;
        let mut vm = VirtualMachine::new(cfg, PrepConfig::default(), [0; 3]);
        vm.push(&line(100_000, 0, 6000.0)).unwrap();
        let ev = run(&mut vm);
        assert_eq!(ev.len(), 100_000);
        let f2 = rate(&ev, 1.99, 2.01);
        assert!((f2 - 20_000.0).abs() <= 100.0, "{f2}");
        let f_half = rate(&ev, 0.49, 0.51);
        assert!((f_half - 10_000.0).abs() <= 200.0, "{f_half}");
        let t_end = ev.last().unwrap().t as f64 / HZ;
        assert!((t_end - 6.0).abs() < 2e-3, "{t_end}");
    }

    #[test]
    fn feed_hold_brakes_to_rest_and_resumes_without_losing_a_step() {
        let mut vm = VirtualMachine::new(PlannerConfig::default(), PrepConfig::default(), [0; 3]);
        vm.push(&line(8000, 0, 3000.0)).unwrap();
        vm.push(&line(8000, 4000, 3000.0)).unwrap();
        let mut ev = Vec::new();
        vm.run_until((0.8 * HZ) as u64, &mut |e| ev.push(e));
        vm.prep.hold();
        vm.run_to_idle(&mut |e| ev.push(e));
        assert_eq!(vm.prep.hold_state(), HoldState::Held);
        let stop = ev.last().unwrap().pos;
        // Braking from 50 mm/s at 500 mm/s^2 takes 2.5 mm = 200 steps, plus what was
        // already queued (at most the queue).
        let at_hold = ev.iter().rfind(|e| (e.t as f64) <= 0.8 * HZ).unwrap().pos[0];
        assert!(
            stop[0] - at_hold >= 200 - 5 && stop[0] - at_hold <= 200 + STEP_QUEUE as i32,
            "{at_hold} {stop:?}"
        );
        // Nothing moves while held.
        let held_t = vm.now();
        vm.run_until(held_t + (0.5 * HZ) as u64, &mut |e| ev.push(e));
        assert_eq!(ev.last().unwrap().pos, stop);
        vm.prep.resume(&mut vm.planner);
        vm.run_to_idle(&mut |e| ev.push(e));
        assert_eq!(ev.last().unwrap().pos, [8000, 4000, 0]);
        assert_eq!(ev.iter().filter(|e| e.step & 1 != 0).count(), 8000);
        assert_eq!(ev.iter().filter(|e| e.step & 2 != 0).count(), 4000);
    }

    #[test]
    fn emergency_stop_emits_no_further_step() {
        let mut vm = VirtualMachine::new(PlannerConfig::default(), PrepConfig::default(), [0; 3]);
        vm.push(&line(8000, 0, 3000.0)).unwrap();
        let mut ev = Vec::new();
        vm.run_until((0.5 * HZ) as u64, &mut |e| ev.push(e));
        let n = ev.len();
        vm.exec.halt();
        vm.run_until((3.0 * HZ) as u64, &mut |e| ev.push(e));
        assert_eq!(ev.len(), n);
        assert_eq!(vm.exec.position(), ev.last().unwrap().pos);
    }

    #[test]
    fn circle_keeps_constant_path_speed() {
        let mut vm = VirtualMachine::new(PlannerConfig::default(), PrepConfig::default(), [0; 3]);
        let c = Move {
            target: [0; 3],
            path: Path::Arc {
                center: [1600, 0],
                ccw: false,
                turns: 0,
            },
            feed: Feed::MmPerMin(3000.0),
            line: 0,
        };
        vm.push(&c).unwrap();
        let ev = run(&mut vm);
        assert_eq!(ev.last().unwrap().pos, [0, 0, 0]);
        // Path speed (swept angle times radius) over 50 ms windows in the cruise: 50 mm/s
        // within 1 % (the position is quantised to a step at both ends).
        let at = |t: f64| ev.iter().rfind(|e| e.t as f64 / HZ <= t).unwrap().pos;
        let ang = |p: StepPos| f64::from(p[1]).atan2(f64::from(p[0] - 1600));
        for k in 0..40 {
            let t = 0.2 + 0.05 * f64::from(k);
            let (a, b) = (at(t), at(t + 0.05));
            let mut da = (ang(a) - ang(b)).rem_euclid(std::f64::consts::TAU);
            if da > std::f64::consts::PI {
                da -= std::f64::consts::TAU;
            }
            let v = da * 20.0 / 0.05;
            assert!((v - 50.0).abs() < 0.5, "t={t} v={v}");
        }
        let t_end = ev.last().unwrap().t as f64 / HZ;
        assert!(
            (t_end - (std::f64::consts::TAU * 20.0 / 50.0 + 0.1)).abs() < 5e-3,
            "{t_end}"
        );
    }

    #[test]
    fn feed_override_changes_the_cruise_speed() {
        let mut vm = VirtualMachine::new(PlannerConfig::default(), PrepConfig::default(), [0; 3]);
        vm.push(&line(16000, 0, 3000.0)).unwrap();
        let mut ev = Vec::new();
        vm.run_until((1.0 * HZ) as u64, &mut |e| ev.push(e));
        vm.planner.set_feed_override(50);
        vm.run_to_idle(&mut |e| ev.push(e));
        assert!((rate(&ev, 0.5, 0.6) - 4000.0).abs() <= 20.0);
        assert!((rate(&ev, 2.0, 2.1) - 2000.0).abs() <= 20.0);
        assert_eq!(ev.last().unwrap().pos, [16000, 0, 0]);
    }

    #[test]
    fn s_curve_hold_mid_arc_resumes_to_the_exact_end() {
        let cfg = PlannerConfig {
            shape: Shape::Cosine,
            ..PlannerConfig::default()
        };
        let mut vm = VirtualMachine::new(cfg, PrepConfig::default(), [0; 3]);
        // Two full turns (one extra) around a centre 10 mm to the right, counter-clockwise.
        let arc = Move {
            target: [0; 3],
            path: Path::Arc {
                center: [800, 0],
                ccw: true,
                turns: 1,
            },
            feed: Feed::MmPerMin(2400.0),
            line: 7,
        };
        vm.push(&arc).unwrap();
        let mut ev = Vec::new();
        vm.run_until((0.6 * HZ) as u64, &mut |e| ev.push(e));
        vm.prep.hold();
        vm.run_to_idle(&mut |e| ev.push(e));
        assert_eq!(vm.prep.hold_state(), HoldState::Held);
        let held = ev.len();
        vm.prep.resume(&mut vm.planner);
        vm.run_to_idle(&mut |e| ev.push(e));
        assert!(ev.len() > held);
        assert_eq!(ev.last().unwrap().pos, [0, 0, 0]);
        // Two turns of a 800-step circle: both extremes of X reached, every step within
        // half a step of the circle (DDA).
        assert_eq!(ev.iter().map(|e| e.pos[0]).max(), Some(1600));
        for e in &ev {
            let r = (f64::from(e.pos[0] - 800)).hypot(f64::from(e.pos[1]));
            assert!((r - 800.0).abs() <= 0.71, "{:?}", e.pos);
        }
    }

    #[test]
    fn start_speed_lets_motors_start_without_a_ramp() {
        let cfg = PlannerConfig {
            start_speed: 5.0,
            ..PlannerConfig::default()
        };
        let mut vm = VirtualMachine::new(cfg, PrepConfig::default(), [0; 3]);
        vm.push(&line(800, 0, 3000.0)).unwrap();
        let ev = run(&mut vm);
        // The first step (0.0125 mm) comes accelerating from 5 mm/s at 500 mm/s^2:
        // (-5 + sqrt(25 + 2 * 500 * 0.0125)) / 500 = 2.25 ms, not the 7.07 ms of a ramp
        // from rest.
        let t1 = ev[0].t as f64 / HZ;
        let expect = (-5.0 + (25.0f64 + 2.0 * 500.0 * 0.0125).sqrt()) / 500.0;
        assert!((t1 - expect).abs() < 5e-5, "{t1} vs {expect}");
        assert_eq!(ev.last().unwrap().pos, [800, 0, 0]);
    }

    #[test]
    fn ellipse_sine_and_pen_moves_run_through_the_whole_chain() {
        let mut vm = VirtualMachine::new(PlannerConfig::default(), PrepConfig::default(), [0; 3]);
        let pen_down = Move {
            target: [0, 0, -80],
            path: Path::Line,
            feed: Feed::Rapid,
            line: 1,
        };
        let ellipse = Move {
            target: [0, 0, -80],
            path: Path::Ellipse {
                center: [-1600, 0],
                a: 1600,
                b: 800,
                ccw: true,
            },
            feed: Feed::MmPerMin(1800.0),
            line: 2,
        };
        let sine = Move {
            target: [3200, 0, -80],
            path: Path::Sine {
                amp: 400.0,
                omega: core::f32::consts::TAU / 1600.0,
                phase: 0.0,
            },
            feed: Feed::MmPerMin(1800.0),
            line: 3,
        };
        for m in [pen_down, ellipse, sine] {
            vm.push(&m).unwrap();
        }
        let ev = run(&mut vm);
        assert_eq!(ev.last().unwrap().pos, [3200, 0, -80]);
        assert_eq!(vm.prep.skipped(), 0);
        // The ellipse reached its far end and the sine its crest (amplitude 400 steps).
        assert!(ev.iter().any(|e| e.pos[0] == -3200));
        assert!(ev.iter().any(|e| e.pos[1] == 400 && e.pos[0] > 0));
        // Time is monotonic and no two step events share a timer tick.
        assert!(ev.windows(2).all(|w| w[1].t > w[0].t));
    }
}
