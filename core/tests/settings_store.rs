//! The settings store survives a power cut at every write and erase step: the next boot
//! loads the old or the new value, never garbage; corrupt storage gives defaults and
//! says so.

mod common;

use common::flash::{Cut, CutFlash, SIZE, STORE_RANGE};
use inkstep_core::gcode::interpreter::Coords;
use inkstep_core::settings::Settings;
use inkstep_core::settings_store::{LoadStatus, SettingsStore};

fn store(flash: CutFlash) -> SettingsStore<CutFlash> {
    SettingsStore::new(flash, STORE_RANGE).unwrap()
}

/// The settings as a boot loads them: the defaults, with the stored ones read over them.
fn load_settings(st: &mut SettingsStore<CutFlash>) -> (Settings, LoadStatus) {
    let mut s = Settings::default();
    let status = st.load_settings(&mut s);
    (s, status)
}

fn with(n: u16, v: f32) -> Settings {
    let mut s = Settings::default();
    s.set(n, v).unwrap();
    s
}

#[test]
fn first_boot_is_empty_not_corrupt() {
    let mut st = store(CutFlash::new());
    let (s, status) = load_settings(&mut st);
    assert_eq!((s, status), (Settings::default(), LoadStatus::Empty));
    assert_eq!(status.message(), None);
}

#[test]
fn round_trip_of_settings_coords_and_startup_lines() {
    let mut st = store(CutFlash::new());
    let s = with(100, 123.5);
    st.save_settings(&s).unwrap();
    let mut c = Coords::default();
    c.wcs[1] = [1_000_000, -2_000_000, 3_500_000];
    c.g28 = [10_000_000, 20_000_000, 0];
    st.save_coords(&c).unwrap();
    st.save_startup(1, "G21G90").unwrap();
    let mut st = store(st.into_flash());
    assert_eq!(load_settings(&mut st), (s, LoadStatus::Loaded));
    assert_eq!(st.load_coords(), (c, LoadStatus::Loaded));
    assert_eq!(st.load_startup(1).0.as_str(), "G21G90");
    assert_eq!(st.load_startup(0).1, LoadStatus::Empty);
}

#[test]
fn power_cut_at_every_write_and_erase_step_keeps_old_or_new() {
    let old = with(100, 81.0);
    let new = with(100, 82.0);
    let started = std::time::Instant::now();
    let mut scenarios = 0;
    let mut max_ops = 0;
    let mut saw_old = 0;
    let mut saw_new = 0;
    let mut reported_corrupt = 0;
    // Different amounts of history put the change at every position in the pages,
    // including page switches that erase and copy live items.
    for history in 0..24 {
        for mode in [Cut::Before, Cut::Prefix, Cut::TornWord, Cut::RandomErase] {
            for cut in 0.. {
                let mut st = store(CutFlash::new());
                for h in 0..history {
                    if h % 3 == 2 {
                        st.save_startup(0, "G21").unwrap();
                    } else {
                        st.save_settings(&with(101, 50.0 + h as f32)).unwrap();
                    }
                }
                st.save_settings(&old).unwrap();
                let mut flash = st.into_flash();
                flash.ops = 0;
                flash.cut_at = Some(cut);
                flash.mode = mode;
                let mut st = store(flash);
                let result = st.save_settings(&new);
                let mut flash = st.into_flash();
                let was_cut = flash.dead;
                if !was_cut {
                    assert!(result.is_ok());
                    max_ops = max_ops.max(cut);
                    break;
                }
                scenarios += 1;
                flash.reboot();
                let mut st = store(flash);
                let (loaded, status) = load_settings(&mut st);
                let case = format!("history {history}, cut at operation {cut}, {mode:?}");
                if mode == Cut::RandomErase && status == LoadStatus::Corrupt {
                    // Beyond the store's model: allowed to give up, never to guess.
                    assert_eq!(loaded, Settings::default(), "{case}");
                    reported_corrupt += 1;
                } else if loaded == old {
                    saw_old += 1;
                } else if loaded == new {
                    saw_new += 1;
                } else {
                    panic!("garbage after {case}");
                }
                if status != LoadStatus::Corrupt {
                    assert_eq!(status, LoadStatus::Loaded, "{case}");
                }
                // The startup line written before is still intact, and the store
                // keeps working after the cut.
                if history >= 3 && status == LoadStatus::Loaded {
                    assert_eq!(st.load_startup(0).0.as_str(), "G21");
                }
                let newer = with(100, 83.0);
                if let Err(e) = st.save_settings(&newer) {
                    panic!("save after {case}: {e:?}");
                }
                assert_eq!(load_settings(&mut st).0, newer);
            }
        }
    }
    println!(
        "power-cut scenarios: {scenarios} (old kept {saw_old}, new loaded {saw_new}, random-erase cases reported corrupt {reported_corrupt}), up to {max_ops} flash operations per save, {:?}",
        started.elapsed()
    );
    assert!(saw_old > 0 && saw_new > 0);
    assert!(scenarios > 100);
}

