//! DMA1, the seven-channel DMA controller (RM0008 section 13): per channel CCR, CNDTR,
//! CPAR and CMAR, the shared ISR and IFCR, memory-to-peripheral and peripheral-to-memory
//! transfers of 8, 16 or 32 bits with pointer increments, circular mode, and the
//! transfer-complete, half-transfer and transfer-error flags with their interrupts.
//!
//! Shaped around the board: this model owns the registers and the arbitration, not the
//! buses. A channel moves one item per request of its peripheral (the board computes
//! the request lines, e.g. SPI2's TXE with TXDMAEN for channel 5, and does the read
//! and the write itself, so the item reaches the peripheral through the same register
//! model the CPU uses). One transfer is on the bus at a time; it lands
//! `cycles` bus clocks after the request was taken (the board's estimate of the SRAM
//! read and the APB write); the CPU executes meanwhile and pays nothing. A new request
//! line is one more bit of the board's request mask (TIM2's update on channel 2 would
//! be one line there). Memory-to-memory transfers are refused.

use super::{unknown, Access, BusError};

pub const CHANNELS: usize = 7;

/// CCR bits.
pub const EN: u32 = 1 << 0;
pub const TCIE: u32 = 1 << 1;
pub const HTIE: u32 = 1 << 2;
pub const TEIE: u32 = 1 << 3;
pub const DIR: u32 = 1 << 4;
pub const CIRC: u32 = 1 << 5;
pub const PINC: u32 = 1 << 6;
pub const MINC: u32 = 1 << 7;
pub const MEM2MEM: u32 = 1 << 14;

/// ISR flags of one channel (shifted by 4 x channel index).
pub const GIF: u32 = 1 << 0;
pub const TCIF: u32 = 1 << 1;
pub const HTIF: u32 = 1 << 2;
pub const TEIF: u32 = 1 << 3;

#[derive(Clone, Copy, Debug, Default)]
struct Channel {
    ccr: u32,
    /// Items left (what CNDTR reads).
    ndtr: u32,
    /// CNDTR as written (circular mode reloads it; half transfer is at its half).
    ndtr_set: u32,
    cpar: u32,
    cmar: u32,
    /// The addresses of the next item (CPAR and CMAR plus the increments so far).
    p_at: u32,
    m_at: u32,
}

/// One item to move: read `size` bytes at `from`, write them (zero-extended or
/// truncated to `to_size`) at `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Item {
    pub channel: usize,
    pub from: u32,
    pub from_size: usize,
    pub to: u32,
    pub to_size: usize,
}

pub struct Dma {
    ch: [Channel; CHANNELS],
    isr: u32,
    /// The transfer on the bus: its channel and when it lands.
    inflight: Option<(usize, u64)>,
    /// Items moved since power-up, per channel.
    pub moved: [u64; CHANNELS],
    /// Time units per bus clock cycle.
    pub hclk_t: u64,
}

fn size_of(bits: u32) -> Result<usize, BusError> {
    match bits & 3 {
        0 => Ok(1),
        1 => Ok(2),
        2 => Ok(4),
        _ => Err(BusError("DMA1: reserved transfer size".into())),
    }
}

impl Default for Dma {
    fn default() -> Self {
        Self::new()
    }
}

impl Dma {
    pub fn new() -> Dma {
        Dma {
            ch: [Channel::default(); CHANNELS],
            isr: 0,
            inflight: None,
            moved: [0; CHANNELS],
            hclk_t: 1,
        }
    }

    pub fn reset(&mut self) {
        let hclk_t = self.hclk_t;
        *self = Dma::new();
        self.hclk_t = hclk_t;
    }

    /// When the transfer on the bus lands.
    pub fn next_event(&self) -> Option<u64> {
        self.inflight.map(|(_, t)| t)
    }

    /// Whether channel `c` (0-based) has its interrupt line raised.
    pub fn irq(&self, c: usize) -> bool {
        let Some(ch) = self.ch.get(c) else {
            return false;
        };
        let flags = (self.isr >> (4 * c)) & 0xF;
        (ch.ccr & TCIE != 0 && flags & TCIF != 0)
            || (ch.ccr & HTIE != 0 && flags & HTIF != 0)
            || (ch.ccr & TEIE != 0 && flags & TEIF != 0)
    }

