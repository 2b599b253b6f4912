//! The settings' tests: the `$n` table (numbers, defaults, range checks, listing) and
//! its byte image (round trip, older versions, corrupt or out-of-range images).

use super::*;

/// What the store does: the defaults, then the image read over them.
fn from_image(img: &[u8]) -> Result<Settings, ImageError> {
    let mut s = Settings::default();
    s.read_image(img).map(|()| s)
}

#[test]
fn table_numbers_are_unique_and_defaults_in_range() {
    for (i, a) in TABLE.iter().enumerate() {
        assert!(a.default >= a.min && a.default <= a.max, "${}", a.number);
        // read_image's range check also refuses infinities by this.
        assert!(a.min.is_finite() && a.max.is_finite(), "${}", a.number);
        for b in TABLE.iter().skip(i + 1) {
            assert_ne!(a.number, b.number);
        }
    }
    for n in [
        0, 1, 2, 3, 4, 5, 6, 10, 11, 12, 13, 20, 21, 22, 23, 24, 25, 26, 27,
    ] {
        assert!(index_of(n).is_some(), "${n} missing");
    }
    for base in [100, 110, 120, 130] {
        for a in 0..3 {
            assert!(index_of(base + a).is_some());
        }
    }
}

#[test]
fn set_checks_ranges_like_grbl() {
    let mut s = Settings::default();
    assert_eq!(s.set(999, 1.0), Err(SettingError::Invalid));
    assert_eq!(s.set(0, 2.0), Err(SettingError::PulseTooShort));
    assert_eq!(s.set(100, -1.0), Err(SettingError::Negative));
    assert_eq!(s.set(20, 1.0), Err(SettingError::SoftLimitsNeedHoming));
    assert_eq!(s.set(100, 5000.0), Err(SettingError::StepRateTooHigh));
    assert_eq!(s.steps_per_mm(0), 80.0, "refused change must not apply");
    s.set(22, 1.0).unwrap();
    s.set(20, 5.0).unwrap();
    assert!(s.soft_limits());
    s.set(22, 0.0).unwrap();
    assert!(!s.soft_limits(), "homing off clears soft limits");
    s.set(3, 5.7).unwrap();
    assert_eq!(s.dir_invert_mask(), 5);
    s.set(101, 12.5).unwrap();
    assert_eq!(s.steps_per_mm(1), 12.5);
    assert_eq!(s.set(205, -3.0), Ok(()));
    assert_eq!(s.pen_z_up(), -3.0);
}

#[test]
fn listing_prints_ints_and_floats_like_grbl() {
    let s = Settings::default();
    let mut line: heapless::String<48> = heapless::String::new();
    s.write_entry(index_of(0).unwrap(), &mut line).unwrap();
    assert_eq!(line.as_str(), "$0=10");
    line.clear();
    s.write_entry(index_of(11).unwrap(), &mut line).unwrap();
    assert_eq!(line.as_str(), "$11=0.010");
    assert!(s.write_entry(COUNT, &mut line).is_none());
}

#[test]
fn a_version_1_image_keeps_every_value_but_the_retired_jerk() {
    let mut s = Settings::default();
    s.set(100, 123.25).unwrap();
    s.set(210, 1.0).unwrap();
    s.set(212, 0.0).unwrap();
    s.set(218, 7.5).unwrap();
    assert_eq!(from_image(&v1_image(&s, COUNT + 1)), Ok(s.clone()));
    // An older version 1 image that ended before `$211`, and one that ended after it.
    let mut short = Settings::default();
    short.set(100, 123.25).unwrap();
    assert_eq!(from_image(&v1_image(&short, 30)), Ok(short.clone()));
    let mut mid = Settings::default();
    mid.set(210, 1.0).unwrap();
    mid.set(212, 0.0).unwrap();
    assert_eq!(from_image(&v1_image(&mid, 42)), Ok(mid));
    // This version's count limit still holds for version 2 images.
    let mut long = s.to_image().to_vec();
    long[3] = (COUNT + 1) as u8;
    assert_eq!(from_image(&long), Err(ImageError::Length));
    assert_eq!(
        Settings::default().set(211, 100.0),
        Err(SettingError::Invalid)
    );
}

#[test]
fn image_round_trips_and_rejects_any_flipped_bit() {
    let mut s = Settings::default();
    s.set(100, 123.25).unwrap();
    s.set(201, 1.0).unwrap();
    let img = s.to_image();
    assert_eq!(from_image(&img), Ok(s.clone()));
    for byte in 0..IMAGE_LEN {
        for bit in 0..8 {
            let mut bad = img;
            bad[byte] ^= 1 << bit;
            assert!(from_image(&bad).is_err(), "byte {byte} bit {bit}");
        }
    }
    assert_eq!(from_image(&img[..10]), Err(ImageError::Length));
}

#[test]
fn an_older_shorter_image_keeps_its_values_and_defaults_the_rest() {
    let mut s = Settings::default();
    s.set(100, 42.0).unwrap();
    let full = s.to_image();
    // The image an older build with only the first 30 settings would have written.
    let n = 30;
    let mut old = std::vec::Vec::from(&full[..4 + 4 * n]);
    old[3] = n as u8;
    let crc = crc32(&old);
    old.extend_from_slice(&crc.to_le_bytes());
    let loaded = from_image(&old).unwrap();
    assert_eq!(loaded.steps_per_mm(0), 42.0);
    assert_eq!(loaded, s, "the rest are defaults, as in s");
}

#[test]
fn an_image_with_a_value_out_of_range_nan_or_infinite_is_refused() {
    let img = Settings::default().to_image();
    // $100 (steps per mm) is the value at this table index.
    let at = 4 + 4 * index_of(100).unwrap();
    for bad in [-1.0, 1e9, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut v = img;
        v[at..at + 4].copy_from_slice(&f32::to_le_bytes(bad));
        let crc = crc32(&v[..IMAGE_LEN - 4]);
        v[IMAGE_LEN - 4..].copy_from_slice(&crc.to_le_bytes());
        assert_eq!(from_image(&v), Err(ImageError::Range), "{bad}");
    }
}

#[test]
fn a_refused_image_changes_nothing() {
    // An image whose first value is not the default, with a bad value further on.
    let first = &ENTRIES[0];
    let mut src = Settings::default();
    src.set(first.number, first.max).unwrap();
    assert_ne!(src, Settings::default());
    let mut img = src.to_image();
    let last = 4 + 4 * (COUNT - 1);
    img[last..last + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let crc = crc32(&img[..IMAGE_LEN - 4]);
    img[IMAGE_LEN - 4..].copy_from_slice(&crc.to_le_bytes());
    let mut kept = Settings::default();
    assert_eq!(kept.read_image(&img), Err(ImageError::Range));
    assert_eq!(kept, Settings::default());
}
