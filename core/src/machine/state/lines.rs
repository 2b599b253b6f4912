//! The machine's side of a G-code or jog line: interpreting it against the state (locks,
//! sync points, back-pressure on planner room), queueing its commands and running its
//! stop (M0, M2, M6); `$N` checks a line without running it. Apart from `state` because
//! it is the one path from text into motion, read on its own.

use super::*;

impl Machine {
    /// Execute one cleaned G-code line. `None` means "not now", and the caller keeps
    /// the line and calls again with it (back-pressure):
    /// - the block's commands need more free planner entries than there are: the
    ///   interpreter has taken the block, and its commands wait here
    ///   (`Machine::waiting`) and go to the planner as room appears; the line is
    ///   not interpreted again;
    /// - it is a sync point (G4, M0, M2, G10, G92, ...) and motion before it has not
    ///   finished: nothing has changed (its offsets must change only at rest), and it
    ///   is interpreted again once the machine is at rest.
    pub fn execute<M: MotionControl>(
        &mut self,
        line: &[u8],
        line_no: u32,
        m: &mut M,
        now_ms: u32,
    ) -> Option<Result<Taken, ErrorCode>> {
        // G-code is locked out in alarm, homing, sleep and while jogging (Grbl's
        // error 9).
        if self.locked || self.homing.is_some() || self.jogging || self.sleeping {
            self.forget_line();
            return Some(Err(ErrorCode::SystemLocked));
        }
        if !self.can_accept() {
            return None;
        }
        if !self.waiting {
            if self.sync_waiting && !m.is_idle() {
                return None;
            }
            match self
                .interpreter
                .interpret(line, &self.settings, line_no, &mut self.outcome)
            {
                // A sync point runs only at rest: read again once the machine is (check
                // mode queues nothing, so it need not wait).
                Ok(()) if self.outcome.sync && !(self.check_mode || m.is_idle()) => {
                    self.sync_waiting = true;
                    return None;
                }
                Ok(()) => {
                    self.interpreter.commit(&self.outcome);
                    self.sync_waiting = false;
                    // A curve's line is interpreted in this call and planned in the
                    // next (its commands wait as for planner room): each half is
                    // about half a millisecond of the shell's lock on the board, and
                    // a `?` that comes meanwhile is answered in between (issue 20).
                    if !self.check_mode && self.outcome.has_curve() {
                        self.waiting = true;
                        self.yielded = true;
                        return None;
                    }
                }
                Err(Reject::Error(e)) => return Some(Err(e)),
                Err(Reject::SoftLimit) => {
                    // Grbl: the line is answered ok, motion stops, alarm 2 (no reset
                    // needed).
                    self.raise(Alarm::SoftLimit, m);
                    return Some(Ok(Taken::Now));
                }
            }
        }
        self.waiting = !self.check_mode && self.outcome.cmds.len() > m.free();
        if self.waiting {
            return None;
        }
        let stop = self.outcome.stop;
        if stop == Some(Stop::End) {
            self.event(Event::Msg("Pgm End"));
        }
        if self.outcome.coords.is_some() {
            self.coords_dirty = true;
        }
        if self.check_mode {
            // Dwells and pauses are skipped in check mode, as in Grbl.
            return Some(Ok(Taken::Now));
        }
        let mut next = 0;
        let upto = match stop {
            Some(Stop::PenChange { split, .. }) => usize::from(split),
            _ => usize::MAX,
        };
        while let Some(&cmd) = self.outcome.cmds.get(next).filter(|_| next < upto) {
            next += 1;
            if m.push(cmd).is_err() {
                // free() promised room; if a planner disagrees, stop rather than
                // lose a move silently.
                self.raise(Alarm::AbortCycle, m);
                return Some(Ok(Taken::Now));
            }
            if let Command::Move(_) = cmd {
                self.count_move(now_ms);
            }
        }
        match stop {
            Some(Stop::Pause) => {
                // At rest (M0 is a sync point): hold until cycle start; the lines after
                // it are planned meanwhile and wait in the held queue.
                self.paused = true;
                m.hold();
            }
            Some(Stop::End) => self.job.ending = self.job.running,
            Some(Stop::PenChange { tool, split }) => {
                self.pen_change = Some(PenChange {
                    tool,
                    split,
                    waiting: false,
                });
                self.poll_pen_change(m);
            }
            None => {}
        }
        Some(Ok(if self.outcome.has_dwell() {
            Taken::WhenIdle
        } else {
            Taken::Now
        }))
    }

    /// The last [`Machine::execute`] returned `None` only to plan the line's motion in
    /// the next call (not for lack of room): call again at once, with the same line.
    pub fn take_yielded(&mut self) -> bool {
        core::mem::take(&mut self.yielded)
    }

    /// Check a line (for `$N`) without running it or changing any state.
    pub fn validate(&mut self, line: &[u8]) -> Result<(), ErrorCode> {
        // Read, never committed.
        let mut out = Outcome::default();
        match self
            .interpreter
            .interpret(line, &self.settings, 0, &mut out)
        {
            Err(Reject::Error(e)) => Err(e),
            _ => Ok(()),
        }
    }

    /// `$J=...`: queue a jog (only when idle or already jogging).
    /// Anything else, alarm included, is Grbl's error 8 (a `$` command outside Idle).
    pub fn jog_line<M: MotionControl>(&mut self, body: &[u8], m: &mut M) -> Result<(), ErrorCode> {
        self.may_jog(m)?;
        let jog = self.interpreter.parse_jog(body)?;
        self.jog(&jog, m)
    }

    /// A jog (from `$J=` or the keypad): queued when the machine is idle or jogging.
    pub fn jog<M: MotionControl>(&mut self, jog: &Jog, m: &mut M) -> Result<(), ErrorCode> {
        self.may_jog(m)?;
        let mv: Move = self.interpreter.jog_move(jog, &self.settings)?;
        if m.push(Command::Move(mv)).is_ok() {
            self.jogging = true;
        }
        Ok(())
    }

    /// Whether a jog may be queued now: idle or jogging, not in check mode, room in
    /// the queue.
    fn may_jog<M: MotionControl>(&self, m: &M) -> Result<(), ErrorCode> {
        let st = self.state(m);
        if !(matches!(st, RunState::Idle | RunState::Jog)) || self.check_mode {
            return Err(ErrorCode::IdleError);
        }
        if m.free() == 0 {
            return Err(ErrorCode::Overflow);
        }
        Ok(())
    }
}
