//! Persistence of the settings, the coordinate data and the `$N` startup lines in the
//! MCU's internal flash, power-loss safe.
//!
//! A small log-structured store written for this data (a few hundred bytes in all):
//!
//! - The region is a ring of flash pages. A page starts with an 8-byte header
//!   (sequence number and a check word); the valid page with the highest sequence
//!   number is the *current* page, and it always holds the latest value of every key.
//! - A save appends a record to the current page: `[key, len, !key, !len]`, the data,
//!   a CRC-32 of both, padded to 4 bytes. The newest record of a key whose CRC checks
//!   wins; a record torn by a power cut fails its CRC and the older one stays in force.
//! - When the current page is full, the live records (with the new value) are copied
//!   into the next page of the ring, which is kept erased, and only then is its header
//!   written: until that write completes the old page stays current. After it, the old
//!   page is erased. A page is therefore never erased while it holds the only copy of
//!   live data (a next page found not blank, after a cut, is erased before use).
//!
//! A power cut at any write or erase step leaves either the old or the new value. On
//! top, each value carries its own version and CRC-32 ([`Settings::to_image`]), so a
//! stale layout or damaged data is never taken for settings: the store falls back to
//! defaults and says so.
//!
//! The store is synchronous, over any blocking `embedded-storage` NOR flash (the
//! board's internal flash, the simulator's and the tests' mocks): flash writes stall
//! the CPU anyway, and the controller only saves while the machine is at rest.

use crate::crc::crc32;
use crate::gcode::interpreter::Coords;
use crate::gcode::{startup_line, StartupLine, LINE_MAX, STARTUP_LINES};
use crate::motion::AXES;
use crate::settings::{Settings, IMAGE_MAX_LEN};
use core::ops::Range;
use embedded_storage::nor_flash::NorFlash;

const KEY_SETTINGS: u8 = 0;
const KEY_COORDS: u8 = 1;
const KEY_STARTUP: u8 = 2; // 2 .. 2 + STARTUP_LINES
const KEYS: usize = 2 + STARTUP_LINES;

/// Coordinate image: version, 8 x 3 nanometre values (i64), CRC-32. Version 1 held
/// f32 mm; a stored version 1 image reads as corrupt (defaults, and the user is told).
const COORDS_LEN: usize = 1 + 8 * AXES * 8 + 4;
const COORDS_VERSION: u8 = 2;

/// Page header: sequence number, then its CRC-32 mixed with this tag ("inkstep store
/// v1"), so that neither erased flash nor another layout passes for a header.
const PAGE_TAG: u32 = 0x4953_5431;
const PAGE_HEAD: u32 = 8;
/// Record header bytes; the CRC follows the data.
const REC_HEAD: usize = 4;
/// Largest record: header, 255 bytes of data, CRC, padding.
const BUF_LEN: usize = rec_size(255) as usize;
/// The working buffer of one load or save (reads, record staging): on the caller's
/// stack for the duration of the call, not kept in the store (static RAM in the
/// firmware) between the rare loads and saves.
type Buf = [u8; BUF_LEN];

const fn rec_size(len: usize) -> u32 {
    ((REC_HEAD + len + 4 + 3) & !3) as u32
}

/// What the load found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LoadStatus {
    /// A valid stored value.
    Loaded,
    /// Nothing stored yet (first boot): defaults, nothing to report.
    Empty,
    /// Something was stored but could not be used: defaults, tell the user.
    Corrupt,
}

impl LoadStatus {
    /// The `[MSG:...]` text the protocol should show, if any.
    pub fn message(self) -> Option<&'static str> {
        match self {
            LoadStatus::Corrupt => Some("Stored data corrupt, defaults restored"),
            _ => None,
        }
    }
}

/// A save failed.
#[derive(Debug)]
pub enum StoreError<E> {
    /// The flash driver reported an error.
    Flash(E),
    /// The live data does not fit one page (pages smaller than the data).
    Full,
}

