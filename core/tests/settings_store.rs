//! The settings store survives a power cut at every write and erase step: the next boot
//! loads the old or the new value, never garbage; corrupt storage gives defaults and
//! says so.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use inkstep_core::gcode::interpreter::Coords;
use inkstep_core::settings::Settings;
use inkstep_core::settings_store::{BlockingFlash, LoadStatus, SettingsStore};
use std::ops::Range;

/// The pages memory.x gives the store on the STM32F103CB (0x0801_F000..0x0802_0000), as
/// flash offsets.
const STORE_RANGE: Range<u32> = 0x1_F000..0x2_0000;
const PAGE: usize = 1024;
const BASE: u32 = STORE_RANGE.start;
const SIZE: usize = (STORE_RANGE.end - STORE_RANGE.start) as usize;

#[derive(Debug, Clone, Copy, PartialEq)]
enum MockError {
    PowerCut,
    OutOfBounds,
}
impl NorFlashError for MockError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            MockError::PowerCut => NorFlashErrorKind::Other,
            MockError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
        }
    }
}

/// How the operation that the power fails in is left.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Cut {
    /// Not started.
    Before,
    /// The first half of its bytes done, in address order (the model
    /// log-structured flash stores are usually tested against).
    Prefix,
    /// Writes: half the words done and the next one half-programmed (random bits of
    /// it still 1). Erases: as `Prefix`.
    TornWord,
    /// Erases: every bit of the page in a random state (harsher than the crate's
    /// model). Writes: as `TornWord`.
    RandomErase,
}

/// STM32F1-like flash: 16-bit program unit that must be erased (0xFFFF) before it is
/// programmed, 1 KB pages. Power fails in write/erase number `cut_at`.
struct CutFlash {
    mem: Vec<u8>,
    ops: usize,
    cut_at: Option<usize>,
    mode: Cut,
    dead: bool,
    rng: u64,
}

impl CutFlash {
    fn new() -> Self {
        CutFlash {
            mem: vec![0xFF; SIZE],
            ops: 0,
            cut_at: None,
            mode: Cut::Before,
            dead: false,
            rng: 0x1234_5678,
        }
    }
    fn rand(&mut self) -> u8 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        self.rng as u8
    }
    fn range(&self, offset: u32, len: usize) -> Result<std::ops::Range<usize>, MockError> {
        let start = offset.checked_sub(BASE).ok_or(MockError::OutOfBounds)? as usize;
        if start + len > SIZE {
            return Err(MockError::OutOfBounds);
        }
        Ok(start..start + len)
    }
    /// True if this operation is the one the power fails on.
    fn cut_now(&mut self) -> Result<bool, MockError> {
        if self.dead {
            return Err(MockError::PowerCut);
        }
        let op = self.ops;
        self.ops += 1;
        Ok(self.cut_at == Some(op))
    }
    /// Power back on.
    fn reboot(&mut self) {
        self.dead = false;
        self.cut_at = None;
    }
}

impl ErrorType for CutFlash {
    type Error = MockError;
}
impl ReadNorFlash for CutFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), MockError> {
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.mem[r]);
        Ok(())
    }
    fn capacity(&self) -> usize {
        SIZE
    }
}
impl NorFlash for CutFlash {
    const WRITE_SIZE: usize = 2;
    const ERASE_SIZE: usize = PAGE;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), MockError> {
        let r = self.range(from, (to - from) as usize)?;
        assert!(r.start % PAGE == 0 && r.end % PAGE == 0, "unaligned erase");
        if self.cut_now()? {
            match self.mode {
                Cut::Before => {}
                Cut::Prefix | Cut::TornWord => self.mem[r.start..r.start + PAGE / 2].fill(0xFF),
                Cut::RandomErase => {
                    for i in r {
                        self.mem[i] |= self.rand();
                    }
                }
            }
            self.dead = true;
            return Err(MockError::PowerCut);
        }
        self.mem[r].fill(0xFF);
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), MockError> {
        let r = self.range(offset, bytes.len())?;
        assert!(
            r.start.is_multiple_of(2) && bytes.len().is_multiple_of(2),
            "unaligned write"
        );
        for (w, i) in bytes.chunks(2).zip(r.clone().step_by(2)) {
            let old = [self.mem[i], self.mem[i + 1]];
            assert!(
                old == [0xFF, 0xFF] || w == [0, 0],
                "programming a word that is not erased at {i:#x}"
            );
        }
        let cut = self.cut_now()?;
        let words = bytes.len() / 2;
        let done = match (cut, self.mode) {
            (false, _) => words,
            (true, Cut::Before) => 0,
            (true, _) => words / 2,
        };
        for k in 0..done {
            self.mem[r.start + 2 * k] = bytes[2 * k];
            self.mem[r.start + 2 * k + 1] = bytes[2 * k + 1];
        }
        if cut {
            if self.mode == Cut::Prefix && !bytes.len().is_multiple_of(4) && words > 0 {
                // Byte order: the odd byte of the middle word lands too.
                self.mem[r.start + 2 * done] = bytes[2 * done];
            } else if matches!(self.mode, Cut::TornWord | Cut::RandomErase) && done < words {
                // Half-programmed word: some of its 0 bits did not make it.
                for b in 0..2 {
                    let i = r.start + 2 * done + b;
                    self.mem[i] = bytes[2 * done + b] | self.rand();
                }
            }
            self.dead = true;
            return Err(MockError::PowerCut);
        }
        Ok(())
    }
}

