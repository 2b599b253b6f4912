//! GPIO ports (RM0008 section 9.2), AFIO (9.4) and EXTI (10.3), and the pin levels
//! they produce together with what is wired to the pins outside the chip.
//!
//! A pin's level: an output drives its ODR bit (or, in alternate-function mode, the
//! peripheral's output); an open-drain output only pulls low and is otherwise at the
//! level the outside gives it (high, through the keypad's row pull-ups or the
//! board's); an input reads the outside, or its pull-up/down when nothing drives it.

use super::{unknown, Access};

/// One port's registers.
pub struct Port {
    pub crl: u32,
    pub crh: u32,
    pub odr: u32,
    lckr: u32,
}

impl Port {
    pub fn new() -> Port {
        Port {
            crl: 0x4444_4444,
            crh: 0x4444_4444,
            odr: 0,
            lckr: 0,
        }
    }

    /// The 4-bit configuration of `pin`: `CNF[1:0] MODE[1:0]`.
    pub fn config(&self, pin: usize) -> u32 {
        let reg = if pin < 8 { self.crl } else { self.crh };
        (reg >> (4 * (pin % 8))) & 0xF
    }

    pub fn is_output(&self, pin: usize) -> bool {
        self.config(pin) & 3 != 0
    }

    pub fn is_alternate(&self, pin: usize) -> bool {
        self.is_output(pin) && self.config(pin) & 8 != 0
    }

    /// Level of `pin` given the outside (`ext`, None when undriven) and the alternate
    /// function's output level.
    pub fn level(&self, pin: usize, ext: Option<bool>, af: bool) -> bool {
        let cfg = self.config(pin);
        let odr = self.odr & (1 << pin) != 0;
        if cfg & 3 != 0 {
            let out = if cfg & 8 != 0 { af } else { odr };
            if cfg & 4 != 0 {
                // Open drain: low, or released to the outside (pulled up when free).
                out && ext.unwrap_or(true)
            } else {
                out
            }
        } else {
            match cfg >> 2 {
                // Analog input: the Schmitt trigger is off, IDR reads 0.
                0 => false,
                1 => ext.unwrap_or(false),
                // Pull-up (ODR 1) or pull-down (ODR 0).
                _ => ext.unwrap_or(odr),
            }
        }
    }

    pub fn read(&self, off: u32, idr: u32) -> Access<u32> {
        Ok(match off {
            0x00 => self.crl,
            0x04 => self.crh,
            0x08 => idr,
            0x0C => self.odr,
            0x10 | 0x14 => 0,
            0x18 => self.lckr,
            _ => return Err(unknown("GPIO", off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access<()> {
        match off {
            0x00 => self.crl = v,
            0x04 => self.crh = v,
            0x08 => {}
            0x0C => self.odr = v & 0xFFFF,
            0x10 => {
                // BSRR: set bits 0..15, reset bits 16..31; set wins.
                self.odr &= !(v >> 16);
                self.odr |= v & 0xFFFF;
            }
            0x14 => self.odr &= !(v & 0xFFFF),
            // LCKR: the lock sequence is accepted; locking is not enforced.
            0x18 => self.lckr = v & 0x1_FFFF,
            _ => return Err(unknown("GPIO", off)),
        }
        Ok(())
    }
}

impl Default for Port {
    fn default() -> Self {
        Self::new()
    }
}

/// AFIO: remaps and the EXTI line sources.
pub struct Afio {
    evcr: u32,
    pub mapr: u32,
    pub exticr: [u32; 4],
    mapr2: u32,
}

impl Afio {
    pub fn new() -> Afio {
        Afio {
            evcr: 0,
            mapr: 0,
            exticr: [0; 4],
            mapr2: 0,
        }
    }

    /// The port (0 = A, 1 = B, 2 = C...) line `line` listens to.
    pub fn exti_port(&self, line: usize) -> usize {
        ((self.exticr[line / 4] >> (4 * (line % 4))) & 0xF) as usize
    }

    pub fn read(&self, off: u32) -> Access<u32> {
        Ok(match off {
            0x00 => self.evcr,
            // SWJ_CFG (26:24) is write-only and reads 0.
            0x04 => self.mapr & !(7 << 24),
            0x08..=0x14 => self.exticr[((off - 8) / 4) as usize],
            0x1C => self.mapr2,
            _ => return Err(unknown("AFIO", off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access<()> {
        match off {
            0x00 => self.evcr = v & 0xFF,
            0x04 => {
                // Remaps would move pins under the models' feet: the board uses none,
                // and one is refused rather than ignored.
                if v & 0x001F_FFFF != 0 {
                    return Err(super::BusError(format!(
                        "AFIO_MAPR remap 0x{:06X} is not modelled",
                        v & 0x001F_FFFF
                    )));
                }
                self.mapr = v;
            }
            0x08..=0x14 => self.exticr[((off - 8) / 4) as usize] = v & 0xFFFF,
            0x1C => self.mapr2 = v,
            _ => return Err(unknown("AFIO", off)),
        }
        Ok(())
    }
}

impl Default for Afio {
    fn default() -> Self {
        Self::new()
    }
}

/// EXTI: edge detection on 19 lines (0..15 from the GPIO pins).
pub struct Exti {
    pub imr: u32,
    emr: u32,
    pub rtsr: u32,
    pub ftsr: u32,
    pub pr: u32,
    /// The last level seen on lines 0..15.
    pub levels: u32,
}

impl Exti {
    pub fn new() -> Exti {
        Exti {
            imr: 0,
            emr: 0,
            rtsr: 0,
            ftsr: 0,
            pr: 0,
            levels: 0,
        }
    }

    /// New levels of lines 0..15: configured edges set their pending bits.
    pub fn update(&mut self, levels: u32) {
        let rising = levels & !self.levels;
        let falling = !levels & self.levels & 0xFFFF;
        self.pr |= (rising & self.rtsr) | (falling & self.ftsr);
        self.levels = levels;
    }

    /// Lines with an interrupt request (pending and unmasked).
    pub fn requests(&self) -> u32 {
        self.pr & self.imr
    }

    pub fn read(&self, off: u32) -> Access<u32> {
        Ok(match off {
            0x00 => self.imr,
            0x04 => self.emr,
            0x08 => self.rtsr,
            0x0C => self.ftsr,
            0x10 => 0,
            0x14 => self.pr,
            _ => return Err(unknown("EXTI", off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access<()> {
        let v = v & 0x7_FFFF;
        match off {
            0x00 => self.imr = v,
            0x04 => self.emr = v,
            0x08 => self.rtsr = v,
            0x0C => self.ftsr = v,
            // SWIER: a 0 -> 1 write sets the pending bit of an unmasked line.
            0x10 => self.pr |= v & self.imr,
            0x14 => self.pr &= !v,
            _ => return Err(unknown("EXTI", off)),
        }
        Ok(())
    }
}

impl Default for Exti {
    fn default() -> Self {
        Self::new()
    }
}

/// The NVIC line of EXTI line `line` (RM0008 table 63).
pub fn exti_irq(line: usize) -> usize {
    match line {
        0..=4 => 6 + line,
        5..=9 => 23,
        _ => 40,
    }
}