impl<E> From<E> for StoreError<E> {
    fn from(e: E) -> Self {
        StoreError::Flash(e)
    }
}

/// The region given to [`SettingsStore::new`] is not at least two whole pages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RangeError;

/// Where the latest valid records of the current page are, and where it has room.
struct Scan {
    /// Page start (absolute flash offset) and sequence number.
    page: u32,
    seq: u32,
    /// Offset (absolute) and data length of each key's newest valid record.
    latest: [Option<(u32, u8)>; KEYS],
    /// Absolute offset of the free space (the page end if full).
    free: u32,
}

impl Scan {
    const EMPTY: Scan = Scan {
        page: 0,
        seq: 0,
        latest: [None; KEYS],
        free: 0,
    };
}

/// The store over a flash region.
pub struct SettingsStore<F> {
    flash: F,
    range: Range<u32>,
    page_size: u32,
}

impl<F: NorFlash> SettingsStore<F> {
    /// `range` must be page aligned and hold at least two pages.
    pub fn new(flash: F, range: Range<u32>) -> Result<Self, RangeError> {
        let page_size = F::ERASE_SIZE as u32;
        if page_size < rec_size(255) * 2
            || !range.start.is_multiple_of(page_size)
            || !range.end.is_multiple_of(page_size)
            || range.end < range.start + 2 * page_size
        {
            return Err(RangeError);
        }
        Ok(SettingsStore {
            flash,
            range,
            page_size,
        })
    }

    /// Give the flash back (tests use it to "power-cycle").
    pub fn into_flash(self) -> F {
        self.flash
    }

