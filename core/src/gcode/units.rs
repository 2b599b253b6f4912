//! Lengths, exactly: the interpreter keeps every position and offset in whole
//! nanometres (`i64`), so that G90 and G91 programs in mm or inches end exactly where
//! decimal arithmetic says, whatever the number of moves (a millionth of a mm is a
//! nanometre; a hundred-thousandth of an inch is 254 nm). Here: G-code numbers to
//! nanometres, nanometres to steps (rounded half away from zero from the exact product
//! with the steps/mm setting's exact binary value, so rounding never accumulates),
//! steps back to nanometres after a stop, the step range a target must stay in, and
//! the travel limits that soft limits check. `f32` only appears for what never
//! accumulates: a block's geometry (lengths, arcs) and the settings' own values.

use super::parser::{Value, ONE};
use crate::decimal::round_div;
use crate::motion::{StepPos, AXES};
use crate::settings::Settings;

/// A length in nanometres.
pub type Nm = i64;
/// A point in machine nanometres.
pub type NmPos = [Nm; AXES];

/// Nanometres per mm.
pub const NM_PER_MM: Nm = 1_000_000;

/// Largest step coordinate accepted (2^30): leaves headroom for the planner's
/// differences and sums in `i32`.
pub const MAX_STEPS: u32 = 1 << 30;

/// A G-code length word in nanometres: millionths of a mm are nanometres; inches are
/// exact to five decimals (254 nm), the sixth rounds.
pub fn value_to_nm(v: Value, inches: bool) -> Nm {
    let m = v.millionths();
    if inches {
        // 25.4 nm per millionth of an inch.
        let nm = round_div(i128::from(m) * 127, 5);
        Nm::try_from(nm).unwrap_or(if m < 0 { Nm::MIN } else { Nm::MAX })
    } else {
        m
    }
}

/// A setting in mm (pen heights, travel) in nanometres.
pub fn mm_to_nm(mm: f32) -> Nm {
    // f32 to i64 saturates; the settings' ranges are far inside it.
    crate::fmath::round(mm * NM_PER_MM as f32) as Nm
}

/// Nanometres as mm, for geometry and reports (not exact: never summed).
pub fn nm_to_mm(nm: Nm) -> f32 {
    nm as f32 / NM_PER_MM as f32
}

/// The distance from `a` to `b` in mm (saturating), for geometry.
pub fn mm_between(a: Nm, b: Nm) -> f32 {
    nm_to_mm(b.saturating_sub(a))
}

/// A distance in mm to steps for what never accumulates (homing's search and
/// pull-off distances), rounded half away from zero (saturating).
pub fn mm_to_steps(mm: f32, steps_per_mm: f32) -> i32 {
    crate::decimal::round_i32(mm * steps_per_mm)
}

/// A step position in mm, for reports.
pub fn to_mm(steps: &StepPos, s: &Settings) -> [f32; AXES] {
    let mut out = [0.0; AXES];
    for (axis, (o, &v)) in out.iter_mut().zip(steps.iter()).enumerate() {
        *o = v as f32 / s.steps_per_mm(axis);
    }
    out
}

/// 10^6 = 15,625 * 2^6.
const FIVES: u32 = 15_625;

/// Nanometres to steps: the exact product with `steps_per_mm`, rounded half away from
/// zero. None if the result lies outside +-[`MAX_STEPS`] (or the setting is out of its
/// range).
pub fn nm_to_steps(nm: Nm, steps_per_mm: f32) -> Option<i32> {
    scaled_steps(nm, steps_per_mm, false)
}

/// [`nm_to_steps`] in 1/256 step (the exact line ends of [`crate::motion::Path::LineFine`]),
/// within the same +-2^30 range.
pub fn nm_to_fine_steps(nm: Nm, steps_per_mm: f32) -> Option<i32> {
    scaled_steps(nm, steps_per_mm, true)
}

