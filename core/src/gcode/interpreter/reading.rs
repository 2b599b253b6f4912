//! Reading a block: the parts of [`Interpreter::interpret`], one function each, in the
//! order they run. Each part takes what the earlier ones established, says what it
//! guarantees, and
//! writes only into the block's [`Outcome`] (its commands and `next`, the state the
//! block would leave). Nothing here changes the interpreter itself: a part that
//! refuses the block leaves it as it was, and [`Interpreter::commit`] puts `next` in
//! place only once every part has passed.
//!
//! The order of the checks is the order of the error codes a sender sees when a line
//! has several faults, so it follows the parts and not convenience.

use super::*;

/// Part 1's result: the modal groups the block names ([`NONE`] or the code's index
/// in its group's table).
pub(super) struct Groups {
    pub motion: Option<MotionMode>,
    pub non_modal: Option<NonModal>,
    pub units: u8,
    pub distance: u8,
    pub feed_mode: u8,
    pub wcs: u8,
    pub tool_length: u8,
    pub stop: Option<Stop>,
    pub pen: u8,
    pub tool_change: bool,
}

/// Part 1, grouping. Guarantees: every G and M code is known and each modal group is
/// named at most once (M1 not beside M0/M2, one stop per block).
pub(super) fn groups(b: &WordBlock) -> Result<Groups, Reject> {
    let mut groups = [NONE; GROUPS];
    group_codes(&b.g, &G_CODES, &mut groups, true)?;
    group_codes(&b.m, &M_CODES, &mut groups, false)?;
    let [motion, non_modal, units, distance, feed_mode, wcs, _, _, _, tool_length, _, stop, m1, pen, _, tool_change] =
        groups;
    // M1 (optional stop) is ignored, as Grbl does without a stop switch, but it shares
    // the stop group.
    if m1 != NONE && stop != NONE {
        return Err(ErrorCode::ModalGroupViolation.into());
    }
    let stop = match stop {
        0 => Some(Stop::Pause),
        1 => Some(Stop::End),
        _ => None,
    };
    let tool_change = tool_change != NONE;
    if tool_change && stop.is_some() {
        // One stop per block: a pen change beside M0/M2 is ambiguous.
        return Err(ErrorCode::ModalGroupViolation.into());
    }
    Ok(Groups {
        motion: MOTION_MODES.get(usize::from(motion)).copied(),
        non_modal: NON_MODAL.get(usize::from(non_modal)).copied(),
        units,
        distance,
        feed_mode,
        wcs,
        tool_length,
        stop,
        pen,
        tool_change,
    })
}

/// Part 2's result: the block's value words.
pub(super) struct Values {
    /// The line number the block's moves carry (its N word, or the caller's count).
    pub line_tag: u32,
    /// The block's feed: mm/min, or under G93 its inverse time (never modal).
    pub feed: f32,
    /// A new S value, if the block has one.
    pub spindle: Option<f32>,
    /// The axis words in nanometres, and the mask of the axes named.
    pub words: NmPos,
    pub axes: u8,
}

impl Values {
    pub fn has_axis(&self) -> bool {
        self.axes != 0
    }
}