    fn read<'b>(&mut self, buf: &'b mut Buf, addr: u32, len: usize) -> Result<&'b [u8], F::Error> {
        let part = buf.get_mut(..len).unwrap_or(&mut []);
        self.flash.read(addr, part)?;
        Ok(part)
    }

    /// True if every byte of `from..to` reads as erased.
    fn blank(&mut self, buf: &mut Buf, mut from: u32, to: u32) -> bool {
        while from < to {
            let n = ((to - from) as usize).min(BUF_LEN);
            match self.read(buf, from, n) {
                Ok(b) if b.iter().all(|&x| x == 0xFF) => from += n as u32,
                _ => return false,
            }
        }
        true
    }

    /// The current page: the valid header with the highest sequence number.
    fn current(&mut self, buf: &mut Buf) -> Option<(u32, u32)> {
        let mut best: Option<(u32, u32)> = None;
        let mut page = self.range.start;
        while page < self.range.end {
            if let Ok(h) = self.read(buf, page, PAGE_HEAD as usize) {
                let seq = le32(h, 0);
                if le32(h, 4) == crc32(&seq.to_le_bytes()) ^ PAGE_TAG
                    && best.is_none_or(|(_, s)| seq > s)
                {
                    best = Some((page, seq));
                }
            }
            page += self.page_size;
        }
        best
    }

    /// Walk the records of the current page into `s` (filled in place, not moved
    /// through an `Option`); false if no page is valid.
    fn scan(&mut self, buf: &mut Buf, s: &mut Scan) -> bool {
        let Some((page, seq)) = self.current(buf) else {
            return false;
        };
        let end = page + self.page_size;
        *s = Scan {
            page,
            seq,
            latest: [None; KEYS],
            free: end,
        };
        let mut at = page + PAGE_HEAD;
        while at < end {
            let size = match self.read(buf, at, REC_HEAD) {
                Ok(&[k, n, nk, nn]) if k == !nk && n == !nn => rec_size(usize::from(n)),
                _ => 0,
            };
            if size == 0 || at + size > end {
                // Erased (the free space) or a torn header: full unless blank.
                if self.blank(buf, at, end) {
                    s.free = at;
                }
                break;
            }
            if let Ok(r @ [k, n, ..]) = self.read(buf, at, size as usize) {
                let (k, n) = (*k, *n);
                let body = REC_HEAD + usize::from(n);
                let ok = r.get(..body).map(crc32) == Some(le32(r, body));
                if let (true, Some(slot)) = (ok, s.latest.get_mut(usize::from(k))) {
                    *slot = Some((at, n));
                }
            }
            at += size;
        }
        true
    }

    /// Fetch the newest valid value of `key` into `out`.
    fn fetch(&mut self, buf: &mut Buf, key: u8, out: &mut [u8]) -> (usize, LoadStatus) {
        let mut s = Scan::EMPTY;
        let latest = if self.scan(buf, &mut s) {
            s.latest.get(usize::from(key)).copied().flatten()
        } else {
            None
        };
        let Some((at, n)) = latest else {
            return (0, LoadStatus::Empty);
        };
        let n = usize::from(n);
        let read = match out.get_mut(..n) {
            Some(dst) => self.flash.read(at + REC_HEAD as u32, dst).is_ok(),
            None => false,
        };
        if read {
            (n, LoadStatus::Loaded)
        } else {
            (0, LoadStatus::Corrupt)
        }
    }

    /// Write the record for `key` (data in `buf[REC_HEAD..]`) at `at`.
    fn write_record(&mut self, buf: &mut Buf, at: u32, key: u8, n: u8) -> Result<u32, F::Error> {
        let body = REC_HEAD + usize::from(n);
        let size = rec_size(usize::from(n)) as usize;
        if let Some(h) = buf.get_mut(..REC_HEAD) {
            h.copy_from_slice(&[key, n, !key, !n]);
        }
        // The CRC, then erased flash (0xFF) up to the word boundary.
        let crc = crc32(buf.get(..body).unwrap_or(&[])).to_le_bytes();
        let tail = crc.into_iter().chain(core::iter::repeat(0xFF));
        for (d, b) in buf.iter_mut().take(size).skip(body).zip(tail) {
            *d = b;
        }
        self.flash.write(at, buf.get(..size).unwrap_or(&[]))?;
        Ok(size as u32)
    }

    /// Store `bytes` under `key`: append to the current page, or move the live data
    /// with the new value to the next page of the ring.
    fn store_raw(&mut self, key: u8, bytes: &[u8]) -> Result<(), StoreError<F::Error>> {
        let n = u8::try_from(bytes.len()).map_err(|_| StoreError::Full)?;
        let size = rec_size(bytes.len());
        let mut buf: Buf = [0; BUF_LEN];
        let buf = &mut buf;
        let mut found = Scan::EMPTY;
        let scan = if self.scan(buf, &mut found) {
            Some(&found)
        } else {
            None
        };
        let stage = |buf: &mut Buf| {
            // Past the header (a record always fits the buffer: `rec_size`), byte by
            // byte: no length-mismatch panic for the compiler to keep.
            let data = buf.iter_mut().skip(REC_HEAD);
            for (d, &b) in data.zip(bytes) {
                *d = b;
            }
        };
        if let Some(s) = scan {
            if s.free + size <= s.page + self.page_size {
                stage(buf);
                self.write_record(buf, s.free, key, n)?;
                return Ok(());
            }
        }
        // Next page of the ring (the first if nothing valid is stored).
        let (target, seq) = match scan {
            Some(s) if s.page + self.page_size < self.range.end => (s.page + self.page_size, s.seq),
            Some(s) => (self.range.start, s.seq),
            None => (self.range.start, 0),
        };
        let end = target + self.page_size;
        // Normally erased when it was vacated; not after a cut or on a dirty region.
        if !self.blank(buf, target, end) {
            self.flash.erase(target, end)?;
        }
        let mut at = target + PAGE_HEAD;
        for k in 0..KEYS as u8 {
            let old = scan.and_then(|s| s.latest.get(usize::from(k)).copied().flatten());
            let n = if k == key {
                stage(buf);
                n
            } else if let Some((from, n)) = old {
                let data = buf.get_mut(REC_HEAD..REC_HEAD + usize::from(n));
                self.flash
                    .read(from + REC_HEAD as u32, data.unwrap_or(&mut []))?;
                n
            } else {
                continue;
            };
            if at + rec_size(usize::from(n)) > end {
                return Err(StoreError::Full);
            }
            at += self.write_record(buf, at, k, n)?;
        }
        // The header last: only now does the new page take over.
        let seq = seq.wrapping_add(1);
        let head = [
            seq.to_le_bytes(),
            (crc32(&seq.to_le_bytes()) ^ PAGE_TAG).to_le_bytes(),
        ];
        self.flash.write(target, head.as_flattened())?;
        // Everything live is in the new page: vacate the old one.
        if let Some(s) = scan {
            self.flash.erase(s.page, s.page + self.page_size)?;
        }
        Ok(())
    }

    /// Load the stored settings into `settings` (which holds the defaults), or leave
    /// it unchanged and say why. Settings are the first thing the firmware saves, so a
    /// region that is not blank but holds no settings is reported as corrupt rather
    /// than taken for a first boot. In place: the caller's table is the only copy.
    pub fn load_settings(&mut self, settings: &mut Settings) -> LoadStatus {
        let mut buf: Buf = [0; BUF_LEN];
        let mut img = [0u8; IMAGE_MAX_LEN];
        match self.fetch(&mut buf, KEY_SETTINGS, &mut img) {
            (_, LoadStatus::Empty) if !self.blank(&mut buf, self.range.start, self.range.end) => {
                LoadStatus::Corrupt
            }
            (len, LoadStatus::Loaded) => match settings.read_image(img.get(..len).unwrap_or(&[])) {
                Ok(()) => LoadStatus::Loaded,
                Err(_) => LoadStatus::Corrupt,
            },
            (_, status) => status,
        }
    }

    pub fn save_settings(&mut self, s: &Settings) -> Result<(), StoreError<F::Error>> {
        self.store_raw(KEY_SETTINGS, &s.to_image())
    }

    /// Load G54-G59, G28 and G30 data.
    pub fn load_coords(&mut self) -> (Coords, LoadStatus) {
        let mut buf: Buf = [0; BUF_LEN];
        let mut img = [0u8; COORDS_LEN];
        let status = match self.fetch(&mut buf, KEY_COORDS, &mut img) {
            (COORDS_LEN, LoadStatus::Loaded) => match coords_from_image(&img) {
                Some(c) => return (c, LoadStatus::Loaded),
                None => LoadStatus::Corrupt,
            },
            (_, LoadStatus::Loaded) => LoadStatus::Corrupt,
            (_, status) => status,
        };
        (Coords::default(), status)
    }

    pub fn save_coords(&mut self, c: &Coords) -> Result<(), StoreError<F::Error>> {
        self.store_raw(KEY_COORDS, &coords_to_image(c))
    }

    /// Load startup line `i` (empty if none or unusable).
    pub fn load_startup(&mut self, i: usize) -> (StartupLine, LoadStatus) {
        if i >= STARTUP_LINES {
            return (StartupLine::new(), LoadStatus::Empty);
        }
        let mut buf: Buf = [0; BUF_LEN];
        let mut raw = [0u8; LINE_MAX + 1];
        match self.fetch(&mut buf, KEY_STARTUP + i as u8, &mut raw) {
            (len, LoadStatus::Loaded) => match raw.get(..len).and_then(startup_line) {
                Some(line) => (line, LoadStatus::Loaded),
                None => (StartupLine::new(), LoadStatus::Corrupt),
            },
            (_, status) => (StartupLine::new(), status),
        }
    }

    pub fn save_startup(&mut self, i: usize, text: &str) -> Result<(), StoreError<F::Error>> {
        let key = KEY_STARTUP + (i.min(STARTUP_LINES - 1)) as u8;
        self.store_raw(key, text.as_bytes())
    }
}