    /// Whether channel `c` would serve a request now (enabled, items left).
    pub fn armed(&self, c: usize) -> bool {
        self.ch
            .get(c)
            .is_some_and(|ch| ch.ccr & EN != 0 && ch.ndtr > 0)
    }

    /// Take the most urgent request of `requests` (bit c: channel c's peripheral asks)
    /// when the bus is free: the highest CCR.PL, then the lowest channel (13.3.2). The
    /// item lands after `cycles(item)` bus clocks. Returns whether one was taken.
    pub fn arbitrate(&mut self, requests: u32, now: u64, cycles: impl Fn(&Item) -> u64) -> bool {
        if self.inflight.is_some() {
            return false;
        }
        let best = (0..CHANNELS)
            .filter(|&c| requests & (1 << c) != 0 && self.armed(c))
            .max_by_key(|&c| ((self.ch[c].ccr >> 12) & 3, CHANNELS - c));
        let Some(c) = best else {
            return false;
        };
        let Ok(item) = self.item(c) else {
            return false;
        };
        self.inflight = Some((c, now + cycles(&item) * self.hclk_t));
        true
    }

    /// The item the transfer on the bus moves, once it has landed by `now`.
    pub fn landed(&self, now: u64) -> Option<Item> {
        match self.inflight {
            Some((c, t)) if t <= now => self.item(c).ok(),
            _ => None,
        }
    }

    fn item(&self, c: usize) -> Result<Item, BusError> {
        let ch = &self.ch[c];
        let psize = size_of(ch.ccr >> 8)?;
        let msize = size_of(ch.ccr >> 10)?;
        Ok(if ch.ccr & DIR != 0 {
            Item {
                channel: c,
                from: ch.m_at,
                from_size: msize,
                to: ch.p_at,
                to_size: psize,
            }
        } else {
            Item {
                channel: c,
                from: ch.p_at,
                from_size: psize,
                to: ch.m_at,
                to_size: msize,
            }
        })
    }

    /// The landed item was moved (`ok`) or hit a bus error: count it, set the flags.
    /// A bus error disables the channel (13.3.7).
    pub fn done(&mut self, ok: bool) {
        let Some((c, _)) = self.inflight.take() else {
            return;
        };
        let shift = 4 * c;
        let ch = &mut self.ch[c];
        if !ok {
            ch.ccr &= !EN;
            self.isr |= (TEIF | GIF) << shift;
            return;
        }
        self.moved[c] += 1;
        if ch.ccr & PINC != 0 {
            ch.p_at = ch
                .p_at
                .wrapping_add(size_of(ch.ccr >> 8).unwrap_or(1) as u32);
        }
        if ch.ccr & MINC != 0 {
            ch.m_at = ch
                .m_at
                .wrapping_add(size_of(ch.ccr >> 10).unwrap_or(1) as u32);
        }
        ch.ndtr = ch.ndtr.saturating_sub(1);
        if ch.ndtr == ch.ndtr_set / 2 {
            self.isr |= (HTIF | GIF) << shift;
        }
        if ch.ndtr == 0 {
            self.isr |= (TCIF | GIF) << shift;
            if ch.ccr & CIRC != 0 {
                ch.ndtr = ch.ndtr_set;
                ch.p_at = ch.cpar;
                ch.m_at = ch.cmar;
            }
        }
    }

