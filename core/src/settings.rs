//! Machine settings: the `$n` table (Grbl's numbers where Grbl has them, inkstep's own
//! from `$200`), defaults, range-checked get/set, the `$$` listing and a compact
//! versioned, checksummed byte image for the flash store.
//!
//! Shaped as one table of descriptors plus one `f32` per entry: get/set/list/serialise
//! are then a single loop each, and typed accessors give the rest of the core plain
//! values (`steps_per_mm(X)`, `homing_enabled()`, ...). Every value fits an `f32`
//! exactly (integers stay below 2^24).
//!
//! The board carries only what it looks up (numbers, kinds and ranges in `ENTRIES`, and
//! the defaults, taken from [`TABLE`] at compile time); the descriptions stay on the
//! host side (docs/grbl.md is generated from them), as Grbl 1.1 prints `$n=value` only.

use crate::crc::crc32;
use crate::decimal::{put_int, to_u32, write_fixed3, Sink};
use crate::fmath;
use crate::motion::{AXES, PEN_FULL};

/// What a setting holds; decides range checks and how `$$` prints it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Whole number (printed without decimals).
    Int,
    /// Bit mask over the axes (X = bit 0), or a report mask.
    Mask,
    /// 0 or 1 (any non-zero value is stored as 1, as Grbl does).
    Bool,
    /// Real number, printed with three decimals.
    Float,
}

/// One entry of the settings table.
#[derive(Clone, Copy, Debug)]
pub struct Desc {
    pub number: u16,
    pub kind: Kind,
    pub default: f32,
    pub min: f32,
    pub max: f32,
    /// Short description with unit, for the README and help screens.
    pub name: &'static str,
}

const fn d(number: u16, kind: Kind, default: f32, min: f32, max: f32, name: &'static str) -> Desc {
    Desc {
        number,
        kind,
        default,
        min,
        max,
        name,
    }
}

use Kind::*;

/// Highest step rate one axis may be configured for ($100 x $110 / 60), in Hz.
pub const MAX_AXIS_STEP_RATE_HZ: f32 = 100_000.0;

