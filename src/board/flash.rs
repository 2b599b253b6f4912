//! The internal flash: its size, the settings store's pages (from memory.x) and the
//! NOR-flash driver the store writes them with.

use stm32f1xx_hal::pac;

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
/// settings store in the core. Offsets are chip flash offsets (0 = 0x0800_0000), the
/// store's range ([`settings_pages`]) is the settings pages; reads may look
/// anywhere in the 128 KB, writes and erases only inside the settings pages, so a store
/// bug can never overwrite the program.
///
/// Programming stalls instruction fetch from flash for the duration of a write (~50 µs
/// per half-word) or erase (~20 ms per page), so the firmware only saves at rest.
///
/// The controller is driven by register writes, step for step as the HAL's
/// `FlashWriter` with verification on (RM0008 "Flash program and erase"): unlock with
/// the two keys, program half-words with PG or erase pages with PER/AR/STRT, wait for
/// BSY, check PGERR/WRPRTERR, read back, lock again. The HAL's generic version of
/// the same cost twice the flash.
pub struct SettingsFlash {
    /// Owned so that nothing else reaches the flash controller.
    _flash: stm32f1xx_hal::flash::Parts,
}

/// Where the flash is mapped.
const FLASH_BASE: u32 = 0x0800_0000;

impl SettingsFlash {
    const KEY1: u32 = 0x4567_0123;
    const KEY2: u32 = 0xCDEF_89AB;

    pub(super) fn new(flash: stm32f1xx_hal::flash::Parts) -> Self {
        Self { _flash: flash }
    }

    fn regs(&mut self) -> &pac::flash::RegisterBlock {
        // SAFETY: this struct owns the flash parts, so it alone uses these registers
        // (the HAL's ACR wait-state setting was done at clock setup).
        unsafe { &*pac::FLASH::ptr() }
    }

    fn wait_idle(&mut self) {
        while self.regs().sr().read().bsy().bit_is_set() {}
    }

    fn unlock(&mut self) -> Result<(), FlashError> {
        self.wait_idle();
        let f = self.regs();
        // SAFETY: the key sequence only unlocks FLASH_CR (in this order, or it stays
        // locked until reset).
        unsafe {
            f.keyr().write(|w| w.bits(Self::KEY1));
            f.keyr().write(|w| w.bits(Self::KEY2));
        }
        if f.cr().read().lock().bit_is_set() {
            return Err(FlashError);
        }
        Ok(())
    }

    fn lock(&mut self) -> Result<(), FlashError> {
        self.wait_idle();
        let f = self.regs();
        f.cr().modify(|_, w| w.lock().set_bit());
        if f.cr().read().lock().bit_is_clear() {
            return Err(FlashError);
        }
        Ok(())
    }

    /// Erase the page holding `offset` and check that it reads back blank.
    fn erase_page(&mut self, offset: u32) -> Result<(), FlashError> {
        self.unlock()?;
        let f = self.regs();
        f.cr().modify(|_, w| w.per().set_bit());
        // SAFETY: AR takes any address; the caller checked it is a settings page.
        f.ar().write(|w| unsafe { w.bits(FLASH_BASE + offset) });
        f.cr().modify(|_, w| w.strt().set_bit());
        // BSY rises one cycle after STRT (STM32F10x errata 2.2.8).
        cortex_m::asm::nop();
        self.wait_idle();
        let f = self.regs();
        let sr = f.sr().read();
        f.cr().modify(|_, w| w.per().clear_bit());
        self.lock()?;
        if sr.wrprterr().bit_is_set() {
            self.regs().sr().modify(|_, w| w.wrprterr().set_bit());
            return Err(FlashError);
        }
        let page = (FLASH_BASE + (offset & !(FLASH_PAGE_SIZE - 1))) as *const u16;
        for i in 0..(FLASH_PAGE_SIZE / 2) as usize {
            // SAFETY: a half-word of the page just erased, inside the flash.
            if unsafe { core::ptr::read_volatile(page.add(i)) } != 0xFFFF {
                return Err(FlashError);
            }
        }
        Ok(())
    }

    /// Program one half-word and check it reads back; on failure the flash is locked.
    fn program(&mut self, addr: u32, half: u16) -> Result<(), FlashError> {
        let f = self.regs();
        f.cr().modify(|_, w| w.pg().set_bit());
        self.wait_idle();
        // SAFETY: a half-word of a settings page, with PG set and the flash unlocked.
        unsafe { core::ptr::write_volatile(addr as *mut u16, half) };
        self.wait_idle();
        let f = self.regs();
        f.cr().modify(|_, w| w.pg().clear_bit());
        let ok = if f.sr().read().pgerr().bit_is_set() {
            f.sr().modify(|_, w| w.pgerr().set_bit());
            false
        } else if f.sr().read().wrprterr().bit_is_set() {
            f.sr().modify(|_, w| w.wrprterr().set_bit());
            false
        } else {
            // SAFETY: the half-word just programmed.
            unsafe { core::ptr::read_volatile(addr as *const u16) == half }
        };
        if !ok {
            self.lock()?;
            return Err(FlashError);
        }
        Ok(())
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub struct FlashError;

impl embedded_storage::nor_flash::NorFlashError for FlashError {
    fn kind(&self) -> embedded_storage::nor_flash::NorFlashErrorKind {
        embedded_storage::nor_flash::NorFlashErrorKind::Other
    }
}

impl embedded_storage::nor_flash::ErrorType for SettingsFlash {
    type Error = FlashError;
}

/// `offset..offset + len` lies inside `lo..hi`.
fn within(offset: u32, len: usize, lo: u32, hi: u32) -> bool {
    let Ok(len) = u32::try_from(len) else {
        return false;
    };
    offset >= lo && offset.checked_add(len).is_some_and(|end| end <= hi)
}

impl embedded_storage::nor_flash::ReadNorFlash for SettingsFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        if !within(offset, bytes.len(), 0, FLASH_SIZE) {
            return Err(FlashError);
        }
        // Half-word aligned, as the HAL's reader required.
        if !offset.is_multiple_of(2) {
            return Err(FlashError);
        }
        // SAFETY: inside the 128 KB of flash (checked above), which is always mapped
        // and only changes through `&mut self`.
        let data =
            unsafe { core::slice::from_raw_parts((FLASH_BASE + offset) as *const u8, bytes.len()) };
        bytes.copy_from_slice(data);
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
        let pages = settings_pages();
        if from > to || !within(from, (to - from) as usize, pages.start, pages.end) {
            return Err(FlashError);
        }
        // Half-word aligned, every page from `from` up to `to` (as the HAL did).
        if !from.is_multiple_of(2) || !(to - from).is_multiple_of(2) {
            return Err(FlashError);
        }
        let mut page = from;
        while page < to {
            self.erase_page(page)?;
            page += FLASH_PAGE_SIZE;
        }
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let pages = settings_pages();
        if !within(offset, bytes.len(), pages.start, pages.end) {
            return Err(FlashError);
        }
        if !offset.is_multiple_of(2) || !bytes.len().is_multiple_of(2) {
            return Err(FlashError);
        }
        self.unlock()?;
        let mut addr = FLASH_BASE + offset;
        for pair in bytes.chunks_exact(2) {
            self.program(addr, u16::from_le_bytes([pair[0], pair[1]]))?;
            addr += 2;
        }
        self.lock()
    }
}
