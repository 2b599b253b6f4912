//! The buzzer's pattern player: turns a [`Beep`] into on/off levels over time. The
//! firmware ticks it from its periodic keypad task, so no task ever waits for a beep
//! to end; a new beep replaces the one playing.

use super::io::Beep;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Buzzer {
    /// On/off times in ms, starting with "on" ([`Beep::pattern`]).
    pattern: &'static [u16],
    /// Segments started so far (odd = the current segment is an "on" time).
    started: usize,
    left_ms: u32,
}

impl Buzzer {
    pub const fn new() -> Self {
        Buzzer {
            pattern: &[],
            started: 0,
            left_ms: 0,
        }
    }

    /// Start `beep` now, replacing whatever is playing.
    pub fn play(&mut self, beep: Beep) {
        *self = Buzzer {
            pattern: beep.pattern(),
            started: 0,
            left_ms: 0,
        };
    }

    /// Advance by `dt_ms` (the caller's tick); returns whether the buzzer sounds
    /// during this tick.
    pub fn tick(&mut self, dt_ms: u32) -> bool {
        if self.left_ms == 0 {
            match self.pattern.get(self.started) {
                Some(&ms) => {
                    self.left_ms = u32::from(ms);
                    self.started += 1;
                }
                None => return false,
            }
        }
        self.left_ms = self.left_ms.saturating_sub(dt_ms);
        self.started % 2 == 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The levels of `n` ticks of 5 ms.
    fn levels(b: &mut Buzzer, n: usize) -> std::vec::Vec<bool> {
        (0..n).map(|_| b.tick(5)).collect()
    }

    #[test]
    fn silent_until_a_beep_plays() {
        let mut b = Buzzer::new();
        assert!(levels(&mut b, 10).iter().all(|&on| !on));
    }

    #[test]
    fn done_is_one_chirp_of_150_ms() {
        let mut b = Buzzer::new();
        b.play(Beep::Done);
        let l = levels(&mut b, 40);
        assert!(l[..30].iter().all(|&on| on), "{l:?}");
        assert!(l[30..].iter().all(|&on| !on), "{l:?}");
    }

    #[test]
    fn error_is_two_quick_beeps() {
        let mut b = Buzzer::new();
        b.play(Beep::Error);
        let l = levels(&mut b, 60);
        let on_ticks: usize = l.iter().filter(|&&on| on).count();
        assert_eq!(on_ticks, 32, "two 80 ms beeps at 5 ms ticks");
        assert!(l[..16].iter().all(|&on| on) && l[16..32].iter().all(|&on| !on));
        assert!(l[32..48].iter().all(|&on| on) && l[48..].iter().all(|&on| !on));
    }

    #[test]
    fn a_new_beep_replaces_the_one_playing() {
        let mut b = Buzzer::new();
        b.play(Beep::Alarm);
        levels(&mut b, 10);
        b.play(Beep::Done);
        let l = levels(&mut b, 40);
        assert_eq!(l.iter().filter(|&&on| on).count(), 30);
    }
}
