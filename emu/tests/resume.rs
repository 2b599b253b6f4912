//! Resuming a job on the real image (issue 24 point 6): a line of text, its lines
//! numbered as a sender may number them, is streamed with character counting and a
//! `?` every 200 ms (as `cargo host send` does) and stopped by a soft reset in the
//! middle of a stroke. The host's resume (`inkstep_host::resume`, what `send
//! --resume` runs) picks the line from the board's last `Ln:`, rebuilds the state
//! before it and streams the rest. What the pen drew before the stop and after the
//! resume must together be what the uninterrupted job draws (every pen-down step
//! position on, or a grid neighbour of, one of the other's), and nothing may be
//! drawn twice beyond the line resumed.

mod common;

use common::booted;
use inkstep_core::settings::Settings;
use inkstep_emu::board::Step;
use inkstep_emu::clock::{T_PER_MS, T_PER_S};
use inkstep_emu::session::Session;
use inkstep_host::resume::{resume_lines, resume_point, spans_of, Seen};
use inkstep_serial::grbl::Reply;
use inkstep_serial::sender::{Answer, Event, Flow, Sender};
use inkstep_serial::stream::{prepare, Line};
use std::collections::HashSet;

/// The text job with an `N` number on every line.
fn job() -> String {
    let l = inkstep_host::text::layout("Ok 7", 10.0, "futural").unwrap();
    let route = inkstep_host::geom::Route {
        start: inkstep_host::geom::Pt::new(0.0, 0.0),
        park: Some(inkstep_host::geom::Pt::new(0.0, 0.0)),
    };
    let g = inkstep_host::gcode_out::to_gcode(
        &inkstep_host::plan::plan(&l.strokes, route, &Default::default()),
        &inkstep_host::gcode_out::GcodeOptions {
            route,
            ..Default::default()
        },
    );
    g.lines()
        .enumerate()
        .map(|(i, l)| format!("N{} {l}\n", i + 1))
        .collect()
}

/// Streams `lines` with character counting and a `?` every 200 ms until they are
/// answered and the board is idle, or until `stop_after` (virtual time from the
/// start): then a soft reset. Returns what the host saw.
fn stream(s: &mut Session, lines: &[Line], stop_after: Option<u64>) -> Seen {
    let mut sender: Sender<usize> = Sender::new(Flow::CharCount(128));
    for (i, l) in lines.iter().enumerate() {
        sender.push(i, l.text.as_str());
    }
    let mut seen = Seen::default();
    let start = s.now();
    let mut next_poll = start;
    s.take_received();
    loop {
        if s.now() >= next_poll {
            s.send(b"?");
            next_poll = s.now() + 200 * T_PER_MS;
        }
        let bytes = sender.to_send();
        s.send(&bytes);
        s.run_for(T_PER_MS).unwrap();
        let got = s.take_received();
        for e in sender.received(got.as_bytes()) {
            match e {
                Event::Answered(i, Answer::Error(n)) => panic!("line {}: error:{n}", i + 1),
                Event::Answered(_, Answer::Ok) => seen.acked += 1,
                Event::Reply(Reply::Status(st)) => {
                    if st.line.is_some() {
                        seen.ln = st.line;
                    }
                    if let Some(p) = st.pos {
                        seen.pos = Some(p);
                    }
                }
                _ => {}
            }
        }
        if stop_after.is_some_and(|t| s.now() - start >= t) {
            s.send(&[0x18]);
            s.run_for(200 * T_PER_MS).unwrap();
            s.take_received();
            seen.sent = lines.len();
            return seen;
        }
        if sender.done() {
            s.wait_idle(60 * T_PER_S).unwrap();
            return seen;
        }
        assert!(s.now() - start < 120 * T_PER_S, "the job did not end");
    }
}

/// Pen-down XY positions of a step trace (the Z pen is down below Z 0).
fn drawn(steps: &[Step]) -> HashSet<(i32, i32)> {
    let mut out = HashSet::new();
    for w in steps.windows(2) {
        if w[0].pos[2] < 0 && w[1].pos[2] < 0 {
            out.insert((w[0].pos[0], w[0].pos[1]));
            out.insert((w[1].pos[0], w[1].pos[1]));
        }
    }
    out
}

#[test]
fn a_numbered_text_job_resumes_on_the_image_after_a_soft_reset() {
    let program = job();
    let lines = prepare(&program, 128).unwrap();
    let s0 = Settings::default();
    // The whole job.
    let mut whole = booted(None);
    stream(&mut whole, &lines, None);
    let want = drawn(&whole.m.state().board.steps);
    assert!(want.len() > 500, "the job draws: {}", want.len());
    let job_t = whole.m.state().board.steps.last().unwrap().t - whole.m.state().board.steps[0].t;

    for frac in [0.35, 0.7] {
        let mut s = booted(None);
        let seen = stream(&mut s, &lines, Some((job_t as f64 * frac) as u64));
        let before = s.m.state().board.steps.len();
        let first = drawn(&s.m.state().board.steps);
        assert!(seen.ln.is_some(), "the board reported Ln: while drawing");
        // After a reset mid-move the board is in alarm: unlock, as the docs say.
        let got = s.command("$X", 2 * T_PER_S).unwrap();
        assert!(got.contains("ok"), "$X: {got}");
        let spans = spans_of(&lines, &s0);
        let n = resume_point(&spans, &seen).expect("a line to resume from");
        let rest = resume_lines(&program, n, &s0).unwrap();
        stream(&mut s, &rest, None);
        let steps = s.m.state().board.steps[before..].to_vec();
        let second = drawn(&steps);
        let union: HashSet<_> = first.union(&second).copied().collect();
        let near = |set: &HashSet<(i32, i32)>, q: &(i32, i32)| {
            (-1..=1).any(|dx| (-1..=1).any(|dy| set.contains(&(q.0 + dx, q.1 + dy))))
        };
        let missing = want.iter().filter(|q| !near(&union, q)).count();
        let extra = union.iter().filter(|q| !near(&want, q)).count();
        assert_eq!(
            (missing, extra),
            (0, 0),
            "stopped at {frac}, resumed at line {n}"
        );
        // Drawn twice: at most the resumed line's steps (and a few where it crosses).
        let sp = spans.iter().find(|x| x.file_line == n).unwrap();
        let line_steps = ((sp.to[0] - sp.from[0])
            .abs()
            .max((sp.to[1] - sp.from[1]).abs())
            * 80.0) as usize;
        let twice = first.intersection(&second).count();
        assert!(
            twice <= line_steps + 8,
            "stopped at {frac}, resumed at line {n}: {twice} steps drawn twice (> {})",
            line_steps + 8
        );
        eprintln!(
            "stopped at {frac} of the job, Ln:{:?}, resumed at line {n}: {} positions drawn, {twice} twice",
            seen.ln,
            union.len()
        );
    }
}
