//! The `$` commands: help, the listings (`$$`, `$#`, `$N`, continued one line per round
//! as output room frees up), `$G`, `$I`, `$C`, `$X`, `$H`, `$RST=`, `$J=`, `$Nx=` and
//! `$n=v`, and the startup lines run after a reset.

use super::report::{axis_triplet, report_scale};
use super::{OutWriter, Protocol, RX_BUFFER_SIZE, VERSION};
use crate::decimal::{put_int, write_fixed3, Sink};
use crate::gcode::units::nm_to_mm;
use crate::gcode::ErrorCode;
use crate::gcode::{startup_line, StartupLine, STARTUP_LINES};
use crate::machine::{Machine, MotionControl, RunState};
use crate::settings::Settings;
use crate::stepper::{event_rate_for_pulse, MAX_SINGLE_EVENT_RATE};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Listing {
    Settings(usize),
    Coords(usize),
    Startup(usize),
}

/// A `$` command, told apart before it runs (so that the line's text need not be
/// held while `self` changes).
#[derive(Clone, Copy, PartialEq, Eq)]
enum SysCommand {
    Help,
    List(Listing),
    Modal,
    Info,
    Check,
    Unlock,
    Home,
    Reset(u8),
    Jog,
    Startup,
    Setting,
    /// `$SLP`: motors released until a reset.
    Sleep,
    /// A known command letter with text it does not take (Grbl's error 3).
    Invalid,
    /// Neither a command letter nor a setting number (Grbl reads a number and fails:
    /// error 2).
    Unknown,
}

impl SysCommand {
    /// `cmd`: the line after the `$`.
    fn of(cmd: &[u8]) -> SysCommand {
        match cmd {
            [] => SysCommand::Help,
            [b'$'] => SysCommand::List(Listing::Settings(0)),
            [b'#'] => SysCommand::List(Listing::Coords(0)),
            [b'N'] => SysCommand::List(Listing::Startup(0)),
            [b'G'] => SysCommand::Modal,
            [b'I'] => SysCommand::Info,
            [b'C'] => SysCommand::Check,
            [b'X'] => SysCommand::Unlock,
            [b'H'] => SysCommand::Home,
            [b'R', b'S', b'T', b'=', what @ (b'$' | b'#' | b'*')] => SysCommand::Reset(*what),
            [b'J', b'=', ..] => SysCommand::Jog,
            [b'N', ..] => SysCommand::Startup,
            [b'S', b'L', b'P'] => SysCommand::Sleep,
            [b'0'..=b'9', ..] => SysCommand::Setting,
            [b'$' | b'#' | b'G' | b'I' | b'C' | b'X' | b'H' | b'R' | b'J' | b'S', ..] => {
                SysCommand::Invalid
            }
            _ => SysCommand::Unknown,
        }
    }
}

/// `$n=v`.
fn set_setting<M: MotionControl>(
    machine: &mut Machine,
    cmd: &[u8],
    m: &mut M,
) -> Result<(), ErrorCode> {
    let eq = cmd
        .iter()
        .position(|&c| c == b'=')
        .ok_or(ErrorCode::InvalidStatement)?;
    let (num, val) = cmd.split_at(eq);
    let val = val.get(1..).unwrap_or(&[]);
    if num.is_empty() || !num.iter().all(u8::is_ascii_digit) || num.len() > 4 {
        return Err(ErrorCode::InvalidStatement);
    }
    let n = num
        .iter()
        .fold(0u16, |acc, &d| acc * 10 + u16::from(d - b'0'));
    // A value that is no number is error 2; a number followed by more text (`1.2.3`,
    // `1e30`) is a statement not understood, error 3, as in Grbl.
    let (v, used) = crate::gcode::parser::read_number(val)?;
    if used != val.len() {
        return Err(ErrorCode::InvalidStatement);
    }
    machine.set_setting(n, v.to_f32(), m)
}

/// `$Nx=line`: check the line and store it in slot x.
fn store_startup(
    machine: &mut Machine,
    startup: &mut [StartupLine; STARTUP_LINES],
    rest: &[u8],
) -> Result<(), ErrorCode> {
    let (idx, line) = match rest {
        [d @ b'0'..=b'9', b'=', line @ ..] => (usize::from(d - b'0'), line),
        _ => return Err(ErrorCode::InvalidStatement),
    };
    let slot = startup.get_mut(idx).ok_or(ErrorCode::InvalidStatement)?;
    machine.validate(line)?;
    *slot = startup_line(line).ok_or(ErrorCode::InvalidStatement)?;
    Ok(())
}