/// `steps_per_mm * 2^40`, exactly, from the `f32`'s bits (a 24-bit integer `m` times
/// 2^(exponent - 150)); None unless it lies in the settings' range (0.001 ..= 10,000):
/// then the exponent is at least 116, so the result is a whole number below 2^54.
fn scale_2_40(steps_per_mm: f32) -> Option<u64> {
    let bits = steps_per_mm.to_bits();
    // Positive floats order as their bits; NaN and negative values fall outside.
    if !(0.0009f32.to_bits()..=10_000f32.to_bits()).contains(&bits) {
        return None;
    }
    let m = u64::from((bits & 0x7F_FFFF) | 0x80_0000); // normal: not below 2^-126
    Some(m << ((bits >> 23) - 110))
}

/// `nm * steps_per_mm / 10^6` in whole steps, or in 1/256 step if `fine`, rounded half
/// away from zero.
fn scaled_steps(nm: Nm, steps_per_mm: f32, fine: bool) -> Option<i32> {
    // n = |nm| * spm * 2^40 (below 2^117), so steps = round(n / (2^46 * 15,625)), as
    // floor((floor(n / 2^45) + 15,625) / 31,250); fine steps shift by 8 less. Beyond
    // 2^64 after the shift, the quotient is far beyond MAX_STEPS.
    let n = u128::from(nm.unsigned_abs()) * u128::from(scale_2_40(steps_per_mm)?);
    let n = u64::try_from(n >> 37).ok()?;
    let n = if fine { n } else { n >> 8 };
    let steps = steps_quotient(n + u64::from(FIVES), 2 * FIVES)? as i32;
    Some(if nm < 0 { -steps } else { steps })
}

/// floor(num / d) for `d` below 2^16, if below [`MAX_STEPS`]: then `num` is below
/// 2^46 and two 32-bit hardware divides do it (a general long division of a wide
/// integer was a fifth of a G-code line's CPU time on the M3).
fn steps_quotient(num: u64, d: u32) -> Option<u32> {
    if num >= u64::from(d) << 30 {
        return None;
    }
    let high = (num >> 16) as u32; // below 2^30
    let low = ((high % d) << 16) | (num as u32 & 0xFFFF); // below 2^32: high % d < 2^16
    Some(((high / d) << 16) | (low / d))
}

/// Steps back to nanometres (after a stop, a jog or a keypad move, the step position
/// is the truth). Rounded to the nearest nanometre: converting back gives the same
/// steps (a step is at least 100 nm, $100-$102 being at most 10,000 steps/mm).
pub fn steps_to_nm(steps: i32, steps_per_mm: f32) -> Nm {
    let Some(scale) = scale_2_40(steps_per_mm) else {
        return 0;
    };
    // |steps| * 10^6 * 2^40 / scale = |steps| * 15,625 * 2^(46 - t) / m with scale =
    // m * 2^t (m odd, below 2^24; t >= 6), the power of two on the side where it is
    // positive (beyond 46, the divisor stays below 2^14).
    let t = scale.trailing_zeros();
    let m = (scale >> t) as u32;
    let num = u128::from(steps.unsigned_abs()) * u128::from(FIVES);
    let (num, den) = if t <= 46 {
        (num << (46 - t), m)
    } else {
        (num, m << (t - 46))
    };
    let nm = round_div(num as i128, den) as Nm; // below 2^31 * 10^9
    if steps < 0 {
        -nm
    } else {
        nm
    }
}

/// Machine nanometres to a step position; None if any axis is out of range.
pub fn to_steps(p: &NmPos, s: &Settings) -> Option<StepPos> {
    let mut out = [0; AXES];
    for (axis, (o, &v)) in out.iter_mut().zip(p.iter()).enumerate() {
        *o = nm_to_steps(v, s.steps_per_mm(axis))?;
    }
    Some(out)
}

/// A step position in machine nanometres.
pub fn to_nm(steps: &StepPos, s: &Settings) -> NmPos {
    let mut out = [0; AXES];
    for (axis, (o, &v)) in out.iter_mut().zip(steps.iter()).enumerate() {
        *o = steps_to_nm(v, s.steps_per_mm(axis));
    }
    out
}

