//! The step trace: one row per step-timer interrupt that moved at least one axis.
//!
//! Owns the CSV format (`t_us,x,y,z`) shared by `run --trace`, `plot` and `bench`, and
//! the exact conversion from virtual timer counts to microseconds. Rows are kept as
//! integer ticks in memory so that nothing is rounded until it is printed.

use std::fmt::Write as _;
use std::io::{self, BufRead, Write};

/// One step event: absolute position in steps after the interrupt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Microseconds since the first motion started.
    pub t_us: f64,
    pub pos: [i32; 3],
}

/// A recorded run, in the time base of the step engine.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    pub rows: Vec<Row>,
}

/// Formats `ticks` of a `tick_hz` timer as microseconds, exactly: an integer when the
/// tick divides a microsecond, otherwise with as many decimals as make it exact, up to
/// nanoseconds (rounded half up at the ninth digit after the second's point).
pub fn ticks_to_us_string(ticks: u64, tick_hz: u64) -> String {
    let num = ticks as u128 * 1_000_000;
    let den = tick_hz as u128;
    let int = num / den;
    let rem = num % den;
    if rem == 0 {
        return int.to_string();
    }
    // Three decimals = nanoseconds, rounded.
    let milli = (rem * 1000 + den / 2) / den;
    let (int, milli) = if milli == 1000 {
        (int + 1, 0)
    } else {
        (int, milli)
    };
    let mut s = String::new();
    write!(s, "{int}.{milli:03}").unwrap();
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.pop();
    }
    s
}

/// Streams trace rows to a CSV writer as the simulation produces them.
pub struct TraceWriter<W: Write> {
    out: W,
    tick_hz: u64,
}

impl<W: Write> TraceWriter<W> {
    pub fn new(mut out: W, tick_hz: u64) -> io::Result<Self> {
        writeln!(out, "t_us,x,y,z")?;
        Ok(Self { out, tick_hz })
    }

    /// One row: `ticks` since the first motion started, position after the event.
    pub fn row(&mut self, ticks: u64, pos: [i32; 3]) -> io::Result<()> {
        writeln!(
            self.out,
            "{},{},{},{}",
            ticks_to_us_string(ticks, self.tick_hz),
            pos[0],
            pos[1],
            pos[2]
        )
    }

    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

impl Trace {
    /// Parses a trace CSV (header `t_us,x,y,z`).
    pub fn read(input: impl BufRead) -> io::Result<Trace> {
        let bad = |n: usize, why: &str| {
            io::Error::new(io::ErrorKind::InvalidData, format!("trace line {n}: {why}"))
        };
        let mut rows = Vec::new();
        for (i, line) in input.lines().enumerate() {
            let line = line?;
            let n = i + 1;
            if i == 0 {
                if line.trim() != "t_us,x,y,z" {
                    return Err(bad(n, "expected header t_us,x,y,z"));
                }
                continue;
            }
            if line.trim().is_empty() {
                continue;
            }
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != 4 {
                return Err(bad(n, "expected 4 fields"));
            }
            let t_us = f[0].trim().parse::<f64>().map_err(|_| bad(n, "bad time"))?;
            let mut pos = [0i32; 3];
            for (p, s) in pos.iter_mut().zip(&f[1..]) {
                *p = s.trim().parse().map_err(|_| bad(n, "bad position"))?;
            }
            rows.push(Row { t_us, pos });
        }
        Ok(Trace { rows })
    }

    pub fn read_file(path: &std::path::Path) -> io::Result<Trace> {
        let f = std::fs::File::open(path)?;
        Trace::read(io::BufReader::new(f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_conversion_is_exact() {
        assert_eq!(ticks_to_us_string(0, 1_000_000), "0");
        assert_eq!(ticks_to_us_string(1234, 1_000_000), "1234");
        assert_eq!(ticks_to_us_string(3, 2_000_000), "1.5");
        assert_eq!(ticks_to_us_string(1, 72_000_000), "0.014");
        assert_eq!(ticks_to_us_string(72, 72_000_000), "1");
        assert_eq!(ticks_to_us_string(8_000_000_000, 8_000_000), "1000000000");
        assert_eq!(ticks_to_us_string(2, 3_000_000), "0.667");
        // 999.9999 us rounds up to the next integer microsecond at nanosecond precision.
        assert_eq!(ticks_to_us_string(9_999_999, 10_000_000_000), "1000");
    }

    #[test]
    fn csv_round_trip() {
        let mut w = TraceWriter::new(Vec::new(), 2_000_000).unwrap();
        w.row(3, [1, 0, 0]).unwrap();
        w.row(10, [1, -1, 0]).unwrap();
        w.row(11, [2, -2, 5]).unwrap();
        let bytes = w.finish().unwrap();
        let text = String::from_utf8(bytes.clone()).unwrap();
        assert_eq!(text, "t_us,x,y,z\n1.5,1,0,0\n5,1,-1,0\n5.5,2,-2,5\n");
        let t = Trace::read(&bytes[..]).unwrap();
        assert_eq!(t.rows.len(), 3);
        assert_eq!(
            t.rows[2],
            Row {
                t_us: 5.5,
                pos: [2, -2, 5]
            }
        );
    }

    #[test]
    fn rejects_wrong_header() {
        assert!(Trace::read(&b"t,x,y\n1,2,3\n"[..]).is_err());
        assert!(Trace::read(&b"t_us,x,y,z\n1,2,3\n"[..]).is_err());
    }
}
