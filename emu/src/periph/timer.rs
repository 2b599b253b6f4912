//! TIM1 (advanced-control, RM0008 section 14) and TIM2 and TIM3 (general-purpose,
//! section 15) in what the board uses of them: up-counting, edge-aligned, with the
//! prescaler, the auto-reload and compare preloads, update events (overflow and UG,
//! URS, UDIS, OPM: the counter stops at any update event, CEN cleared), the four
//! compare channels in output mode (frozen, active/inactive/toggle on match, forced
//! levels, PWM modes 1 and 2) with their polarity and enable bits, TIM1's main output
//! enable (MOE, set by software or, with AOE, at the next update event), the status flags and their interrupts.
//!
//! The counter is computed from the time, never stepped: the board asks for the next
//! event (a compare match or an overflow) and the timer produces the output edges at
//! exactly their timer count. The PWM modes compare the counter with the compare
//! register continuously, so a write of the counter moves the output at once.
//! Down-counting, centre-aligned, slave and master modes and DMA requests are refused
//! (the run stops) rather than half-modelled.

use super::{unknown, Access, BusError};

/// An output edge of a compare channel at an exact time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    pub t: u64,
    pub channel: usize,
    pub level: bool,
}

pub struct Timer {
    name: &'static str,
    advanced: bool,
    cr1: u32,
    cr2: u32,
    smcr: u32,
    dier: u32,
    pub sr: u32,
    ccmr: [u32; 2],
    ccer: u32,
    psc: u32,
    psc_active: u32,
    arr: u32,
    arr_active: u32,
    ccr: [u32; 4],
    ccr_active: [u32; 4],
    rcr: u32,
    bdtr: u32,
    /// The counter value at `since`, where a prescaled count period starts.
    cnt: u32,
    since: u64,
    /// Time units per timer clock cycle.
    pub tick_t: u64,
    /// OCxREF of each channel.
    oc_ref: [bool; 4],
    /// Output level of each channel (after polarity and enables).
    pub out: [bool; 4],
}

impl Timer {
    pub fn new(name: &'static str, advanced: bool) -> Timer {
        Timer {
            name,
            advanced,
            cr1: 0,
            cr2: 0,
            smcr: 0,
            dier: 0,
            sr: 0,
            ccmr: [0; 2],
            ccer: 0,
            psc: 0,
            psc_active: 0,
            arr: 0xFFFF,
            arr_active: 0xFFFF,
            ccr: [0; 4],
            ccr_active: [0; 4],
            rcr: 0,
            bdtr: 0,
            cnt: 0,
            since: 0,
            tick_t: 1,
            oc_ref: [false; 4],
            out: [false; 4],
        }
    }

    pub fn reset(&mut self) {
        let tick_t = self.tick_t;
        *self = Timer::new(self.name, self.advanced);
        self.tick_t = tick_t;
    }

    fn running(&self) -> bool {
        self.cr1 & 1 != 0
    }

    fn count_t(&self) -> u64 {
        self.tick_t * (u64::from(self.psc_active) + 1)
    }

    fn oc_mode(&self, ch: usize) -> u32 {
        (self.ccmr[ch / 2] >> (8 * (ch % 2) + 4)) & 7
    }

    fn is_output(&self, ch: usize) -> bool {
        (self.ccmr[ch / 2] >> (8 * (ch % 2))) & 3 == 0
    }

    fn ccr_preload(&self, ch: usize) -> bool {
        (self.ccmr[ch / 2] >> (8 * (ch % 2) + 3)) & 1 != 0
    }

    /// The counter value at `now` and the time its current count began.
    fn counter_at(&self, now: u64) -> u32 {
        if !self.running() {
            return self.cnt;
        }
        let k = (now.saturating_sub(self.since)) / self.count_t();
        // Events are processed in order, so no overflow lies between since and now.
        (u64::from(self.cnt) + k).min(0xFFFF) as u32
    }

    /// Counts from `since` until the next event: a compare match or the overflow.
    fn counts_to_next(&self) -> Option<u64> {
        if !self.running() {
            return None;
        }
        let cnt = self.cnt;
        let top = if cnt > self.arr_active {
            0xFFFF
        } else {
            self.arr_active
        };
        let mut k = u64::from(top - cnt) + 1;
        for ch in 0..4 {
            let c = self.ccr_active[ch];
            if self.is_output(ch) && c > cnt && c <= top {
                k = k.min(u64::from(c - cnt));
            }
        }
        Some(k)
    }

