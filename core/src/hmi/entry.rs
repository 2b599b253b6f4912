//! Numeric entry: one editable field (digits, sign, decimal point, backspace) and the
//! parameter forms of the drawing modes, with range checks and their messages.
//!
//! A field shows its current value until the first digit is typed, which starts a new
//! text (so the last job's values are defaults you can confirm with Enter). The report's
//! problem 5 (one key press filling every digit) cannot happen: a field changes only on
//! Press events, and the form moves to the next field only on Enter.

use super::job::Job;
use super::text::Text;
use crate::keypad::Key;

/// Longest text a field accepts ("-123.456").
pub const FIELD_CHARS: usize = 8;

/// One numeric parameter: its entry in the field table (label, unit, limits, decimals)
/// by index, the committed value and the text being typed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    spec: u8,
    editing: bool,
    /// The committed value.
    pub value: f32,
    text: Text<FIELD_CHARS>,
}

/// What a key did to a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldInput {
    /// The field used the key.
    Edited,
    /// Backspace on an untouched field: leave the form.
    Cancel,
    /// Not a field key.
    Ignored,
}

impl Field {
    /// The field of entry `spec` of the field table, holding `value` (clamped to its
    /// limits).
    pub fn new(spec: usize, value: f32) -> Self {
        let mut f = Field {
            spec: spec as u8,
            editing: false,
            value: 0.0,
            text: Text::new(),
        };
        // Not `clamp`: that panics (formatting both f32s) if min > max.
        f.value = value.max(f.min()).min(f.max());
        f
    }

    /// This field's table entry.
    fn spec(&self) -> &'static FieldSpec {
        FIELD_SPECS.get(usize::from(self.spec)).unwrap_or(&NO_SPEC)
    }
    pub fn label(&self) -> &'static str {
        self.spec().0
    }
    pub fn unit(&self) -> &'static str {
        self.spec().1
    }
    pub fn min(&self) -> f32 {
        self.spec().2
    }
    pub fn max(&self) -> f32 {
        self.spec().3
    }
    /// Decimals accepted and shown.
    pub fn decimals(&self) -> u8 {
        self.spec().4
    }

    /// Whether the user has started typing a new value.
    pub fn editing(&self) -> bool {
        self.editing
    }

    /// What the field shows: the text being typed, or the committed value.
    pub fn display(&self) -> Text<12> {
        let mut s = Text::new();
        self.push_display(&mut s);
        s
    }

    /// Append [`Field::display`] to `out` (the form page's line, built in place);
    /// false if it does not fit.
    pub fn push_display<const N: usize>(&self, out: &mut Text<N>) -> bool {
        if self.editing {
            out.push_text(&self.text)
        } else {
            out.push_fixed(self.value, self.decimals())
        }
    }

    /// Apply a key press (or a backspace repeat, `repeat = true`).
    pub fn key(&mut self, key: Key, repeat: bool) -> FieldInput {
        match key {
            Key::Digit(d) if !repeat && d <= 9 => {
                self.start_editing();
                let full = self
                    .typed_decimals()
                    .is_some_and(|n| n >= usize::from(self.decimals()));
                if !full {
                    self.text.push_ascii(b'0' + d);
                }
                FieldInput::Edited
            }
            Key::Dot if !repeat => {
                self.start_editing();
                if self.decimals() > 0 && self.typed_decimals().is_none() {
                    let t = self.text.as_bytes();
                    if t.is_empty() || t == b"-" {
                        self.text.push_ascii(b'0');
                    }
                    self.text.push_ascii(b'.');
                }
                FieldInput::Edited
            }
            Key::Sign if !repeat => {
                if self.min() >= 0.0 {
                    return FieldInput::Edited;
                }
                // On an untouched field the sign starts a new negative number.
                self.start_editing();
                let neg = self.text.as_bytes().first() == Some(&b'-');
                let mut t: Text<FIELD_CHARS> = Text::new();
                let mut ok = neg || t.push_ascii(b'-');
                // The field text is ASCII: copied byte by byte, kept only if it all fits.
                for &b in self.text.bytes().iter().skip(usize::from(neg)) {
                    ok &= t.push_ascii(b);
                }
                if ok {
                    self.text = t;
                }
                FieldInput::Edited
            }
            Key::Back => {
                if self.editing {
                    if !self.text.pop() && !repeat {
                        // Empty text: back to the committed value.
                        self.editing = false;
                    }
                    FieldInput::Edited
                } else if repeat {
                    // Holding backspace never falls through into leaving the form.
                    FieldInput::Edited
                } else {
                    FieldInput::Cancel
                }
            }
            _ => FieldInput::Ignored,
        }
    }

    /// How many digits follow the decimal point typed so far; None before the point.
    /// One byte-wise scan for the digit and the point keys (the text is ASCII; str's
    /// pattern search and slice `contains`, which goes through `memchr`, cost more).
    fn typed_decimals(&self) -> Option<usize> {
        let t = self.text.as_bytes();
        t.iter()
            .position(|&c| c == b'.')
            .map(|dot| t.len() - dot - 1)
    }

    fn start_editing(&mut self) {
        if !self.editing {
            self.editing = true;
            self.text.clear();
        }
    }

    /// Parse and range-check the text; on success it becomes the value.
    pub fn commit(&mut self) -> Result<f32, Text<28>> {
        if !self.editing {
            return Ok(self.value);
        }
        let parsed = parse_decimal(self.text.bytes());
        match parsed {
            Some(v) if v >= self.min() && v <= self.max() => {
                self.value = v;
                self.editing = false;
                self.text.clear();
                Ok(v)
            }
            _ => Err(self.range_message()),
        }
    }

    /// "R: 0.50..100.00 mm"
    pub fn range_message(&self) -> Text<28> {
        let (label, unit, min, max, decimals) = *self.spec();
        let mut s: Text<28> = Text::new();
        s.push_str(label);
        s.push_str(": ");
        s.push_fixed(min, decimals);
        s.push_str("..");
        s.push_fixed(max, decimals);
        s.push_str(" ");
        s.push_str(unit);
        s
    }
}

