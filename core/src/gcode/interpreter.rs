//! The G-code interpreter: modal state, coordinate systems and the translation of one
//! block into planner [`Command`]s in steps.
//!
//! Each block is checked completely before anything changes (Grbl's rule: a rejected
//! line has no effect), then applied in the NIST order (feed, pen, dwell, units,
//! coordinate system, distance mode, non-modal commands, motion, program stop). The
//! position and the offsets are kept in whole machine nanometres, exact decimals
//! ([`super::units`]), and converted to steps per target with round-half-away-from-zero,
//! so that neither rounding nor a binary fraction ever accumulates. Soft limits are checked
//! here, on every target of the block (for arcs, on their extent), before any command
//! leaves.

use super::arcs::{arc_extremes, arc_geometry, arc_path};
use super::modal::{
    group_codes, Modal, MotionMode, NonModal, GROUPS, G_CODES, MOTION_MODES, M_CODES, NONE,
    NON_MODAL,
};
use super::parser::{Block, Value, ONE};
use super::units::{
    mm_between, mm_to_nm, nm_to_fine_steps, to_nm, to_steps, value_to_ms, value_to_nm,
    within_travel, Nm, NmPos, Reach,
};
use super::Status;
use crate::decimal::{put_int, round_i32, Sink};
use crate::fmath;
use crate::motion::{Command, PEN_FULL};
use crate::motion::{Feed, Move, Path, StepPos, AXES};
use crate::settings::{PenMode, Settings};
use heapless::Vec;

/// Most commands one block can queue (pen, G28 intermediate, G28 target, pen at M2).
pub const MAX_COMMANDS: usize = 4;
pub(super) const MM_PER_INCH: f32 = 25.4;
/// Largest line number Grbl accepts.
pub const MAX_LINE_NUMBER: i64 = 10_000_000;

/// Coordinate data that Grbl keeps across resets (and inkstep in flash), nanometres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Coords {
    /// G54..G59 offsets.
    pub wcs: [NmPos; 6],
    /// G28 and G30 stored positions, machine coordinates.
    pub g28: NmPos,
    pub g30: NmPos,
}

/// Program flow requested by a block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// M0: pause (the motion before it has finished: a sync point) until cycle start.
    Pause,
    /// M2 / M30: end of program (modal state already reset).
    End,
    /// M6 T`tool`: a manual pen change. The block's first `split` commands (the
    /// lift and the way to the pen-change place) run, then the machine waits at rest
    /// for cycle start, then the rest (the way back and the drop) runs.
    PenChange { tool: u8, split: u8 },
}

/// A block's effect for the machine to carry out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outcome {
    pub cmds: Vec<Command, MAX_COMMANDS>,
    pub stop: Option<Stop>,
    /// G10, G28.1 or G30.1 changed the coordinate data (worth saving).
    pub coords_changed: bool,
    /// The block is a sync point, as in Grbl: it runs only once every earlier motion
    /// has finished (G4, M0, M2/M30, and whatever writes stored data or changes the
    /// work coordinate offset: G10, G28.1, G30.1, G92, G92.1, G43.1, G49 and a new
    /// G54-G59). A G4's answer also waits for its dwell ([`Outcome::has_dwell`]).
    pub sync: bool,
}

impl Outcome {
    /// The block queued a dwell (G4): its `ok` waits until the dwell has elapsed.
    pub fn has_dwell(&self) -> bool {
        self.cmds.iter().any(|c| matches!(c, Command::Dwell { .. }))
    }
}

/// What the caller of [`Interpreter::execute_into`] can take now. Planner room is not
/// asked: a block that does not fit yet is committed all the same, and its commands
/// wait with the caller ([`crate::machine::Machine::execute`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Room {
    /// The queue has run empty and the machine is at rest (a sync point may run).
    pub idle: bool,
}

/// Why a block was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reject {
    /// `error:N`.
    Error(Status),
    /// A target lies outside the travel with soft limits on (alarm 2 for G-code).
    SoftLimit,
}

impl From<Status> for Reject {
    fn from(s: Status) -> Self {
        Reject::Error(s)
    }
}

/// The interpreter.
#[derive(Clone, Debug, PartialEq)]
pub struct Interpreter {
    modal: Modal,
    /// Programmed feed in mm/min (G94) or per-block inverse time; 0 = undefined.
    feed: f32,
    spindle: f32,
    /// An `S` word has been given since the last reset: `M3` sets the pen level from
    /// it (without one, `M3` drops the pen fully, as before `S` meant a height).
    s_given: bool,
    /// The last T word: the pen an M6 without T changes to.
    tool_next: u8,
    /// Position in machine nanometres, the end of the last queued block.
    pos: NmPos,
    coords: Coords,
    g92: NmPos,
    /// Dynamic tool length offset (G43.1 Z), nanometres; 0 under G49.
    tlo: Nm,
}

impl Default for Interpreter {
    fn default() -> Self {
        Self::new()
    }
}

impl Interpreter {
    pub const fn new() -> Self {
        Interpreter {
            modal: Modal::INITIAL,
            feed: 0.0,
            spindle: 0.0,
            s_given: false,
            tool_next: 0,
            pos: [0; AXES],
            coords: Coords {
                wcs: [[0; AXES]; 6],
                g28: [0; AXES],
                g30: [0; AXES],
            },
            g92: [0; AXES],
            tlo: 0,
        }
    }

    pub fn modal(&self) -> &Modal {
        &self.modal
    }
    pub fn coords(&self) -> &Coords {
        &self.coords
    }
    /// Replace the coordinate data (loaded from flash at boot).
    pub fn set_coords(&mut self, c: Coords) {
        self.coords = c;
    }
    pub fn g92(&self) -> &NmPos {
        &self.g92
    }
    /// The tool length offset (G43.1): `[TLO:]` in `$#`.
    pub fn tool_length_offset(&self) -> Nm {
        self.tlo
    }
    /// Position at the end of the queued program, machine nanometres.
    pub fn position(&self) -> &NmPos {
        &self.pos
    }
    /// Last programmed S value.
    pub fn spindle(&self) -> f32 {
        self.spindle
    }
    /// Feed in mm/min as programmed (0 if undefined).
    pub fn feed(&self) -> f32 {
        self.feed
    }
    /// The work coordinate offset (active system + G92 + tool length offset).
    pub fn work_offset(&self) -> NmPos {
        self.offset_of(self.modal.wcs)
    }

    /// Offset of coordinate system `wcs` (0 = G54) plus G92 and the tool length
    /// offset on Z.
    fn offset_of(&self, wcs: u8) -> NmPos {
        let mut o = self.g92;
        o[2] = o[2].saturating_add(self.tlo);
        if let Some(w) = self.coords.wcs.get(usize::from(wcs)) {
            for (o, w) in o.iter_mut().zip(w.iter()) {
                *o = o.saturating_add(*w);
            }
        }
        o
    }