impl Protocol {
    /// The `$` command in `line`. `None` if the command must wait for planner room.
    pub(super) fn system_command<M: MotionControl>(
        &mut self,
        m: &mut M,
    ) -> Option<Result<(), ErrorCode>> {
        let at_rest = matches!(
            self.machine.state(m),
            RunState::Idle | RunState::Alarm | RunState::Check
        );
        let kind = SysCommand::of(self.line.get(1..).unwrap_or(&[]));
        // Everything but help, $G, $C (checks itself) and jogging needs the machine at
        // rest; refuse before doing anything.
        let anytime = matches!(
            kind,
            SysCommand::Help | SysCommand::Modal | SysCommand::Check | SysCommand::Jog
        );
        if !anytime && !at_rest {
            return Some(Err(ErrorCode::IdleError));
        }
        // A board that refuses to run shows what it has but changes nothing (and
        // writes no flash): only the listings, help and `$G` / `$I` answer (and `$J=`
        // gets the alarm's error 8 from the machine).
        let shows = matches!(
            kind,
            SysCommand::Help
                | SysCommand::List(_)
                | SysCommand::Modal
                | SysCommand::Info
                | SysCommand::Jog
        );
        if let (Some(why), false) = (self.machine.refusal(), shows) {
            self.notify(why);
            return Some(Err(ErrorCode::SystemLocked));
        }
        Some(match kind {
            SysCommand::Help => {
                self.say(&[b"[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H $RST=$ $RST=# $RST=* ~ ! ? ctrl-x]"]);
                Ok(())
            }
            SysCommand::List(l) => {
                self.listing = Some(l);
                Ok(())
            }
            SysCommand::Modal => {
                let mut w = OutWriter {
                    out: &mut self.out,
                    truncated: &mut self.truncated,
                };
                w.put(b"[");
                self.machine.interpreter().write_modal(&mut w);
                w.put(b"]\r\n");
                Ok(())
            }
            SysCommand::Info => {
                self.say(&[
                    b"[VER:1.1h.inkstep-",
                    VERSION.as_bytes(),
                    b":inkstep pen plotter]",
                ]);
                let cap = m.capacity();
                let rate = event_rate_for_pulse(self.machine.settings().step_pulse_us());
                let mut w = self.w();
                w.put(b"[OPT:NL,");
                put_int(&mut w, cap as i32);
                w.put(b",");
                put_int(&mut w, RX_BUFFER_SIZE as i32);
                // The step-event rate the planner caps moves at with these settings
                // (`$0` lowers it: every period at least the pulse and the low time):
                // a feedback message, which Grbl 1.1 senders show (or skip) wherever
                // it comes. Curves whose steps are timed one by one have a cap of
                // their own.
                w.put(b"]\r\n[MSG:Max step rate ");
                put_int(&mut w, rate as i32);
                w.put(b"/s; ellipses, sines, point-by-point arcs ");
                put_int(&mut w, MAX_SINGLE_EVENT_RATE.min(rate) as i32);
                w.put(b"/s]\r\n");
                Ok(())
            }
            SysCommand::Check => {
                let was = self.machine.check_mode();
                let r = self.machine.toggle_check(m);
                if was && r.is_ok() {
                    self.flush_events();
                    self.startup_next = Some(0);
                    self.welcome_after_ok();
                }
                r
            }
            SysCommand::Unlock => self.machine.unlock(),
            SysCommand::Home => self.machine.start_homing(m),
            // $RST=$ settings, $RST=# coordinate data, $RST=* both.
            SysCommand::Reset(what) => {
                if what != b'#' {
                    self.machine.replace_settings(Settings::default(), m);
                }
                if what != b'$' {
                    self.machine.clear_coords();
                }
                Ok(())
            }
            // These read the line's text: borrowed in place, beside the fields they
            // change.
            SysCommand::Jog => {
                if m.free() == 0 {
                    return None;
                }
                self.machine.jog_line(self.line.get(3..).unwrap_or(&[]), m)
            }
            SysCommand::Startup => {
                let rest = self.line.get(2..).unwrap_or(&[]);
                let r = store_startup(&mut self.machine, &mut self.startup, rest);
                if r.is_ok() {
                    self.startup_dirty = true;
                }
                r
            }
            SysCommand::Setting => {
                set_setting(&mut self.machine, self.line.get(1..).unwrap_or(&[]), m)
            }
            SysCommand::Sleep => {
                self.machine.sleep();
                Ok(())
            }
            SysCommand::Invalid => Err(ErrorCode::InvalidStatement),
            SysCommand::Unknown => Err(ErrorCode::BadNumberFormat),
        })
    }

