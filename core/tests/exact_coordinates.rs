//! Exact coordinates: G-code numbers are exact decimals and positions whole nanometres,
//! so programs end exactly where decimal arithmetic says (the nearest step to it),
//! whatever the number of moves. Before, targets were f32 sums: a million
//! `G91 G1 X0.0125` ended 9,582 steps too far.

mod common;

use common::{drain, Drive, FakePlanner};
use inkstep_core::gcode::parser::clean_line;
use inkstep_core::gcode::Interpreter;
use inkstep_core::motion::Command;
use inkstep_core::protocol::Protocol;
use inkstep_core::settings::Settings;
use proptest::prelude::*;

/// Streams `first`, then `line` `n` times, through the protocol into a planner that
/// executes every move; returns the machine's final step position.
fn stream(first: &str, line: &str, n: usize) -> [i32; 3] {
    let mut p = Protocol::new(Settings::default());
    let mut m = FakePlanner::new(16);
    drain(&mut p);
    let feed = |text: &[u8], p: &mut Protocol, m: &mut FakePlanner| {
        let mut rest = text;
        while !rest.is_empty() {
            let k = p.receive(rest, m, 0);
            rest = &rest[k..];
            p.poll(m, 0);
            m.step();
        }
    };
    feed(format!("{first}\n").as_bytes(), &mut p, &mut m);
    let line = format!("{line}\n");
    for _ in 0..n {
        feed(line.as_bytes(), &mut p, &mut m);
        drain(&mut p);
    }
    p.poll(&mut m, 0);
    m.run_all();
    let out = drain(&mut p);
    assert!(!out.contains("error"), "{out}");
    m.pos
}

#[test]
fn a_million_one_step_relative_moves_end_exactly() {
    // 1,000,000 x 0.0125 mm = 12,500 mm = 1,000,000 steps at 80 steps/mm.
    assert_eq!(
        stream("G21 G91 G1 F3000", "X0.0125", 1_000_000),
        [1_000_000, 0, 0]
    );
}

#[test]
fn a_million_relative_moves_in_inches_end_exactly() {
    // 1,000,000 x 0.001 in = 1,000 in = 25,400 mm = 2,032,000 steps.
    assert_eq!(
        stream("G20 G91 G1 F100", "X0.001", 1_000_000),
        [2_032_000, 0, 0]
    );
}

/// One line of a random program, with the numbers as written: (mantissa, decimals).
#[derive(Clone, Debug)]
enum Op {
    Mm,
    Inch,
    Absolute,
    Relative,
    Move(i64, u32, i64, u32),
    /// G92: the current position reads as these values.
    SetG92(i64, u32, i64, u32),
    ClearG92,
}

fn number(m: i64, d: u32) -> String {
    let sign = if m < 0 { "-" } else { "" };
    let a = m.unsigned_abs();
    let p = 10u64.pow(d);
    if d == 0 {
        format!("{sign}{a}")
    } else {
        format!("{sign}{}.{:0w$}", a / p, a % p, w = d as usize)
    }
}

fn op() -> impl Strategy<Value = Op> {
    // Up to 500 mm or inches with up to four decimals.
    let value = (0u32..=4).prop_flat_map(|d| {
        let r = 500 * 10i64.pow(d);
        (-r..=r, Just(d))
    });
    prop_oneof![
        1 => Just(Op::Mm),
        1 => Just(Op::Inch),
        1 => Just(Op::Absolute),
        1 => Just(Op::Relative),
        12 => (value.clone(), value.clone()).prop_map(|((a, b), (c, d))| Op::Move(a, b, c, d)),
        1 => (value.clone(), value).prop_map(|((a, b), (c, d))| Op::SetG92(a, b, c, d)),
        1 => Just(Op::ClearG92),
    ]
}

/// The value in nanometres, exactly: mm have at most six decimals of a nanometre,
/// inches five (0.00001 in = 254 nm).
fn nm(m: i64, d: u32, inches: bool) -> i128 {
    let m = i128::from(m);
    if inches {
        m * 254 * 10i128.pow(5 - d)
    } else {
        m * 10i128.pow(6 - d)
    }
}

/// Round half away from zero of a / b (b > 0).
fn round_div(a: i128, b: i128) -> i128 {
    let q = (a.abs() + b / 2) / b;
    if a < 0 {
        -q
    } else {
        q
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Random mixes of G90/G91/G20/G21/G92 end on the step nearest the exact end, at
    /// steps/mm that are exact in binary (80, 100, 53.125, 6.25), and the
    /// interpreter's position is the exact decimal one.
    #[test]
    fn random_programs_end_exactly(
        ops in proptest::collection::vec(op(), 1..120),
        spm in prop_oneof![Just((80, 1)), Just((100, 1)), Just((425, 8)), Just((25, 4))],
    ) {
        let mut s = Settings::default();
        s.set(100, spm.0 as f32 / spm.1 as f32).unwrap();
        s.set(101, spm.0 as f32 / spm.1 as f32).unwrap();
        let mut it = Interpreter::new();
        // The exact model: machine position and G92 offset in nm, modes.
        let (mut pos, mut g92) = ([0i128; 2], [0i128; 2]);
        let (mut inches, mut relative) = (false, false);
        let mut last_target = None;
        for (k, op) in ops.iter().enumerate() {
            let line = match *op {
                Op::Mm => { inches = false; "G21".to_string() }
                Op::Inch => { inches = true; "G20".to_string() }
                Op::Absolute => { relative = false; "G90".to_string() }
                Op::Relative => { relative = true; "G91".to_string() }
                Op::Move(a, b, c, d) => {
                    let w = [nm(a, b, inches), nm(c, d, inches)];
                    for i in 0..2 {
                        pos[i] = if relative { pos[i] + w[i] } else { w[i] + g92[i] };
                    }
                    format!("G1 X{} Y{} F1000", number(a, b), number(c, d))
                }
                Op::SetG92(a, b, c, d) => {
                    let w = [nm(a, b, inches), nm(c, d, inches)];
                    for i in 0..2 {
                        g92[i] = pos[i] - w[i];
                    }
                    format!("G92 X{} Y{}", number(a, b), number(c, d))
                }
                Op::ClearG92 => { g92 = [0; 2]; "G92.1".to_string() }
            };
            let mut clean: heapless::Vec<u8, 128> = heapless::Vec::new();
            clean_line(line.as_bytes(), &mut clean).unwrap();
            let out = it.execute(&clean, &s, k as u32).unwrap();
            for c in out.cmds.iter() {
                if let Command::Move(mv) = c {
                    last_target = Some(mv.target);
                }
            }
            prop_assert_eq!(
                [i128::from(it.position()[0]), i128::from(it.position()[1])],
                pos,
                "after {}", line
            );
        }
        // The machine's end: the last move's target (none if nothing moved).
        let want = pos.map(|p| round_div(p * spm.0, spm.1 * 1_000_000) as i32);
        let got = last_target.map_or([0, 0], |t| [t[0], t[1]]);
        prop_assert_eq!(got, want);
    }
}
