//! 4-phase unipolar output (28BYJ-48 through a ULN2003): each step moves an axis one
//! position along the half-step 8-beat sequence A, AB, B, BC, C, CD, D, DA
//! (0x01, 0x03, 0x02, 0x06, 0x04, 0x0C, 0x08, 0x09), backwards for negative steps.
//! Owns only the sequence index per axis; the board module writes the 4 bits to pins.

use crate::interpolation::StepEvent;
use crate::motion::AXES;

/// The half-step sequence (bit 0 = coil A ... bit 3 = coil D).
pub const HALF_STEP: [u8; 8] = [0x01, 0x03, 0x02, 0x06, 0x04, 0x0C, 0x08, 0x09];

/// Sequence position of every axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Phase4 {
    idx: [u8; AXES],
}

impl Phase4 {
    /// Advances the stepping axes and returns the coil pattern of every axis.
    #[inline]
    pub fn step(&mut self, tick: StepEvent) -> [u8; AXES] {
        let (steps, neg) = (tick.steps(), tick.dirs());
        for (i, idx) in self.idx.iter_mut().enumerate() {
            if steps & (1 << i) != 0 {
                *idx = if neg & (1 << i) != 0 {
                    idx.wrapping_sub(1)
                } else {
                    idx.wrapping_add(1)
                } & 7;
            }
        }
        self.coils()
    }
    /// Present coil pattern of every axis.
    pub fn coils(&self) -> [u8; AXES] {
        core::array::from_fn(|i| HALF_STEP[usize::from(self.idx[i] & 7)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walks_the_half_step_sequence_both_ways() {
        let mut p = Phase4::default();
        let fwd = StepEvent::from_deltas([1, 0, 0]);
        let mut seen = std::vec![p.coils()[0]];
        for _ in 0..8 {
            seen.push(p.step(fwd)[0]);
        }
        assert_eq!(seen, [0x01, 0x03, 0x02, 0x06, 0x04, 0x0C, 0x08, 0x09, 0x01]);
        let back = StepEvent::from_deltas([-1, 0, 0]);
        assert_eq!(p.step(back)[0], 0x09);
        assert_eq!(p.step(back)[0], 0x08);
        // Other axes untouched.
        assert_eq!(p.coils()[1], 0x01);
    }
}
