//! Robustness: over a million random and mutated lines through the protocol, parser
//! and interpreter. Nothing may panic, every line gets exactly one `ok` or `error:N`
//! with a known Grbl error number, and the machine keeps answering afterwards.
//! Deterministic (fixed seed); prints the count and the time.

mod common;

use common::{drain, Drive, FakePlanner};
use inkstep_core::protocol::Protocol;
use inkstep_core::settings::Settings;
use std::time::Instant;

/// Lines per run; `INKSTEP_FUZZ_LINES` and `INKSTEP_FUZZ_SEED` allow deeper runs.
const LINES: usize = 1_000_000;
const KNOWN_ERRORS: &[u32] = &[
    1, 2, 3, 4, 5, 6, 8, 9, 10, 11, 12, 15, 16, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32,
    33, 34, 35, 36, 37, 38,
];

const CORPUS: &[&str] = &[
    "G0 X10 Y20",
    "G1 X10.5 Y-3.25 F600",
    "g1x1y1f100",
    "G2 X10 Y0 I5 J0 F300",
    "G3 X0 Y10 R10 F300",
    "G2 X5 Y5 R-5 F200",
    "G91 G1 X1 Y-1 F1000",
    "G90 G21 G17 G94",
    "G20 G0 X0.5",
    "G93 G1 X1 F10",
    "G94",
    "G4 P0.5",
    "G10 L2 P1 X5 Y5",
    "G10 L20 P2 X0",
    "G28 G91 Z1",
    "G28.1",
    "G30",
    "G30.1",
    "G53 G0 X0 Y0",
    "G54",
    "G59 G0 X1",
    "G80",
    "G91.1",
    "G92 X0 Y0",
    "G92.1",
    "M3 S1000",
    "M4",
    "M5",
    "M0",
    "M2",
    "M30",
    "N100 G1 X2 F100",
    "(comment) G0 X1 ; trailing",
    "$$",
    "$#",
    "$G",
    "$I",
    "$N",
    "$N0=G21",
    "$C",
    "$X",
    "$H",
    "$100=80",
    "$110=3000.5",
    "$13=1",
    "$13=0",
    "$J=G91 X1 F500",
    "$J=G53 X0 Y0 F1000",
    "$RST=*",
    "",
    "T1 M6",
    "G38.2 Z-1 F10",
    "G1 X1e5 F100",
];

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

const ALPHABET: &[u8] = b"GMXYZIJKRFSNPLTABCDEHOQUVW0123456789.-+ ()$=;%/*#\t";

fn random_byte(r: &mut Rng) -> u8 {
    if r.below(8) == 0 {
        (r.next() & 0x7F) as u8
    } else {
        ALPHABET[r.below(ALPHABET.len())]
    }
}

fn random_number(r: &mut Rng, out: &mut Vec<u8>) {
    let v = match r.below(5) {
        0 => format!("{}", r.next() as i64),
        1 => format!("{:.6}", (r.next() % 2_000_000) as f64 / 1000.0 - 1000.0),
        2 => "9".repeat(1 + r.below(40)),
        3 => format!("-{}.{}", r.below(100), "0".repeat(r.below(30))),
        _ => format!("{}", r.below(10)),
    };
    out.extend_from_slice(v.as_bytes());
}

fn make_line(r: &mut Rng) -> Vec<u8> {
    let mut line: Vec<u8> = match r.below(4) {
        0 => {
            let len = r.below(100);
            (0..len).map(|_| random_byte(r)).collect()
        }
        1 => {
            // Random words with random numbers.
            let mut v = Vec::new();
            for _ in 0..r.below(8) {
                v.push(b"GMXYZIJKRFSNPLT"[r.below(15)]);
                random_number(r, &mut v);
            }
            v
        }
        _ => CORPUS[r.below(CORPUS.len())].as_bytes().to_vec(),
    };
    // Mutations.
    for _ in 0..r.below(4) {
        let at = if line.is_empty() {
            0
        } else {
            r.below(line.len() + 1)
        };
        match r.below(5) {
            0 => line.insert(at, random_byte(r)),
            1 if at < line.len() => {
                line.remove(at);
            }
            2 if at < line.len() => line[at] ^= 1 << r.below(7),
            3 => {
                let mut n = Vec::new();
                random_number(r, &mut n);
                line.splice(at..at, n);
            }
            _ => {
                let copy = line.clone();
                line.extend_from_slice(&copy[..at.min(copy.len())]);
            }
        }
    }
    // Line ends would split the line; real-time bytes are injected separately.
    line.retain(|&b| {
        b != b'\n' && b != b'\r' && !matches!(b, b'?' | b'!' | b'~' | 0x18 | 0x80..=0xFF)
    });
    line
}