/// The table. Order is the serialisation order: append only, and bump
/// [`FORMAT_VERSION`] if an entry is removed or reordered.
pub const TABLE: [Desc; 51] = [
    d(0, Int, 10.0, 3.0, 255.0, "Step pulse time, us"),
    d(
        1,
        Int,
        25.0,
        0.0,
        255.0,
        "Step idle delay, ms (255 = keep enabled)",
    ),
    d(2, Mask, 0.0, 0.0, 7.0, "Step pulse invert, mask"),
    d(3, Mask, 0.0, 0.0, 7.0, "Step direction invert, mask"),
    d(4, Bool, 0.0, 0.0, 1.0, "Invert step enable pin"),
    d(5, Bool, 0.0, 0.0, 1.0, "Invert limit pins"),
    d(6, Bool, 0.0, 0.0, 1.0, "Invert probe pin"),
    d(
        10,
        Mask,
        3.0,
        0.0,
        3.0,
        "Status report options, mask (1 = MPos, 2 = Bf)",
    ),
    d(11, Float, 0.010, 0.0, 10.0, "Junction deviation, mm"),
    d(12, Float, 0.002, 0.0001, 1.0, "Arc tolerance, mm"),
    d(13, Bool, 0.0, 0.0, 1.0, "Report in inches"),
    d(20, Bool, 0.0, 0.0, 1.0, "Soft limits enable"),
    d(21, Bool, 0.0, 0.0, 1.0, "Hard limits enable"),
    d(22, Bool, 0.0, 0.0, 1.0, "Homing cycle enable"),
    d(
        23,
        Mask,
        3.0,
        0.0,
        7.0,
        "Homing direction invert, mask (set = home toward -)",
    ),
    d(
        24,
        Float,
        25.0,
        1.0,
        10_000.0,
        "Homing locate feed rate, mm/min",
    ),
    d(
        25,
        Float,
        500.0,
        1.0,
        20_000.0,
        "Homing search seek rate, mm/min",
    ),
    d(
        26,
        Int,
        250.0,
        0.0,
        10_000.0,
        "Homing switch debounce delay, ms",
    ),
    d(
        27,
        Float,
        1.0,
        0.0,
        100.0,
        "Homing switch pull-off distance, mm",
    ),
    d(
        100,
        Float,
        80.0,
        0.001,
        10_000.0,
        "X-axis travel resolution, step/mm",
    ),
    d(
        101,
        Float,
        80.0,
        0.001,
        10_000.0,
        "Y-axis travel resolution, step/mm",
    ),
    d(
        102,
        Float,
        400.0,
        0.001,
        10_000.0,
        "Z-axis travel resolution, step/mm",
    ),
    d(
        110,
        Float,
        3000.0,
        1.0,
        100_000.0,
        "X-axis maximum rate, mm/min",
    ),
    d(
        111,
        Float,
        3000.0,
        1.0,
        100_000.0,
        "Y-axis maximum rate, mm/min",
    ),
    d(
        112,
        Float,
        600.0,
        1.0,
        100_000.0,
        "Z-axis maximum rate, mm/min",
    ),
    d(
        120,
        Float,
        200.0,
        0.1,
        100_000.0,
        "X-axis acceleration, mm/s^2",
    ),
    d(
        121,
        Float,
        200.0,
        0.1,
        100_000.0,
        "Y-axis acceleration, mm/s^2",
    ),
    d(
        122,
        Float,
        100.0,
        0.1,
        100_000.0,
        "Z-axis acceleration, mm/s^2",
    ),
    d(
        130,
        Float,
        300.0,
        0.0,
        10_000.0,
        "X-axis maximum travel, mm",
    ),
    d(
        131,
        Float,
        200.0,
        0.0,
        10_000.0,
        "Y-axis maximum travel, mm",
    ),
    d(132, Float, 10.0, 0.0, 10_000.0, "Z-axis maximum travel, mm"),
    d(
        200,
        Int,
        0.0,
        0.0,
        1.0,
        "Output mode: 0 step/dir, 1 4-phase half-step",
    ),
    d(201, Int, 0.0, 0.0, 1.0, "Pen mode: 0 Z axis, 1 RC servo"),
    d(202, Float, 90.0, 0.0, 180.0, "Pen servo up angle, deg"),
    d(203, Float, 30.0, 0.0, 180.0, "Pen servo down angle, deg"),
    d(204, Int, 150.0, 0.0, 5000.0, "Pen lift time, ms"),
    d(
        205,
        Float,
        0.0,
        -1000.0,
        1000.0,
        "Pen up Z position (Z-axis pen), mm",
    ),
    d(
        206,
        Float,
        -2.0,
        -1000.0,
        1000.0,
        "Pen down Z position (Z-axis pen), mm",
    ),
    d(
        210,
        Int,
        0.0,
        0.0,
        1.0,
        "Acceleration profile: 0 trapezoid, 1 cosine S-curve",
    ),
    d(
        212,
        Int,
        1.0,
        0.0,
        1.0,
        "Interpolation: 0 point-by-point, 1 DDA",
    ),
    d(
        213,
        Float,
        60.0,
        0.0,
        10_000.0,
        "Start rate (motors start instantly below it), mm/min",
    ),
    d(
        214,
        Mask,
        3.0,
        0.0,
        7.0,
        "Axes with home/limit switches, mask",
    ),
    d(
        215,
        Bool,
        0.0,
        0.0,
        1.0,
        "Invert e-stop, feed-hold and cycle-start inputs",
    ),
    // Grbl's spindle settings, appended (the store's image grows by appending). The
    // pen is the spindle: S is reported while it is down, held to $31..$30.
    d(
        30,
        Float,
        1000.0,
        0.0,
        100_000.0,
        "Maximum S (spindle speed), RPM",
    ),
    d(
        31,
        Float,
        0.0,
        0.0,
        100_000.0,
        "Minimum S (spindle speed), RPM",
    ),
    d(
        32,
        Bool,
        0.0,
        0.0,
        1.0,
        "Laser mode (the pen never stops motion either way)",
    ),
    // The pen's motion (issue 24), appended. $204 became the lift time alone; the
    // drop time defaults to the same 150 ms, so an unchanged board waits as before.
    d(207, Int, 150.0, 0.0, 5000.0, "Pen drop time, ms"),
    d(
        208,
        Float,
        0.0,
        0.0,
        10_000.0,
        "Pen servo speed, deg/s (0 = as fast as it goes)",
    ),
    d(
        216,
        Bool,
        0.0,
        0.0,
        1.0,
        "Pen change (M6) goes to $217/$218 (0 = stays)",
    ),
    d(
        217,
        Float,
        0.0,
        -100_000.0,
        100_000.0,
        "Pen change X, machine mm",
    ),
    d(
        218,
        Float,
        0.0,
        -100_000.0,
        100_000.0,
        "Pen change Y, machine mm",
    ),
];