    /// The servo pen went up with a stop that discarded the queue: the next `M3`
    /// drops it again.
    pub fn pen_lifted(&mut self) {
        self.modal.pen_down = false;
        self.modal.pen_level = 0;
    }

    /// Take the position from the planner after a stop that discarded the queue.
    pub fn sync_position(&mut self, steps: &StepPos, s: &Settings) {
        self.pos = to_nm(steps, s);
    }

    /// Soft reset: modal state back to defaults (G0 G54 G17 G21 G90 G94 G49 M5, F0)
    /// and the G92 and tool length offsets cleared, as Grbl re-initialises its
    /// parser; the position and the stored coordinate data stay.
    pub fn reset_modal(&mut self) {
        self.modal = Modal::default();
        self.feed = 0.0;
        self.spindle = 0.0;
        self.s_given = false;
        self.g92 = [0; AXES];
        self.tlo = 0;
    }

    /// `[GC:...]` body for `$G` (without brackets).
    pub fn write_modal(&self, w: &mut dyn Sink) {
        let m = &self.modal;
        w.put(match m.motion {
            MotionMode::Rapid => b"GC:G0",
            MotionMode::Linear => b"GC:G1",
            MotionMode::ArcCw => b"GC:G2",
            MotionMode::ArcCcw => b"GC:G3",
            MotionMode::Cancel => b"GC:G80",
        });
        // The defaults, with the digits that the modal state changes patched in.
        let mut modes = *b" G54 G17 G21 G90 G94";
        modes[3] = b'4' + m.wcs.min(5); // G54..G59
        modes[11] -= u8::from(m.inches); // G20
        modes[15] += u8::from(m.incremental); // G91
        modes[19] -= u8::from(m.inverse_time); // G93
        w.put(&modes);
        // The tool length offset group only while G43.1 is in effect: the default
        // (G49) is left out like Grbl's other unprinted defaults, so that a sender
        // replaying these words after a reset never sends a G43.1 without its Z.
        if m.tool_length {
            w.put(b" G43.1");
        }
        let mut tail = *b" M5 M9 T0 F";
        tail[2] -= 2 * u8::from(m.pen_down); // M3
        w.put(&tail);
        let scale = if m.inches { MM_PER_INCH } else { 1.0 };
        put_int(w, round_i32(self.feed / scale));
        w.put(b" S");
        put_int(w, round_i32(self.spindle));
    }

    /// Interpret one cleaned line (no spaces, upper case, no comments).
    /// `line_no` is used for the queued moves when the block has no N word.
    pub fn execute(&mut self, line: &[u8], s: &Settings, line_no: u32) -> Result<Outcome, Reject> {
        let mut out = Outcome::default();
        self.execute_into(line, s, line_no, &mut out, Some(Room { idle: true }))?;
        Ok(out)
    }

