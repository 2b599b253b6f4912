//! The `--keys` script: scripted keypad input for the standalone modes.
//!
//! Owns the script syntax only. A script is whitespace-separated tokens:
//! - a key: its legend `0`-`9`, `*`, `#`, `A`-`D`, or a name `up`, `down`, `back`,
//!   `enter`, `sign`, `dot`: pressed for 80 ms, then released for 80 ms;
//! - `KEY:MS` holds the key for MS milliseconds (hold-to-move jogging), e.g. `6:1500`;
//! - a number such as `12.5` or `-3` is typed digit by digit (`-` is the sign key `*`,
//!   `.` is `#`), each press as above;
//! - `wait:MS` (or `MSms`, `Ns`) lets virtual time pass;
//! - `idle` waits until the machine has finished moving;
//! - `lcd:NAME` writes the LCD as NAME.png in the output folder.
//!
//! Presses become row levels on the simulated matrix, which the core's keypad scanner
//! debounces exactly as on the board.

use inkstep_core::keypad::{Key, KEYMAP, LEGEND};

/// Default press and gap lengths, long enough for the core's debounce.
pub const TAP_MS: u32 = 80;

#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Hold `key` for `ms`, then release it and wait [`TAP_MS`].
    Press {
        key: Key,
        ms: u32,
    },
    Wait {
        ms: u32,
    },
    Idle,
    Lcd {
        name: String,
    },
}

/// (row, column) of a key in the matrix.
pub fn matrix_pos(key: Key) -> (usize, usize) {
    for (r, row) in KEYMAP.iter().enumerate() {
        for (c, k) in row.iter().enumerate() {
            if *k == key {
                return (r, c);
            }
        }
    }
    unreachable!("every Key is in KEYMAP")
}

fn key_by_name(name: &str) -> Option<Key> {
    let named = match name.to_ascii_lowercase().as_str() {
        "up" => Some(Key::Up),
        "down" => Some(Key::Down),
        "back" | "esc" | "cancel" => Some(Key::Back),
        "enter" | "ok" => Some(Key::Enter),
        "sign" => Some(Key::Sign),
        "dot" => Some(Key::Dot),
        _ => None,
    };
    named.or_else(|| {
        for (r, row) in LEGEND.iter().enumerate() {
            for (c, l) in row.iter().enumerate() {
                if l.eq_ignore_ascii_case(name) {
                    return Some(KEYMAP[r][c]);
                }
            }
        }
        None
    })
}

fn parse_ms(s: &str) -> Option<u32> {
    if let Some(v) = s.strip_suffix("ms") {
        v.parse().ok()
    } else if let Some(v) = s.strip_suffix('s') {
        v.parse::<f64>().ok().map(|x| (x * 1000.0).round() as u32)
    } else {
        s.parse().ok()
    }
}

pub fn parse(script: &str) -> Result<Vec<Step>, String> {
    let mut out = Vec::new();
    for tok in script.split_whitespace() {
        let bad = || format!("--keys: cannot read {tok:?}");
        if tok == "idle" {
            out.push(Step::Idle);
        } else if let Some(name) = tok.strip_prefix("lcd:") {
            if name.is_empty() || name.contains('/') {
                return Err(bad());
            }
            out.push(Step::Lcd {
                name: name.to_string(),
            });
        } else if let Some(t) = tok.strip_prefix("wait:") {
            out.push(Step::Wait {
                ms: parse_ms(t).ok_or_else(bad)?,
            });
        } else if let Some(key) = key_by_name(tok) {
            out.push(Step::Press { key, ms: TAP_MS });
        } else if let Some((k, ms)) = tok.split_once(':') {
            let key = key_by_name(k).ok_or_else(bad)?;
            out.push(Step::Press {
                key,
                ms: parse_ms(ms).ok_or_else(bad)?,
            });
        } else if tok.ends_with("ms") || tok.ends_with('s') {
            out.push(Step::Wait {
                ms: parse_ms(tok).ok_or_else(bad)?,
            });
        } else if tok
            .chars()
            .all(|c| c.is_ascii_digit() || c == '.' || c == '-')
        {
            for c in tok.chars() {
                let key = match c {
                    '-' => Key::Sign,
                    '.' => Key::Dot,
                    d => Key::Digit(d as u8 - b'0'),
                };
                out.push(Step::Press { key, ms: TAP_MS });
            }
        } else {
            return Err(bad());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_kind_of_token() {
        let s = parse("down enter -12.5 D 6:1500 wait:200 2s idle lcd:after").unwrap();
        let p = |key| Step::Press { key, ms: TAP_MS };
        assert_eq!(
            s,
            vec![
                p(Key::Down),
                p(Key::Enter),
                p(Key::Sign),
                p(Key::Digit(1)),
                p(Key::Digit(2)),
                p(Key::Dot),
                p(Key::Digit(5)),
                p(Key::Enter),
                Step::Press {
                    key: Key::Digit(6),
                    ms: 1500
                },
                Step::Wait { ms: 200 },
                Step::Wait { ms: 2000 },
                Step::Idle,
                Step::Lcd {
                    name: "after".into()
                },
            ]
        );
    }

    #[test]
    fn rejects_nonsense() {
        assert!(parse("E").is_err());
        assert!(parse("wait:soon").is_err());
        assert!(parse("lcd:../x").is_err());
        assert!(parse("q:100").is_err());
    }

    #[test]
    fn matrix_positions_match_the_keymap() {
        assert_eq!(matrix_pos(Key::Digit(1)), (0, 0));
        assert_eq!(matrix_pos(Key::Enter), (3, 3));
        assert_eq!(matrix_pos(Key::Digit(0)), (3, 1));
    }
}
