//! What a block's reading queues and how targets become paths: the commands of one block
//! (rapid moves, pen moves, straight paths with their fine end points) and the offset
//! arithmetic of G10 / G92. Shared by the parts of [`Interpreter::interpret`] and the
//! jog; each function pushes to a block's commands or computes, and none changes the
//! interpreter.

use super::*;

/// A straight move's path: XY lines carry their exact end points (1/256 step) so the
/// steps follow the programmed line, not the line between rounded ends; moves that
/// change Z (or lie outside the fine range) stay plain lines.
pub(super) fn line_path(pos: &NmPos, target: &NmPos, s: &Settings) -> Path {
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

pub(super) fn push(cmds: &mut BlockCommands, c: Command) -> Result<(), ErrorCode> {
    cmds.push(c).map_err(|_| ErrorCode::Overflow)
}

/// A rapid straight move to `p` (checked as planned; out of range is refused before
/// anything commits).
pub(super) fn push_rapid(
    cmds: &mut BlockCommands,
    p: &NmPos,
    s: &Settings,
    line: u32,
    planned: &mut Reach,
) -> Result<(), ErrorCode> {
    planned.add(p, s);
    push(
        cmds,
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
pub(super) fn pen_move(
    cmds: &mut BlockCommands,
    pos: &mut NmPos,
    level: u16,
    s: &Settings,
    line: u32,
    planned: &mut Reach,
) -> Result<(), ErrorCode> {
    match s.pen_mode() {
        PenMode::Servo => push(cmds, Command::Pen { level }),
        PenMode::ZAxis => {
            pos[2] = mm_to_nm(s.pen_z_at(level));
            push_rapid(cmds, pos, s, line, planned)
        }
    }
}

/// G10 / G92: each named axis of `dst` becomes its word (`from` None), or the offset
/// that makes the current position read as the word past the other offsets `from`
/// (an offset and the tool length offset on Z): `pos - other - word`.
pub(super) fn set_axes(
    dst: &mut NmPos,
    axes: u8,
    words: &NmPos,
    pos: &NmPos,
    from: Option<(&NmPos, Nm)>,
) {
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
pub(super) fn path_length(a: &NmPos, b: &NmPos) -> f32 {
    let mut sum = 0.0;
    for (x, y) in a.iter().zip(b.iter()) {
        let d = mm_between(*x, *y);
        sum += d * d;
    }
    fmath::sqrt(sum)
}