    /// [`Interpreter::execute`] into `out` (which must be empty), committing the block
    /// unless it is a sync point and the machine is not at rest (`room`): `Ok(false)`
    /// leaves the interpreter unchanged (the outcome is still filled in), and `room:
    /// None` only checks the block. The machine needs no trial copy of the interpreter
    /// that way.
    pub fn execute_into(
        &mut self,
        line: &[u8],
        s: &Settings,
        line_no: u32,
        out: &mut Outcome,
        room: Option<Room>,
    ) -> Result<bool, Reject> {
        let mut b = Block::default();
        b.parse_into(line)?;

        // --- Group the codes (one modal group may be named once per block). ---
        let mut groups = [NONE; GROUPS];
        group_codes(&b.g, &G_CODES, &mut groups, true)?;
        group_codes(&b.m, &M_CODES, &mut groups, false)?;
        let [motion, non_modal, units, distance, feed_mode, wcs, _, _, _, tool_length, _, stop, m1, pen, _, tool_change] =
            groups;
        let motion = MOTION_MODES.get(usize::from(motion)).copied();
        let non_modal = NON_MODAL.get(usize::from(non_modal)).copied();
        // M1 (optional stop) is ignored, as Grbl does without a stop switch, but it
        // shares the stop group.
        if m1 != NONE && stop != NONE {
            return Err(Status::ModalGroupViolation.into());
        }
        let mut stop = match stop {
            0 => Some(Stop::Pause),
            1 => Some(Stop::End),
            _ => None,
        };
        if tool_change != NONE && stop.is_some() {
            // One stop per block: a pen change beside M0/M2 is ambiguous.
            return Err(Status::ModalGroupViolation.into());
        }

        // --- Value words. ---
        for &letter in b"FNPSTL" {
            if b.get(letter).is_some_and(Value::is_negative) {
                return Err(Status::NegativeValue.into());
            }
        }
        let n_word = b.take(b'N').map(Value::round);
        if n_word.is_some_and(|n| n > MAX_LINE_NUMBER) {
            return Err(Status::InvalidLineNumber.into());
        }
        let line_tag = n_word.map_or(line_no, |n| n as u32);
        let tool = b.take(b'T');
        if tool.is_some_and(|t| t.millionths() > 255 * ONE) {
            return Err(Status::MaxValueExceeded.into());
        }
        let tool = tool.map(|t| t.round() as u8);
        let spindle = b.take(b'S').map(Value::to_f32);

        let mut modal = self.modal;
        if units != NONE {
            modal.inches = units != 0;
        }
        if distance != NONE {
            modal.incremental = distance != 0;
        }
        if wcs != NONE {
            modal.wcs = wcs;
        }
        let scale = if modal.inches { MM_PER_INCH } else { 1.0 };

        let mut feed = self.feed;
        if feed_mode != NONE {
            let inverse = feed_mode != 0;
            if inverse != modal.inverse_time {
                feed = 0.0; // switching feed modes leaves the feed undefined
            }
            modal.inverse_time = inverse;
        }
        let f_word = b.take(b'F').map(Value::to_f32);
        if modal.inverse_time {
            feed = f_word.unwrap_or(0.0); // per block, never modal
        } else if let Some(f) = f_word {
            feed = f * scale;
        }

        // Axis words in nanometres, and the mask of the axes named.
        let mut words: NmPos = [0; AXES];
        let mut axes = 0u8;
        for (k, (w, &letter)) in words.iter_mut().zip(b"XYZ").enumerate() {
            if let Some(v) = b.take(letter) {
                *w = value_to_nm(v, modal.inches);
                axes |= 1 << k;
            }
        }
        let has_axis = axes != 0;

        // Which command uses the axis words: a non-modal one, G43.1 (its Z word is the
        // offset, and Z is the only axis it may name: error 37), or else motion.
        let dynamic_tlo = tool_length == 1;
        if dynamic_tlo && axes & !(1 << 2) != 0 {
            return Err(Status::G43DynamicAxisError.into());
        }
        let non_modal_axes = matches!(
            non_modal,
            Some(NonModal::SetCoord | NonModal::Home28 | NonModal::Home30 | NonModal::SetG92)
        );
        let nm_uses_axes = non_modal_axes || dynamic_tlo;
        // A motion mode beside G43.1 only conflicts if there are axis words to fight
        // over: a bare `G0 ... G43.1` (bCNC replaying the `$G` words) just sets modes.
        let motion_conflict =
            motion.is_some_and(|m| m != MotionMode::Cancel) && (non_modal_axes || has_axis);
        if (nm_uses_axes && motion_conflict) || (non_modal_axes && dynamic_tlo) {
            return Err(Status::AxisCommandConflict.into());
        }
        if let Some(m) = motion {
            modal.motion = m;
        }
        // G43.1 Z sets the offset (a bare G43.1 keeps the one in effect); G49 clears it.
        let mut tlo = self.tlo;
        if tool_length != NONE {
            modal.tool_length = dynamic_tlo;
            tlo = match (dynamic_tlo, axes & 1 << 2 != 0) {
                (true, true) => words[2],
                (true, false) => tlo,
                (false, _) => 0,
            };
        }
        // Motion runs if it was named in the block, or implicitly for axis words.
        let motion_cmd = !nm_uses_axes && (motion.is_some() || has_axis);
        if motion_cmd && modal.motion == MotionMode::Cancel && has_axis {
            return Err(Status::AxisWordsExist.into());
        }
        let absolute_override = non_modal == Some(NonModal::Absolute);
        if absolute_override
            && !(motion_cmd && matches!(modal.motion, MotionMode::Rapid | MotionMode::Linear))
        {
            return Err(Status::G53InvalidMotionMode.into());
        }
        let feed_motion = motion_cmd
            && matches!(
                modal.motion,
                MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
            );
        if feed_motion && feed <= 0.0 {
            return Err(Status::UndefinedFeedRate.into());
        }

        let mut coords = self.coords;
        let mut g92 = self.g92;
        let mut pos = self.pos;
        let mut planned = Reach {
            in_range: true,
            in_travel: true,
        };

        // Pen (M3/M4/M5) runs before motion; so does a new S while the pen is down
        // (a new height, in order with the strokes).
        if pen != NONE {
            modal.pen_down = pen != 0;
        }
        if pen != NONE || (modal.pen_down && spindle.is_some()) {
            let level = match (modal.pen_down, spindle) {
                (false, _) => 0,
                (true, Some(v)) => s.pen_level_of(v),
                (true, None) if self.s_given => s.pen_level_of(self.spindle),
                (true, None) => PEN_FULL,
            };
            if level != modal.pen_level {
                pen_move(out, &mut pos, level, s, line_tag, &mut planned)?;
            }
            modal.pen_level = level;
        }
        // M6: lift, to the pen-change place ($216-$218), wait, back, drop again.
        if tool_change != NONE {
            let (back, level) = (pos, modal.pen_level);
            if level != 0 {
                pen_move(out, &mut pos, 0, s, line_tag, &mut planned)?;
            }
            let place = s.pen_change_xy();
            if let Some(xy) = place {
                pos[0] = mm_to_nm(xy[0]);
                pos[1] = mm_to_nm(xy[1]);
                push_rapid(out, &pos, s, line_tag, &mut planned)?;
            }
            let split = out.cmds.len() as u8;
            if place.is_some() {
                pos = [back[0], back[1], pos[2]];
                push_rapid(out, &pos, s, line_tag, &mut planned)?;
            }
            if level != 0 {
                pen_move(out, &mut pos, level, s, line_tag, &mut planned)?;
            }
            let tool = tool.unwrap_or(self.tool_next);
            stop = Some(Stop::PenChange { tool, split });
        }

        // --- Targets, in machine nanometres. ---
        let offset = self.offset_of(modal.wcs);
        let mut target = pos;
        for (k, ((t, &v), (&p, &o))) in target
            .iter_mut()
            .zip(words.iter())
            .zip(pos.iter().zip(offset.iter()))
            .enumerate()
        {
            if axes >> k & 1 != 0 {
                *t = if absolute_override {
                    v
                } else if modal.incremental {
                    p.saturating_add(v)
                } else {
                    v.saturating_add(o)
                };
            }
        }

        match non_modal {
            Some(NonModal::Dwell) => {
                let p = b.take(b'P').ok_or(Status::ValueWordMissing)?;
                push(out, Command::Dwell { ms: value_to_ms(p) })?;
            }
            Some(NonModal::SetCoord) => {
                let l = b.take(b'L').ok_or(Status::ValueWordMissing)?;
                let p = b.take(b'P').ok_or(Status::ValueWordMissing)?;
                let (Some(l), Some(p)) = (l.whole(), p.whole()) else {
                    return Err(Status::CommandValueNotInteger.into());
                };
                if p > 6 {
                    return Err(Status::UnsupportedCoordSys.into());
                }
                if !has_axis {
                    return Err(Status::NoAxisWords.into());
                }
                let idx = if p == 0 {
                    usize::from(modal.wcs)
                } else {
                    p as usize - 1
                };
                // L20: the offset that makes the current position read as the words,
                // past G92 and the tool length offset.
                let from = match l {
                    2 => None,
                    20 => Some((&g92, tlo)),
                    _ => return Err(Status::UnsupportedCommand.into()),
                };
                if let Some(sys) = coords.wcs.get_mut(idx) {
                    set_axes(sys, axes, &words, &pos, from);
                }
                out.coords_changed = true;
            }
            Some(NonModal::Home28 | NonModal::Home30) => {
                let stored = if non_modal == Some(NonModal::Home28) {
                    coords.g28
                } else {
                    coords.g30
                };
                if has_axis {
                    push_rapid(out, &target, s, line_tag, &mut planned)?;
                }
                push_rapid(out, &stored, s, line_tag, &mut planned)?;
                pos = stored;
            }
            Some(NonModal::Set28) => {
                coords.g28 = pos;
                out.coords_changed = true;
            }
            Some(NonModal::Set30) => {
                coords.g30 = pos;
                out.coords_changed = true;
            }
            Some(NonModal::SetG92) => {
                if !has_axis {
                    return Err(Status::NoAxisWords.into());
                }
                let w = coords.wcs.get(usize::from(modal.wcs)).unwrap_or(&[0; AXES]);
                set_axes(&mut g92, axes, &words, &pos, Some((w, tlo)));
            }
            Some(NonModal::ResetG92) => g92 = [0; AXES],
            Some(NonModal::Absolute) | None => {}
        }

        if motion_cmd {
            let arc = matches!(modal.motion, MotionMode::ArcCw | MotionMode::ArcCcw);
            if arc || (has_axis && modal.motion != MotionMode::Cancel) {
                let ccw = modal.motion == MotionMode::ArcCcw;
                let (len, path) = if arc {
                    if !has_axis {
                        return Err(Status::NoAxisWords.into());
                    }
                    if axes & 3 == 0 {
                        return Err(Status::NoAxisWordsInPlane.into());
                    }
                    let g = arc_geometry(&mut b, &pos, &target, ccw, modal.inches)?;
                    arc_extremes(&g, &pos, &target, ccw, &mut planned, s);
                    let rise = mm_between(pos[2], target[2]);
                    let arc_len = fmath::hypot(g.radius * g.sweep, rise);
                    (arc_len, arc_path(&g, &pos, ccw, s))
                } else {
                    planned.add(&target, s);
                    (path_length(&pos, &target), line_path(&pos, &target, s))
                };
                let f = if modal.motion == MotionMode::Rapid {
                    Feed::Rapid
                } else if modal.inverse_time {
                    Feed::MmPerMin(len * feed)
                } else {
                    Feed::MmPerMin(feed)
                };
                // Out of range is refused below (`planned`), before anything commits.
                let steps = to_steps(&target, s);
                if arc || steps != to_steps(&pos, s) {
                    push(
                        out,
                        Command::Move(Move {
                            target: steps.unwrap_or([0; AXES]),
                            path,
                            feed: f,
                            line: line_tag,
                        }),
                    )?;
                }
                pos = target;
            }
        }

        // Everything the block asked for must have been used.
        let leftover_axes = has_axis && !motion_cmd && !nm_uses_axes;
        if leftover_axes {
            return Err(Status::AxisWordsExist.into());
        }
        if b.any_value() {
            return Err(Status::UnusedWords.into());
        }
        if !planned.in_range {
            return Err(Status::InvalidTarget.into());
        }
        if s.soft_limits() && !planned.in_travel {
            return Err(Reject::SoftLimit);
        }

        if stop == Some(Stop::End) {
            if modal.pen_level != 0 {
                // Checked already: the lift stays where the block's moves went.
                pen_move(out, &mut pos, 0, s, line_tag, &mut planned)?;
            }
            modal = Modal {
                inches: modal.inches,
                tool_length: modal.tool_length,
                motion: MotionMode::Linear,
                ..Modal::default()
            };
        }

        out.stop = stop;
        let wcs_changed = modal.wcs != self.modal.wcs;
        out.sync = stop.is_some()
            || wcs_changed
            || tool_length != NONE
            || matches!(
                non_modal,
                Some(
                    NonModal::Dwell
                        | NonModal::SetCoord
                        | NonModal::Set28
                        | NonModal::Set30
                        | NonModal::SetG92
                        | NonModal::ResetG92
                )
            );
        let fits = room.is_some_and(|r| r.idle || !out.sync);
        if !fits {
            return Ok(false);
        }

        // Commit.
        self.modal = modal;
        self.feed = if modal.inverse_time { 0.0 } else { feed };
        if let Some(sp) = spindle {
            self.spindle = sp;
            self.s_given = true;
        }
        if let Some(t) = tool {
            self.tool_next = t;
        }
        self.pos = pos;
        self.coords = coords;
        self.g92 = g92;
        self.tlo = tlo;
        Ok(true)
    }

