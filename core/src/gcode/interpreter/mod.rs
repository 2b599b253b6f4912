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
//! This module holds the state, [`Interpreter::interpret`] (a block read into an
//! [`Outcome`] without changing anything) and [`Interpreter::commit`]; `reading` holds
//! the parts of that reading, one function each, each stating what it guarantees;
//! `commands` what the parts queue (rapid and pen moves, straight paths) and the G10 / G92 offset
//! arithmetic; `jog` the `$J=` line.

mod commands;
mod jog;
mod reading;
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
/// The commands of one block, in order.
pub type BlockCommands = Vec<Command, MAX_COMMANDS>;
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
    pub cmds: BlockCommands,
    pub stop: Option<Stop>,
    /// G10, G28.1 or G30.1 changes the coordinate data (worth saving).
    pub coords: Option<CoordChange>,
    /// The block is a sync point, as in Grbl: it runs only once every earlier motion
    /// has finished (G4, M0, M2/M30, and whatever writes stored data or changes the
    /// work coordinate offset: G10, G28.1, G30.1, G92, G92.1, G43.1, G49 and a new
    /// G54-G59). A G4's answer also waits for its dwell ([`Outcome::has_dwell`]).
    pub sync: bool,
    /// The interpreter's state after the block ([`Interpreter::commit`] puts it in
    /// place with `coords`).
    pub next: BlockState,
}

impl Outcome {
    /// The block queued a dwell (G4): its `ok` waits until the dwell has elapsed.
    pub fn has_dwell(&self) -> bool {
        self.cmds.iter().any(|c| matches!(c, Command::Dwell { .. }))
    }

    /// The block queued a curve (an arc, an ellipse, a sine): planning it (the
    /// curve's geometry) costs about as much again as interpreting it.
    pub fn has_curve(&self) -> bool {
        self.cmds.iter().any(|c| {
            matches!(c, Command::Move(mv) if !matches!(mv.path, Path::Line | Path::LineFine { .. }))
        })
    }
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

/// What a block reads and may change, apart from the stored coordinate data: the
/// modes, the feed, S and T, the position and the G92 and tool length offsets. A block
/// is read into a copy of it ([`Outcome::next`]), put in place when it commits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockState {
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
    g92: NmPos,
    /// Dynamic tool length offset (G43.1 Z), nanometres; 0 under G49.
    tlo: Nm,
}

impl BlockState {
    /// At power-on.
    const INITIAL: BlockState = BlockState {
        modal: Modal::INITIAL,
        feed: 0.0,
        spindle: 0.0,
        s_given: false,
        tool_next: 0,
        pos: [0; AXES],
        g92: [0; AXES],
        tlo: 0,
    };
}

impl Default for BlockState {
    fn default() -> Self {
        Self::INITIAL
    }
}

/// A change a block makes to the stored coordinate data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoordChange {
    /// G10 L2/L20: the offset of work coordinate system `index` (0 = G54).
    Wcs { index: u8, offset: NmPos },
    /// G28.1: the G28 position.
    G28(NmPos),
    /// G30.1: the G30 position.
    G30(NmPos),
}

impl Coords {
    fn apply(&mut self, c: CoordChange) {
        match c {
            CoordChange::Wcs { index, offset } => {
                if let Some(w) = self.wcs.get_mut(usize::from(index)) {
                    *w = offset;
                }
            }
            CoordChange::G28(p) => self.g28 = p,
            CoordChange::G30(p) => self.g30 = p,
        }
    }
}

/// The interpreter.
#[derive(Clone, Debug, PartialEq)]
pub struct Interpreter {
    state: BlockState,
    coords: Coords,
}

impl Default for Interpreter {
    fn default() -> Self {
        Self::new()
    }
}

impl Interpreter {
    pub const fn new() -> Self {
        Interpreter {
            state: BlockState::INITIAL,
            coords: Coords {
                wcs: [[0; AXES]; 6],
                g28: [0; AXES],
                g30: [0; AXES],
            },
        }
    }

    pub fn modal(&self) -> &Modal {
        &self.state.modal
    }
    pub fn coords(&self) -> &Coords {
        &self.coords
    }
    /// Replace the coordinate data (loaded from flash at boot).
    pub fn set_coords(&mut self, c: Coords) {
        self.coords = c;
    }
    pub fn g92(&self) -> &NmPos {
        &self.state.g92
    }
    /// The tool length offset (G43.1): `[TLO:]` in `$#`.
    pub fn tool_length_offset(&self) -> Nm {
        self.state.tlo
    }
    /// Position at the end of the queued program, machine nanometres.
    pub fn position(&self) -> &NmPos {
        &self.state.pos
    }
    /// Last programmed S value.
    pub fn spindle(&self) -> f32 {
        self.state.spindle
    }
    /// Feed in mm/min as programmed (0 if undefined).
    pub fn feed(&self) -> f32 {
        self.state.feed
    }
    /// The work coordinate offset (active system + G92 + tool length offset).
    pub fn work_offset(&self) -> NmPos {
        self.offset_of(self.state.modal.wcs)
    }