#[test]
fn a_million_random_and_mutated_lines_never_panic() {
    let started = Instant::now();
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let lines = env("INKSTEP_FUZZ_LINES").map_or(LINES, |n| n as usize);
    let mut r = Rng(env("INKSTEP_FUZZ_SEED").unwrap_or(0x9E37_79B9_7F4A_7C15) | 1);
    let mut p = Protocol::new(Settings::default());
    let mut m = FakePlanner::new(16);
    drain(&mut p);
    let mut counts = std::collections::BTreeMap::<String, usize>::new();
    let mut realtime_injected = 0;
    let mut resets = 0;
    let mut pending = String::new();
    for i in 0..lines {
        let mut bytes = make_line(&mut r);
        // Now and then a real-time byte in the middle of a line.
        let mut reset = false;
        if r.below(50) == 0 && !bytes.is_empty() {
            let rt = [b'?', b'!', b'~', 0x84, 0x85, 0x91, 0x97, 0x18][r.below(8)];
            reset = rt == 0x18;
            let at = r.below(bytes.len());
            bytes.insert(at, rt);
            realtime_injected += 1;
        }
        bytes.push(b'\n');
        let mut rest = &bytes[..];
        let mut answered = 0;
        let mut spins = 0;
        while answered == 0 || !rest.is_empty() {
            let n = p.receive(rest, &mut m, i as u32);
            rest = &rest[n..];
            p.poll(&mut m, i as u32);
            m.step();
            pending.push_str(&drain(&mut p));
            while let Some(end) = pending.find("\r\n") {
                let resp: String = pending.drain(..end + 2).collect();
                let resp = resp.trim_end();
                if resp == "ok" {
                    answered += 1;
                    *counts.entry("ok".into()).or_default() += 1;
                } else if let Some(code) = resp.strip_prefix("error:") {
                    let code: u32 = code
                        .parse()
                        .unwrap_or_else(|_| panic!("bad response {resp:?}"));
                    assert!(
                        KNOWN_ERRORS.contains(&code),
                        "unknown error {code} for {bytes:?}"
                    );
                    answered += 1;
                    *counts.entry(format!("error:{code}")).or_default() += 1;
                }
            }
            if reset && rest.is_empty() {
                // A soft reset flushes the line it interrupted; what followed the reset
                // byte is a line of its own. Settle (read until the protocol has had
                // its say: the welcome, startup lines, and whatever that line was,
                // which for a `$$` listing takes many rounds of the output buffer),
                // then start clean.
                let mut quiet = 0;
                let mut rounds = 0;
                while quiet < 8 {
                    p.poll(&mut m, i as u32);
                    m.run_all();
                    quiet = if drain(&mut p).is_empty() {
                        quiet + 1
                    } else {
                        0
                    };
                    rounds += 1;
                    assert!(
                        rounds < 10_000,
                        "line {i}: no end to the output after a reset"
                    );
                }
                pending.clear();
                resets += 1;
                break;
            }
            spins += 1;
            if spins % 64 == 0 {
                // Stuck behind M0, a hold or a full queue: do what a sender does.
                p.receive(b"~", &mut m, i as u32);
            }
            if spins % 1024 == 0 {
                m.holding = false;
                m.run_all();
            }
            assert!(
                spins < 100_000,
                "line {i} never answered: {:?}",
                String::from_utf8_lossy(&bytes)
            );
        }
        assert!(
            answered <= 1 || reset,
            "line {i} answered {answered} times: {bytes:?}"
        );
        // Alarms lock G-code; unlock now and then so motion paths stay exercised.
        if r.below(200) == 0 {
            p.receive(b"\x18$X\n", &mut m, 0);
            p.poll(&mut m, 0);
            pending.clear();
            drain(&mut p);
        }
    }
    // Still alive and answering.
    p.receive(b"\x18", &mut m, 0);
    drain(&mut p);
    p.receive(b"$X\nG4P0\n", &mut m, 0);
    p.poll(&mut m, 0);
    let tail = drain(&mut p);
    assert!(tail.ends_with("ok\r\n"), "{tail}");
    let elapsed = started.elapsed();
    println!("fuzz: {lines} lines ({realtime_injected} with a real-time byte, {resets} resets) in {elapsed:?}");
    println!("fuzz responses: {counts:?}");
    assert!(counts.len() > 10, "the fuzz reached only {counts:?}");
}

#[test]
fn rejected_blocks_change_nothing() {
    use inkstep_core::gcode::parser::clean_line;
    use inkstep_core::gcode::Interpreter;
    let mut r = Rng(0x0DDB_1A5E_5BAD_5EED);
    let mut s = Settings::default();
    s.set(22, 1.0).unwrap();
    s.set(20, 1.0).unwrap();
    let mut it = Interpreter::new();
    let (mut ok, mut rejected) = (0, 0);
    for _ in 0..200_000 {
        let raw = make_line(&mut r);
        let mut line: heapless::Vec<u8, 256> = heapless::Vec::new();
        if clean_line(&raw, &mut line).is_err() {
            continue;
        }
        let before = it.clone();
        match it.execute(&line, &s, 1) {
            Ok(_) => ok += 1,
            Err(_) => {
                assert_eq!(
                    it,
                    before,
                    "a rejected block changed state: {:?}",
                    String::from_utf8_lossy(&line)
                );
                rejected += 1;
            }
        }
        // Every accepted block leaves the position inside the travel (soft limits on).
        assert!(inkstep_core::gcode::units::within_travel(it.position(), &s) || ok == 0);
    }
    println!("interpreter: {ok} accepted, {rejected} rejected without side effects");
    assert!(ok > 1000 && rejected > 1000);
}