    pub fn read(&self, off: u32) -> Access<u32> {
        if off == 0x00 {
            return Ok(self.isr);
        }
        if off == 0x04 {
            return Ok(0);
        }
        let (c, reg) = channel_reg(off)?;
        let ch = &self.ch[c];
        Ok(match reg {
            0 => ch.ccr,
            1 => ch.ndtr,
            2 => ch.cpar,
            _ => ch.cmar,
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access<()> {
        if off == 0x00 {
            // ISR is read-only.
            return Ok(());
        }
        if off == 0x04 {
            // IFCR: a 1 clears the flag; CGIFx clears all four of channel x.
            let mut clear = v & 0x0FFF_FFFF;
            for c in 0..CHANNELS {
                if clear & (GIF << (4 * c)) != 0 {
                    clear |= 0xF << (4 * c);
                }
            }
            self.isr &= !clear;
            // GIF stays while another flag of its channel does.
            for c in 0..CHANNELS {
                if (self.isr >> (4 * c)) & 0xE == 0 {
                    self.isr &= !(GIF << (4 * c));
                }
            }
            return Ok(());
        }
        let (c, reg) = channel_reg(off)?;
        let ch = &mut self.ch[c];
        let enabled = ch.ccr & EN != 0;
        match reg {
            0 => {
                let v = v & 0x7FFF;
                if v & MEM2MEM != 0 {
                    return Err(BusError(format!(
                        "DMA1 channel {}: memory-to-memory is not modelled",
                        c + 1
                    )));
                }
                size_of(v >> 8)?;
                size_of(v >> 10)?;
                if v & EN != 0 && !enabled {
                    // Enabling starts from the programmed addresses.
                    ch.p_at = ch.cpar;
                    ch.m_at = ch.cmar;
                }
                ch.ccr = v;
            }
            // CNDTR, CPAR, CMAR are read-only while the channel is enabled.
            _ if enabled => {}
            1 => {
                ch.ndtr = v & 0xFFFF;
                ch.ndtr_set = ch.ndtr;
            }
            2 => ch.cpar = v,
            _ => ch.cmar = v,
        }
        Ok(())
    }
}

/// A channel register offset: (channel index, 0 CCR / 1 CNDTR / 2 CPAR / 3 CMAR).
fn channel_reg(off: u32) -> Result<(usize, u32), BusError> {
    let rel = off.wrapping_sub(0x08);
    let c = (rel / 0x14) as usize;
    let reg = (rel % 0x14) / 4;
    if off < 0x08 || c >= CHANNELS || reg > 3 || !off.is_multiple_of(4) {
        return Err(unknown("DMA1", off));
    }
    Ok((c, reg))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Channel 5's registers (0-based index 4).
    const CCR5: u32 = 0x08 + 0x14 * 4;
    const CNDTR5: u32 = CCR5 + 4;
    const CPAR5: u32 = CCR5 + 8;
    const CMAR5: u32 = CCR5 + 12;

    fn spi_tx_channel(n: u32, ccr: u32) -> Dma {
        let mut d = Dma::new();
        d.write(CNDTR5, n).unwrap();
        d.write(CPAR5, 0x4000_380C).unwrap();
        d.write(CMAR5, 0x2000_0100).unwrap();
        d.write(CCR5, ccr).unwrap();
        d
    }

    /// Serve one request of channel 5 at `t` and move it: the item's addresses.
    fn serve(d: &mut Dma, t: u64) -> Item {
        assert!(d.arbitrate(1 << 4, t, |_| 6));
        assert_eq!(d.landed(t + 5), None, "not before its bus cycles");
        let item = d.landed(t + 6).expect("landed");
        d.done(true);
        item
    }

    #[test]
    fn memory_to_peripheral_walks_memory_and_counts_down_with_flags() {
        let mut d = spi_tx_channel(4, EN | DIR | MINC | TCIE | HTIE);
        let items: Vec<Item> = (0..4).map(|i| serve(&mut d, 100 * i)).collect();
        assert_eq!(
            items.iter().map(|i| (i.from, i.to)).collect::<Vec<_>>(),
            [
                (0x2000_0100, 0x4000_380C),
                (0x2000_0101, 0x4000_380C),
                (0x2000_0102, 0x4000_380C),
                (0x2000_0103, 0x4000_380C),
            ]
        );
        assert!(items.iter().all(|i| i.from_size == 1 && i.to_size == 1));
        assert_eq!(d.read(CNDTR5), Ok(0));
        assert_eq!(d.read(0), Ok((GIF | TCIF | HTIF) << 16));
        assert!(d.irq(4));
        // Nothing left: a request is not served.
        assert!(!d.arbitrate(1 << 4, 1000, |_| 6));
        // Clearing the flags drops the interrupt line.
        d.write(4, TCIF << 16).unwrap();
        assert_eq!(d.read(0), Ok((GIF | HTIF) << 16));
        assert!(d.irq(4));
        d.write(4, GIF << 16).unwrap();
        assert_eq!(d.read(0), Ok(0));
        assert!(!d.irq(4));
    }

    #[test]
    fn half_transfer_comes_at_the_half_and_interrupts_only_when_enabled() {
        let mut d = spi_tx_channel(6, EN | DIR | MINC | TCIE);
        for i in 0..3 {
            serve(&mut d, 10 * i);
        }
        assert_eq!(d.read(0), Ok((GIF | HTIF) << 16));
        assert!(!d.irq(4), "HTIE is off");
        serve(&mut d, 100);
        assert_eq!(d.read(CNDTR5), Ok(2));
    }

    #[test]
    fn registers_are_locked_while_enabled_and_reload_on_enable() {
        let mut d = spi_tx_channel(2, EN | DIR | MINC);
        serve(&mut d, 0);
        d.write(CMAR5, 0x2000_0200).unwrap();
        d.write(CNDTR5, 9).unwrap();
        assert_eq!(d.read(CMAR5), Ok(0x2000_0100));
        assert_eq!(d.read(CNDTR5), Ok(1));
        d.write(CCR5, DIR | MINC).unwrap();
        assert!(!d.arbitrate(1 << 4, 50, |_| 6), "disabled");
        d.write(CMAR5, 0x2000_0200).unwrap();
        d.write(CNDTR5, 3).unwrap();
        d.write(CCR5, EN | DIR | MINC).unwrap();
        assert_eq!(serve(&mut d, 60).from, 0x2000_0200);
    }

    #[test]
    fn circular_mode_starts_over() {
        let mut d = spi_tx_channel(2, EN | DIR | MINC | CIRC);
        let from: Vec<u32> = (0..5).map(|i| serve(&mut d, 10 * i).from).collect();
        assert_eq!(
            from,
            [
                0x2000_0100,
                0x2000_0101,
                0x2000_0100,
                0x2000_0101,
                0x2000_0100
            ]
        );
        assert_eq!(d.read(CNDTR5), Ok(1));
    }

    #[test]
    fn sizes_and_direction_shape_the_item() {
        // Peripheral to memory, 16-bit peripheral, 32-bit memory, both incremented.
        let mut d = spi_tx_channel(2, EN | MINC | PINC | (1 << 8) | (2 << 10));
        let a = serve(&mut d, 0);
        let b = serve(&mut d, 10);
        assert_eq!(
            (a.from, a.from_size, a.to, a.to_size),
            (0x4000_380C, 2, 0x2000_0100, 4)
        );
        assert_eq!((b.from, b.to), (0x4000_380E, 0x2000_0104));
    }

    #[test]
    fn arbitration_takes_priority_then_the_lower_channel_one_at_a_time() {
        let mut d = Dma::new();
        for c in [1usize, 4, 6] {
            let base = 0x08 + 0x14 * c as u32;
            d.write(base + 4, 5).unwrap();
            d.write(base + 8, 0x4000_0000 + c as u32).unwrap();
            d.write(base + 12, 0x2000_0000).unwrap();
        }
        d.write(0x08 + 0x14, EN | DIR).unwrap(); // channel 2, low
        d.write(0x08 + 0x14 * 4, EN | DIR).unwrap(); // channel 5, low
        d.write(0x08 + 0x14 * 6, EN | DIR | (2 << 12)).unwrap(); // channel 7, high
        let all = (1 << 1) | (1 << 4) | (1 << 6);
        assert!(d.arbitrate(all, 0, |_| 4));
        assert!(!d.arbitrate(all, 1, |_| 4), "the bus is busy");
        assert_eq!(d.landed(4).map(|i| i.channel), Some(6));
        d.done(true);
        assert!(d.arbitrate(all & !(1 << 6), 4, |_| 4));
        assert_eq!(d.landed(8).map(|i| i.channel), Some(1));
    }

    #[test]
    fn a_bus_error_disables_the_channel_with_teif() {
        let mut d = spi_tx_channel(3, EN | DIR | MINC | TEIE);
        assert!(d.arbitrate(1 << 4, 0, |_| 1));
        d.done(false);
        assert_eq!(d.read(CCR5).map(|v| v & EN), Ok(0));
        assert_eq!(d.read(0), Ok((GIF | TEIF) << 16));
        assert!(d.irq(4));
        assert_eq!(d.read(CNDTR5), Ok(3));
    }

    #[test]
    fn unknown_offsets_and_memory_to_memory_are_refused() {
        let mut d = Dma::new();
        assert!(d.read(0x18).is_err()); // the reserved word after CMAR1
        assert!(d.read(0x08 + 0x14 * 7).is_err());
        assert!(d.write(CCR5, MEM2MEM).is_err());
        assert!(d.write(CCR5, 3 << 8).is_err());
    }
}