    /// The time of the next event (flag, interrupt or output edge).
    pub fn next_event(&self) -> Option<u64> {
        self.counts_to_next()
            .map(|k| self.since + k * self.count_t())
    }

    /// Process every event up to `now`, collecting output edges.
    pub fn advance(&mut self, now: u64, edges: &mut Vec<Edge>) {
        while let Some(k) = self.counts_to_next() {
            let t = self.since + k * self.count_t();
            if t > now {
                break;
            }
            let top = if self.cnt > self.arr_active {
                0xFFFF
            } else {
                self.arr_active
            };
            let next = u64::from(self.cnt) + k;
            self.since = t;
            if next > u64::from(top) {
                self.cnt = 0;
                self.update_event(true);
            } else {
                self.cnt = next as u32;
            }
            self.compare(t, edges);
        }
    }

    /// An update event: preloads transferred, UIF set (not for UG with URS set), and in
    /// one-pulse mode the counter stopped (RM0008 15.4.1, OPM: "counter stops counting
    /// at the next update event").
    fn update_event(&mut self, overflow: bool) {
        if self.cr1 & 2 != 0 {
            // UDIS: no update event.
            return;
        }
        if self.cr1 & 8 != 0 {
            // One-pulse mode: the counter stops at the update event.
            self.cr1 &= !1;
        }
        // AOE (BDTR bit 14, advanced timers): MOE is set again at the update event
        // (RM0008 14.4.18); the HAL's PWM sets AOE, not MOE.
        if self.advanced && self.bdtr & (1 << 14) != 0 {
            self.bdtr |= 1 << 15;
        }
        self.psc_active = self.psc;
        self.arr_active = self.arr;
        for ch in 0..4 {
            if self.ccr_preload(ch) {
                self.ccr_active[ch] = self.ccr[ch];
            }
        }
        if overflow || self.cr1 & 4 == 0 {
            self.sr |= 1;
        }
    }

    /// Compare logic at the current counter value: flags and reference levels.
    fn compare(&mut self, t: u64, edges: &mut Vec<Edge>) {
        for ch in 0..4 {
            if !self.is_output(ch) {
                continue;
            }
            let c = self.ccr_active[ch];
            let matched = self.cnt == c;
            if matched {
                self.sr |= 2 << ch;
            }
            let r = self.oc_ref[ch];
            self.oc_ref[ch] = match self.oc_mode(ch) {
                0 => r,
                1 => r || matched,
                2 => r && !matched,
                3 => r ^ matched,
                4 => false,
                5 => true,
                6 => self.cnt < c,
                _ => self.cnt >= c,
            };
        }
        self.update_outputs(t, edges);
    }

    fn outputs_enabled(&self) -> bool {
        !self.advanced || self.bdtr & (1 << 15) != 0
    }

    fn update_outputs(&mut self, t: u64, edges: &mut Vec<Edge>) {
        for ch in 0..4 {
            let enabled = self.ccer & (1 << (4 * ch)) != 0 && self.outputs_enabled();
            let inverted = self.ccer & (2 << (4 * ch)) != 0;
            let level = enabled && (self.oc_ref[ch] != inverted);
            if level != self.out[ch] {
                self.out[ch] = level;
                edges.push(Edge {
                    t,
                    channel: ch,
                    level,
                });
            }
        }
    }

    /// Interrupt requests: (update, capture/compare) flags with their enables.
    pub fn irq(&self) -> (bool, bool) {
        let f = self.sr & self.dier;
        (f & 1 != 0, f & 0x1E != 0)
    }

    fn sync(&mut self, now: u64) {
        if self.running() {
            let c = self.counter_at(now);
            let k = u64::from(c - self.cnt);
            self.since += k * self.count_t();
            self.cnt = c;
        } else {
            self.since = now;
        }
    }

