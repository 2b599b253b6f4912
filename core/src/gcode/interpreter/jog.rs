//! Jogging: a [`Jog`] is one jog as a value, read from a `$J=` line's words (checked
//! against what a jog may name) or made by the keypad, and turned into one move,
//! leaving the modal state as it was. Apart from [`Interpreter::interpret`]
//! because a jog is not a block: it shares the parser and the unit conversions only.

use super::*;

/// Where a jog's axis values are measured from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JogFrame {
    /// Work coordinates (G90 with the active offsets).
    Work,
    /// From where the machine is (G91).
    Incremental,
    /// Machine coordinates (G53).
    Machine,
}

/// One jog as a value: what a `$J=` line names, or what the keypad asks for. Axis
/// values in nanometres (units already applied), `None` for an axis not named.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jog {
    pub axes: [Option<Nm>; AXES],
    pub frame: JogFrame,
    /// Feed, mm/min (> 0).
    pub feed_mm_min: f32,
}

impl Interpreter {
    /// Read the body of a `$J=` jog line (cleaned, without `$J=`): only G20/G21,
    /// G90/G91, G53, axis words, F and N are allowed; the modal units and distance
    /// mode apply where the line names none, and stay as they were.
    pub fn parse_jog(&self, line: &[u8]) -> Result<Jog, ErrorCode> {
        let mut b = WordBlock::default();
        b.parse_into(line)?;
        if !b.m.is_empty() {
            return Err(ErrorCode::InvalidJogCommand);
        }
        let mut inches = self.state.modal.inches;
        let mut incremental = self.state.modal.incremental;
        let mut machine = false;
        for &code in b.g.iter() {
            match code {
                200 => inches = true,
                210 => inches = false,
                900 => incremental = false,
                910 => incremental = true,
                530 => machine = true,
                _ => return Err(ErrorCode::InvalidJogCommand),
            }
        }
        let _ = b.take(b'N');
        let scale = if inches { MM_PER_INCH } else { 1.0 };
        let f = b.take(b'F').ok_or(ErrorCode::UndefinedFeedRate)?;
        if f.millionths() <= 0 {
            return Err(if f.is_negative() {
                ErrorCode::NegativeValue
            } else {
                ErrorCode::UndefinedFeedRate
            });
        }
        let mut axes = [None; AXES];
        for (slot, &letter) in axes.iter_mut().zip(b"XYZ") {
            *slot = b.take(letter).map(|v| value_to_nm(v, inches));
        }
        // Value words a jog does not use (S, T, I, P, ...): Grbl's unused-words error.
        if b.any_value() {
            return Err(ErrorCode::UnusedWords);
        }
        if axes.iter().all(Option::is_none) {
            return Err(ErrorCode::NoAxisWords);
        }
        let frame = if machine {
            JogFrame::Machine
        } else if incremental {
            JogFrame::Incremental
        } else {
            JogFrame::Work
        };
        Ok(Jog {
            axes,
            frame,
            feed_mm_min: f.to_f32() * scale,
        })
    }

    /// The move of a jog, from where the interpreter is; the interpreter continues
    /// from its end. A target outside travel with soft limits on is `error:15`.
    pub fn jog_move(&mut self, jog: &Jog, s: &Settings) -> Result<Move, ErrorCode> {
        // NaN and anything not above zero: no feed to jog at.
        if jog.feed_mm_min.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return Err(ErrorCode::UndefinedFeedRate);
        }
        let offset = self.work_offset();
        let mut target = self.state.pos;
        for (axis, v) in jog.axes.iter().enumerate() {
            if let (Some(v), Some(t), Some(&p), Some(&o)) = (
                *v,
                target.get_mut(axis),
                self.state.pos.get(axis),
                offset.get(axis),
            ) {
                *t = match jog.frame {
                    JogFrame::Machine => v,
                    JogFrame::Incremental => p.saturating_add(v),
                    JogFrame::Work => v.saturating_add(o),
                };
            }
        }
        let steps = to_steps(&target, s).ok_or(ErrorCode::InvalidTarget)?;
        if s.soft_limits() && !within_travel(&target, s) {
            return Err(ErrorCode::TravelExceeded);
        }
        self.state.pos = target;
        Ok(Move {
            target: steps,
            path: Path::Line,
            feed: Feed::MmPerMin(jog.feed_mm_min),
            line: 0,
        })
    }

    /// A `$J=` line's body read and made into its move ([`Interpreter::parse_jog`],
    /// then [`Interpreter::jog_move`]).
    pub fn jog(&mut self, line: &[u8], s: &Settings) -> Result<Move, ErrorCode> {
        let jog = self.parse_jog(line)?;
        self.jog_move(&jog, s)
    }
}