/// Number of settings.
pub const COUNT: usize = TABLE.len();

/// What the board looks up of each [`TABLE`] entry at run time: its number, kind and
/// range (the defaults are copied once into [`Settings::default`]; the descriptions
/// stay on the host side, as Grbl 1.1 prints `$n=value` only).
#[derive(Clone, Copy)]
struct Entry {
    number: u16,
    kind: Kind,
    min: f32,
    max: f32,
}

/// [`TABLE`]'s numbers, kinds and ranges, built at compile time.
static ENTRIES: [Entry; COUNT] = {
    let blank = Entry {
        number: 0,
        kind: Kind::Int,
        min: 0.0,
        max: 0.0,
    };
    let mut out = [blank; COUNT];
    let mut i = 0;
    while i < COUNT {
        let d = &TABLE[i];
        out[i] = Entry {
            number: d.number,
            kind: d.kind,
            min: d.min,
            max: d.max,
        };
        i += 1;
    }
    out
};

/// The defaults, in table order (computed at compile time).
const DEFAULTS: [f32; COUNT] = {
    let mut out = [0.0; COUNT];
    let mut i = 0;
    while i < COUNT {
        out[i] = TABLE[i].default;
        i += 1;
    }
    out
};

/// Table indices in the order of their numbers: `$$` lists by number, as Grbl does,
/// whatever order the table grew in (computed at compile time).
const LISTING: [u8; COUNT] = {
    let mut out = [0u8; COUNT];
    let mut i = 0;
    while i < COUNT {
        out[i] = i as u8;
        i += 1;
    }
    // Insertion sort by number.
    let mut i = 1;
    while i < COUNT {
        let mut j = i;
        while j > 0 && TABLE[out[j - 1] as usize].number > TABLE[out[j] as usize].number {
            let t = out[j];
            out[j] = out[j - 1];
            out[j - 1] = t;
            j -= 1;
        }
        i += 1;
    }
    out
};

/// Table index of setting `number`, for the accessors: evaluated at compile time, so
/// a number missing from the table fails the build.
const fn ix(number: u16) -> usize {
    let mut i = 0;
    while i < COUNT {
        if TABLE[i].number == number {
            return i;
        }
        i += 1;
    }
    panic!("setting not in TABLE")
}
// The per-axis accessors index from the X entry.
const _: () = {
    let mut b = 0;
    while b < 4 {
        let base = 100 + 10 * b as u16;
        assert!(ix(base + 1) == ix(base) + 1 && ix(base + 2) == ix(base) + 2);
        b += 1;
    }
};
/// Version of the byte image; bump when [`TABLE`] changes other than by appending.
/// Version 2 dropped `$211` (a jerk that no ramp read: the cosine S-curve's jerk
/// follows from its acceleration and speed change); a version 1 image still loads.
pub const FORMAT_VERSION: u8 = 2;
/// Where version 1 of the image kept the retired `$211`: its value is skipped.
const V1_RETIRED_SLOT: usize = 39;
const _: () =
    assert!(TABLE[V1_RETIRED_SLOT - 1].number == 210 && TABLE[V1_RETIRED_SLOT].number == 212);
