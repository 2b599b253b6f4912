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
//!
//! This module holds the state and [`Interpreter::execute_into`], whose stages (marked
//! in its body) each state what they guarantee; `commands` holds what the stages queue
//! (rapid and pen moves, straight paths) and the G10 / G92 offset arithmetic, `jog` the
//! `$J=` line.

mod commands;
mod jog;
pub use jog::{Jog, JogFrame};
#[cfg(test)]
mod tests;

use super::arcs::{arc_extremes, arc_geometry, arc_path};
use super::modal::{
    group_codes, Modal, MotionMode, NonModal, GROUPS, G_CODES, MOTION_MODES, M_CODES, NONE,
    NON_MODAL,
};
use super::parser::{Value, WordBlock, ONE};
use super::units::{
    mm_between, mm_to_nm, nm_to_fine_steps, to_nm, to_steps, value_to_ms, value_to_nm,
    within_travel, Nm, NmPos, Reach,
};
use super::ErrorCode;
use crate::decimal::{put_int, round_i32, Sink};
use crate::fmath;
use crate::motion::{Command, PEN_FULL};
use crate::motion::{Feed, Move, Path, StepPos, AXES};
use crate::settings::{PenMode, Settings};
use commands::{line_path, path_length, pen_move, push, push_rapid, set_axes};
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
    Error(ErrorCode),
    /// A target lies outside the travel with soft limits on (alarm 2 for G-code).
    SoftLimit,
}

impl From<ErrorCode> for Reject {
    fn from(s: ErrorCode) -> Self {
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
        let mut b = WordBlock::default();
        b.parse_into(line)?;

        // --- Stage 1, grouping. Guarantees: every G and M code is known and each modal
        // group is named at most once (M1 not beside M0/M2); nothing has changed. ---
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
            return Err(ErrorCode::ModalGroupViolation.into());
        }
        let mut stop = match stop {
            0 => Some(Stop::Pause),
            1 => Some(Stop::End),
            _ => None,
        };
        if tool_change != NONE && stop.is_some() {
            // One stop per block: a pen change beside M0/M2 is ambiguous.
            return Err(ErrorCode::ModalGroupViolation.into());
        }

        // --- Stage 2, value words and modes. Guarantees: no negative F, N, P, S, T or L,
        // N and T in range, the feed in mm/min (or per block in inverse time); the new
        // modes are in the copy `modal`, never yet in `self`. ---
        for &letter in b"FNPSTL" {
            if b.get(letter).is_some_and(Value::is_negative) {
                return Err(ErrorCode::NegativeValue.into());
            }
        }
        let n_word = b.take(b'N').map(Value::round);
        if n_word.is_some_and(|n| n > MAX_LINE_NUMBER) {
            return Err(ErrorCode::InvalidLineNumber.into());
        }
        let line_tag = n_word.map_or(line_no, |n| n as u32);
        let tool = b.take(b'T');
        if tool.is_some_and(|t| t.millionths() > 255 * ONE) {
            return Err(ErrorCode::MaxValueExceeded.into());
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

        // --- Stage 3, the owner of the axis words. Guarantees: exactly one command uses
        // them (or none is named), a feed motion has a feed. ---
        // Which command uses the axis words: a non-modal one, G43.1 (its Z word is the
        // offset, and Z is the only axis it may name: error 37), or else motion.
        let dynamic_tlo = tool_length == 1;
        if dynamic_tlo && axes & !(1 << 2) != 0 {
            return Err(ErrorCode::G43DynamicAxisError.into());
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
            return Err(ErrorCode::AxisCommandConflict.into());
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
            return Err(ErrorCode::AxisWordsExist.into());
        }
        let absolute_override = non_modal == Some(NonModal::Absolute);
        if absolute_override
            && !(motion_cmd && matches!(modal.motion, MotionMode::Rapid | MotionMode::Linear))
        {
            return Err(ErrorCode::G53InvalidMotionMode.into());
        }
        let feed_motion = motion_cmd
            && matches!(
                modal.motion,
                MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
            );
        if feed_motion && feed <= 0.0 {
            return Err(ErrorCode::UndefinedFeedRate.into());
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

        // --- Stage 4, targets, in machine nanometres. Guarantees: `target` is where the
        // axis words lead in the block's modes; `out` holds at most the pen move. ---
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

        // --- Stage 5, non-modal commands, then motion. Guarantees: their commands are in
        // `out` in execution order, coordinate changes only in the copies `coords`,
        // `g92`, `pos`; every target reached is recorded in `planned`. ---
        match non_modal {
            Some(NonModal::Dwell) => {
                let p = b.take(b'P').ok_or(ErrorCode::ValueWordMissing)?;
                push(out, Command::Dwell { ms: value_to_ms(p) })?;
            }
            Some(NonModal::SetCoord) => {
                let l = b.take(b'L').ok_or(ErrorCode::ValueWordMissing)?;
                let p = b.take(b'P').ok_or(ErrorCode::ValueWordMissing)?;
                let (Some(l), Some(p)) = (l.whole(), p.whole()) else {
                    return Err(ErrorCode::CommandValueNotInteger.into());
                };
                if p > 6 {
                    return Err(ErrorCode::UnsupportedCoordSys.into());
                }
                if !has_axis {
                    return Err(ErrorCode::NoAxisWords.into());
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
                    _ => return Err(ErrorCode::UnsupportedCommand.into()),
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
                    return Err(ErrorCode::NoAxisWords.into());
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
                        return Err(ErrorCode::NoAxisWords.into());
                    }
                    if axes & 3 == 0 {
                        return Err(ErrorCode::NoAxisWordsInPlane.into());
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

        // --- Stage 6, completeness. Guarantees: every word was used, every target is in
        // the step range and (with soft limits) in travel; an error still leaves `self`
        // unchanged. ---
        // Everything the block asked for must have been used.
        let leftover_axes = has_axis && !motion_cmd && !nm_uses_axes;
        if leftover_axes {
            return Err(ErrorCode::AxisWordsExist.into());
        }
        if b.any_value() {
            return Err(ErrorCode::UnusedWords.into());
        }
        if !planned.in_range {
            return Err(ErrorCode::InvalidTarget.into());
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

        // --- Stage 7, commit. Guarantees: only with `room` (a sync point waits for
        // rest), the copies replace the state all at once. ---
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
}
