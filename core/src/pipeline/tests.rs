//! The pipeline's tests: pen timing, holds with a servo and a Z pen, the reported
//! speed and state, against a step queue the test drains by hand.

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
    type Queue = StepQueue<256>;
    fn sink(&mut self) -> &mut Self::Queue {
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
    // Seen at one tick, started RESUME_MS later.
    assert_eq!(start_from_rest(&mut pipeline), super::RESUME_MS + 1);
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
    start_from_rest(&mut pipeline);
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
    // Ticks already run into the next millisecond (a command longer than the rest of
    // this one, such as a start's lead).
    let mut t = 0u64;
    for _ in 0..ms {
        pipeline.fill();
        let side = pipeline.side_mut();
        while t < per_ms {
            let Some(c) = side.queue.pop() else {
                t = per_ms;
                break;
            };
            c.tick().apply(&mut side.pos);
            t += u64::from(c.wait());
        }
        t -= per_ms;
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

/// Service ticks until work pushed at rest starts ([`super::RESUME_MS`]); their count.
fn start_from_rest(pipeline: &mut Pipeline<TestSide>) -> u8 {
    let mut ms = 0;
    while MotionControl::queued(pipeline) > 0 && !pipeline.is_moving() {
        pipeline.fill();
        ms += 1;
        assert!(ms <= super::RESUME_MS + 1, "never started");
    }
    ms
}

/// Milliseconds until the pipeline is at rest, from the start of the work pushed.
fn ms_to_rest(pipeline: &mut Pipeline<TestSide>, log: &mut Vec<(u16, StepPos)>) -> usize {
    start_from_rest(pipeline);
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

/// A Z pen's up and down places ($205, $206) in steps.
fn z_places(s: &Settings) -> (i32, i32) {
    let spm = s.steps_per_mm(2);
    (
        crate::fmath::round(s.pen_z_up() * spm) as i32,
        crate::fmath::round(s.pen_z_down() * spm) as i32,
    )
}

/// A Z pen ($201=0): a hold mid-stroke lifts Z to $205 once XY is at rest (XY
/// still, Hold:0 only once Z is up), resume brings it back to the same step before
/// XY moves on, and the steps drawn with the pen down are exactly those of the
/// uninterrupted job. An abort leaves Z where it stands.
#[test]
fn a_z_pen_goes_up_for_a_hold_and_back_down_before_the_stroke_goes_on() {
    let s = Settings::default();
    let (up, down) = z_places(&s);
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

/// The one motion state through a job with a hold: Idle, Running, Holding while XY
/// brakes, Held at rest (with the position still), Running again on resume, Idle at
/// the exact end; a clear ends the hold.
#[test]
fn the_motion_state_follows_a_hold_from_braking_to_rest_and_back() {
    let mut log = Vec::new();
    let mut p = test_pipeline(&Settings::default());
    assert_eq!(p.motion(), MotionState::Idle);
    p.push(mv([8000, 0, 0], Feed::MmPerMin(600.0))).unwrap();
    run_timed(&mut p, 300, &mut log);
    assert_eq!(p.motion(), MotionState::Running);
    p.hold();
    assert_eq!(p.motion(), MotionState::Holding, "braking");
    let mut braking_ms = 0;
    while p.motion() == MotionState::Holding {
        run_timed(&mut p, 1, &mut log);
        braking_ms += 1;
        assert!(braking_ms < 1000, "never at rest");
    }
    assert_eq!(p.motion(), MotionState::Held);
    assert!(braking_ms > 1, "it braked: {braking_ms} ms");
    let held = p.position();
    run_timed(&mut p, 100, &mut log);
    assert_eq!((p.motion(), p.position()), (MotionState::Held, held));
    p.resume();
    run_timed(&mut p, 2, &mut log);
    assert_eq!(p.motion(), MotionState::Running);
    ms_to_rest(&mut p, &mut log);
    assert_eq!(
        (p.motion(), p.position()),
        (MotionState::Idle, [8000, 0, 0])
    );

    p.push(mv([0, 0, 0], Feed::MmPerMin(600.0))).unwrap();
    run_timed(&mut p, 300, &mut log);
    p.hold();
    p.clear();
    assert_eq!(p.motion(), MotionState::Idle, "a clear ends the hold");
}

/// A hold that comes to rest at the end of the last planned move (asked while that
/// move was still being prepared, in its last ramp) holds what follows too: the dwell
/// after it and the move after that wait for the resume, as with a hold asked
/// mid-move.
#[test]
fn a_hold_in_the_last_ramp_holds_the_dwell_and_moves_behind_it() {
    let job = |p: &mut Pipeline<TestSide>| {
        p.push(mv([800, 0, 0], Feed::MmPerMin(600.0))).unwrap();
        p.push(Command::Dwell { ms: 500 }).unwrap();
        p.push(mv([1600, 0, 0], Feed::MmPerMin(600.0))).unwrap();
    };
    // The latest moment the move is still in preparation, and the hold then comes
    // to rest at its end.
    let mut found = None;
    for ms in (300..1500).step_by(5) {
        let (mut log, mut p) = (Vec::new(), test_pipeline(&Settings::default()));
        job(&mut p);
        run_timed(&mut p, ms, &mut log);
        if !p.prep.in_block() {
            break;
        }
        p.hold();
        run_timed(&mut p, 1000, &mut log);
        if p.position() == [800, 0, 0] {
            found = Some(ms);
        }
    }
    let ms = found.expect("no hold in the last ramp that ends at the move's end");
    let (mut log, mut p) = (Vec::new(), test_pipeline(&Settings::default()));
    job(&mut p);
    run_timed(&mut p, ms, &mut log);
    p.hold();
    run_timed(&mut p, 2000, &mut log);
    assert_eq!(
        (p.motion(), p.position()),
        (MotionState::Held, [800, 0, 0]),
        "held at the move's end"
    );
    p.resume();
    // The dwell runs now, after the resume, whole.
    run_timed(&mut p, 450, &mut log);
    assert_eq!(p.position(), [800, 0, 0], "the dwell waited for the resume");
    ms_to_rest(&mut p, &mut log);
    assert_eq!(
        (p.motion(), p.position()),
        (MotionState::Idle, [1600, 0, 0])
    );
}

/// No call prepares more than twice its horizon, however uneven the step waits:
/// point by point (`$212=0`) a circle's minor-axis step comes a few tens of µs after
/// a major one, and the count of commands estimated from that last wait once
/// prepared 77 single ticks, 45 ms of motion, in one call (every one of them
/// committed before a hold or an override could shape it, and 19 ms of the
/// preparation task under the emulator's pessimistic cycle model).
#[test]
fn no_call_prepares_far_past_its_horizon_after_a_short_wait() {
    let mut s = Settings::default();
    s.set(212, 0.0).unwrap(); // point by point
    s.set(210, 1.0).unwrap(); // S-curve
    let mut pipeline = test_pipeline(&s);
    pipeline
        .push(Command::Move(Move {
            target: [0, 0, 0],
            path: Path::Arc {
                center: [-400, 80],
                ccw: false,
                turns: 0,
            },
            feed: Feed::MmPerMin(1200.0),
            line: 0,
        }))
        .unwrap();
    let horizon = u64::from(TIMER_HZ / 1000 * HORIZON_MS);
    let per_ms = u64::from(TIMER_HZ / 1000);
    // The commands handed to the "timer", and the timer counts left of the first.
    let mut running: std::collections::VecDeque<StepCmd> = Default::default();
    let (mut left, mut worst, mut calls, mut steps) = (0u64, 0.0f64, 0, 0);
    for _ in 0..20_000 {
        pipeline.fill();
        calls += 1;
        let side = pipeline.side_mut();
        // What this call prepared: at most twice the horizon, and the steps the
        // queue keeps at least (`MIN_AHEAD`, each as long as the longest of the
        // call's), and the step that crosses the bound.
        let (mut span, mut longest) = (0u64, 0u64);
        while let Some(c) = side.queue.pop() {
            span += u64::from(c.wait());
            longest = longest.max(u64::from(c.wait()));
            running.push_back(c);
        }
        let bound = (2 * horizon).max(MIN_AHEAD as u64 * longest) + longest;
        worst = worst.max(span as f64 / bound as f64);
        let mut budget = per_ms;
        while budget > 0 {
            if left == 0 {
                let Some(c) = running.front() else { break };
                left = u64::from(c.wait());
            }
            let take = left.min(budget);
            left -= take;
            budget -= take;
            if left == 0 {
                if let Some(c) = running.pop_front() {
                    c.tick().apply(&mut side.pos);
                    steps += c.tick().steps().count_ones();
                }
            }
        }
        side.busy = running.iter().map(|c| u64::from(c.wait())).sum::<u64>();
        if side.busy == 0 && !pipeline.executing() && calls > 100 {
            break;
        }
    }
    // Point by point, one axis a step: the circle's length in steps (radius 408)
    // times 4/pi, about 3,260.
    assert!(steps > 3000, "{steps} steps");
    assert_eq!(pipeline.position(), [0, 0, 0], "the whole circle ran");
    assert!(worst <= 1.0, "a call prepared {worst:.1} times its bound");
}

/// A hold at rest lifts a Z pen a horizon at a time, as XY is prepared: each step's
/// wait costs a square root and two divisions, and 32 at once took the call that
/// starts the step timer 1.6 ms under the emulator's pessimistic cycle model, past
/// what the lift's first wait absorbs (`.ci/emu-random`, seed 456428396).
#[test]
fn a_hold_at_rest_queues_the_z_lift_a_horizon_at_a_time() {
    let s = Settings::default();
    let (up, down) = z_places(&s);
    let mut p = test_pipeline(&s);
    p.push(mv([0, 0, down], Feed::MmPerMin(600.0))).unwrap();
    let mut log = Vec::new();
    run_steps(&mut p, &mut log, |_| false);
    assert_eq!(p.position(), [0, 0, down]);
    for _ in 0..30 {
        p.fill();
    }
    p.hold();
    p.fill();
    let horizon = u64::from(TIMER_HZ / 1000 * HORIZON_MS);
    let mut waits = Vec::new();
    let side = p.side_mut();
    while let Some(c) = side.queue.pop() {
        c.tick().apply(&mut side.pos);
        waits.push(u64::from(c.wait()));
    }
    assert!(!waits.is_empty(), "the lift began");
    let before_last: u64 = waits[..waits.len() - 1].iter().sum();
    assert!(
        waits.len() <= MIN_AHEAD || before_last < horizon,
        "{} Z steps queued at once, {:?}",
        waits.len(),
        waits
    );
    run_steps(&mut p, &mut log, |p| p.position()[2] == up);
    assert_eq!(p.position(), [0, 0, up], "the pen went all the way up");
}