const MAGIC: [u8; 2] = *b"IS";
/// Size of the byte image: magic, version, count, values, CRC-32.
pub const IMAGE_LEN: usize = 4 + 4 * COUNT + 4;
/// The longest image any version wrote (version 1 held one value more).
pub const IMAGE_MAX_LEN: usize = IMAGE_LEN + 4;

/// Why a `$n=v` was refused; maps onto Grbl's error numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SettingError {
    /// No such setting, or value outside its range (error 3).
    Invalid,
    /// Negative value (error 4).
    Negative,
    /// Step pulse shorter than 3 us (error 6).
    PulseTooShort,
    /// Soft limits need homing (error 10).
    SoftLimitsNeedHoming,
    /// Axis step rate above [`MAX_AXIS_STEP_RATE_HZ`] (error 12).
    StepRateTooHigh,
}

/// Why a byte image could not be loaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ImageError {
    Length,
    Magic,
    Version,
    Checksum,
    /// A value outside its range (checksum fine, so written by a buggy build).
    Range,
}

/// Output mode of the step generator ($200).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputMode {
    StepDir,
    FourPhase,
}
/// `up` at level 0, `down` at [`PEN_FULL`] (both exactly), in proportion between.
fn between(up: f32, down: f32, level: u16) -> f32 {
    match level {
        0 => up,
        PEN_FULL.. => down,
        _ => up + (down - up) * (f32::from(level) / f32::from(PEN_FULL)),
    }
}

/// How the pen is lifted ($201).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PenMode {
    ZAxis,
    Servo,
}
/// Acceleration profile ($210).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelProfile {
    Trapezoid,
    SCurve,
}
/// Interpolation method ($212).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    PointByPoint,
    Dda,
}

/// All settings, one value per [`TABLE`] entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    vals: [f32; COUNT],
}

impl Default for Settings {
    fn default() -> Self {
        Settings { vals: DEFAULTS }
    }
}

/// Table index of setting `number`.
pub fn index_of(number: u16) -> Option<usize> {
    ENTRIES.iter().position(|e| e.number == number)
}

impl Settings {
    /// Value of setting `number`, if it exists.
    pub fn get(&self, number: u16) -> Option<f32> {
        index_of(number).and_then(|i| self.vals.get(i).copied())
    }

