//! What the Grbl 1.1 protocol says back, parsed: `ok`, `error:N`,
//! `ALARM:N`, status reports `<State|MPos:x,y,z|...>`, feedback `[...]`,
//! settings lines `$N=V` and the welcome line; plus the meaning of Grbl's error
//! and alarm numbers so a failed job can say what went wrong. No I/O here.

/// One line received from the controller.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    Ok,
    Error(u32),
    Alarm(u32),
    Status(Status),
    /// `[MSG:...]`, `[GC:...]` and other bracketed feedback.
    Feedback(String),
    /// `Grbl 1.1h ['$' for help]`: the controller (re)started.
    Welcome(String),
    /// `$N=V`, a line of the `$$` listing.
    Setting(u16, String),
    Other(String),
}

/// A status report.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Status {
    /// "Idle", "Run", "Hold:0", "Alarm", ...
    pub state: String,
    /// Machine position, or work position when the report gives WPos.
    pub pos: Option<[f64; 3]>,
    pub work: bool,
    /// Planner blocks and receive-buffer bytes free, from `Bf:`.
    pub buffer: Option<(u32, u32)>,
    /// Feed (mm/min) and spindle value from `FS:` (or `F:`); inkstep reports the
    /// spindle value while the pen is down.
    pub feed: Option<(f64, f64)>,
    /// Feed, rapid and spindle overrides in percent, from `Ov:` (sent now and then).
    pub overrides: Option<[u32; 3]>,
    /// Work coordinate offset, from `WCO:` (sent now and then).
    pub wco: Option<[f64; 3]>,
    /// Input pins that are active, from `Pn:`.
    pub pins: String,
    /// The line number (`N` word) of the motion executing, from `Ln:` (sent by
    /// controllers that report it when lines carry numbers).
    pub line: Option<u32>,
}

impl Status {
    /// The machine position, from a work position and the last known offset.
    pub fn machine_pos(&self, wco: [f64; 3]) -> Option<[f64; 3]> {
        let p = self.pos?;
        Some(if self.work {
            [p[0] + wco[0], p[1] + wco[1], p[2] + wco[2]]
        } else {
            p
        })
    }
}

/// Parses one received line (without its line end).
pub fn parse_reply(line: &str) -> Reply {
    let l = line.trim();
    if l == "ok" {
        return Reply::Ok;
    }
    if let Some(n) = l.strip_prefix("error:") {
        return Reply::Error(n.trim().parse().unwrap_or(0));
    }
    if let Some(n) = l.strip_prefix("ALARM:") {
        return Reply::Alarm(n.trim().parse().unwrap_or(0));
    }
    if let Some(body) = l.strip_prefix('<').and_then(|b| b.strip_suffix('>')) {
        return Reply::Status(parse_status(body));
    }
    if l.starts_with('[') && l.ends_with(']') {
        return Reply::Feedback(l[1..l.len() - 1].to_string());
    }
    if let Some((n, v)) = l.strip_prefix('$').and_then(|r| r.split_once('=')) {
        if let Ok(n) = n.parse() {
            return Reply::Setting(n, v.to_string());
        }
    }
    if l.starts_with("Grbl ") {
        return Reply::Welcome(l.to_string());
    }
    Reply::Other(l.to_string())
}

fn numbers<T: std::str::FromStr>(val: &str) -> Vec<T> {
    val.split(',')
        .filter_map(|x| x.trim().parse().ok())
        .collect()
}

fn triplet(v: &[f64]) -> Option<[f64; 3]> {
    (v.len() >= 2).then(|| [v[0], v[1], v.get(2).copied().unwrap_or(0.0)])
}

fn parse_status(body: &str) -> Status {
    let mut parts = body.split('|');
    let mut st = Status {
        state: parts.next().unwrap_or("").to_string(),
        ..Status::default()
    };
    for p in parts {
        let (key, val) = p.split_once(':').unwrap_or((p, ""));
        match key {
            "MPos" | "WPos" => {
                st.pos = triplet(&numbers(val));
                st.work = key == "WPos";
            }
            "Bf" => {
                if let [a, b] = numbers::<u32>(val)[..] {
                    st.buffer = Some((a, b));
                }
            }
            "FS" | "F" => {
                let v = numbers::<f64>(val);
                st.feed = v.first().map(|&f| (f, v.get(1).copied().unwrap_or(0.0)));
            }
            "Ov" => {
                if let [f, r, s] = numbers::<u32>(val)[..] {
                    st.overrides = Some([f, r, s]);
                }
            }
            "WCO" => st.wco = triplet(&numbers(val)),
            "Pn" => st.pins = val.to_string(),
            "Ln" => st.line = val.trim().parse().ok(),
            _ => {}
        }
    }
    st
}