    fn welcome_after_ok(&mut self) {
        self.pending_welcome = true;
    }

    /// Run stored startup line `i` (after reset, when not locked). False to wait.
    /// The line is borrowed where it is stored (the machine and the output are other
    /// fields), not moved out: no copy of it sits on the stack under the G-code path.
    pub(super) fn run_startup<M: MotionControl>(
        &mut self,
        i: usize,
        m: &mut M,
        now_ms: u32,
    ) -> bool {
        if self.machine.is_locked() {
            self.startup_next = None;
            return true;
        }
        let Some(text) = self.startup.get(i) else {
            self.startup_next = None;
            return true;
        };
        self.startup_next = Some(i + 1);
        if text.is_empty() {
            return true;
        }
        let Some(r) = self.machine.execute(text.as_bytes(), 0, m, now_ms) else {
            self.startup_next = Some(i);
            return self.machine.take_yielded();
        };
        self.flush_events();
        let text = self.startup.get(i).map_or(&[][..], |t| t.as_bytes());
        let mut w = OutWriter {
            out: &mut self.out,
            truncated: &mut self.truncated,
        };
        w.put(b">");
        w.put(text);
        match r {
            // A startup line's dwell is not waited for: nothing is counted against it.
            Ok(_) => w.put(b":ok"),
            Err(e) => {
                w.put(b":error:");
                put_int(&mut w, i32::from(e.code()));
            }
        }
        w.put(b"\r\n");
        true
    }

    pub(super) fn continue_listing(&mut self, l: Listing) {
        let next = self.listing_line(l);
        self.listing = next;
        if next.is_none() {
            // The listing's end answers its line.
            self.respond(Ok(()));
        }
    }

    /// Write one line of a listing; the next step, `None` past the end.
    fn listing_line(&mut self, l: Listing) -> Option<Listing> {
        let machine = &self.machine;
        let mut w = OutWriter {
            out: &mut self.out,
            truncated: &mut self.truncated,
        };
        let scale = report_scale(machine.settings());
        let next = match l {
            Listing::Settings(i) => {
                machine.settings().write_listed(i, &mut w)?;
                Listing::Settings(i + 1)
            }
            Listing::Coords(i) => {
                let interpreter = machine.interpreter();
                let c = interpreter.coords();
                let v = match i {
                    0..=5 => c.wcs.get(i),
                    6 => Some(&c.g28),
                    7 => Some(&c.g30),
                    8 => Some(interpreter.g92()),
                    9 => {
                        w.put(b"[TLO:");
                        write_fixed3(&mut w, nm_to_mm(interpreter.tool_length_offset()) / scale);
                        w.put(b"]");
                        None
                    }
                    10 => {
                        w.put(b"[PRB:0.000,0.000,0.000:0]");
                        None
                    }
                    _ => return None,
                };
                if let Some(v) = v {
                    // [G54:..] .. [G59:..], [G28:..], [G30:..], [G92:..].
                    let mut head = *b"[G54:";
                    if let (Some(code), Some(d)) = (
                        b"545556575859283092".get(2 * i..2 * i + 2),
                        head.get_mut(2..4),
                    ) {
                        d.copy_from_slice(code);
                    }
                    w.put(&head);
                    axis_triplet(&mut w, &v.map(nm_to_mm), scale);
                    w.put(b"]");
                }
                Listing::Coords(i + 1)
            }
            Listing::Startup(i) => {
                let text = self.startup.get(i)?;
                w.put(b"$N");
                put_int(&mut w, i as i32);
                w.put(b"=");
                w.put(text.as_bytes());
                Listing::Startup(i + 1)
            }
        };
        w.put(b"\r\n");
        Some(next)
    }
}