fn store(flash: CutFlash) -> SettingsStore<BlockingFlash<CutFlash>> {
    SettingsStore::new(BlockingFlash(flash), STORE_RANGE).unwrap()
}

fn with(n: u16, v: f32) -> Settings {
    let mut s = Settings::default();
    s.set(n, v).unwrap();
    s
}

#[test]
fn first_boot_is_empty_not_corrupt() {
    let mut st = store(CutFlash::new());
    let (s, status) = st.load_settings();
    assert_eq!((s, status), (Settings::default(), LoadStatus::Empty));
    assert_eq!(status.message(), None);
}

#[test]
fn round_trip_of_settings_coords_and_startup_lines() {
    let mut st = store(CutFlash::new());
    let s = with(100, 123.5);
    st.save_settings(&s).unwrap();
    let mut c = Coords::default();
    c.wcs[1] = [1.0, -2.0, 3.5];
    c.g28 = [10.0, 20.0, 0.0];
    st.save_coords(&c).unwrap();
    st.save_startup(1, "G21G90").unwrap();
    let mut st = store(st.into_flash().0);
    assert_eq!(st.load_settings(), (s, LoadStatus::Loaded));
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
                let mut flash = st.into_flash().0;
                flash.ops = 0;
                flash.cut_at = Some(cut);
                flash.mode = mode;
                let mut st = store(flash);
                let result = st.save_settings(&new);
                let mut flash = st.into_flash().0;
                let was_cut = flash.dead;
                if !was_cut {
                    assert!(result.is_ok());
                    max_ops = max_ops.max(cut);
                    break;
                }
                scenarios += 1;
                flash.reboot();
                let mut st = store(flash);
                let (loaded, status) = st.load_settings();
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
                assert_eq!(st.load_settings().0, newer);
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
        g28: [1.0, 2.0, 3.0],
        ..Coords::default()
    };
    let c_new = Coords {
        g28: [4.0, 5.0, 6.0],
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
                    let mut flash = st.into_flash().0;
                    flash.ops = 0;
                    flash.cut_at = Some(cut);
                    flash.mode = mode;
                    let mut st = store(flash);
                    let _ = if target == 0 {
                        st.save_coords(&c_new)
                    } else {
                        st.save_startup(1, "G90")
                    };
                    let mut flash = st.into_flash().0;
                    if !flash.dead {
                        break;
                    }
                    scenarios += 1;
                    flash.reboot();
                    let mut st = store(flash);
                    let case = format!("history {history}, key {target}, cut {cut}, {mode:?}");
                    assert_eq!(
                        st.load_settings(),
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
                        assert_eq!(st.load_settings(), (v, LoadStatus::Loaded), "{case}");
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
    let (s, status) = st.load_settings();
    assert_eq!(s, Settings::default());
    assert_eq!(status, LoadStatus::Corrupt);
    // A value that the storage layer accepts but that is not a settings image.
    let mut st = store(CutFlash::new());
    st.save_settings(&with(100, 90.0)).unwrap();
    let mut flash = st.into_flash().0;
    // Flip bits inside the stored image's values (0 bits set to 1 are what decay does).
    let pos = flash
        .mem
        .windows(2)
        .position(|w| w == b"IS")
        .expect("image stored");
    flash.mem[pos + 10] ^= 0x01;
    let mut st = store(flash);
    let (s, status) = st.load_settings();
    assert_eq!(s, Settings::default());
    assert_eq!(status, LoadStatus::Corrupt);
    assert_eq!(
        status.message(),
        Some("Stored data corrupt, defaults restored")
    );
    // Saving again repairs it.
    st.save_settings(&with(100, 91.0)).unwrap();
    assert_eq!(st.load_settings().1, LoadStatus::Loaded);
}