/// Parse what a field can hold: optional '-', digits, optional '.' and digits.
/// By hand, because the parser is also what decides what a field accepts (no sign but
/// '-', no exponent, no "inf" or "NaN", which core's float parser would take); None for
/// empty, lone "-" or "." and anything else.
pub fn parse_decimal(text: &[u8]) -> Option<f32> {
    // Byte-wise: anything but ASCII digits and one '.' is refused anyway.
    let (neg, body) = match text {
        [b'-', rest @ ..] => (true, rest),
        all => (false, all),
    };
    let mut mantissa: u32 = 0;
    let mut scale: f32 = 1.0;
    let mut digits = 0;
    let mut after_dot = false;
    for &c in body {
        match c {
            b'0'..=b'9' => {
                mantissa = mantissa.checked_mul(10)?.checked_add(u32::from(c - b'0'))?;
                digits += 1;
                if after_dot {
                    scale *= 10.0;
                }
            }
            b'.' if !after_dot => after_dot = true,
            _ => return None,
        }
    }
    if digits == 0 {
        return None;
    }
    let v = mantissa as f32 / scale;
    Some(if neg { -v } else { v })
}

/// The parameter forms, one per drawing mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormKind {
    Line,
    Arc,
    Ellipse,
    Sine,
    Star,
}

pub const FORM_KINDS: [FormKind; 5] = [
    FormKind::Line,
    FormKind::Arc,
    FormKind::Ellipse,
    FormKind::Sine,
    FormKind::Star,
];

/// The remembered parameters of each form (defaults until a job is drawn).
pub type FormMemory = [[f32; 4]; 5];

pub const DEFAULT_PARAMS: FormMemory = [
    [30.0, 20.0, 0.0, 0.0],
    [20.0, 150.0, 0.0, 0.0],
    [25.0, 15.0, 0.0, 0.0],
    [10.0, 0.2, 0.0, 60.0],
    [40.0, 0.0, 0.0, 0.0],
];

impl FormKind {
    pub fn index(self) -> usize {
        match self {
            FormKind::Line => 0,
            FormKind::Arc => 1,
            FormKind::Ellipse => 2,
            FormKind::Sine => 3,
            FormKind::Star => 4,
        }
    }