/// Grbl 1.1's meaning of `error:N`.
pub fn error_text(n: u32) -> &'static str {
    match n {
        1 => "G-code words consist of a letter and a value; letter was not found",
        2 => "numeric value format is not valid or missing an expected value",
        3 => "Grbl '$' system command was not recognized or supported",
        4 => "negative value received for an expected positive value",
        5 => "homing cycle is not enabled via settings",
        6 => "minimum step pulse time must be greater than 3 us",
        7 => "EEPROM read failed; restored defaults",
        8 => "'$' command cannot be used unless Grbl is IDLE",
        9 => "G-code locked out during alarm or jog state",
        10 => "soft limits cannot be enabled without homing also enabled",
        11 => "max characters per line exceeded",
        12 => "'$' setting value exceeds the maximum step rate supported",
        13 => "safety door detected as opened and door state initiated",
        14 => "build info or startup line exceeded EEPROM line length limit",
        15 => "jog target exceeds machine travel",
        16 => "jog command with no '=' or contains prohibited g-code",
        17 => "laser mode requires PWM output",
        20 => "unsupported or invalid g-code command",
        21 => "more than one g-code command from the same modal group",
        22 => "feed rate has not yet been set or is undefined",
        23 => "g-code command requires an integer value",
        24 => "two g-code commands that both require axis words",
        25 => "a g-code word was repeated in the block",
        26 => "a g-code command requires axis words but none were found",
        27 => "line number value is invalid",
        28 => "a g-code command is missing a required value word",
        29 => "G59.x work coordinate systems are not supported",
        30 => "G53 only allowed with G0 and G1 motion modes",
        31 => "axis words found in block when no command or mode uses them",
        32 => "G2 and G3 arcs require at least one in-plane axis word",
        33 => "motion command target is invalid",
        34 => "arc radius value is invalid",
        35 => "G2 and G3 arcs require at least one in-plane offset word",
        36 => "unused value words found in block",
        37 => "G43.1 dynamic tool length offset is not assigned to the tool length axis",
        38 => "tool number greater than max supported value",
        _ => "unknown error",
    }
}

/// Grbl 1.1's meaning of `ALARM:N`.
pub fn alarm_text(n: u32) -> &'static str {
    match n {
        1 => "hard limit triggered; position likely lost, re-home",
        2 => "soft limit: target exceeds machine travel",
        3 => "reset while in motion; position likely lost, re-home",
        4 => "probe fail: not in the expected initial state",
        5 => "probe fail: did not contact the workpiece",
        6 => "homing fail: the cycle was reset",
        7 => "homing fail: safety door opened during homing",
        8 => "homing fail: pull-off failed to clear the limit switch",
        9 => "homing fail: could not find the limit switch",
        10 => "emergency stop",
        _ => "unknown alarm",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replies() {
        assert_eq!(parse_reply("ok\r"), Reply::Ok);
        assert_eq!(parse_reply("error:22"), Reply::Error(22));
        assert_eq!(parse_reply("ALARM:1"), Reply::Alarm(1));
        assert_eq!(
            parse_reply("[MSG:Pgm End]"),
            Reply::Feedback("MSG:Pgm End".into())
        );
        assert!(matches!(
            parse_reply("Grbl 1.1h ['$' for help]"),
            Reply::Welcome(_)
        ));
        let Reply::Status(s) = parse_reply("<Run|MPos:1.500,-2.000,0.000|Bf:15,128|FS:500,0>")
        else {
            panic!()
        };
        assert_eq!(s.state, "Run");
        assert_eq!(s.pos, Some([1.5, -2.0, 0.0]));
        assert!(!s.work);
        assert_eq!(s.buffer, Some((15, 128)));
        assert_eq!(s.feed, Some((500.0, 0.0)));
        let Reply::Status(s) = parse_reply("<Hold:0|WPos:0,0,1|WCO:1,2,0|Ov:120,50,100|Pn:XH>")
        else {
            panic!()
        };
        assert_eq!((s.state.as_str(), s.work), ("Hold:0", true));
        assert_eq!(s.wco, Some([1.0, 2.0, 0.0]));
        assert_eq!(s.overrides, Some([120, 50, 100]));
        assert_eq!(s.pins, "XH");
        assert_eq!(s.line, None);
        assert_eq!(s.machine_pos([1.0, 2.0, 0.0]), Some([1.0, 2.0, 1.0]));
        let Reply::Status(s) = parse_reply("<Run|MPos:1,2,0|Ln:1234|FS:500,0>") else {
            panic!()
        };
        assert_eq!((s.line, s.feed), (Some(1234), Some((500.0, 0.0))));
        assert_eq!(
            parse_reply("$110=3000.000"),
            Reply::Setting(110, "3000.000".into())
        );
        assert!(error_text(20).contains("unsupported"));
        assert!(alarm_text(1).contains("hard limit"));
    }
}