#[test]
fn power_cut_while_saving_any_key_leaves_the_others_and_the_store_working() {
    let s = with(100, 70.0);
    let c_old = Coords {
        g28: [1_000_000, 2_000_000, 3_000_000],
        ..Coords::default()
    };
    let c_new = Coords {
        g28: [4_000_000, 5_000_000, 6_000_000],
        ..Coords::default()
    };
    let mut scenarios = 0;
    for history in 0..20 {
        for mode in [Cut::Before, Cut::Prefix, Cut::TornWord, Cut::RandomErase] {
            for target in 0..2 {
                for cut in 0.. {
                    let mut st = store(CutFlash::new());
                    st.save_settings(&s).unwrap();
                    st.save_coords(&c_old).unwrap();
                    st.save_startup(1, "G21").unwrap();
                    for h in 0..history {
                        st.save_startup(0, &format!("G0X{h}")).unwrap();
                    }
                    let mut flash = st.into_flash();
                    flash.ops = 0;
                    flash.cut_at = Some(cut);
                    flash.mode = mode;
                    let mut st = store(flash);
                    let _ = if target == 0 {
                        st.save_coords(&c_new)
                    } else {
                        st.save_startup(1, "G90")
                    };
                    let mut flash = st.into_flash();
                    if !flash.dead {
                        break;
                    }
                    scenarios += 1;
                    flash.reboot();
                    let mut st = store(flash);
                    let case = format!("history {history}, key {target}, cut {cut}, {mode:?}");
                    assert_eq!(
                        load_settings(&mut st),
                        (s.clone(), LoadStatus::Loaded),
                        "{case}"
                    );
                    let (c, status) = st.load_coords();
                    assert_eq!(status, LoadStatus::Loaded, "{case}");
                    assert!(c == c_old || (target == 0 && c == c_new), "{case}");
                    let line = st.load_startup(1).0;
                    assert!(
                        line == "G21" || (target == 1 && line == "G90"),
                        "{case}: {line}"
                    );
                    // Keep saving: pages left dirty by the cut are cleaned before use.
                    for k in 0..10 {
                        let v = with(101, 60.0 + k as f32);
                        st.save_settings(&v)
                            .unwrap_or_else(|e| panic!("{case}: {e:?}"));
                        st.save_startup(0, "G1").unwrap();
                        assert_eq!(load_settings(&mut st), (v, LoadStatus::Loaded), "{case}");
                        assert_eq!(st.load_coords().0, c, "{case}");
                        assert_eq!(st.load_startup(1).0, line, "{case}");
                    }
                }
            }
        }
    }
    assert!(scenarios > 100, "{scenarios}");
}

#[test]
fn corrupt_storage_falls_back_to_defaults_and_reports_it() {
    // Random bytes all over the region.
    let mut flash = CutFlash::new();
    for i in 0..SIZE {
        flash.mem[i] = flash.rand();
    }
    let mut st = store(flash);
    let (s, status) = load_settings(&mut st);
    assert_eq!(s, Settings::default());
    assert_eq!(status, LoadStatus::Corrupt);
    // A value that the storage layer accepts but that is not a settings image.
    let mut st = store(CutFlash::new());
    st.save_settings(&with(100, 90.0)).unwrap();
    let mut flash = st.into_flash();
    // Flip bits inside the stored image's values (0 bits set to 1 are what decay does).
    let pos = flash
        .mem
        .windows(2)
        .position(|w| w == b"IS")
        .expect("image stored");
    flash.mem[pos + 10] ^= 0x01;
    let mut st = store(flash);
    let (s, status) = load_settings(&mut st);
    assert_eq!(s, Settings::default());
    assert_eq!(status, LoadStatus::Corrupt);
    assert_eq!(
        status.message(),
        Some("Stored data corrupt, defaults restored")
    );
    // Saving again repairs it.
    st.save_settings(&with(100, 91.0)).unwrap();
    assert_eq!(load_settings(&mut st).1, LoadStatus::Loaded);
}
