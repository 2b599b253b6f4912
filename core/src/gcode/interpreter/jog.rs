//! `$J=` jogging: a jog line's words checked against what a jog may name and turned into
//! one move, leaving the modal state as it was. Apart from [`Interpreter::execute_into`]
//! because a jog is not a block: it shares the parser and the unit conversions only.

use super::*;

impl Interpreter {
    /// Interpret the body of a `$J=` jog line (cleaned, without `$J=`): only G20/G21,
    /// G90/G91, G53, axis words, F and N are allowed; modal state is left unchanged.
    /// A target outside travel with soft limits on is `error:15`.
    pub fn jog(&mut self, line: &[u8], s: &Settings) -> Result<Move, ErrorCode> {
        let mut b = WordBlock::default();
        b.parse_into(line)?;
        if !b.m.is_empty() {
            return Err(ErrorCode::InvalidJogCommand);
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
            return Err(ErrorCode::UnusedWords);
        }
        if !any {
            return Err(ErrorCode::NoAxisWords);
        }
        let steps = to_steps(&target, s).ok_or(ErrorCode::InvalidTarget)?;
        if s.soft_limits() && !within_travel(&target, s) {
            return Err(ErrorCode::TravelExceeded);
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