/// Part 2, value words and modes. Guarantees: no negative F, N, P, S, T or L, N and T
/// in range, the feed in mm/min (or per block in inverse time); the new units,
/// distance, coordinate system and feed modes, the S value and the T word are in
/// `next`.
pub(super) fn values(
    b: &mut WordBlock,
    g: &Groups,
    line_no: u32,
    next: &mut BlockState,
) -> Result<Values, Reject> {
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
    if let Some(t) = tool {
        next.tool_next = t.round() as u8;
    }
    let spindle = b.take(b'S').map(Value::to_f32);
    if let Some(sp) = spindle {
        next.spindle = sp;
        next.s_given = true;
    }

    let modal = &mut next.modal;
    if g.units != NONE {
        modal.inches = g.units != 0;
    }
    if g.distance != NONE {
        modal.incremental = g.distance != 0;
    }
    if g.wcs != NONE {
        modal.wcs = g.wcs;
    }
    let scale = if modal.inches { MM_PER_INCH } else { 1.0 };

    let mut feed = next.feed;
    if g.feed_mode != NONE {
        let inverse = g.feed_mode != 0;
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

    let mut words: NmPos = [0; AXES];
    let mut axes = 0u8;
    for (k, (w, &letter)) in words.iter_mut().zip(b"XYZ").enumerate() {
        if let Some(v) = b.take(letter) {
            *w = value_to_nm(v, modal.inches);
            axes |= 1 << k;
        }
    }
    Ok(Values {
        line_tag,
        feed,
        spindle,
        words,
        axes,
    })
}

/// Part 3's result: which command uses the axis words.
pub(super) struct AxisOwner {
    /// A motion runs (named in the block, or implied by axis words).
    pub motion: bool,
    /// A non-modal command (G10, G28, G30, G92) or G43.1 takes them.
    pub non_modal: bool,
    /// G53: this motion's axis words are machine coordinates.
    pub machine_coords: bool,
}

/// What parts 1-3 read from the block, for the parts that act on it.
pub(super) struct Read {
    pub g: Groups,
    pub v: Values,
    pub owner: AxisOwner,
}

/// Part 3, the owner of the axis words. Guarantees: exactly one command uses them (or
/// none is named), a feed motion has a feed; the motion mode and the tool length offset
/// are in `next`.
pub(super) fn axis_owner(
    g: &Groups,
    v: &Values,
    next: &mut BlockState,
) -> Result<AxisOwner, Reject> {
    // Which command uses the axis words: a non-modal one, G43.1 (its Z word is the
    // offset, and Z is the only axis it may name: error 37), or else motion.
    let dynamic_tlo = g.tool_length == 1;
    if dynamic_tlo && v.axes & !(1 << 2) != 0 {
        return Err(ErrorCode::G43DynamicAxisError.into());
    }
    let non_modal_axes = matches!(
        g.non_modal,
        Some(NonModal::SetCoord | NonModal::Home28 | NonModal::Home30 | NonModal::SetG92)
    );
    let nm_uses_axes = non_modal_axes || dynamic_tlo;
    // A motion mode beside G43.1 only conflicts if there are axis words to fight over:
    // a bare `G0 ... G43.1` (bCNC replaying the `$G` words) just sets modes.
    let motion_conflict =
        g.motion.is_some_and(|m| m != MotionMode::Cancel) && (non_modal_axes || v.has_axis());
    if (nm_uses_axes && motion_conflict) || (non_modal_axes && dynamic_tlo) {
        return Err(ErrorCode::AxisCommandConflict.into());
    }
    let modal = &mut next.modal;
    if let Some(m) = g.motion {
        modal.motion = m;
    }
    // G43.1 Z sets the offset (a bare G43.1 keeps the one in effect); G49 clears it.
    if g.tool_length != NONE {
        modal.tool_length = dynamic_tlo;
        next.tlo = match (dynamic_tlo, v.axes & 1 << 2 != 0) {
            (true, true) => v.words[2],
            (true, false) => next.tlo,
            (false, _) => 0,
        };
    }
    // Motion runs if it was named in the block, or implicitly for axis words.
    let motion = !nm_uses_axes && (g.motion.is_some() || v.has_axis());
    if motion && modal.motion == MotionMode::Cancel && v.has_axis() {
        return Err(ErrorCode::AxisWordsExist.into());
    }
    let machine_coords = g.non_modal == Some(NonModal::Absolute);
    if machine_coords && !(motion && matches!(modal.motion, MotionMode::Rapid | MotionMode::Linear))
    {
        return Err(ErrorCode::G53InvalidMotionMode.into());
    }
    let feed_motion = motion
        && matches!(
            modal.motion,
            MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
        );
    if feed_motion && v.feed <= 0.0 {
        return Err(ErrorCode::UndefinedFeedRate.into());
    }
    Ok(AxisOwner {
        motion,
        non_modal: nm_uses_axes,
        machine_coords,
    })
}

/// Part 4, the pen, which runs before motion: M3/M4/M5, a new S while the pen is down
/// (a new height, in order with the strokes), and M6's way to the pen-change place
/// and back. Guarantees: `out` holds the pen's commands in order, `next` its level and
/// the position after them, `out.stop` the block's stop (M6 makes one).
pub(super) fn pen(
    r: &Read,
    s: &Settings,
    out: &mut Outcome,
    planned: &mut Reach,
) -> Result<(), Reject> {
    let (g, v) = (&r.g, &r.v);
    out.stop = g.stop;
    let (cmds, next) = (&mut out.cmds, &mut out.next);
    let line = v.line_tag;
    if g.pen != NONE {
        next.modal.pen_down = g.pen != 0;
    }
    if g.pen != NONE || (next.modal.pen_down && v.spindle.is_some()) {
        let level = match (next.modal.pen_down, next.s_given) {
            (false, _) => 0,
            (true, true) => s.pen_level_of(next.spindle),
            (true, false) => PEN_FULL,
        };
        if level != next.modal.pen_level {
            pen_move(cmds, &mut next.pos, level, s, line, planned)?;
        }
        next.modal.pen_level = level;
    }
    if !g.tool_change {
        return Ok(());
    }
    // M6: lift, to the pen-change place ($216-$218), wait, back, drop again.
    let (back, level) = (next.pos, next.modal.pen_level);
    if level != 0 {
        pen_move(cmds, &mut next.pos, 0, s, line, planned)?;
    }
    let place = s.pen_change_xy();
    if let Some(xy) = place {
        next.pos[0] = mm_to_nm(xy[0]);
        next.pos[1] = mm_to_nm(xy[1]);
        push_rapid(cmds, &next.pos, s, line, planned)?;
    }
    let split = cmds.len() as u8;
    if place.is_some() {
        next.pos = [back[0], back[1], next.pos[2]];
        push_rapid(cmds, &next.pos, s, line, planned)?;
    }
    if level != 0 {
        pen_move(cmds, &mut next.pos, level, s, line, planned)?;
    }
    out.stop = Some(Stop::PenChange {
        tool: next.tool_next,
        split,
    });
    Ok(())
}

/// Part 5, the target, in machine nanometres. Guarantees: it is where the axis words
/// lead from `pos` in the block's modes. The offsets are `before`'s, the ones in effect
/// when the block was read: a G49 or G43.1 in the same block applies from the next one
/// on (as in Grbl).
pub(super) fn target(before: &Interpreter, r: &Read, next: &BlockState) -> NmPos {
    let (v, owner) = (&r.v, &r.owner);
    let offset = before.offset_of(next.modal.wcs);
    let pos = &next.pos;
    let mut target = *pos;
    for (k, ((t, &w), (&p, &o))) in target
        .iter_mut()
        .zip(v.words.iter())
        .zip(pos.iter().zip(offset.iter()))
        .enumerate()
    {
        if v.axes >> k & 1 != 0 {
            *t = if owner.machine_coords {
                w
            } else if next.modal.incremental {
                p.saturating_add(w)
            } else {
                w.saturating_add(o)
            };
        }
    }
    target
}

/// Part 6, the non-modal commands (G4, G10, G28/G30, G28.1/G30.1, G92/G92.1).
/// Guarantees: their commands follow the pen's in `out`, a change to the stored
/// coordinates is in `out.coords` and to the offsets and position in `next` only, every target reached is recorded in `planned`.
#[inline(never)]
pub(super) fn non_modal(
    before: &Interpreter,
    b: &mut WordBlock,
    r: &Read,
    target: &NmPos,
    s: &Settings,
    out: &mut Outcome,
    planned: &mut Reach,
) -> Result<(), Reject> {
    let (g, v) = (&r.g, &r.v);
    let (cmds, next) = (&mut out.cmds, &mut out.next);
    let line = v.line_tag;
    match g.non_modal {
        Some(NonModal::Dwell) => {
            let p = b.take(b'P').ok_or(ErrorCode::ValueWordMissing)?;
            push(cmds, Command::Dwell { ms: value_to_ms(p) })?;
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
            if !v.has_axis() {
                return Err(ErrorCode::NoAxisWords.into());
            }
            let idx = if p == 0 {
                usize::from(next.modal.wcs)
            } else {
                p as usize - 1
            };
            // L20: the offset that makes the current position read as the words, past
            // G92 and the tool length offset.
            let from = match l {
                2 => None,
                20 => Some((&next.g92, next.tlo)),
                _ => return Err(ErrorCode::UnsupportedCommand.into()),
            };
            if let Some(&(mut offset)) = before.coords.wcs.get(idx) {
                set_axes(&mut offset, v.axes, &v.words, &next.pos, from);
                out.coords = Some(CoordChange::Wcs {
                    index: idx as u8,
                    offset,
                });
            }
        }
        Some(nm @ (NonModal::Home28 | NonModal::Home30)) => {
            let stored = if nm == NonModal::Home28 {
                before.coords.g28
            } else {
                before.coords.g30
            };
            if v.has_axis() {
                push_rapid(cmds, target, s, line, planned)?;
            }
            push_rapid(cmds, &stored, s, line, planned)?;
            next.pos = stored;
        }
        Some(NonModal::Set28) => out.coords = Some(CoordChange::G28(next.pos)),
        Some(NonModal::Set30) => out.coords = Some(CoordChange::G30(next.pos)),
        Some(NonModal::SetG92) => {
            if !v.has_axis() {
                return Err(ErrorCode::NoAxisWords.into());
            }
            let w = before
                .coords
                .wcs
                .get(usize::from(next.modal.wcs))
                .unwrap_or(&[0; AXES]);
            set_axes(
                &mut next.g92,
                v.axes,
                &v.words,
                &next.pos,
                Some((w, next.tlo)),
            );
        }
        Some(NonModal::ResetG92) => next.g92 = [0; AXES],
        Some(NonModal::Absolute) | None => {}
    }
    Ok(())
}

/// Part 7, motion: a line or an arc to `target` at the block's feed. Guarantees: the
/// move follows the other commands in `out`, `next.pos` is its end, and every point
/// it reaches (an arc's extent too) is recorded in `planned`.
pub(super) fn motion(
    b: &mut WordBlock,
    r: &Read,
    target: &NmPos,
    s: &Settings,
    out: &mut Outcome,
    planned: &mut Reach,
) -> Result<(), Reject> {
    let (v, owner) = (&r.v, &r.owner);
    let (cmds, next) = (&mut out.cmds, &mut out.next);
    let mode = next.modal.motion;
    let arc = matches!(mode, MotionMode::ArcCw | MotionMode::ArcCcw);
    if !owner.motion || !(arc || (v.has_axis() && mode != MotionMode::Cancel)) {
        return Ok(());
    }
    let pos = next.pos;
    let ccw = mode == MotionMode::ArcCcw;
    // The way there: one path, or an arc's two halves.
    let mut half: Option<(NmPos, Path)> = None;
    let (len, path) = if arc {
        if !v.has_axis() {
            return Err(ErrorCode::NoAxisWords.into());
        }
        if v.axes & 3 == 0 {
            return Err(ErrorCode::NoAxisWordsInPlane.into());
        }
        let g = arc_geometry(b, &pos, target, ccw, next.modal.inches)?;
        arc_extremes(&g, &pos, target, ccw, planned, s);
        let rise = mm_between(pos[2], target[2]);
        let arc_len = fmath::hypot(g.radius * g.sweep, rise);
        // An arc's path ends at the first pass of its target in step space (a whole
        // turn when the target is the start), so ends on one XY step or close to it
        // are ambiguous:
        // - an arc of at most half a turn there is a sliver (CAM's arcs of a few
        //   micrometres): its nearest grid points are its ends, so it goes straight
        //   (Z only, if the ends are one step);
        // - a full circle, or a nearly closed one, goes as two halves, to the point
        //   opposite its start and on, each with ends far apart.
        let near = |d: u32| match (to_steps(&pos, s), to_steps(target, s)) {
            (Some(a), Some(b)) => a[0].abs_diff(b[0]) <= d && a[1].abs_diff(b[1]) <= d,
            _ => false,
        };
        if g.sweep <= core::f32::consts::PI && near(1) {
            (arc_len, line_path(&pos, target, s))
        } else if g.sweep > core::f32::consts::PI && near(2) {
            let mid_angle = g.start_angle + if ccw { 0.5 } else { -0.5 } * g.sweep;
            let (sin, cos) = fmath::sin_cos(mid_angle);
            let mid = [
                g.center[0].saturating_add(mm_to_nm(g.radius * cos)),
                g.center[1].saturating_add(mm_to_nm(g.radius * sin)),
                pos[2].saturating_add((target[2] - pos[2]) / 2),
            ];
            half = Some((mid, arc_path(&g, &pos, ccw, s)));
            (arc_len, arc_path(&g, &mid, ccw, s))
        } else {
            (arc_len, arc_path(&g, &pos, ccw, s))
        }
    } else {
        planned.add(target, s);
        (path_length(&pos, target), line_path(&pos, target, s))
    };
    let feed = if mode == MotionMode::Rapid {
        Feed::Rapid
    } else if next.modal.inverse_time {
        Feed::MmPerMin(len * v.feed)
    } else {
        Feed::MmPerMin(v.feed)
    };
    let mut from = pos;
    for (to, path) in half.into_iter().chain(core::iter::once((*target, path))) {
        // Out of range is refused at completeness (`planned`), before anything
        // commits.
        let steps = to_steps(&to, s);
        let curved = !matches!(path, Path::Line | Path::LineFine { .. });
        if curved || steps != to_steps(&from, s) {
            push(
                cmds,
                Command::Move(Move {
                    target: steps.unwrap_or([0; AXES]),
                    path,
                    feed,
                    line: v.line_tag,
                }),
            )?;
        }
        from = to;
    }
    next.pos = *target;
    Ok(())
}

/// Part 8, completeness and program end. Guarantees: every word was used, every target
/// is in the step range and (with soft limits) in travel; M2/M30 lifts the pen and
/// resets the modes in `next`; `out` says whether the block is a sync point.
pub(super) fn complete(
    before: &Interpreter,
    b: &WordBlock,
    r: &Read,
    s: &Settings,
    out: &mut Outcome,
    mut planned: Reach,
) -> Result<(), Reject> {
    let (g, v, owner) = (&r.g, &r.v, &r.owner);
    let stop = out.stop;
    if v.has_axis() && !owner.motion && !owner.non_modal {
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
    let next = &mut out.next;
    if stop == Some(Stop::End) {
        if next.modal.pen_level != 0 {
            // Checked already: the lift stays where the block's moves went.
            pen_move(&mut out.cmds, &mut next.pos, 0, s, v.line_tag, &mut planned)?;
        }
        next.modal = Modal {
            inches: next.modal.inches,
            tool_length: next.modal.tool_length,
            motion: MotionMode::Linear,
            ..Modal::default()
        };
    }
    // The feed stays for the next block, except an inverse-time one.
    next.feed = if next.modal.inverse_time { 0.0 } else { v.feed };
    out.sync = stop.is_some()
        || next.modal.wcs != before.state.modal.wcs
        || g.tool_length != NONE
        || matches!(
            g.non_modal,
            Some(
                NonModal::Dwell
                    | NonModal::SetCoord
                    | NonModal::Set28
                    | NonModal::Set30
                    | NonModal::SetG92
                    | NonModal::ResetG92
            )
        );
    Ok(())
}
