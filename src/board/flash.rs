//! The internal flash: its size, the settings store's pages (from memory.x) and the
//! NOR-flash driver the store writes them with.

use stm32f1xx_hal::flash;

/// Flash pages are 1 KB on the medium-density STM32F103 (RM0008 3.3.3).
pub const FLASH_PAGE_SIZE: u32 = 1024;
/// The chip's flash: 128 KB on the STM32F103CB this firmware is built for.
pub const FLASH_SIZE: u32 = 128 * 1024;

/// The settings store's flash pages, as chip flash offsets (0 = 0x0800_0000, how the
/// store addresses them). memory.x places them (`_settings_start`, `_settings_end`) and
/// links the program below them; this reads the symbols, so their place is said once.
pub fn settings_pages() -> core::ops::Range<u32> {
    extern "C" {
        static _settings_start: u8;
        static _settings_end: u8;
    }
    // Only the symbols' addresses are taken, never their contents.
    let start = core::ptr::addr_of!(_settings_start) as u32;
    let end = core::ptr::addr_of!(_settings_end) as u32;
    (start - FLASH_BASE)..(end - FLASH_BASE)
}

/// The flash size the chip reports (its F_SIZE register, RM0008 30.1), in KB: 128 on a
/// CB, 64 on a C8.
pub fn flash_size_kb() -> u32 {
    const F_SIZE: *const u16 = 0x1FFF_F7E0 as *const u16;
    // SAFETY: F_SIZE is a read-only factory register, always mapped.
    u32::from(unsafe { core::ptr::read_volatile(F_SIZE) })
}

/// The internal flash as a NOR flash (embedded-storage traits) for the power-loss-safe
/// settings store in the core, through the HAL's `FlashWriter` (1 KB pages, 128 KB,
/// every erase and write verified by reading it back). Offsets are chip flash offsets
/// (0 = 0x0800_0000); reads may look anywhere in the 128 KB, writes and erases only
/// inside [`settings_pages`], so a store bug can never overwrite the program.
///
/// Programming stalls instruction fetch from flash for the duration of a write (~50 us
/// per half-word) or erase (~20 ms per page), so the core only saves at rest.
pub struct SettingsFlash {
    /// Owned so that nothing else reaches the flash controller.
    parts: flash::Parts,
}

/// Where the flash is mapped.
const FLASH_BASE: u32 = flash::FLASH_START;

impl SettingsFlash {
    pub(super) fn new(parts: flash::Parts) -> Self {
        Self { parts }
    }

    fn writer(&mut self) -> flash::FlashWriter<'_> {
        self.parts
            .writer(flash::SectorSize::Sz1K, flash::FlashSize::Sz128K)
    }
}

/// Why a flash operation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum FlashError {
    /// A write or erase outside the settings pages, or a read outside the flash.
    OutOfBounds,
    /// The flash controller reported an error, or what it wrote did not read back.
    Failed,
}

impl embedded_storage::nor_flash::NorFlashError for FlashError {
    fn kind(&self) -> embedded_storage::nor_flash::NorFlashErrorKind {
        match self {
            FlashError::OutOfBounds => embedded_storage::nor_flash::NorFlashErrorKind::OutOfBounds,
            FlashError::Failed => embedded_storage::nor_flash::NorFlashErrorKind::Other,
        }
    }
}

impl embedded_storage::nor_flash::ErrorType for SettingsFlash {
    type Error = FlashError;
}

/// `offset..offset + len` lies inside `range`.
fn within(offset: u32, len: usize, range: core::ops::Range<u32>) -> bool {
    let Ok(len) = u32::try_from(len) else {
        return false;
    };
    offset >= range.start && offset.checked_add(len).is_some_and(|end| end <= range.end)
}

impl embedded_storage::nor_flash::ReadNorFlash for SettingsFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        if !within(offset, bytes.len(), 0..FLASH_SIZE) {
            return Err(FlashError::OutOfBounds);
        }
        let writer = self.writer();
        let data = writer
            .read(offset, bytes.len())
            .map_err(|_| FlashError::Failed)?;
        // The HAL hands back `bytes.len()` bytes; copied pairwise, so that no
        // length-mismatch panic stays in the image.
        for (b, &d) in bytes.iter_mut().zip(data) {
            *b = d;
        }
        Ok(())
    }
    fn capacity(&self) -> usize {
        FLASH_SIZE as usize
    }
}

impl embedded_storage::nor_flash::NorFlash for SettingsFlash {
    const WRITE_SIZE: usize = 2;
    const ERASE_SIZE: usize = FLASH_PAGE_SIZE as usize;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let len = to.checked_sub(from).ok_or(FlashError::OutOfBounds)? as usize;
        if !within(from, len, settings_pages()) {
            return Err(FlashError::OutOfBounds);
        }
        self.writer()
            .erase(from, len)
            .map_err(|_| FlashError::Failed)
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        if !within(offset, bytes.len(), settings_pages()) {
            return Err(FlashError::OutOfBounds);
        }
        self.writer()
            .write(offset, bytes)
            .map_err(|_| FlashError::Failed)
    }
}