    /// A one-line reminder shown under the fields (when there is room).
    pub fn note(self) -> &'static str {
        match self {
            FormKind::Line => "from the pen; *:sign #:.",
            FormKind::Arc => "angle < 0: clockwise",
            FormKind::Ellipse => "a along X, b along Y",
            FormKind::Sine => "",
            FormKind::Star => "S: diameter of the tips",
        }
    }

    pub fn title(self) -> &'static str {
        match self {
            FormKind::Line => "Line to dX, dY",
            FormKind::Arc => "Arc R, angle",
            FormKind::Ellipse => "Ellipse a, b",
            FormKind::Sine => "Sine A sin(wx+p)",
            FormKind::Star => "Five-point star",
        }
    }
}

/// A mode's parameter form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Form {
    pub kind: FormKind,
    /// Index of the field being edited.
    pub cur: usize,
    /// The first `count` slots are the fields.
    slots: [Field; 4],
    count: u8,
}

/// An unused field slot.
const NO_FIELD: Field = Field {
    spec: u8::MAX,
    editing: false,
    value: 0.0,
    text: Text::new(),
};
/// What a field outside the table shows.
const NO_SPEC: FieldSpec = ("", "", 0.0, 0.0, 0);

/// The fields of every form as data: (label, unit, min, max, decimals), grouped by
/// [`FormKind`] in [`FORM_KINDS`] order; [`FORM_FIELDS`] gives each kind's slice.
type FieldSpec = (&'static str, &'static str, f32, f32, u8);
const FIELD_SPECS: [FieldSpec; 11] = [
    ("dX", "mm", -200.0, 200.0, 2),
    ("dY", "mm", -200.0, 200.0, 2),
    ("R", "mm", 0.5, 100.0, 2),
    ("Angle", "deg", -360.0, 360.0, 1),
    ("a", "mm", 0.5, 100.0, 2),
    ("b", "mm", 0.5, 100.0, 2),
    ("A", "mm", -50.0, 50.0, 2),
    ("w", "rad/mm", 0.01, 5.0, 3),
    ("phi", "deg", -360.0, 360.0, 1),
    ("Len", "mm", 1.0, 200.0, 1),
    ("S", "mm", 2.0, 150.0, 1),
];
/// (first spec, number of fields) of each form kind.
const FORM_FIELDS: [(u8, u8); 5] = [(0, 2), (2, 2), (4, 2), (6, 4), (10, 1)];

impl Form {
    pub fn new(kind: FormKind, p: &[f32; 4]) -> Self {
        let (first, n) = FORM_FIELDS.get(kind.index()).copied().unwrap_or((0, 0));
        // Fields first + 0, 1, ... of the table (at most 4), the other slots unused.
        let count = n.min(4);
        let slots = core::array::from_fn(|i| match p.get(i) {
            Some(&v) if i < usize::from(count) => Field::new(usize::from(first) + i, v),
            _ => NO_FIELD,
        });
        Form {
            kind,
            cur: 0,
            slots,
            count,
        }
    }

    /// The fields, in order.
    pub fn fields(&self) -> &[Field] {
        self.slots.get(..usize::from(self.count)).unwrap_or(&[])
    }

    pub fn current(&mut self) -> Option<&mut Field> {
        self.slots
            .get_mut(..usize::from(self.count))
            .and_then(|f| f.get_mut(self.cur))
    }

    pub fn is_last(&self) -> bool {
        self.cur + 1 >= self.fields().len()
    }

    /// The committed values, in field order (unused slots 0).
    pub fn values(&self) -> [f32; 4] {
        let mut v = [0.0; 4];
        for (slot, f) in v.iter_mut().zip(self.fields()) {
            *slot = f.value;
        }
        v
    }

