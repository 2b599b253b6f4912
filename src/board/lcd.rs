//! The ST7920 LCD on SPI2: the transmit-only link and the controller's start-up.

use super::SYSCLK_HZ;
use stm32f1xx_hal::gpio::{Output, PushPull, PB12};
use stm32f1xx_hal::pac;
use stm32f1xx_hal::spi::Spi;

/// SPI clock for the ST7920: the HAL picks 36 MHz / 128 = 281 kHz, so one 24-bit
/// serial write (85 µs) outlasts the controller's 72 µs execution time and the bytes
/// can stream back to back without delays (see core::screens::st7920).
pub const LCD_SPI_HZ: u32 = 300_000;

/// The LCD link: SPI2, transmit only (the ST7920's serial mode has no read-back),
/// and the controller's chip select on PB12, which is active high.
pub struct LcdSpi {
    pub(super) spi: Spi<pac::SPI2, u8>,
    pub(super) cs: PB12<Output<PushPull>>,
}

impl LcdSpi {
    /// Send `bytes` as one transaction: chip select raised around them.
    pub fn write(&mut self, bytes: &[u8]) -> Result<(), stm32f1xx_hal::spi::Error> {
        self.cs.set_high();
        let sent = self.spi.write(bytes);
        self.cs.set_low();
        sent
    }
}

/// The ST7920's power-up, the st7920 crate's sequence (its reset wait on a tied reset
/// pin, then basic function set, display on, clear, entry mode, extended function
/// set, graphics on, each followed by its execution time), without building that
/// crate's 1 KB frame buffer: wait [`POWER_UP_MS`], then each instruction of
/// [`INIT_SEQUENCE`] followed by its wait. The product image runs it off the 1 ms tick
/// (src/main.rs, `lcd_refresh`): the waits cost no CPU.
pub const POWER_UP_MS: u32 = 80;
/// (instruction, wait after it in µs)
pub const INIT_SEQUENCE: [(u8, u32); 6] = [
    (0x30, 200),
    (0x0C, 100),
    (0x01, 10_000),
    (0x06, 100),
    (0x34, 10_000),
    (0x36, 100_000),
];

impl LcdSpi {
    /// One instruction: a serial frame (command start byte, high nibble, low nibble).
    pub fn command(&mut self, cmd: u8) -> Result<(), stm32f1xx_hal::spi::Error> {
        self.write(&[0xF8, cmd & 0xF0, cmd << 4])
    }
}

/// The power-up with busy waits, for the bring-up image (src/bin/bringup.rs).
pub fn lcd_init(spi: &mut LcdSpi) -> Result<(), stm32f1xx_hal::spi::Error> {
    const CYCLES_PER_US: u32 = SYSCLK_HZ / 1_000_000;
    cortex_m::asm::delay(POWER_UP_MS * 1000 * CYCLES_PER_US);
    for (cmd, wait_us) in INIT_SEQUENCE {
        spi.command(cmd)?;
        cortex_m::asm::delay(wait_us * CYCLES_PER_US);
    }
    Ok(())
}
