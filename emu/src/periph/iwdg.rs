//! The independent watchdog (RM0008 section 19): a 12-bit down counter on the 40 kHz
//! LSI behind a prescaler of 4 << PR; key 0xCCCC starts it, 0xAAAA reloads it from RLR,
//! 0x5555 opens PR and RLR for writing. When it reaches 0 the MCU resets. PR and RLR
//! updates take 5 LSI periods (PVU, RVU in SR).

use super::{unknown, Access};
use crate::clock::T_PER_S;

pub const LSI_HZ: u64 = 40_000;
const LSI_T: u64 = T_PER_S / LSI_HZ;

pub struct Iwdg {
    running: bool,
    unlocked: bool,
    pr: u32,
    rlr: u32,
    /// When the counter was last reloaded.
    reloaded_at: u64,
    pr_busy_until: u64,
    rlr_busy_until: u64,
    /// Reloads so far (the soak test reads them).
    pub feeds: u64,
}

impl Iwdg {
    pub fn new() -> Iwdg {
        Iwdg {
            running: false,
            unlocked: false,
            pr: 0,
            rlr: 0xFFF,
            reloaded_at: 0,
            pr_busy_until: 0,
            rlr_busy_until: 0,
            feeds: 0,
        }
    }

    /// The time the counter reaches 0 (the reset), when running.
    pub fn deadline(&self) -> Option<u64> {
        self.running.then(|| {
            let ticks = (u64::from(self.rlr) + 1) * (4u64 << self.pr);
            self.reloaded_at + ticks * LSI_T
        })
    }

    pub fn read(&self, off: u32, now: u64) -> Access<u32> {
        Ok(match off {
            0x00 => 0,
            0x04 => self.pr,
            0x08 => self.rlr,
            0x0C => {
                u32::from(now < self.pr_busy_until) | (u32::from(now < self.rlr_busy_until) << 1)
            }
            _ => return Err(unknown("IWDG", off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32, now: u64) -> Access<()> {
        match off {
            0x00 => match v & 0xFFFF {
                0x5555 => self.unlocked = true,
                0xAAAA => {
                    self.unlocked = false;
                    self.reloaded_at = now;
                    self.feeds += 1;
                }
                0xCCCC => {
                    if !self.running {
                        self.running = true;
                        self.reloaded_at = now;
                    }
                }
                _ => self.unlocked = false,
            },
            0x04 => {
                if self.unlocked {
                    self.pr = v & 7;
                    self.pr_busy_until = now + 5 * LSI_T;
                }
            }
            0x08 => {
                if self.unlocked {
                    self.rlr = v & 0xFFF;
                    self.rlr_busy_until = now + 5 * LSI_T;
                }
            }
            0x0C => {}
            _ => return Err(unknown("IWDG", off)),
        }
        Ok(())
    }
}

impl Default for Iwdg {
    fn default() -> Self {
        Self::new()
    }
}
