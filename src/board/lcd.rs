//! The ST7920 LCD on SPI2: the transmit-only link, fed by DMA1 channel 5, and the
//! controller's start-up.
//!
//! Shaped for a task that must not wait: the bytes of a refresh go out a buffer at a
//! time (core::screens::st7920::encode_chunk fills it), one DMA transfer per buffer,
//! paced by SPI2's transmit-buffer-empty request at the SPI's bit rate; the CPU only
//! starts each transfer. Chip select stays high for good: every ST7920 serial frame
//! starts with its sync byte, so the controller needs no select edge between frames.

use super::SYSCLK_HZ;
use inkstep_core::screens::st7920::MAX_SPAN_BYTES;
use stm32f1xx_hal::dma::{dma1, Event};
use stm32f1xx_hal::gpio::{Output, PushPull, PB12};
use stm32f1xx_hal::pac;
use stm32f1xx_hal::spi::SpiTxDma;

/// SPI clock for the ST7920: the HAL picks 36 MHz / 128 = 281 kHz, so one 24-bit
/// serial write (85 µs) outlasts the controller's 72 µs execution time and the bytes
/// can stream back to back without delays (see core::screens::st7920).
pub const LCD_SPI_HZ: u32 = 300_000;

/// Bytes per DMA transfer: one span of the largest size always fits.
pub const LCD_CHUNK: usize = MAX_SPAN_BYTES;

/// The LCD link: SPI2 with its transmit DMA (channel 5), transmit only (the ST7920's
/// serial mode has no read-back), the controller's chip select on PB12 (active high,
/// held high), and the buffer the DMA reads.
pub struct LcdSpi {
    pub(super) dma: SpiTxDma<pac::SPI2, dma1::C5>,
    pub(super) _cs: PB12<Output<PushPull>>,
    pub(super) buf: &'static mut [u8; LCD_CHUNK],
}

impl LcdSpi {
    /// Set the channel up (8-bit memory to SPI2's DR, memory incremented, an
    /// interrupt at transfer complete); nothing is sent yet.
    pub(super) fn new(
        mut dma: SpiTxDma<pac::SPI2, dma1::C5>,
        cs: PB12<Output<PushPull>>,
        buf: &'static mut [u8; LCD_CHUNK],
    ) -> LcdSpi {
        // SAFETY: only the address of SPI2's data register is taken; nothing is
        // read or written through it here.
        let dr = unsafe { (*pac::SPI2::ptr()).dr().as_ptr() } as u32;
        let ch = &mut dma.channel;
        ch.set_peripheral_address(dr, false);
        ch.set_memory_address(buf.as_ptr() as u32, true);
        ch.ch().cr().modify(|_, w| {
            w.mem2mem().clear_bit();
            w.pl().low();
            w.msize().bits8();
            w.psize().bits8();
            w.circ().clear_bit();
            w.dir().set_bit()
        });
        ch.listen(Event::TransferComplete);
        LcdSpi { dma, _cs: cs, buf }
    }

    /// The last transfer's bytes are all in SPI2 (its last one or two may still be
    /// shifting out): the buffer is free and the next transfer may start.
    pub fn sent(&self) -> bool {
        self.dma.channel.get_ndtr() == 0
    }

    /// Sent, and SPI2 has clocked the last byte out (BSY clear).
    pub fn idle(&self) -> bool {
        // SAFETY: a read of SPI2's status register, which has no side effect (OVR is
        // cleared by reading DR after SR; DR is never read).
        let busy = unsafe { (*pac::SPI2::ptr()).sr().read().bsy().bit_is_set() };
        self.sent() && !busy
    }

    /// The buffer the next transfer sends, while no transfer reads it.
    pub fn buffer(&mut self) -> Option<&mut [u8; LCD_CHUNK]> {
        if self.sent() {
            Some(&mut *self.buf)
        } else {
            None
        }
    }

    /// Send the first `len` bytes of the buffer by DMA; false (nothing sent) while a
    /// transfer runs or for nothing to send.
    pub fn send(&mut self, len: usize) -> bool {
        if !self.sent() || len == 0 {
            return false;
        }
        let ch = &mut self.dma.channel;
        // Clears the flags and disables the channel, so that its count can be set.
        ch.stop();
        ch.set_transfer_length(len.min(LCD_CHUNK));
        ch.start();
        true
    }

    /// Clear the channel's flags (its transfer-complete interrupt line with them).
    pub fn ack(&mut self) {
        let ch = &mut self.dma.channel;
        ch.ifcr().write(|w| w.cgif(4).set_bit());
    }

    /// One instruction (a serial frame: command start byte, high nibble, low nibble),
    /// started by DMA; false while a transfer runs.
    pub fn command(&mut self, cmd: u8) -> bool {
        let Some(buf) = self.buffer() else {
            return false;
        };
        buf[..3].copy_from_slice(&[0xF8, cmd & 0xF0, cmd << 4]);
        self.send(3)
    }

    /// Send `bytes` and wait until they are out: for the bring-up image, whose LCD
    /// task may wait (it is the lowest priority).
    pub fn write_blocking(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(LCD_CHUNK) {
            while !self.sent() {}
            if let Some(buf) = self.buffer() {
                if let Some(dst) = buf.get_mut(..chunk.len()) {
                    dst.copy_from_slice(chunk);
                }
            }
            self.send(chunk.len());
        }
        while !self.idle() {}
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

/// The power-up with busy waits, for the bring-up image (src/bin/bringup.rs).
pub fn lcd_init(spi: &mut LcdSpi) {
    const CYCLES_PER_US: u32 = SYSCLK_HZ / 1_000_000;
    cortex_m::asm::delay(POWER_UP_MS * 1000 * CYCLES_PER_US);
    for (cmd, wait_us) in INIT_SEQUENCE {
        spi.command(cmd);
        while !spi.idle() {}
        cortex_m::asm::delay(wait_us * CYCLES_PER_US);
    }
}