    /// Set `$number = value` with Grbl's checks. Integer kinds are truncated toward zero.
    pub fn set(&mut self, number: u16, value: f32) -> Result<(), SettingError> {
        let i = index_of(number).ok_or(SettingError::Invalid)?;
        let Some(&Entry { kind, min, max, .. }) = ENTRIES.get(i) else {
            return Err(SettingError::Invalid);
        };
        if !value.is_finite() {
            return Err(SettingError::Invalid);
        }
        if value < 0.0 && min >= 0.0 {
            return Err(SettingError::Negative);
        }
        let v = match kind {
            Kind::Float => value,
            Kind::Int => fmath::trunc(value),
            // Any byte is a mask, as in Grbl; the bits no axis or option uses are
            // dropped.
            Kind::Mask if value < 256.0 => {
                f32::from((to_u32(fmath::trunc(value)) & to_u32(max)) as u8)
            }
            Kind::Mask => fmath::trunc(value),
            Kind::Bool => {
                if value != 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
        };
        if number == 0 && v < 3.0 {
            return Err(SettingError::PulseTooShort);
        }
        if number == 20 && v != 0.0 && !self.homing_enabled() {
            return Err(SettingError::SoftLimitsNeedHoming);
        }
        // Try the value in place; put the old one back if it is refused. A resolution
        // or rate too high for the step rate is error 12 before it is out of range
        // (`$110=99999999`: Grbl has no upper bound but the step rate).
        let Some(slot) = self.vals.get_mut(i) else {
            return Err(SettingError::Invalid);
        };
        let old = core::mem::replace(slot, v);
        let too_fast = (0..AXES).any(|axis| {
            self.steps_per_mm(axis) * self.max_rate(axis) / 60.0 > MAX_AXIS_STEP_RATE_HZ
        });
        if too_fast || v < min || v > max {
            if let Some(slot) = self.vals.get_mut(i) {
                *slot = old;
            }
            return Err(if too_fast {
                SettingError::StepRateTooHigh
            } else {
                SettingError::Invalid
            });
        }
        // Turning homing off also turns soft limits off: they would refer to nothing.
        if number == 22 && v == 0.0 {
            if let Some(slot) = self.vals.get_mut(const { ix(20) }) {
                *slot = 0.0;
            }
        }
        Ok(())
    }

    fn at(&self, index: usize) -> f32 {
        self.vals.get(index).copied().unwrap_or(0.0)
    }
    fn v<const N: u16>(&self) -> f32 {
        self.at(const { ix(N) })
    }
    fn flag<const N: u16>(&self) -> bool {
        // `!= 0.0` without a soft-float compare: values are never NaN, and the shift
        // drops the sign so that -0.0 is zero too.
        self.v::<N>().to_bits() << 1 != 0
    }
    fn mask<const N: u16>(&self) -> u8 {
        to_u32(self.v::<N>()) as u8
    }
    fn axis<const BASE: u16>(&self, axis: usize) -> f32 {
        self.at(const { ix(BASE) } + axis.min(AXES - 1))
    }

    pub fn step_pulse_us(&self) -> u8 {
        to_u32(self.v::<0>()) as u8
    }
    pub fn step_idle_delay_ms(&self) -> u8 {
        to_u32(self.v::<1>()) as u8
    }
    pub fn step_invert_mask(&self) -> u8 {
        self.mask::<2>()
    }
    pub fn dir_invert_mask(&self) -> u8 {
        self.mask::<3>()
    }
    pub fn invert_enable(&self) -> bool {
        self.flag::<4>()
    }
    pub fn invert_limits(&self) -> bool {
        self.flag::<5>()
    }
    pub fn status_mask(&self) -> u8 {
        self.mask::<10>()
    }
    pub fn junction_deviation(&self) -> f32 {
        self.v::<11>()
    }
    pub fn arc_tolerance(&self) -> f32 {
        self.v::<12>()
    }
    pub fn report_inches(&self) -> bool {
        self.flag::<13>()
    }
    pub fn soft_limits(&self) -> bool {
        self.flag::<20>()
    }
    pub fn hard_limits(&self) -> bool {
        self.flag::<21>()
    }
    pub fn homing_enabled(&self) -> bool {
        self.flag::<22>()
    }
    pub fn homing_dir_mask(&self) -> u8 {
        self.mask::<23>()
    }
    pub fn homing_feed(&self) -> f32 {
        self.v::<24>()
    }
    pub fn homing_seek(&self) -> f32 {
        self.v::<25>()
    }
    pub fn homing_debounce_ms(&self) -> u32 {
        to_u32(self.v::<26>())
    }
    pub fn homing_pulloff(&self) -> f32 {
        self.v::<27>()
    }
    /// $100-$102.
    pub fn steps_per_mm(&self, axis: usize) -> f32 {
        self.axis::<100>(axis)
    }
    /// $110-$112, mm/min.
    pub fn max_rate(&self, axis: usize) -> f32 {
        self.axis::<110>(axis)
    }
    /// $120-$122, mm/s^2.
    pub fn acceleration(&self, axis: usize) -> f32 {
        self.axis::<120>(axis)
    }
    /// $130-$132, mm (positive).
    pub fn max_travel(&self, axis: usize) -> f32 {
        self.axis::<130>(axis)
    }
    pub fn output_mode(&self) -> OutputMode {
        if self.flag::<200>() {
            OutputMode::FourPhase
        } else {
            OutputMode::StepDir
        }
    }
    pub fn pen_mode(&self) -> PenMode {
        if self.flag::<201>() {
            PenMode::Servo
        } else {
            PenMode::ZAxis
        }
    }
    pub fn pen_up_angle(&self) -> f32 {
        self.v::<202>()
    }
    pub fn pen_down_angle(&self) -> f32 {
        self.v::<203>()
    }
    /// The servo angle at pen level `level` (0 = up, [`PEN_FULL`] = down), deg:
    /// in proportion between the up and down angles.
    pub fn pen_angle(&self, level: u16) -> f32 {
        between(self.pen_up_angle(), self.pen_down_angle(), level)
    }
    /// RC-servo pulse width for pen level `level`, µs: 0..180 degrees maps linearly
    /// onto 500..2500 µs, the range most hobby servos accept.
    pub fn pen_servo_pulse_us(&self, level: u16) -> u32 {
        500 + to_u32(self.pen_angle(level).clamp(0.0, 180.0) * (2000.0 / 180.0))
    }
    /// The wait after lifting the pen ($204), ms.
    pub fn pen_lift_ms(&self) -> u32 {
        to_u32(self.v::<204>())
    }
    /// The wait after dropping the pen ($207), ms.
    pub fn pen_drop_ms(&self) -> u32 {
        to_u32(self.v::<207>())
    }
    /// The servo's turning speed ($208), deg/s; 0 = no limit (a jump).
    pub fn pen_speed(&self) -> f32 {
        self.v::<208>()
    }
    /// Where a pen change (M6) goes, machine mm; `None`: it stays.
    pub fn pen_change_xy(&self) -> Option<[f32; 2]> {
        self.flag::<216>()
            .then(|| [self.v::<217>(), self.v::<218>()])
    }
    /// The Z-axis pen's Z at level `level`, mm: in proportion between up and down.
    pub fn pen_z_at(&self, level: u16) -> f32 {
        between(self.pen_z_up(), self.pen_z_down(), level)
    }
    /// The pen level `S` asks for: its place within $31..$30 (S max = down, S min =
    /// up), in [`PEN_FULL`]ths; fully down when the range is empty.
    pub fn pen_level_of(&self, s: f32) -> u16 {
        let (lo, hi) = self.spindle_range();
        if hi <= lo {
            return PEN_FULL;
        }
        let f = ((s - lo) / (hi - lo)).clamp(0.0, 1.0);
        to_u32(f * f32::from(PEN_FULL) + 0.5).min(u32::from(PEN_FULL)) as u16
    }
    pub fn pen_z_up(&self) -> f32 {
        self.v::<205>()
    }
    pub fn pen_z_down(&self) -> f32 {
        self.v::<206>()
    }
    pub fn accel_profile(&self) -> AccelProfile {
        if self.flag::<210>() {
            AccelProfile::SCurve
        } else {
            AccelProfile::Trapezoid
        }
    }
    pub fn interpolation(&self) -> Interpolation {
        if self.flag::<212>() {
            Interpolation::Dda
        } else {
            Interpolation::PointByPoint
        }
    }
    pub fn start_rate(&self) -> f32 {
        self.v::<213>()
    }
    /// Axes that have a home/limit switch ($214).
    pub fn switch_mask(&self) -> u8 {
        self.mask::<214>()
    }
    pub fn invert_inputs(&self) -> bool {
        self.flag::<215>()
    }
    /// $31..$30: the range S is held to.
    pub fn spindle_range(&self) -> (f32, f32) {
        (self.v::<31>(), self.v::<30>())
    }

    /// Write the `position`-th line of the `$$` listing (by setting number; no line
    /// ending). `None` past the end.
    pub fn write_listed(&self, position: usize, w: &mut dyn Sink) -> Option<()> {
        self.write_entry(usize::from(*LISTING.get(position)?), w)
    }

    /// Write `$n=value` for table entry `index` (no line ending). `None` past the end.
    pub fn write_entry(&self, index: usize, w: &mut dyn Sink) -> Option<()> {
        let Entry { number, kind, .. } = *ENTRIES.get(index)?;
        let v = *self.vals.get(index)?;
        w.put(b"$");
        put_int(w, i32::from(number));
        w.put(b"=");
        if kind == Kind::Float {
            write_fixed3(w, v);
        } else {
            // Whole, non-negative and below 2^24 (checked on set and load).
            put_int(w, to_u32(v) as i32);
        }
        Some(())
    }

    /// The compact byte image: `"IS"`, version, count, each value as little-endian
    /// `f32` in table order, then a CRC-32 of everything before it.
    pub fn to_image(&self) -> [u8; IMAGE_LEN] {
        let mut out = [0u8; IMAGE_LEN];
        let (head, rest) = out.split_at_mut(4);
        head.copy_from_slice(&[MAGIC[0], MAGIC[1], FORMAT_VERSION, COUNT as u8]);
        for (chunk, v) in rest.as_chunks_mut::<4>().0.iter_mut().zip(self.vals.iter()) {
            *chunk = v.to_le_bytes();
        }
        let body = IMAGE_LEN - 4;
        let crc = crc32(out.get(..body).unwrap_or(&[]));
        if let Some(tail) = out.get_mut(body..) {
            tail.copy_from_slice(&crc.to_le_bytes());
        }
        out
    }

    /// Take the values of a byte image written by [`Settings::to_image`], checking
    /// everything first: on an error nothing changes. An image from an older build
    /// with fewer (appended-to) settings loads too: the settings it lacks keep their
    /// values (the defaults, read into `Settings::default()`), so an update keeps the
    /// user's values. In place, so the value table is not copied around.
    pub fn read_image(&mut self, img: &[u8]) -> Result<(), ImageError> {
        let version = *img.get(2).ok_or(ImageError::Length)?;
        // Version 1 had one more slot (the retired `$211`).
        let slots = if version == 1 { COUNT + 1 } else { COUNT };
        let count = usize::from(*img.get(3).ok_or(ImageError::Length)?);
        if count > slots || img.len() != 4 + 4 * count + 4 {
            return Err(ImageError::Length);
        }
        let (body, tail) = img.split_at(img.len() - 4);
        let stored = u32::from_le_bytes(tail.try_into().map_err(|_| ImageError::Length)?);
        if crc32(body) != stored {
            return Err(ImageError::Checksum);
        }
        if body.get(..2) != Some(&MAGIC[..]) {
            return Err(ImageError::Magic);
        }
        if version != FORMAT_VERSION && version != 1 {
            return Err(ImageError::Version);
        }
        let stored = body.get(4..).unwrap_or(&[]).as_chunks::<4>().0;
        // A version 1 image read as this version's table: the retired slot left out.
        let (head, tail) = stored.split_at(stored.len().min(if version == 1 {
            V1_RETIRED_SLOT
        } else {
            usize::MAX
        }));
        let tail = if version == 1 {
            tail.get(1..).unwrap_or(&[])
        } else {
            tail
        };
        let values = || head.iter().chain(tail.iter());
        // NaN fails both comparisons; every range is finite.
        let in_range = |(chunk, entry): (&[u8; 4], &Entry)| {
            let v = f32::from_le_bytes(*chunk);
            v >= entry.min && v <= entry.max
        };
        if !values().zip(ENTRIES.iter()).all(in_range) {
            return Err(ImageError::Range);
        }
        for (slot, chunk) in self.vals.iter_mut().zip(values()) {
            *slot = f32::from_le_bytes(*chunk);
        }
        Ok(())
    }
}

/// A version 1 image: this version's values with the retired `$211` slot put back.
#[cfg(test)]
pub(crate) fn v1_image(s: &Settings, count: usize) -> std::vec::Vec<u8> {
    let mut vals: std::vec::Vec<f32> = s.vals.to_vec();
    vals.insert(V1_RETIRED_SLOT, 5000.0);
    vals.truncate(count);
    let mut img = std::vec![MAGIC[0], MAGIC[1], 1, count as u8];
    for v in vals {
        img.extend_from_slice(&v.to_le_bytes());
    }
    let crc = crc32(&img);
    img.extend_from_slice(&crc.to_le_bytes());
    img
}

#[cfg(test)]
mod tests;
