//! Persistence of the settings, the coordinate data and the `$N` startup lines in the
//! MCU's internal flash, power-loss safe.
//!
//! Built on `sequential-storage`'s key-value map: every save appends a new item (CRC
//! protected by the crate) and only after it is complete does it shadow the old one,
//! and pages are erased only after their live items were copied, so a power cut at any
//! write or erase leaves either the old or the new value. On top, each value carries
//! its own version and CRC-32 ([`Settings::to_image`]), so a stale layout or damaged
//! data is never taken for settings: the store falls back to defaults and says so.
//!
//! The crate is async; the firmware awaits it from an RTIC task and host code can use
//! [`block_on`]. [`BlockingFlash`] adapts a blocking `embedded-storage` flash (such as
//! the stm32f1xx-hal writer) to the async traits.

use crate::gcode::interp::Coords;
use crate::motion::AXES;
use crate::protocol::{StartupLine, LINE_MAX, STARTUP_LINES};
use crate::settings::{crc32, Settings, IMAGE_LEN};
use core::future::Future;
use core::ops::Range;
use core::pin::pin;
use core::task::{Context, Poll, Waker};
use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

/// Flash range the firmware gives the store: the last four 1 KB pages of the 64 KB
/// part (0x0800_F000..0x0801_0000), as offsets from the start of flash, which is how
/// stm32f1xx-hal's flash writer addresses it.
pub const STORE_RANGE: Range<u32> = 0xF000..0x1_0000;

const KEY_SETTINGS: u8 = 0;
const KEY_COORDS: u8 = 1;
const KEY_STARTUP: u8 = 2; // 2 .. 2 + STARTUP_LINES

/// Coordinate image: version, 8 x 3 floats, CRC-32.
const COORDS_LEN: usize = 1 + 8 * AXES * 4 + 4;
const COORDS_VERSION: u8 = 1;
/// Working buffer: the largest value plus the key, rounded up to the flash word.
const BUF_LEN: usize = 256;

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
    Storage(sequential_storage::Error<E>),
    /// The flash was lost in an earlier failed scan (only after a driver error).
    NoFlash,
}

impl<E> From<sequential_storage::Error<E>> for StoreError<E> {
    fn from(e: sequential_storage::Error<E>) -> Self {
        StoreError::Storage(e)
    }
}

type Map<F> = MapStorage<u8, F, Cache<Uncached, Uncached, Uncached, u8>>;

/// The store over a flash region.
pub struct SettingsStore<F: NorFlash> {
    map: Option<Map<F>>,
    range: Range<u32>,
    buf: [u8; BUF_LEN],
}

impl<F: NorFlash> SettingsStore<F> {
    /// `range` must be page aligned and hold at least two pages.
    pub fn new(
        flash: F,
        range: Range<u32>,
    ) -> Result<Self, sequential_storage::map::MapConfigError> {
        let config = MapConfig::try_new(range.clone())?;
        let map = MapStorage::new(flash, config, Cache::new_uncached());
        Ok(SettingsStore {
            map: Some(map),
            range,
            buf: [0; BUF_LEN],
        })
    }

    /// Give the flash back (tests use it to "power-cycle").
    pub fn into_flash(self) -> Option<F> {
        self.map.map(|m| m.destroy().0)
    }

    /// True if every byte of the region reads as erased. Used to tell a first boot
    /// (blank) from storage that holds something the map cannot make sense of.
    async fn region_blank(&mut self) -> bool {
        let Some(map) = self.map.take() else {
            return false;
        };
        let (mut flash, cache) = map.destroy();
        let mut blank = true;
        let mut chunk = [0u8; 64];
        let mut addr = self.range.start;
        while blank && addr < self.range.end {
            let n = ((self.range.end - addr) as usize).min(chunk.len());
            let part = chunk.get_mut(..n).unwrap_or(&mut []);
            blank = flash.read(addr, part).await.is_ok() && part.iter().all(|&b| b == 0xFF);
            addr += n as u32;
        }
        if let Ok(config) = MapConfig::try_new(self.range.clone()) {
            self.map = Some(MapStorage::new(flash, config, cache));
        }
        blank
    }

    /// Store `bytes` under `key`. If the map finds its pages inconsistent (a power cut
    /// beyond what it can repair), the region is wiped and the value written to a
    /// clean region: what was unreadable is lost, the new value is kept.
    async fn store_raw(&mut self, key: u8, bytes: &[u8]) -> Result<(), StoreError<F::Error>> {
        let map = self.map.as_mut().ok_or(StoreError::NoFlash)?;
        match map.store_item(&mut self.buf, &key, &bytes).await {
            Err(sequential_storage::Error::Corrupted { .. }) => {
                map.erase_all().await?;
                map.store_item(&mut self.buf, &key, &bytes).await?;
                Ok(())
            }
            r => Ok(r?),
        }
    }

    /// Fetch the raw bytes of `key` into `out`; the status says what was found.
    async fn fetch(&mut self, key: u8, out: &mut [u8]) -> (usize, LoadStatus) {
        let Some(map) = self.map.as_mut() else {
            return (0, LoadStatus::Corrupt);
        };
        match map.fetch_item::<&[u8]>(&mut self.buf, &key).await {
            Ok(Some(bytes)) if bytes.len() <= out.len() => {
                if let Some(dst) = out.get_mut(..bytes.len()) {
                    dst.copy_from_slice(bytes);
                }
                (bytes.len(), LoadStatus::Loaded)
            }
            Ok(Some(_)) => (0, LoadStatus::Corrupt),
            Ok(None) => (0, LoadStatus::Empty),
            Err(_) => {
                // Unreadable region: wipe it so that the next save starts clean.
                let _ = map.erase_all().await;
                (0, LoadStatus::Corrupt)
            }
        }
    }