    /// Offset of coordinate system `wcs` (0 = G54) plus G92 and the tool length
    /// offset on Z.
    fn offset_of(&self, wcs: u8) -> NmPos {
        let mut o = self.state.g92;
        o[2] = o[2].saturating_add(self.state.tlo);
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
        self.state.modal.pen_down = false;
        self.state.modal.pen_level = 0;
    }

    /// Take the position from the planner after a stop that discarded the queue.
    pub fn sync_position(&mut self, steps: &StepPos, s: &Settings) {
        self.state.pos = to_nm(steps, s);
    }

    /// Soft reset: modal state back to defaults (G0 G54 G17 G21 G90 G94 G49 M5, F0)
    /// and the G92 and tool length offsets cleared, as Grbl re-initialises its
    /// parser; the position and the stored coordinate data stay.
    pub fn reset_modal(&mut self) {
        self.state.modal = Modal::default();
        self.state.feed = 0.0;
        self.state.spindle = 0.0;
        self.state.s_given = false;
        self.state.g92 = [0; AXES];
        self.state.tlo = 0;
    }

    /// `[GC:...]` body for `$G` (without brackets).
    pub fn write_modal(&self, w: &mut dyn Sink) {
        let m = &self.state.modal;
        w.put(match m.motion {
            MotionMode::Rapid => b"GC:G0",
            MotionMode::Linear => b"GC:G1",
            MotionMode::ArcCw => b"GC:G2",
            MotionMode::ArcCcw => b"GC:G3",
            MotionMode::Cancel => b"GC:G80",
        });
        const WCS: [&[u8; 4]; 6] = [b" G54", b" G55", b" G56", b" G57", b" G58", b" G59"];
        w.put(*WCS.get(usize::from(m.wcs)).unwrap_or(&b" G59"));
        w.put(b" G17");
        w.put(if m.inches { b" G20" } else { b" G21" });
        w.put(if m.incremental { b" G91" } else { b" G90" });
        w.put(if m.inverse_time { b" G93" } else { b" G94" });
        // The tool length offset group only while G43.1 is in effect: the default
        // (G49) is left out like Grbl's other unprinted defaults, so that a sender
        // replaying these words after a reset never sends a G43.1 without its Z.
        if m.tool_length {
            w.put(b" G43.1");
        }
        w.put(if m.pen_down { b" M3" } else { b" M5" });
        w.put(b" M9 T0 F");
        let scale = if m.inches { MM_PER_INCH } else { 1.0 };
        put_int(w, round_i32(self.state.feed / scale));
        w.put(b" S");
        put_int(w, round_i32(self.state.spindle));
    }

    /// Interpret one cleaned line (no spaces, upper case, no comments) and put its
    /// state in place. `line_no` is used for the queued moves when the block has no N
    /// word.
    pub fn execute(&mut self, line: &[u8], s: &Settings, line_no: u32) -> Result<Outcome, Reject> {
        let mut out = Outcome::default();
        self.interpret(line, s, line_no, &mut out)?;
        self.commit(&out);
        Ok(out)
    }

    /// Read one cleaned line into `out`: its commands, its stop, whether it is a sync
    /// point, and `out.next`, the state the interpreter would have after it. Nothing
    /// changes here, so a refused block has no effect, and the caller decides whether
    /// to [`commit`](Interpreter::commit) (a sync point waits for the machine to rest
    /// and is read again then; `$N` lines are only checked).
    ///
    /// The parts of the reading (module `reading`) run in the order of Grbl's checks,
    /// each on what the earlier ones established.
    pub fn interpret(
        &self,
        line: &[u8],
        s: &Settings,
        line_no: u32,
        out: &mut Outcome,
    ) -> Result<(), Reject> {
        let mut b = WordBlock::default();
        b.parse_into(line)?;
        out.cmds.clear();
        out.stop = None;
        out.coords = None;
        out.sync = false;
        out.next = self.state;
        let g = reading::groups(&b)?;
        let v = reading::values(&mut b, &g, line_no, &mut out.next)?;
        let owner = reading::axis_owner(&g, &v, &mut out.next)?;
        let r = reading::Read { g, v, owner };
        let mut planned = Reach {
            in_range: true,
            in_travel: true,
        };
        reading::pen(&r, s, out, &mut planned)?;
        let target = reading::target(self, &r, &out.next);
        reading::non_modal(self, &mut b, &r, &target, s, out, &mut planned)?;
        reading::motion(&mut b, &r, &target, s, out, &mut planned)?;
        reading::complete(self, &b, &r, s, out, planned)
    }

    /// Put in place the state a block read by [`Interpreter::interpret`] leaves.
    pub fn commit(&mut self, out: &Outcome) {
        self.state = out.next;
        if let Some(c) = out.coords {
            self.coords.apply(c);
        }
    }
}