    /// Interpret the body of a `$J=` jog line (cleaned, without `$J=`): only G20/G21,
    /// G90/G91, G53, axis words, F and N are allowed; modal state is left unchanged.
    /// A target outside travel with soft limits on is `error:15`.
    pub fn jog(&mut self, line: &[u8], s: &Settings) -> Result<Move, Status> {
        let mut b = Block::default();
        b.parse_into(line)?;
        if !b.m.is_empty() {
            return Err(Status::InvalidJogCommand);
        }
        let mut inches = self.modal.inches;
        let mut incremental = self.modal.incremental;
        let mut absolute_override = false;
        for &code in b.g.iter() {
            match code {
                200 => inches = true,
                210 => inches = false,
                900 => incremental = false,
                910 => incremental = true,
                530 => absolute_override = true,
                _ => return Err(Status::InvalidJogCommand),
            }
        }
        let _ = b.take(b'N');
        let scale = if inches { MM_PER_INCH } else { 1.0 };
        let f = b.take(b'F').ok_or(Status::UndefinedFeedRate)?;
        if f.millionths() <= 0 {
            return Err(if f.is_negative() {
                Status::NegativeValue
            } else {
                Status::UndefinedFeedRate
            });
        }
        let offset = self.work_offset();
        let mut target = self.pos;
        let mut any = false;
        for (axis, &letter) in b"XYZ".iter().enumerate() {
            if let Some(v) = b.take(letter) {
                any = true;
                let v = value_to_nm(v, inches);
                if let (Some(t), Some(&p), Some(&o)) =
                    (target.get_mut(axis), self.pos.get(axis), offset.get(axis))
                {
                    *t = if absolute_override {
                        v
                    } else if incremental {
                        p.saturating_add(v)
                    } else {
                        v.saturating_add(o)
                    };
                }
            }
        }
        // Value words a jog does not use (S, T, I, P, ...): Grbl's unused-words error.
        if b.any_value() {
            return Err(Status::UnusedWords);
        }
        if !any {
            return Err(Status::NoAxisWords);
        }
        let steps = to_steps(&target, s).ok_or(Status::InvalidTarget)?;
        if s.soft_limits() && !within_travel(&target, s) {
            return Err(Status::TravelExceeded);
        }
        self.pos = target;
        Ok(Move {
            target: steps,
            path: Path::Line,
            feed: Feed::MmPerMin(f.to_f32() * scale),
            line: 0,
        })
    }
}

/// A straight move's path: XY lines carry their exact end points (1/256 step) so the
/// steps follow the programmed line, not the line between rounded ends; moves that
/// change Z (or lie outside the fine range) stay plain lines.
fn line_path(pos: &NmPos, target: &NmPos, s: &Settings) -> Path {
    let (sx, sy) = (s.steps_per_mm(0), s.steps_per_mm(1));
    match (
        nm_to_fine_steps(pos[0], sx),
        nm_to_fine_steps(pos[1], sy),
        nm_to_fine_steps(target[0], sx),
        nm_to_fine_steps(target[1], sy),
    ) {
        (Some(x0), Some(y0), Some(x1), Some(y1)) if pos[2] == target[2] => Path::LineFine {
            from: [x0, y0],
            to: [x1, y1],
        },
        _ => Path::Line,
    }
}

fn push(out: &mut Outcome, c: Command) -> Result<(), Status> {
    out.cmds.push(c).map_err(|_| Status::Overflow)
}

/// A rapid straight move to `p` (checked as planned; out of range is refused before
/// anything commits).
fn push_rapid(
    out: &mut Outcome,
    p: &NmPos,
    s: &Settings,
    line: u32,
    planned: &mut Reach,
) -> Result<(), Status> {
    planned.add(p, s);
    push(
        out,
        Command::Move(Move {
            target: to_steps(p, s).unwrap_or([0; AXES]),
            path: Path::Line,
            feed: Feed::Rapid,
            line,
        }),
    )
}