    /// Load the settings, or defaults with the reason. Settings are the first thing
    /// the firmware saves, so a region that is not blank but holds no settings is
    /// reported as corrupt rather than taken for a first boot.
    pub async fn load_settings(&mut self) -> (Settings, LoadStatus) {
        let mut img = [0u8; IMAGE_LEN];
        let fetched = self.fetch(KEY_SETTINGS, &mut img).await;
        match fetched {
            (_, LoadStatus::Empty) if !self.region_blank().await => {
                (Settings::default(), LoadStatus::Corrupt)
            }
            (len, LoadStatus::Loaded) => {
                match Settings::from_image(img.get(..len).unwrap_or(&[])) {
                    Ok(s) => (s, LoadStatus::Loaded),
                    Err(_) => (Settings::default(), LoadStatus::Corrupt),
                }
            }
            (_, status) => (Settings::default(), status),
        }
    }

    pub async fn save_settings(&mut self, s: &Settings) -> Result<(), StoreError<F::Error>> {
        let img = s.to_image();
        self.store_raw(KEY_SETTINGS, &img).await
    }

    /// Load G54-G59, G28 and G30 data.
    pub async fn load_coords(&mut self) -> (Coords, LoadStatus) {
        let mut img = [0u8; COORDS_LEN];
        match self.fetch(KEY_COORDS, &mut img).await {
            (COORDS_LEN, LoadStatus::Loaded) => match coords_from_image(&img) {
                Some(c) => (c, LoadStatus::Loaded),
                None => (Coords::default(), LoadStatus::Corrupt),
            },
            (_, LoadStatus::Loaded) => (Coords::default(), LoadStatus::Corrupt),
            (_, status) => (Coords::default(), status),
        }
    }

    pub async fn save_coords(&mut self, c: &Coords) -> Result<(), StoreError<F::Error>> {
        let img = coords_to_image(c);
        self.store_raw(KEY_COORDS, &img).await
    }

    /// Load startup line `i` (empty if none or unusable).
    pub async fn load_startup(&mut self, i: usize) -> (StartupLine, LoadStatus) {
        let mut line = StartupLine::new();
        if i >= STARTUP_LINES {
            return (line, LoadStatus::Empty);
        }
        let key = KEY_STARTUP + i as u8;
        let Some(map) = self.map.as_mut() else {
            return (line, LoadStatus::Corrupt);
        };
        let status = match map.fetch_item::<&[u8]>(&mut self.buf, &key).await {
            Ok(Some(bytes)) => match core::str::from_utf8(bytes) {
                Ok(text) if text.len() <= LINE_MAX => {
                    let _ = line.push_str(text);
                    LoadStatus::Loaded
                }
                _ => LoadStatus::Corrupt,
            },
            Ok(None) => LoadStatus::Empty,
            Err(_) => LoadStatus::Corrupt,
        };
        (line, status)
    }

    pub async fn save_startup(&mut self, i: usize, text: &str) -> Result<(), StoreError<F::Error>> {
        let key = KEY_STARTUP + (i.min(STARTUP_LINES - 1)) as u8;
        self.store_raw(key, text.as_bytes()).await
    }
}

fn coords_to_image(c: &Coords) -> [u8; COORDS_LEN] {
    let mut out = [0u8; COORDS_LEN];
    out[0] = COORDS_VERSION;
    let all = c.wcs.iter().chain([&c.g28, &c.g30]).flat_map(|p| p.iter());
    if let Some(body) = out.get_mut(1..COORDS_LEN - 4) {
        for (chunk, v) in body.chunks_exact_mut(4).zip(all) {
            chunk.copy_from_slice(&v.to_le_bytes());
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
    if crc32(body) != u32::from_le_bytes(tail.try_into().ok()?)
        || body.first() != Some(&COORDS_VERSION)
    {
        return None;
    }
    let mut vals = [0.0f32; 8 * AXES];
    for (v, chunk) in vals.iter_mut().zip(body.get(1..)?.chunks_exact(4)) {
        *v = f32::from_le_bytes(chunk.try_into().ok()?);
        if !v.is_finite() {
            return None;
        }
    }
    let mut c = Coords::default();
    let points = c.wcs.iter_mut().chain([&mut c.g28, &mut c.g30]);
    for (p, src) in points.zip(vals.chunks_exact(AXES)) {
        p.copy_from_slice(src);
    }
    Some(c)
}

/// Run a future to completion by polling it. Enough for flash drivers that complete
/// synchronously (the blocking adapter below, the host mocks); never use it on a
/// future that waits for an interrupt.
pub fn block_on<T>(f: impl Future<Output = T>) -> T {
    let mut f = pin!(f);
    let mut cx = Context::from_waker(Waker::noop());
    loop {
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
}

/// Adapter: a blocking `embedded-storage` NOR flash seen through the async traits.
pub struct BlockingFlash<F>(pub F);

impl<F: embedded_storage::nor_flash::ErrorType> embedded_storage_async::nor_flash::ErrorType
    for BlockingFlash<F>
{
    type Error = F::Error;
}

impl<F: embedded_storage::nor_flash::ReadNorFlash> embedded_storage_async::nor_flash::ReadNorFlash
    for BlockingFlash<F>
{
    const READ_SIZE: usize = F::READ_SIZE;
    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes)
    }
    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl<F: embedded_storage::nor_flash::NorFlash> NorFlash for BlockingFlash<F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;
    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.0.erase(from, to)
    }
    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.write(offset, bytes)
    }
}