/// Allowed machine range of `axis` with soft limits, in nanometres, or `None` if
/// unchecked. Axes homed toward - live in [0, travel], axes homed toward + in
/// [-travel, 0] (Grbl's convention); axes without a switch ($214) are not checked.
pub fn travel_range(axis: usize, s: &Settings) -> Option<(Nm, Nm)> {
    let bit = 1u8 << axis;
    if s.switch_mask() & bit == 0 {
        return None;
    }
    let t = mm_to_nm(s.max_travel(axis));
    Some(if s.homing_dir_mask() & bit != 0 {
        (0, t)
    } else {
        (-t, 0)
    })
}

/// True if `p` (machine nanometres) lies within travel on every checked axis, give or
/// take 100 nm (the travel settings have three decimals).
pub fn within_travel(p: &NmPos, s: &Settings) -> bool {
    const SLACK: Nm = 100;
    p.iter().enumerate().all(|(axis, &v)| {
        travel_range(axis, s).is_none_or(|(lo, hi)| v >= lo - SLACK && v <= hi + SLACK)
    })
}

/// Every point a block moves to, checked as it is planned; the verdicts are reported
/// after the block's word checks, in Grbl's order.
pub(super) struct Reach {
    /// All points convert to steps within range ([`to_steps`]).
    pub(super) in_range: bool,
    /// All points lie within travel ([`within_travel`]).
    pub(super) in_travel: bool,
}

impl Reach {
    pub(super) fn add(&mut self, p: &NmPos, s: &Settings) {
        self.in_range &= to_steps(p, s).is_some();
        self.in_travel &= within_travel(p, s);
    }
}

