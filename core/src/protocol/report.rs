//! What the protocol tells the host on its own: the welcome line, `ok` / `error:N`,
//! alarms and messages from the machine's events, and the status report
//! (`<Idle|MPos:...|FS:...>`).

use super::{OutWriter, Protocol, REFRESH_EVERY, RX_BUFFER_SIZE, WELCOME};
use crate::decimal::{put_decimal, put_int, round_i32, write_fixed3, Sink};
use crate::gcode::units::nm_to_mm;
use crate::gcode::ErrorCode;
use crate::machine::state::Event;
use crate::machine::{MotionControl, RunState};
use crate::motion::AXES;
use crate::settings::{PenMode, Settings};

/// Millimetres per reported unit: 25.4 when reports are in inches ($13), else 1
/// (dividing by it is then exact).
pub(super) fn report_scale(settings: &Settings) -> f32 {
    if settings.report_inches() {
        25.4
    } else {
        1.0
    }
}

pub(super) fn axis_triplet(w: &mut dyn Sink, v: &[f32; AXES], scale: f32) {
    for (i, x) in v.iter().enumerate() {
        if i > 0 {
            w.put(b",");
        }
        write_fixed3(w, x / scale);
    }
}

/// A status field of two whole numbers: `head`, `a`, a comma, `b`.
fn field_pair(w: &mut dyn Sink, head: &[u8], a: i32, b: i32) {
    w.put(head);
    put_int(w, a);
    w.put(b",");
    put_int(w, b);
}

impl Protocol {
    /// The welcome line (power-up, reset, leaving check mode, the host opening the
    /// port), followed, as in Grbl, by how to unlock whenever the machine starts in
    /// alarm.
    pub(super) fn welcome(&mut self) {
        self.say(&[b"\r\n", WELCOME.as_bytes()]);
        if let Some(why) = self.machine.refusal() {
            self.notify(why);
        }
        if self.machine.needs_unlock() {
            self.notify("'$H'|'$X' to unlock");
        }
    }

    pub(super) fn respond(&mut self, r: Result<(), ErrorCode>) {
        match r {
            Ok(()) => self.say(&[b"ok"]),
            Err(e) => self.say_n(b"error:", e.code()),
        }
    }

    pub(super) fn flush_events(&mut self) {
        while let Some(e) = self.machine.next_event() {
            match e {
                Event::Alarm(a) => self.say_n(b"ALARM:", a.code()),
                Event::Msg(t) => self.notify(t),
                Event::JobStarted => self.notify("Job started"),
                Event::PenChange(tool) => {
                    let mut w = self.w();
                    w.put(b"[MSG:Pen change: pen ");
                    put_decimal(&mut w, u64::from(tool), false, 0);
                    w.put(b", cycle start to continue]\r\n");
                }
                Event::JobFinished { ms, moves } => {
                    let mut w = self.w();
                    w.put(b"[MSG:Job finished: ");
                    // Seconds with three decimals: exact, as f32 holds any u32 / 1000
                    // only approximately, so the digits come from the integer.
                    put_decimal(&mut w, u64::from(ms), false, 3);
                    w.put(b" s, ");
                    put_decimal(&mut w, u64::from(moves), false, 0);
                    w.put(b" moves]\r\n");
                }
            }
        }
    }

    /// `<State|MPos:...|FS:...|Bf:...|...>`.
    pub(super) fn status_report<M: MotionControl>(&mut self, m: &M) {
        self.status_requested = self.status_requested.saturating_sub(1);
        self.reports = self.reports.wrapping_add(1);
        let reports = self.reports;
        // Each value is fetched where it is written: fewer live values to spill. The
        // writer borrows only the output fields, so the machine stays reachable.
        let machine = &mut self.machine;
        let mut w = OutWriter {
            out: &mut self.out,
            truncated: &mut self.truncated,
        };
        w.put(match machine.state(m) {
            RunState::Idle => b"<Idle",
            RunState::Run => b"<Run",
            RunState::Hold { complete: true } => b"<Hold:0",
            RunState::Hold { complete: false } => b"<Hold:1",
            RunState::Jog => b"<Jog",
            RunState::Door { at_rest: true } => b"<Door:0",
            RunState::Door { at_rest: false } => b"<Door:2",
            RunState::Alarm => b"<Alarm",
            RunState::Home => b"<Home",
            RunState::Check => b"<Check",
            RunState::Sleep => b"<Sleep",
        });
        let settings = machine.settings();
        let scale = report_scale(settings);
        let mask = settings.status_mask();
        let mut pos = machine.machine_position(m);
        let wco_nm = machine.interpreter().work_offset();
        let wco = wco_nm.map(nm_to_mm);
        if mask & 1 != 0 {
            w.put(b"|MPos:");
        } else {
            for (p, o) in pos.iter_mut().zip(wco.iter()) {
                *p -= o;
            }
            w.put(b"|WPos:");
        }
        axis_triplet(&mut w, &pos, scale);
        if mask & 2 != 0 {
            let rx_free = RX_BUFFER_SIZE - self.rx.len();
            field_pair(&mut w, b"|Bf:", m.free() as i32, rx_free as i32);
        }
        // The pen is the spindle: report S while it is down.
        let interpreter = machine.interpreter();
        let spindle = if interpreter.modal().pen_down {
            let (lo, hi) = settings.spindle_range();
            // max/min, not `clamp`: its assertion's message would link float
            // formatting into the image.
            round_i32(interpreter.spindle().min(hi).max(lo))
        } else {
            0
        };
        // Grbl 1.1's `Ln:`: the N number of the line whose motion runs.
        if let Some(n) = m.line().filter(|&n| n > 0) {
            w.put(b"|Ln:");
            put_decimal(&mut w, u64::from(n), false, 0);
        }
        field_pair(&mut w, b"|FS:", round_i32(m.speed() / scale), spindle);
        // Grbl 1.1's accessory field: the pen touching the paper is the spindle on
        // (`S`, clockwise). The servo as it is now; a Z pen by where Z stands (a
        // partial `M3 S` height is down too).
        let pen_down = match settings.pen_mode() {
            PenMode::Servo => m.pen_down(),
            PenMode::ZAxis => {
                // Off the up position toward down (by more than 1 % of the way).
                let z = machine.machine_position(m)[2];
                let (up, down) = (settings.pen_z_up(), settings.pen_z_down());
                (z - up) * (down - up) > 0.01 * (down - up) * (down - up)
            }
        };
        let inputs = machine.inputs();
        let pins = [
            inputs.limits[0],
            inputs.limits[1],
            inputs.limits[2],
            inputs.feed_hold,
            inputs.cycle_start,
            inputs.estop,
        ];
        if pins.contains(&true) {
            w.put(b"|Pn:");
            for (on, c) in pins.iter().zip(b"XYZHSE".chunks(1)) {
                if *on {
                    w.put(c);
                }
            }
        }
        if reports % REFRESH_EVERY == 1 || wco_nm != self.wco_shown {
            w.put(b"|WCO:");
            axis_triplet(&mut w, &wco, scale);
            self.wco_shown = wco_nm;
        }
        if machine.take_overrides_changed() || reports % REFRESH_EVERY == 6 {
            let (fo, ro) = machine.overrides();
            field_pair(&mut w, b"|Ov:", i32::from(fo), i32::from(ro));
            w.put(b",100");
        }
        if pen_down {
            w.put(b"|A:S");
        }
        w.put(b">\r\n");
    }
}
