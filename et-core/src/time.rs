//! Time is passed in, never read: [`Micros`] stamps frames and status from whatever clock the
//! caller owns (a monotonic timer on the board, a simulated clock in tests).

use serde::{Deserialize, Serialize};

/// Microseconds on the device's clock, wrapping after about 71.6 minutes.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Serialize, Deserialize,
)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Micros(pub u32);

impl Micros {
    /// Time from `earlier` to `self`, correct across one wrap of the counter.
    #[must_use]
    pub fn since(self, earlier: Micros) -> u32 {
        self.0.wrapping_sub(earlier.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn since_survives_the_wrap() {
        assert_eq!(Micros(10).since(Micros(u32::MAX - 5)), 16);
        assert_eq!(Micros(500).since(Micros(200)), 300);
    }
}