/// Milliseconds from a dwell's P (seconds), rounded.
pub fn value_to_ms(v: Value) -> u32 {
    let ms = round_div(i128::from(v.millionths()), (ONE / 1000) as u32);
    u32::try_from(ms.max(0)).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The two-divide quotient is the u128 one, and None exactly from MAX_STEPS.
        #[test]
        fn steps_quotient_is_the_wide_division(num in 0u64..(1u64 << 50), big: bool, five: bool) {
            let d = if five { FIVES } else { 2 * FIVES };
            let num = if big { num << 13 } else { num };
            let want = num / u64::from(d);
            let got = steps_quotient(num, d);
            if want < u64::from(MAX_STEPS) {
                proptest::prop_assert_eq!(got, Some(want as u32));
            } else {
                proptest::prop_assert_eq!(got, None);
            }
        }
    }

    /// round(|nm| * spm * scale / 10^6) from the f32's own bits with the u128 division,
    /// signed, if below MAX_STEPS.
    fn exact_steps(nm: Nm, spm: f32, fine: bool) -> Option<i32> {
        let bits = spm.to_bits();
        let m = u128::from((bits & 0x7F_FFFF) | 0x80_0000);
        let e = ((bits >> 23) & 0xFF) as i32 - 150; // below -9 in the settings' range
        let num = u128::from(nm.unsigned_abs()) * m * if fine { 256 } else { 1 };
        let den = 1_000_000u128 << -e;
        let q = (2 * num + den) / (2 * den);
        let q = i32::try_from(q).ok().filter(|&q| q < MAX_STEPS as i32)?;
        Some(if nm < 0 { -q } else { q })
    }

    proptest::proptest! {
        /// Whole and fine steps are the exactly rounded product, over every length and
        /// every steps/mm the settings allow.
        #[test]
        fn steps_are_the_rounded_exact_product(
            nm: i64,
            shift in 0u32..64,
            spm_bits in 0.0009f32.to_bits()..=10_000f32.to_bits(),
            fine: bool,
        ) {
            let (nm, spm) = (nm >> shift, f32::from_bits(spm_bits));
            proptest::prop_assert_eq!(scaled_steps(nm, spm, fine), exact_steps(nm, spm, fine));
        }

        /// Steps back to the nearest nanometre, and to the same steps again.
        #[test]
        fn steps_return_to_the_nearest_nanometre(
            steps in -(1i32 << 30) + 1..(1i32 << 30),
            spm_bits in 0.0009f32.to_bits()..=10_000f32.to_bits(),
        ) {
            let spm = f32::from_bits(spm_bits);
            let bits = spm.to_bits();
            let m = u128::from((bits & 0x7F_FFFF) | 0x80_0000);
            let e = ((bits >> 23) & 0xFF) as i32 - 150;
            let num = (u128::from(steps.unsigned_abs()) * 1_000_000) << -e;
            let nm = ((2 * num + m) / (2 * m)) as Nm;
            let nm = if steps < 0 { -nm } else { nm };
            proptest::prop_assert_eq!(steps_to_nm(steps, spm), nm);
            proptest::prop_assert_eq!(nm_to_steps(nm, spm), Some(steps));
        }

        /// The same next to the half-step boundaries, where whole steps/mm (and their
        /// 64ths) put exact ties.
        #[test]
        fn half_steps_round_away_from_zero(
            q in -(1i64 << 20)..(1i64 << 20),
            spm_64ths in 1u32..=640_000,
            delta in -2i64..=2,
            fine: bool,
        ) {
            let spm = spm_64ths as f32 / 64.0;
            let scale = if fine { 256.0 } else { 1.0 };
            let tie = (q as f64 + 0.5) * 1e6 / (f64::from(spm) * scale);
            let nm = tie.round() as i64 + delta;
            proptest::prop_assert_eq!(scaled_steps(nm, spm, fine), exact_steps(nm, spm, fine));
        }
    }

    #[test]
    fn lengths_convert_exactly() {
        let v = Value::from_millionths;
        assert_eq!(value_to_nm(v(12_500), false), 12_500);
        assert_eq!(value_to_nm(v(1_000), true), 25_400, "0.001 in");
        assert_eq!(value_to_nm(v(-10), true), -254, "0.00001 in");
        assert_eq!(value_to_nm(v(1), true), 25, "0.000001 in rounds");
        assert_eq!(nm_to_steps(12_500, 80.0), Some(1));
        assert_eq!(nm_to_steps(6_250, 80.0), Some(1), "half a step rounds away");
        assert_eq!(nm_to_steps(-6_250, 80.0), Some(-1));
        assert_eq!(nm_to_steps(6_249, 80.0), Some(0));
        assert_eq!(nm_to_fine_steps(12_500, 80.0), Some(256));
        assert_eq!(nm_to_fine_steps(-49, 80.0), Some(-1), "0.98 / 256 step");
        assert_eq!(nm_to_steps(12_500_000_000, 80.0), Some(1_000_000));
        assert_eq!(nm_to_steps(25_400_000_000, 80.0), Some(2_032_000));
        // 78.74 is 78.73999786376953125 in f32: 1 m is 78,739.99786 steps.
        assert_eq!(nm_to_steps(1_000_000_000, 78.74), Some(78_740));
        assert_eq!(nm_to_steps(1_000_000_000_000, 78.74), Some(78_739_998));
        assert_eq!(nm_to_steps(1 << 40, 0.001), Some(1_100));
        assert_eq!(
            nm_to_steps(14_000_000_000_000, 80.0),
            None,
            "beyond 2^30 steps"
        );
        assert_eq!(nm_to_steps(i64::MAX, 10_000.0), None);
        assert_eq!(nm_to_steps(1, f32::NAN), None);
        for spm in [80.0, 78.74, 0.001, 3.3, 400.0, 10_000.0, 1234.567] {
            for steps in [0, 1, -1, 7, 12_345, -1_000_000, (1 << 30) - 1] {
                let nm = steps_to_nm(steps, spm);
                assert_eq!(nm_to_steps(nm, spm), Some(steps), "{spm} {steps}");
            }
        }
        assert_eq!(value_to_ms(v(500_000)), 500);
        assert_eq!(value_to_ms(v(1_234_567)), 1_235);
    }
}