    /// The job described by the committed values.
    pub fn job(&self) -> Job {
        let v = self.values();
        match self.kind {
            FormKind::Line => Job::Line { dx: v[0], dy: v[1] },
            FormKind::Arc => Job::Arc {
                r: v[0],
                theta: v[1],
            },
            FormKind::Ellipse => Job::Ellipse { a: v[0], b: v[1] },
            FormKind::Sine => Job::Sine {
                amp: v[0],
                omega: v[1],
                phase: v[2],
                len: v[3],
            },
            FormKind::Star => Job::Star { size: v[0] },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The field table entry labelled `label` (its limits are checked in the tests).
    fn spec(label: &str) -> usize {
        FIELD_SPECS.iter().position(|s| s.0 == label).unwrap()
    }

    #[test]
    fn field_table_entries_used_by_the_tests() {
        for (label, want) in [
            ("R", ("R", "mm", 0.5, 100.0, 2)),
            ("dX", ("dX", "mm", -200.0, 200.0, 2)),
            ("a", ("a", "mm", 0.5, 100.0, 2)),
            ("A", ("A", "mm", -50.0, 50.0, 2)),
        ] {
            let f = Field::new(spec(label), 0.0);
            assert_eq!((f.label(), f.unit(), f.min(), f.max(), f.decimals()), want);
        }
    }

    fn typed(f: &mut Field, keys: &[Key]) {
        for k in keys {
            assert_ne!(f.key(*k, false), FieldInput::Ignored);
        }
    }

    #[test]
    fn decimal_parser_accepts_field_text_only() {
        assert_eq!(parse_decimal(b"12.5"), Some(12.5));
        assert_eq!(parse_decimal(b"-0.25"), Some(-0.25));
        assert_eq!(parse_decimal(b"7."), Some(7.0));
        assert_eq!(parse_decimal(b".5"), Some(0.5));
        for bad in ["", "-", ".", "-.", "1.2.3", "1-2", "+3", "1e5"] {
            assert_eq!(parse_decimal(bad.as_bytes()), None, "{bad:?}");
        }
    }

    #[test]
    fn typing_replaces_the_default_and_commits_in_range() {
        let mut f = Field::new(spec("R"), 20.0);
        assert_eq!(f.display().as_str(), "20.00");
        typed(
            &mut f,
            &[Key::Digit(1), Key::Digit(2), Key::Dot, Key::Digit(5)],
        );
        assert_eq!(f.display().as_str(), "12.5");
        assert_eq!(f.commit(), Ok(12.5));
        assert_eq!(f.display().as_str(), "12.50");
    }

    #[test]
    fn sign_decimals_and_backspace() {
        let mut f = Field::new(spec("dX"), 0.0);
        typed(&mut f, &[Key::Digit(7), Key::Sign, Key::Dot, Key::Digit(1)]);
        typed(&mut f, &[Key::Digit(2), Key::Digit(3)]); // third decimal dropped
        assert_eq!(f.display().as_str(), "-7.12");
        assert_eq!(f.key(Key::Back, true), FieldInput::Edited);
        assert_eq!(f.display().as_str(), "-7.1");
        assert_eq!(f.commit(), Ok(-7.1));
    }

    #[test]
    fn out_of_range_keeps_the_old_value_and_explains() {
        let mut f = Field::new(spec("R"), 20.0);
        typed(&mut f, &[Key::Digit(5), Key::Digit(0), Key::Digit(0)]);
        assert_eq!(f.commit().unwrap_err().as_str(), "R: 0.50..100.00 mm");
        assert_eq!(f.value, 20.0);
        // A positive-only field ignores the sign key.
        let mut g = Field::new(spec("a"), 3.0);
        typed(&mut g, &[Key::Sign]);
        assert_eq!(g.display().as_str(), "3.00");
    }

    #[test]
    fn backspace_empties_then_restores_then_cancels_but_repeat_never_cancels() {
        let mut f = Field::new(spec("A"), 10.0);
        typed(&mut f, &[Key::Digit(4)]);
        assert_eq!(f.key(Key::Back, true), FieldInput::Edited); // "4" -> ""
        assert_eq!(f.key(Key::Back, true), FieldInput::Edited); // repeat on empty: stays
        assert!(f.editing());
        assert_eq!(f.key(Key::Back, false), FieldInput::Edited); // press: restore 10.00
        assert!(!f.editing());
        assert_eq!(f.display().as_str(), "10.00");
        assert_eq!(f.key(Key::Back, true), FieldInput::Edited);
        assert_eq!(f.key(Key::Back, false), FieldInput::Cancel);
    }

    #[test]
    fn every_form_builds_its_job_from_the_defaults() {
        for kind in FORM_KINDS {
            let form = Form::new(kind, &DEFAULT_PARAMS[kind.index()]);
            assert!(!form.fields().is_empty());
            let job = form.job();
            assert!(job.length_mm() > 1.0, "{kind:?}: {job:?}");
        }
    }
}