    pub fn read(&mut self, off: u32, now: u64) -> Access<u32> {
        Ok(match off {
            0x00 => self.cr1,
            0x04 => self.cr2,
            0x08 => self.smcr,
            0x0C => self.dier,
            0x10 => self.sr,
            0x14 => 0,
            0x18 => self.ccmr[0],
            0x1C => self.ccmr[1],
            0x20 => self.ccer,
            0x24 => self.counter_at(now),
            0x28 => self.psc,
            0x2C => self.arr,
            0x30 if self.advanced => self.rcr,
            0x34..=0x40 => self.ccr[((off - 0x34) / 4) as usize],
            0x44 if self.advanced => self.bdtr,
            0x48 | 0x4C => 0,
            _ => return Err(unknown(self.name, off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32, now: u64, edges: &mut Vec<Edge>) -> Access<()> {
        self.sync(now);
        let v16 = v & 0xFFFF;
        match off {
            0x00 => {
                if v & 0x70 != 0 {
                    return Err(BusError(format!(
                        "{}: down-counting or centre-aligned mode (CR1 0x{v:X}) is not modelled",
                        self.name
                    )));
                }
                let starting = self.cr1 & 1 == 0 && v & 1 != 0;
                self.cr1 = v & 0x3FF;
                if starting {
                    self.since = now;
                }
            }
            0x04 => {
                if v & 0x70 != 0 {
                    return Err(BusError(format!(
                        "{}: master mode (CR2 0x{v:X}) is not modelled",
                        self.name
                    )));
                }
                self.cr2 = v16;
            }
            0x08 => {
                if v & 7 != 0 {
                    return Err(BusError(format!(
                        "{}: slave mode is not modelled",
                        self.name
                    )));
                }
                self.smcr = v16;
            }
            0x0C => {
                if v & 0x7F00 != 0 {
                    return Err(BusError(format!(
                        "{}: DMA requests are not modelled",
                        self.name
                    )));
                }
                self.dier = v16;
            }
            // SR: rc_w0.
            0x10 => self.sr &= v,
            0x14 => {
                if v & 1 != 0 {
                    // UG: counter and prescaler restart, preloads transferred.
                    self.cnt = 0;
                    self.since = now;
                    self.update_event(false);
                    self.compare(now, edges);
                }
                self.sr |= v & 0x1E;
            }
            0x18 | 0x1C => {
                let i = ((off - 0x18) / 4) as usize;
                if v & 0x0303 != 0 {
                    return Err(BusError(format!(
                        "{}: input capture is not modelled",
                        self.name
                    )));
                }
                self.ccmr[i] = v16;
                // Forced levels act at once.
                self.compare_levels_now(now, edges);
            }
            0x20 => {
                self.ccer = v16;
                self.update_outputs(now, edges);
            }
            0x24 => {
                self.cnt = v16;
                self.since = now;
                self.compare_levels_now(now, edges);
            }
            0x28 => self.psc = v16,
            0x2C => {
                self.arr = v16;
                if self.cr1 & 0x80 == 0 {
                    self.arr_active = v16;
                }
            }
            0x30 if self.advanced => self.rcr = v & 0xFF,
            0x34..=0x40 => {
                let ch = ((off - 0x34) / 4) as usize;
                self.ccr[ch] = v16;
                if !self.ccr_preload(ch) {
                    self.ccr_active[ch] = v16;
                    self.compare_levels_now(now, edges);
                }
            }
            0x44 if self.advanced => {
                self.bdtr = v16;
                self.update_outputs(now, edges);
            }
            0x48 | 0x4C => {}
            _ => return Err(unknown(self.name, off)),
        }
        Ok(())
    }

    /// Forced modes take effect on the write, and the PWM modes compare the counter
    /// with the compare register continuously (RM0008 15.3.9), not only at a match.
    fn compare_levels_now(&mut self, now: u64, edges: &mut Vec<Edge>) {
        let cnt = self.counter_at(now);
        for ch in 0..4 {
            let c = self.ccr_active[ch];
            match self.oc_mode(ch) {
                4 => self.oc_ref[ch] = false,
                5 => self.oc_ref[ch] = true,
                6 => self.oc_ref[ch] = cnt < c,
                7 => self.oc_ref[ch] = cnt >= c,
                _ => {}
            }
        }
        self.update_outputs(now, edges);
    }
}

#[cfg(test)]
mod tests {
    //! RM0008 15.3 (TIM2): the counter, update events and the compare outputs.
    use super::*;

    /// TIM2 at one time unit per timer clock.
    fn tim2() -> Timer {
        let mut t = Timer::new("TIM2", false);
        t.tick_t = 1;
        t
    }

    fn w(t: &mut Timer, off: u32, v: u32, now: u64, edges: &mut Vec<Edge>) {
        t.write(off, v, now, edges).unwrap();
    }

    #[test]
    fn pwm_mode_1_rises_at_the_period_start_and_falls_at_the_compare_tick() {
        let (mut t, mut e) = (tim2(), Vec::new());
        // CH1 PWM mode 1 (OC1M = 110) with CCR preload, output enabled, ARR 99, CCR 30.
        w(&mut t, 0x18, 0x68, 0, &mut e);
        w(&mut t, 0x2C, 99, 0, &mut e);
        w(&mut t, 0x34, 30, 0, &mut e);
        w(&mut t, 0x20, 1, 0, &mut e);
        w(&mut t, 0x14, 1, 0, &mut e); // UG: preloads in, counter 0: OC1REF high
        assert_eq!(
            e,
            [Edge {
                t: 0,
                channel: 0,
                level: true
            }]
        );
        e.clear();
        w(&mut t, 0x10, 0, 0, &mut e); // clear UIF from UG
        w(&mut t, 0x00, 1, 10, &mut e); // CEN at t = 10
        t.advance(250, &mut e);
        // Low from CNT = CCR (10 + 30), high again at each update (CNT 0 after 99).
        let want = [
            (40, false),
            (110, true),
            (140, false),
            (210, true),
            (240, false),
        ];
        let got: Vec<(u64, bool)> = e.iter().map(|x| (x.t, x.level)).collect();
        assert_eq!(got, want);
        assert_eq!(t.sr & 1, 1, "UIF set by the overflows");
        assert_eq!(t.sr & 2, 2, "CC1IF set by the matches");
    }

    #[test]
    fn polarity_inverts_and_a_disabled_channel_stays_low() {
        let (mut t, mut e) = (tim2(), Vec::new());
        w(&mut t, 0x18, 0x60 | 0x6000, 0, &mut e); // CH1 and CH2 PWM mode 1
        w(&mut t, 0x2C, 9, 0, &mut e);
        w(&mut t, 0x34, 5, 0, &mut e);
        w(&mut t, 0x38, 5, 0, &mut e);
        w(&mut t, 0x20, 0x3, 0, &mut e); // CC1E with CC1P (active low); CH2 off
        w(&mut t, 0x00, 1, 0, &mut e);
        t.advance(20, &mut e);
        assert!(e.iter().all(|x| x.channel == 0), "{e:?}");
        let got: Vec<(u64, bool)> = e.iter().map(|x| (x.t, x.level)).collect();
        // REF is high at CNT 0 .. 4 (output low), low from 5 (output high).
        assert_eq!(got, [(5, true), (10, false), (15, true), (20, false)]);
    }

    #[test]
    fn one_pulse_mode_stops_the_counter_at_the_update_event() {
        let (mut t, mut e) = (tim2(), Vec::new());
        w(&mut t, 0x2C, 49, 0, &mut e);
        w(&mut t, 0x00, 0x9, 0, &mut e); // OPM + CEN
        t.advance(200, &mut e);
        assert_eq!(t.read(0x00, 200).unwrap() & 1, 0, "CEN cleared");
        assert_eq!(t.read(0x24, 200).unwrap(), 0);
        assert_eq!(t.sr & 1, 1);
        assert_eq!(t.next_event(), None);
    }

    #[test]
    fn one_pulse_mode_fires_an_armed_pwm_pulse_once_and_waits_for_the_restart() {
        // The step output of issue 20: CH1 PWM mode 1 with CCR preload, OPM. A pulse
        // armed through the preload starts at the update event, where the counter
        // stops; it ends CCR ticks after a restart from 0 or at once when the counter
        // is written past CCR; and with no restart nothing more happens, however long.
        let (mut t, mut e) = (tim2(), Vec::new());
        w(&mut t, 0x18, 0x68, 0, &mut e);
        w(&mut t, 0x20, 1, 0, &mut e);
        w(&mut t, 0x2C, 99, 0, &mut e);
        w(&mut t, 0x34, 30, 0, &mut e); // armed for the end of the first period
        w(&mut t, 0x00, 0xD, 0, &mut e); // CEN, URS, OPM
        t.advance(100_000, &mut e);
        let got: Vec<(u64, bool)> = e.iter().map(|x| (x.t, x.level)).collect();
        assert_eq!(got, [(100, true)], "one rising edge, held while stopped");
        assert_eq!(t.read(0x00, 100_000).unwrap() & 1, 0, "CEN cleared");
        assert_eq!(t.next_event(), None);
        e.clear();
        // A late restart: the counter written past CCR ends the pulse at once; the
        // period ends ARR + 1 - CNT ticks after the start. The preload still holds 30:
        // the next update fires it once more, exactly once, and stops again.
        w(&mut t, 0x24, 90, 100_050, &mut e);
        w(&mut t, 0x00, 0xD, 100_051, &mut e);
        assert_eq!(t.next_event(), Some(100_061));
        t.advance(300_000, &mut e);
        let got: Vec<(u64, bool)> = e.iter().map(|x| (x.t, x.level)).collect();
        assert_eq!(got, [(100_050, false), (100_061, true)]);
        e.clear();
        // An on-time restart from CNT 5 keeps the pulse's end at CCR: 25 ticks on.
        w(&mut t, 0x34, 0, 300_010, &mut e); // disarm the next update
        w(&mut t, 0x24, 5, 300_010, &mut e);
        w(&mut t, 0x00, 0xD, 300_010, &mut e);
        t.advance(400_000, &mut e);
        let got: Vec<(u64, bool)> = e.iter().map(|x| (x.t, x.level)).collect();
        assert_eq!(
            got,
            [(300_035, false)],
            "ends at CCR, no pulse at the update"
        );
    }

    #[test]
    fn tim1_automatic_output_enable_sets_moe_at_the_next_update() {
        // What the servo's PWM setup does: BDTR = AOE only, CH1 PWM mode 1 enabled.
        let mut t = Timer::new("TIM1", true);
        let mut e = Vec::new();
        w(&mut t, 0x2C, 99, 0, &mut e); // ARR
        w(&mut t, 0x34, 30, 0, &mut e); // CCR1
        w(&mut t, 0x18, 0x68, 0, &mut e); // OC1M PWM 1, preload
        w(&mut t, 0x20, 1, 0, &mut e); // CC1E
        w(&mut t, 0x44, 0x4000, 0, &mut e); // AOE, MOE clear
        w(&mut t, 0x00, 1, 0, &mut e); // CEN
        t.advance(99, &mut e);
        assert!(e.is_empty(), "no output before the first update: {e:?}");
        t.advance(100, &mut e);
        assert_eq!(
            e,
            [Edge {
                t: 100,
                channel: 0,
                level: true
            }],
            "MOE set at the update"
        );
        assert_eq!(t.read(0x44, 100).unwrap() & 0xC000, 0xC000);
        e.clear();
        t.advance(130, &mut e);
        assert_eq!(
            e,
            [Edge {
                t: 130,
                channel: 0,
                level: false
            }]
        );
        // Without AOE the output stays off.
        let mut t = Timer::new("TIM1", true);
        let mut e = Vec::new();
        w(&mut t, 0x2C, 99, 0, &mut e);
        w(&mut t, 0x34, 30, 0, &mut e);
        w(&mut t, 0x18, 0x68, 0, &mut e);
        w(&mut t, 0x20, 1, 0, &mut e);
        w(&mut t, 0x00, 1, 0, &mut e);
        t.advance(1000, &mut e);
        assert!(e.is_empty(), "{e:?}");
    }

    #[test]
    fn unmodelled_master_and_slave_modes_are_refused() {
        let (mut t, mut e) = (tim2(), Vec::new());
        assert!(t.write(0x04, 0x20, 0, &mut e).is_err(), "TRGO = update");
        assert!(t.write(0x08, 0x04, 0, &mut e).is_err(), "slave reset mode");
        assert!(t.write(0x04, 0x08, 0, &mut e).is_ok(), "CCDS alone");
    }

    #[test]
    fn arr_preload_takes_effect_at_the_update_and_urs_keeps_ug_quiet() {
        let (mut t, mut e) = (tim2(), Vec::new());
        w(&mut t, 0x2C, 9, 0, &mut e);
        w(&mut t, 0x00, 0x80 | 0x4 | 1, 0, &mut e); // ARPE, URS, CEN
        w(&mut t, 0x14, 1, 0, &mut e); // UG: no UIF with URS
        assert_eq!(t.sr & 1, 0);
        w(&mut t, 0x2C, 19, 3, &mut e); // preloaded: the period in progress stays 10
        assert_eq!(t.next_event(), Some(10));
        t.advance(10, &mut e);
        assert_eq!(t.sr & 1, 1, "overflow sets UIF even with URS");
        assert_eq!(t.next_event(), Some(30), "the new period of 20");
    }

    #[test]
    fn the_counter_reads_from_the_time_and_the_prescaler() {
        let (mut t, mut e) = (tim2(), Vec::new());
        w(&mut t, 0x28, 3, 0, &mut e); // PSC 3: /4, taken at the update
        w(&mut t, 0x14, 1, 0, &mut e);
        w(&mut t, 0x00, 1, 100, &mut e);
        assert_eq!(t.read(0x24, 100 + 4 * 7 + 3).unwrap(), 7);
    }
}