/// Move the pen to `level` (0 = up, [`PEN_FULL`] = down): a servo command, or a
/// rapid Z move to its place between $205 and $206.
fn pen_move(
    out: &mut Outcome,
    pos: &mut NmPos,
    level: u16,
    s: &Settings,
    line: u32,
    planned: &mut Reach,
) -> Result<(), Status> {
    match s.pen_mode() {
        PenMode::Servo => push(out, Command::Pen { level }),
        PenMode::ZAxis => {
            pos[2] = mm_to_nm(s.pen_z_at(level));
            push_rapid(out, pos, s, line, planned)
        }
    }
}

/// G10 / G92: each named axis of `dst` becomes its word (`from` None), or the offset
/// that makes the current position read as the word past the other offsets `from`
/// (an offset and the tool length offset on Z): `pos - other - word`.
fn set_axes(dst: &mut NmPos, axes: u8, words: &NmPos, pos: &NmPos, from: Option<(&NmPos, Nm)>) {
    for (k, ((d, &v), &p)) in dst.iter_mut().zip(words.iter()).zip(pos.iter()).enumerate() {
        if axes >> k & 1 != 0 {
            *d = match from {
                Some((offset, tlo)) => {
                    // The other offsets on this axis (the tool length offset is Z's).
                    let mut other = offset.get(k).copied().unwrap_or(0);
                    if k == 2 {
                        other = other.saturating_add(tlo);
                    }
                    p.saturating_sub(other).saturating_sub(v)
                }
                None => v,
            };
        }
    }
}