fn le32(b: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(s) = b.get(at..at + 4) {
        w.copy_from_slice(s);
    }
    u32::from_le_bytes(w)
}

fn coords_to_image(c: &Coords) -> [u8; COORDS_LEN] {
    // The version is byte 0; the body and CRC below overwrite every other byte.
    let mut out = [COORDS_VERSION; COORDS_LEN];
    if let Some(body) = out.get_mut(1..COORDS_LEN - 4) {
        // Point by point, then axis by axis (one flattened iterator kept more state
        // than the loop does work).
        let mut chunks = body.chunks_exact_mut(8);
        for p in c.wcs.iter().chain([&c.g28, &c.g30]) {
            for (v, chunk) in p.iter().zip(chunks.by_ref()) {
                chunk.copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    let crc = crc32(out.get(..COORDS_LEN - 4).unwrap_or(&[]));
    if let Some(tail) = out.get_mut(COORDS_LEN - 4..) {
        tail.copy_from_slice(&crc.to_le_bytes());
    }
    out
}

fn coords_from_image(img: &[u8; COORDS_LEN]) -> Option<Coords> {
    let (body, tail) = img.split_at(COORDS_LEN - 4);
    if crc32(body) != le32(tail, 0) || body.first() != Some(&COORDS_VERSION) {
        return None;
    }
    let mut c = Coords::default();
    let mut chunks = body.get(1..)?.chunks_exact(8);
    for p in c.wcs.iter_mut().chain([&mut c.g28, &mut c.g30]) {
        for v in p.iter_mut() {
            *v = i64::from_le_bytes(chunks.next()?.try_into().ok()?);
        }
    }
    Some(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_storage::nor_flash::{ErrorType, NorFlashErrorKind, ReadNorFlash};

    /// Two erased 1 KB pages of NOR flash in RAM (writes only clear bits).
    struct RamFlash([u8; 2048]);
    impl ErrorType for RamFlash {
        type Error = NorFlashErrorKind;
    }
    impl ReadNorFlash for RamFlash {
        const READ_SIZE: usize = 1;
        fn read(&mut self, at: u32, out: &mut [u8]) -> Result<(), Self::Error> {
            let src = self.0.get(at as usize..at as usize + out.len());
            out.copy_from_slice(src.ok_or(NorFlashErrorKind::OutOfBounds)?);
            Ok(())
        }
        fn capacity(&self) -> usize {
            self.0.len()
        }
    }
    impl NorFlash for RamFlash {
        const WRITE_SIZE: usize = 2;
        const ERASE_SIZE: usize = 1024;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            let dst = self.0.get_mut(from as usize..to as usize);
            dst.ok_or(NorFlashErrorKind::OutOfBounds)?.fill(0xFF);
            Ok(())
        }
        fn write(&mut self, at: u32, data: &[u8]) -> Result<(), Self::Error> {
            let dst = self.0.get_mut(at as usize..at as usize + data.len());
            for (d, s) in dst
                .ok_or(NorFlashErrorKind::OutOfBounds)?
                .iter_mut()
                .zip(data)
            {
                *d &= *s;
            }
            Ok(())
        }
    }

    /// Settings saved by a build before `$211` was retired load after the update, every
    /// value kept (not "corrupt, defaults").
    #[test]
    fn settings_saved_by_the_version_1_layout_load_after_the_update() {
        let mut st = SettingsStore::new(RamFlash([0xFF; 2048]), 0..2048).unwrap();
        let mut saved = Settings::default();
        saved.set(100, 123.25).unwrap();
        saved.set(210, 1.0).unwrap();
        saved.set(212, 0.0).unwrap();
        saved.set(218, 7.5).unwrap();
        st.store_raw(KEY_SETTINGS, &crate::settings::v1_image(&saved, 52))
            .unwrap();
        let mut loaded = Settings::default();
        assert_eq!(st.load_settings(&mut loaded), LoadStatus::Loaded);
        assert_eq!(loaded, saved);
    }
}