/// Straight-line length between two points, mm.
fn path_length(a: &NmPos, b: &NmPos) -> f32 {
    let mut sum = 0.0;
    for (x, y) in a.iter().zip(b.iter()) {
        let d = mm_between(*x, *y);
        sum += d * d;
    }
    fmath::sqrt(sum)
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::parser::clean_line;
    use crate::gcode::units::nm_to_mm;

    fn run(it: &mut Interpreter, s: &Settings, line: &str) -> Result<Outcome, Reject> {
        let mut buf: heapless::Vec<u8, 128> = heapless::Vec::new();
        clean_line(line.as_bytes(), &mut buf).map_err(Reject::Error)?;
        it.execute(&buf, s, 7)
    }

    fn moves(o: &Outcome) -> std::vec::Vec<Move> {
        o.cmds
            .iter()
            .filter_map(|c| match c {
                Command::Move(m) => Some(*m),
                _ => None,
            })
            .collect()
    }

    fn err(n: Status) -> Result<Outcome, Reject> {
        Err(Reject::Error(n))
    }

    #[test]
    fn lines_round_to_steps_and_carry_feed_and_line_numbers() {
        let s = Settings::default(); // 80 step/mm on X and Y
        let mut it = Interpreter::new();
        let o = run(&mut it, &s, "G1 X10.0031 Y-0.00624 F600").unwrap();
        // The rounded target, and the exact ends in 1/256 step for the interpolator:
        // 10.0031 mm = 800.248 steps = 204,863.488 / 256, -0.00624 mm = -0.4992 steps
        // = -127.7952 / 256 (f32 mm had made the first 204,864).
        assert_eq!(
            moves(&o),
            [Move {
                target: [800, 0, 0],
                path: Path::LineFine {
                    from: [0, 0],
                    to: [204863, -128]
                },
                feed: Feed::MmPerMin(600.0),
                line: 7
            }]
        );
        let o = run(&mut it, &s, "N42 G91 X1 Y1").unwrap();
        let m = moves(&o)[0];
        assert_eq!((m.target, m.line), ([880, 80, 0], 42));
        let o = run(&mut it, &s, "G0 X-1").unwrap();
        assert_eq!(moves(&o)[0].feed, Feed::Rapid);
        assert_eq!(moves(&o)[0].target, [800, 80, 0]);
        // Inches apply to axes and feed.
        let o = run(&mut it, &s, "G20 G90 G1 X1 F10").unwrap();
        assert_eq!(moves(&o)[0].target, [2032, 80, 0]);
        assert_eq!(moves(&o)[0].feed, Feed::MmPerMin(254.0));
    }

    #[test]
    fn grbl_error_numbers_for_bad_blocks() {
        let s = Settings::default();
        let mut it = Interpreter::new();
        assert_eq!(run(&mut it, &s, "G1 X1"), err(Status::UndefinedFeedRate));
        assert_eq!(
            run(&mut it, &s, "G0 G1 X1"),
            err(Status::ModalGroupViolation)
        );
        assert_eq!(run(&mut it, &s, "G5 X1"), err(Status::UnsupportedCommand));
        assert_eq!(run(&mut it, &s, "G0 X1 I2"), err(Status::UnusedWords));
        assert_eq!(
            run(&mut it, &s, "G0 G92 X1"),
            err(Status::AxisCommandConflict)
        );
        assert_eq!(run(&mut it, &s, "G80 X1"), err(Status::AxisWordsExist));
        assert_eq!(run(&mut it, &s, "G4"), err(Status::ValueWordMissing));
        assert_eq!(run(&mut it, &s, "G4 P-1"), err(Status::NegativeValue));
        assert_eq!(
            run(&mut it, &s, "N10000001 G0 X1"),
            err(Status::InvalidLineNumber)
        );
        assert_eq!(
            run(&mut it, &s, "G59.1"),
            err(Status::CommandValueNotInteger)
        );
        assert_eq!(
            run(&mut it, &s, "G53 G2 X1 I1 F10"),
            err(Status::G53InvalidMotionMode)
        );
        assert_eq!(run(&mut it, &s, "G2 I1 F10"), err(Status::NoAxisWords));
        assert_eq!(
            run(&mut it, &s, "G2 Z1 I1 F10"),
            err(Status::NoAxisWordsInPlane)
        );
        assert_eq!(run(&mut it, &s, "G2 X1 F10"), err(Status::NoOffsetsInPlane));
        assert_eq!(
            run(&mut it, &s, "G2 X10 R2 F10"),
            err(Status::ArcRadiusError)
        );
        assert_eq!(run(&mut it, &s, "G2 X0 R2 F10"), err(Status::InvalidTarget));
        assert_eq!(
            run(&mut it, &s, "G10 L3 P1 X1"),
            err(Status::UnsupportedCommand)
        );
        assert_eq!(
            run(&mut it, &s, "G10 L2 P7 X1"),
            err(Status::UnsupportedCoordSys)
        );
        assert_eq!(run(&mut it, &s, "M62"), err(Status::UnsupportedCommand));
        assert_eq!(run(&mut it, &s, "M0 M6"), err(Status::ModalGroupViolation));
        assert_eq!(
            run(&mut it, &s, "G1.5 X1"),
            err(Status::CommandValueNotInteger)
        );
        assert_eq!(run(&mut it, &s, "T300"), err(Status::MaxValueExceeded));
        // A rejected block changes nothing.
        assert_eq!(it, Interpreter::new());
    }

    #[test]
    fn every_g_code_lands_in_its_modal_group() {
        let s = Settings::default();
        // Each supported code with its modal group (Grbl's groups).
        let codes: [(&str, u8); 31] = [
            ("G0", 1),
            ("G1", 1),
            ("G2", 1),
            ("G3", 1),
            ("G80", 1),
            ("G4", 0),
            ("G10", 0),
            ("G28", 0),
            ("G28.1", 0),
            ("G30", 0),
            ("G30.1", 0),
            ("G53", 0),
            ("G92", 0),
            ("G92.1", 0),
            ("G17", 2),
            ("G20", 6),
            ("G21", 6),
            ("G90", 3),
            ("G91", 3),
            ("G91.1", 4),
            ("G93", 5),
            ("G94", 5),
            ("G40", 7),
            ("G43.1", 8),
            ("G49", 8),
            ("G54", 12),
            ("G55", 12),
            ("G56", 12),
            ("G57", 12),
            ("G58", 12),
            ("G59", 12),
        ];
        for (a, ga) in codes {
            for (b, gb) in codes {
                let r = run(&mut Interpreter::new(), &s, &std::format!("{a} {b}"));
                let violation = r == err(Status::ModalGroupViolation);
                assert_eq!(violation, ga == gb, "{a} {b}: {r:?}");
            }
        }
        let modal = |line: &str| {
            let mut it = Interpreter::new();
            run(&mut it, &s, line).unwrap();
            *it.modal()
        };
        assert_eq!(modal("G1 F100").motion, MotionMode::Linear);
        assert_eq!(modal("G0").motion, MotionMode::Rapid);
        assert_eq!(modal("G2 X1 I0.5 F100").motion, MotionMode::ArcCw);
        assert_eq!(modal("G3 X1 I0.5 F100").motion, MotionMode::ArcCcw);
        assert_eq!(modal("G80").motion, MotionMode::Cancel);
        assert!(modal("G20").inches && !modal("G21").inches);
        assert!(modal("G91").incremental && !modal("G90").incremental);
        assert!(modal("G93").inverse_time && !modal("G94").inverse_time);
        for (k, w) in ["G54", "G55", "G56", "G57", "G58", "G59"]
            .iter()
            .enumerate()
        {
            assert_eq!(usize::from(modal(w).wcs), k);
        }
        assert_eq!(modal("G61 G17 G91.1 G40 G49 G94").motion, MotionMode::Rapid);
    }

    /// The exact start and centre of an arc, in 1/256 step, and its direction.
    fn fine_arc(m: &Move) -> ([i32; 2], [i32; 2], bool) {
        let Path::ArcFine {
            from, center, ccw, ..
        } = m.path
        else {
            panic!("not a fine arc: {:?}", m.path)
        };
        (from, center, ccw)
    }

    #[test]
    fn arcs_in_ij_and_r_form_with_cam_tolerance() {
        let s = Settings::default();
        let mut it = Interpreter::new();
        let o = run(&mut it, &s, "G2 X10 Y0 I5 J0 F300").unwrap();
        let m = moves(&o)[0];
        assert_eq!(m.target, [800, 0, 0]);
        // Exact start and centre in 1/256 step (5 mm = 400 steps).
        assert_eq!(fine_arc(&m), ([0, 0], [102_400, 0], false));
        // Negative R: the long way round (centre on the other side).
        let mut it = Interpreter::new();
        let short = moves(&run(&mut it, &s, "G2 X10 Y0 R7.0710678 F300").unwrap())[0];
        let mut it = Interpreter::new();
        let long = moves(&run(&mut it, &s, "G2 X10 Y0 R-7.0710678 F300").unwrap())[0];
        let near = |c: [i32; 2], want: [i32; 2]| {
            (c[0] - want[0]).abs() <= 2 && (c[1] - want[1]).abs() <= 2
        };
        assert!(near(fine_arc(&short).1, [102_400, -102_400]), "{short:?}");
        assert!(near(fine_arc(&long).1, [102_400, 102_400]), "{long:?}");
        // End point 0.004 mm off the circle (CAM rounding) is accepted, 0.1 mm is not.
        let mut it = Interpreter::new();
        assert!(run(&mut it, &s, "G3 X10.004 Y0 I5 F300").is_ok());
        let mut it = Interpreter::new();
        assert_eq!(
            run(&mut it, &s, "G3 X10.1 Y0 I5 F300"),
            err(Status::InvalidTarget)
        );
        // Full circle with I/J: target equals start.
        let mut it = Interpreter::new();
        let full = moves(&run(&mut it, &s, "G3 X0 Y0 I5 F300").unwrap())[0];
        assert_eq!(full.target, [0, 0, 0]);
        assert_eq!(fine_arc(&full), ([0, 0], [102_400, 0], true));
        // Inch units and offsets between steps: the centre keeps its fraction of a step.
        let mut it = Interpreter::new();
        let inch = moves(&run(&mut it, &s, "G20 G3 X0 Y0 I0.123 J0.0457 F10").unwrap())[0];
        let q = |mm: f32| (mm * 80.0 * 256.0).round() as i32;
        assert!(
            near(fine_arc(&inch).1, [q(0.123 * 25.4), q(0.0457 * 25.4)]),
            "{inch:?}"
        );
    }

    #[test]
    fn arcs_with_unequal_resolution_become_ellipses_in_step_space() {
        let mut s = Settings::default();
        s.set(101, 40.0).unwrap();
        let mut it = Interpreter::new();
        let m = moves(&run(&mut it, &s, "G3 X10 Y0 I5 F300").unwrap())[0];
        assert_eq!(m.target, [800, 0, 0]);
        assert_eq!(
            m.path,
            Path::Ellipse {
                center: [400, 0],
                a: 400,
                b: 200,
                ccw: true
            }
        );
    }

    proptest::proptest! {
        /// R-form arcs: the centre is equidistant from both ends, on the side that
        /// gives at most half a turn for positive R and at least half for negative R.
        #[test]
        fn r_form_centres_are_consistent(
            x0 in -100.0f32..100.0, y0 in -100.0f32..100.0,
            dx in -50.0f32..50.0, dy in -50.0f32..50.0,
            extra in 0.0f32..50.0, neg in proptest::bool::ANY, ccw in proptest::bool::ANY,
        ) {
            let chord = libm::hypotf(dx, dy);
            proptest::prop_assume!(chord > 0.5);
            let r = chord / 2.0 + extra + 0.01;
            let s = Settings::default();
            let mut it = Interpreter::new();
            run(&mut it, &s, &std::format!("G0 X{x0:.4} Y{y0:.4}")).unwrap();
            let start = it.position().map(nm_to_mm);
            let line = std::format!("G{} X{:.4} Y{:.4} R{}{:.4} F100", if ccw { 3 } else { 2 }, x0 + dx, y0 + dy, if neg { "-" } else { "" }, r);
            let o = run(&mut it, &s, &line).unwrap();
            let m = moves(&o)[0];
            let (_, center, dir) = fine_arc(&m);
            proptest::prop_assert_eq!(dir, ccw);
            let spm = s.steps_per_mm(0);
            // The exact centre, in 1/256 step.
            let c = [center[0] as f32 / (256.0 * spm), center[1] as f32 / (256.0 * spm)];
            let end = it.position().map(nm_to_mm);
            let r0 = libm::hypotf(start[0] - c[0], start[1] - c[1]);
            let r1 = libm::hypotf(end[0] - c[0], end[1] - c[1]);
            proptest::prop_assert!((r0 - r1).abs() < 0.1 / spm, "r0 {} r1 {}", r0, r1);
            // Which side: cross product of chord and centre offset.
            let cross = dx * (c[1] - start[1]) - dy * (c[0] - start[0]);
            let short = (cross > 0.0) == ccw; // centre left of travel for a short CCW arc
            if extra > 0.5 {
                proptest::prop_assert_eq!(short, !neg, "cross {}", cross);
            }
        }
    }

    /// A near-semicircle whose centre lies close to the chord (where the R form is most
    /// sensitive): the centre is the exact one, to the 1/256 step.
    #[test]
    fn r_form_near_semicircle_centre_is_exact() {
        let s = Settings::default();
        let mut it = Interpreter::new();
        run(&mut it, &s, "G0 X40.4444 Y-47.9680").unwrap();
        let o = run(&mut it, &s, "G2 X84.4295 Y-30.6952 R24.8752 F100").unwrap();
        let (from, center, _) = fine_arc(&moves(&o)[0]);
        // Exact centre (65.28043, -46.57250) mm = (5222.43, -3725.80) steps.
        assert!(
            (center[0] - 1_336_943).abs() <= 64 && (center[1] + 953_805).abs() <= 64,
            "{center:?}"
        );
        assert_eq!(
            from,
            [
                (40.4444f32 * 80.0 * 256.0).round() as i32,
                (-47.968f32 * 80.0 * 256.0).round() as i32
            ]
        );
    }

    #[test]
    fn targets_beyond_the_step_range_are_refused() {
        let s = Settings::default();
        let mut it = Interpreter::new();
        assert_eq!(run(&mut it, &s, "G0 X99999999"), err(Status::InvalidTarget));
        assert_eq!(it.jog(b"X99999999F10", &s), Err(Status::InvalidTarget));
        assert_eq!(it, Interpreter::new());
    }

    #[test]
    fn work_offsets_g92_g10_g28_g53() {
        let s = Settings::default();
        let mut it = Interpreter::new();
        run(&mut it, &s, "G10 L2 P2 X10 Y20").unwrap();
        run(&mut it, &s, "G55 G0 X1 Y1").unwrap();
        assert_eq!(it.position(), &[11_000_000, 21_000_000, 0]);
        run(&mut it, &s, "G92 X0 Y0").unwrap();
        let o = run(&mut it, &s, "G0 X1").unwrap();
        assert_eq!(moves(&o)[0].target, [12 * 80, 21 * 80, 0]);
        run(&mut it, &s, "G92.1").unwrap();
        let o = run(&mut it, &s, "G53 G0 X0 Y0").unwrap();
        assert_eq!(moves(&o)[0].target, [0, 0, 0]);
        run(&mut it, &s, "G0 X5 Y5").unwrap(); // G55: machine 15, 25
        run(&mut it, &s, "G28.1").unwrap();
        assert_eq!(it.coords().g28, [15_000_000, 25_000_000, 0]);
        run(&mut it, &s, "G53 G0 X0 Y0").unwrap();
        let o = run(&mut it, &s, "G28 G91 X1").unwrap();
        let ms = moves(&o);
        assert_eq!(ms.len(), 2, "intermediate point, then the stored position");
        assert_eq!(ms[0].target, [80, 0, 0]);
        assert_eq!(ms[1].target, [15 * 80, 25 * 80, 0]);
        run(&mut it, &s, "G90 G10 L20 P0 X0").unwrap();
        assert_eq!(it.work_offset()[0], 15_000_000);
        // G92 and G10 L20 on Z look past the other offsets and the tool length offset.
        let mut it = Interpreter::new();
        run(&mut it, &s, "G10 L2 P1 Z5").unwrap();
        run(&mut it, &s, "G43.1 Z2").unwrap();
        run(&mut it, &s, "G0 Z0").unwrap();
        assert_eq!(it.position()[2], 7_000_000);
        run(&mut it, &s, "G92 Z1").unwrap();
        assert_eq!(it.g92()[2], -1_000_000, "7 - (5 + 2) - 1");
        run(&mut it, &s, "G10 L20 P1 Z0").unwrap();
        assert_eq!(it.coords().wcs[0][2], 6_000_000, "7 - (-1 + 2) - 0");
        assert_eq!(it.work_offset()[2], 7_000_000, "Z reads 0");
    }

    #[test]
    fn pen_dwell_and_program_end() {
        let mut s = Settings::default();
        let mut it = Interpreter::new();
        let o = run(&mut it, &s, "M3 G1 X1 F100").unwrap();
        assert_eq!(moves(&o)[0].target, [0, 0, -800], "Z pen drops first");
        assert_eq!(moves(&o)[1].target, [80, 0, -800]);
        let o = run(&mut it, &s, "G4 P0.25").unwrap();
        assert_eq!(&o.cmds[..], &[Command::Dwell { ms: 250 }]);
        let o = run(&mut it, &s, "M30").unwrap();
        assert_eq!(o.stop, Some(Stop::End));
        assert_eq!(moves(&o)[0].target, [80, 0, 0], "program end lifts the pen");
        assert_eq!(it.modal().motion, MotionMode::Linear);
        s.set(201, 1.0).unwrap();
        let o = run(&mut it, &s, "M3").unwrap();
        assert_eq!(&o.cmds[..], &[Command::Pen { level: PEN_FULL }]);
        let o = run(&mut it, &s, "M3").unwrap();
        assert!(o.cmds.is_empty(), "no change, nothing queued");
        assert_eq!(run(&mut it, &s, "M0").unwrap().stop, Some(Stop::Pause));
    }

    /// `M3 S` puts the pen in proportion within $31..$30 (S max = down): the servo's
    /// level, the Z pen's height; a new S while down is a new height in order with
    /// the strokes; `M3` without any S drops it fully; `M5` lifts.
    #[test]
    fn m3_s_sets_the_pen_height_within_the_spindle_range() {
        let mut s = Settings::default();
        s.set(201, 1.0).unwrap();
        let mut it = Interpreter::new();
        let pen = |o: &Outcome| -> std::vec::Vec<Command> {
            o.cmds
                .iter()
                .copied()
                .filter(|c| matches!(c, Command::Pen { .. }))
                .collect()
        };
        assert_eq!(
            pen(&run(&mut it, &s, "M3").unwrap()),
            [Command::Pen { level: PEN_FULL }]
        );
        assert_eq!(
            pen(&run(&mut it, &s, "M5").unwrap()),
            [Command::Pen { level: 0 }]
        );
        assert_eq!(
            pen(&run(&mut it, &s, "M3 S500").unwrap()),
            [Command::Pen { level: 500 }]
        );
        let o = run(&mut it, &s, "G1 X1 F100 S250").unwrap();
        assert_eq!(o.cmds[0], Command::Pen { level: 250 }, "before the stroke");
        assert!(matches!(o.cmds[1], Command::Move(_)));
        assert!(
            pen(&run(&mut it, &s, "G1 X2 S250").unwrap()).is_empty(),
            "same S"
        );
        assert_eq!(
            pen(&run(&mut it, &s, "S2000").unwrap()),
            [Command::Pen { level: PEN_FULL }]
        );
        assert_eq!(
            pen(&run(&mut it, &s, "M5").unwrap()),
            [Command::Pen { level: 0 }]
        );
        assert!(
            pen(&run(&mut it, &s, "S800").unwrap()).is_empty(),
            "S while up"
        );
        assert_eq!(
            pen(&run(&mut it, &s, "M3").unwrap()),
            [Command::Pen { level: 800 }],
            "modal S"
        );
        s.set(31, 200.0).unwrap();
        assert_eq!(
            pen(&run(&mut it, &s, "S200").unwrap()),
            [Command::Pen { level: 0 }],
            "S min: up"
        );

        // The Z pen: between $205 (0) and $206 (-2 mm), 400 steps/mm.
        let s = Settings::default();
        let mut it = Interpreter::new();
        let o = run(&mut it, &s, "M3 S250").unwrap();
        assert_eq!(moves(&o)[0].target, [0, 0, -200]);
        let o = run(&mut it, &s, "S1000").unwrap();
        assert_eq!(moves(&o)[0].target, [0, 0, -800]);
        let o = run(&mut it, &s, "M5").unwrap();
        assert_eq!(moves(&o)[0].target, [0, 0, 0]);
    }

    /// `M6 T2`: lift, to the pen-change place ($216-$218), pause (the split), back,
    /// down again at the same height; without a place only the lift and drop.
    #[test]
    fn m6_lifts_goes_to_the_pen_change_place_and_comes_back() {
        let mut s = Settings::default();
        for (n, v) in [(201, 1.0), (216, 1.0), (217, 10.0), (218, 20.0)] {
            s.set(n, v).unwrap();
        }
        let mut it = Interpreter::new();
        run(&mut it, &s, "G0 X5 Y5").unwrap();
        run(&mut it, &s, "M3 S600").unwrap();
        let o = run(&mut it, &s, "M6 T2").unwrap();
        assert_eq!(o.stop, Some(Stop::PenChange { tool: 2, split: 2 }));
        assert!(o.sync, "at rest only");
        assert_eq!(o.cmds[0], Command::Pen { level: 0 });
        assert_eq!(moves(&o)[0].target, [800, 1600, 0], "to the place");
        assert_eq!(moves(&o)[1].target, [400, 400, 0], "and back");
        assert_eq!(o.cmds[3], Command::Pen { level: 600 });
        assert_eq!(it.position(), &[5_000_000, 5_000_000, 0]);
        s.set(216, 0.0).unwrap();
        run(&mut it, &s, "M5").unwrap();
        let o = run(&mut it, &s, "T7").unwrap();
        assert!(o.cmds.is_empty());
        let o = run(&mut it, &s, "M6").unwrap();
        assert_eq!(
            o.stop,
            Some(Stop::PenChange { tool: 7, split: 0 }),
            "the last T"
        );
        assert!(o.cmds.is_empty(), "pen up, no place: nothing moves");
    }

    #[test]
    fn modal_report_names_every_changed_mode() {
        let s = Settings::default();
        let report = |it: &Interpreter| {
            let mut v: heapless::Vec<u8, 64> = heapless::Vec::new();
            it.write_modal(&mut v);
            std::string::String::from_utf8(v.to_vec()).unwrap()
        };
        let mut it = Interpreter::new();
        assert_eq!(report(&it), "GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0");
        run(&mut it, &s, "G20 G91 G93 G59 M3 G1 X1 F1 S12").unwrap();
        assert_eq!(report(&it), "GC:G1 G59 G17 G20 G91 G93 M3 M9 T0 F0 S12");
        run(&mut it, &s, "G21 G90 G94 G56 M5 G80 F300").unwrap();
        assert_eq!(report(&it), "GC:G80 G56 G17 G21 G90 G94 M5 M9 T0 F300 S12");
    }

    #[test]
    fn inverse_time_feed_needs_f_every_block() {
        let s = Settings::default();
        let mut it = Interpreter::new();
        let o = run(&mut it, &s, "G93 G1 X10 F2").unwrap();
        assert_eq!(moves(&o)[0].feed, Feed::MmPerMin(20.0));
        assert_eq!(run(&mut it, &s, "G1 X20"), err(Status::UndefinedFeedRate));
        run(&mut it, &s, "G94").unwrap();
        assert_eq!(run(&mut it, &s, "G1 X20"), err(Status::UndefinedFeedRate));
    }

    #[test]
    fn soft_limits_reject_targets_and_arc_extents() {
        let mut s = Settings::default();
        s.set(22, 1.0).unwrap();
        s.set(20, 1.0).unwrap(); // X, Y in [0, 300] x [0, 200]
        let mut it = Interpreter::new();
        assert!(run(&mut it, &s, "G0 X100 Y100").is_ok());
        assert_eq!(run(&mut it, &s, "G0 X301"), Err(Reject::SoftLimit));
        assert_eq!(run(&mut it, &s, "G0 Y-0.1"), Err(Reject::SoftLimit));
        // Ends inside, but the arc bulges below Y = 0.
        assert_eq!(
            run(&mut it, &s, "G2 X100 Y100 J-60 F100"),
            Err(Reject::SoftLimit)
        );
        assert!(run(&mut it, &s, "G2 X100 Y100 J-50 F100").is_ok());
        assert_eq!(it.jog(b"G91X-200F100", &s), Err(Status::TravelExceeded));
        assert!(it.jog(b"G91X-100F100", &s).is_ok());
        assert_eq!(it.jog(b"G1X1F100", &s), Err(Status::InvalidJogCommand));
        assert_eq!(it.jog(b"X1", &s), Err(Status::UndefinedFeedRate));
    }
}
