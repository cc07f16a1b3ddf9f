//! The hardware seam: everything the scan engine needs from a sensor.
//!
//! One trait, [`Frontend`], with several implementations: the board (firmware), the simulated
//! sheet (`sim`), and wrappers (fault injection, recording). Where real pins and delays are
//! involved, [`MuxLines`] drives the two 16:1 multiplexers of docs/method.md §2 through embedded-hal 1.0
//! [`OutputPin`]s and a [`DelayNs`], so a board's `Frontend` is mostly wiring.

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;

use crate::config::ScanConfig;
use crate::protocol::{Injection, Measurement, MuxWord, ProtocolError};

/// How raw ADC codes map to volts at the electrodes.
///
/// `volts = (code - zero_code) * volts_per_code`. Codes `0` and `2^bits - 1` are the rails:
/// a sample there may be clipped and is flagged by the scan engine.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdcScale {
    /// ADC resolution in bits (16 on the reference board), `1..=16`.
    pub bits: u8,
    /// The code that reads 0 V (32 768 for a bipolar 16-bit ADC).
    pub zero_code: f32,
    /// Volts at the electrodes per code, gain included (about 150 uV on the reference board
    /// at unity gain: 10 V / 65 536).
    pub volts_per_code: f32,
}

impl AdcScale {
    /// The reference board's ADC (docs/method.md §2): 16 bits over +-5 V, divided by the PGIA `gain`.
    #[must_use]
    pub fn bipolar_16bit(range_volts: f32, gain: u8) -> Self {
        Self {
            bits: 16,
            zero_code: 32_768.0,
            volts_per_code: 2.0 * range_volts / 65_536.0 / f32::from(gain.max(1)),
        }
    }

    /// The highest code (the upper rail).
    #[must_use]
    pub fn max_code(&self) -> u16 {
        if self.bits >= 16 {
            u16::MAX
        } else {
            (1u16 << self.bits.max(1)) - 1
        }
    }

    /// Whether `code` sits on a rail (possibly clipped).
    #[must_use]
    pub fn at_rail(&self, code: u16) -> bool {
        code == 0 || code >= self.max_code()
    }

    /// `code` (possibly fractional, e.g. a median of an even count) in volts.
    #[must_use]
    pub fn volts(&self, code: f32) -> f32 {
        (code - self.zero_code) * self.volts_per_code
    }

    /// Whether the scale is usable (bits in range, finite positive step).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        (1..=16).contains(&self.bits)
            && self.zero_code.is_finite()
            && self.volts_per_code.is_finite()
            && self.volts_per_code > 0.0
    }
}

/// The hardware seam: a sensor the scan engine can drive.
///
/// The engine calls [`configure`](Frontend::configure) once per configuration, then for every
/// step of the protocol [`select`](Frontend::select) and [`acquire`](Frontend::acquire). A
/// front end that samples all channels of an injection in parallel (the reference board) may
/// acquire once per injection and answer the measurements of that injection from memory.
pub trait Frontend {
    /// What can go wrong in this front end (a HAL error, a disconnected simulator, ...).
    type Error: core::fmt::Debug;

    /// Applies `config` (current, gain, sample rate) and says how codes map to volts.
    ///
    /// # Errors
    /// When the hardware cannot do what `config` asks.
    fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, Self::Error>;

    /// Routes the current to `injection` and the amplifier to `measurement`. Switching the
    /// injection may start a transient: the engine drops the first t_s samples of each burst.
    ///
    /// # Errors
    /// When the switch cannot be made.
    fn select(&mut self, injection: Injection, measurement: Measurement)
    -> Result<(), Self::Error>;

    /// Fills `samples` with consecutive raw ADC codes of the selected measurement.
    ///
    /// # Errors
    /// When sampling fails (timeout, DMA error, ...).
    fn acquire(&mut self, samples: &mut [u16]) -> Result<(), Self::Error>;

    /// Whether the current source was in compliance during the selected step: its load
    /// needed more than V_out_max / (2 I), so it delivered less than the set current and the
    /// readings are smaller than the protocol expects. A front end that cannot tell (the
    /// reference board has no monitor on the pump's output) says `false`.
    fn in_compliance(&self) -> bool {
        false
    }
}

impl<F: Frontend + ?Sized> Frontend for &mut F {
    type Error = F::Error;
    fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, Self::Error> {
        (**self).configure(config)
    }
    fn select(
        &mut self,
        injection: Injection,
        measurement: Measurement,
    ) -> Result<(), Self::Error> {
        (**self).select(injection, measurement)
    }
    fn acquire(&mut self, samples: &mut [u16]) -> Result<(), Self::Error> {
        (**self).acquire(samples)
    }
    fn in_compliance(&self) -> bool {
        (**self).in_compliance()
    }
}

/// Error of [`MuxLines::route`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MuxError<E> {
    /// A pin refused the level (the HAL's error).
    Pin(E),
    /// The injection uses an electrode the muxes cannot address.
    Range(ProtocolError),
}

/// The 10 mux control lines of docs/method.md §2 on embedded-hal pins, with the settling delay after
/// each switch.
///
/// `lines[n]` carries bit `n` of the [`MuxWord`]: 0-3 source address, 4 source enable, 5-8
/// sink address, 9 sink enable. Switching is break-before-make: both enables drop, the
/// addresses change, then the enables rise, then the driver waits `settle_ns` (the PGIA needs
/// about 8 us, the ADG1606 143 ns).
#[derive(Debug)]
pub struct MuxLines<P, D> {
    lines: [P; MuxWord::LINES],
    delay: D,
    settle_ns: u32,
    current: MuxWord,
}

impl<P: OutputPin, D: DelayNs> MuxLines<P, D> {
    /// Takes the pins (line order as in [`MuxWord`]) and a delay; starts with every line low.
    ///
    /// # Errors
    /// The pin error if a line cannot be driven low.
    pub fn new(mut lines: [P; MuxWord::LINES], delay: D, settle_ns: u32) -> Result<Self, P::Error> {
        for pin in &mut lines {
            pin.set_low()?;
        }
        Ok(Self {
            lines,
            delay,
            settle_ns,
            current: MuxWord::OFF,
        })
    }

    /// The word currently on the lines.
    #[must_use]
    pub fn word(&self) -> MuxWord {
        self.current
    }

    /// Routes `injection` (no-op if it is already routed).
    ///
    /// # Errors
    /// [`MuxError::Range`] for an electrode above 15, [`MuxError::Pin`] from the HAL.
    pub fn route(&mut self, injection: Injection) -> Result<(), MuxError<P::Error>> {
        let word = MuxWord::for_injection(injection).map_err(MuxError::Range)?;
        if word == self.current {
            return Ok(());
        }
        self.write(self.current.disabled()).map_err(MuxError::Pin)?;
        self.write(word.disabled()).map_err(MuxError::Pin)?;
        self.write(word).map_err(MuxError::Pin)?;
        self.delay.delay_ns(self.settle_ns);
        Ok(())
    }

    /// Disables both muxes (no current flows).
    ///
    /// # Errors
    /// The pin error.
    pub fn off(&mut self) -> Result<(), P::Error> {
        self.write(self.current.disabled())
    }

    fn write(&mut self, word: MuxWord) -> Result<(), P::Error> {
        for (n, pin) in self.lines.iter_mut().enumerate() {
            if word.line(n) {
                pin.set_high()?;
            } else {
                pin.set_low()?;
            }
        }
        self.current = word;
        Ok(())
    }

    /// Gives the pins and the delay back.
    pub fn release(self) -> ([P; MuxWord::LINES], D) {
        (self.lines, self.delay)
    }
}

/// A burst of scans of every electrode's potential, as a board that samples all electrodes in
/// parallel delivers it: `scans` rounds of `channels` single-ended codes of a unipolar
/// `bits`-bit ADC, interleaved (code of channel c in scan i at `i * channels + c`). A
/// measurement is the difference of two channels; [`difference`](Self::difference) gives its
/// burst on the [`difference_scale`], so the scan engine (settle, median, rail flags) runs on it
/// unchanged.
#[derive(Debug, Clone, Copy)]
pub struct ParallelBurst<'a> {
    codes: &'a [u16],
    channels: usize,
    bits: u8,
}

/// Why a [`ParallelBurst`] refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BurstError {
    /// No channels, bits outside 1..=15, or codes not a whole number of scans.
    Shape,
    /// A probe channel outside the burst.
    Channel,
    /// The output holds fewer samples than the burst has scans.
    Output,
}

/// The scale of [`ParallelBurst::difference`] codes for a `bits`-bit single-ended ADC of
/// `volts_per_code` (gain included): one bit more, zero at 2^bits.
#[must_use]
pub fn difference_scale(bits: u8, volts_per_code: f32) -> AdcScale {
    AdcScale {
        bits: bits + 1,
        zero_code: f32::from(1u16 << bits),
        volts_per_code,
    }
}

impl<'a> ParallelBurst<'a> {
    /// Wraps `codes` of `channels` interleaved channels.
    ///
    /// # Errors
    /// [`BurstError::Shape`].
    pub fn new(codes: &'a [u16], channels: usize, bits: u8) -> Result<Self, BurstError> {
        if channels == 0 || !(1..=15).contains(&bits) || !codes.len().is_multiple_of(channels) {
            return Err(BurstError::Shape);
        }
        Ok(Self {
            codes,
            channels,
            bits,
        })
    }

    /// Scans in the burst.
    #[must_use]
    pub fn scans(&self) -> usize {
        self.codes.len() / self.channels
    }

    /// Writes the burst of V_p - V_q into `out[..scans]` as [`difference_scale`] codes:
    /// `code_p - code_q + 2^bits`. A sample where either input sits on a rail of its ADC
    /// (0 or 2^bits - 1) goes to the matching rail of the difference scale (the positive one
    /// when p is high or q low), so the scan engine flags it; no other difference reaches a
    /// rail.
    ///
    /// # Errors
    /// [`BurstError::Channel`] for a probe outside the burst, [`BurstError::Output`] for a short
    /// `out`.
    pub fn difference(&self, p: usize, q: usize, out: &mut [u16]) -> Result<(), BurstError> {
        if p >= self.channels || q >= self.channels {
            return Err(BurstError::Channel);
        }
        let out = out.get_mut(..self.scans()).ok_or(BurstError::Output)?;
        let top = (1u16 << self.bits) - 1;
        let zero = 1u16 << self.bits;
        let high = (1u16 << (self.bits + 1)) - 1;
        for (i, o) in out.iter_mut().enumerate() {
            let (a, b) = (
                self.codes[i * self.channels + p].min(top),
                self.codes[i * self.channels + q].min(top),
            );
            *o = if a == top || b == 0 {
                high
            } else if a == 0 || b == top {
                0
            } else {
                a + zero - b
            };
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::ElectrodeId;
    use core::cell::RefCell;
    use core::convert::Infallible;
    use std::vec::Vec;

    /// A pin that logs (line, level) into a shared journal.
    struct Pin<'a> {
        n: usize,
        log: &'a RefCell<Vec<(usize, bool)>>,
    }
    impl embedded_hal::digital::ErrorType for Pin<'_> {
        type Error = Infallible;
    }
    impl OutputPin for Pin<'_> {
        fn set_low(&mut self) -> Result<(), Infallible> {
            self.log.borrow_mut().push((self.n, false));
            Ok(())
        }
        fn set_high(&mut self) -> Result<(), Infallible> {
            self.log.borrow_mut().push((self.n, true));
            Ok(())
        }
    }
    struct Delay<'a>(&'a RefCell<Vec<u32>>);
    impl DelayNs for Delay<'_> {
        fn delay_ns(&mut self, ns: u32) {
            self.0.borrow_mut().push(ns);
        }
    }

    #[test]
    fn routes_break_before_make_and_settles() {
        let log = RefCell::new(Vec::new());
        let delays = RefCell::new(Vec::new());
        let pins = core::array::from_fn(|n| Pin { n, log: &log });
        let mut mux = MuxLines::new(pins, Delay(&delays), 8_000).unwrap();
        let inj = Injection {
            source: ElectrodeId(3),
            sink: ElectrodeId(11),
        };
        log.borrow_mut().clear();
        mux.route(inj).unwrap();
        assert_eq!(mux.word().injection(), Some(inj));
        // Replay the journal: the enables never rise while an address line still changes.
        let mut level = [false; 10];
        let mut enabled_at = None;
        for (i, &(n, high)) in log.borrow().iter().enumerate() {
            if (n == 4 || n == 9) && high && enabled_at.is_none() {
                enabled_at = Some(i);
            }
            if enabled_at.is_some() && n != 4 && n != 9 {
                assert_eq!(level[n], high, "address line {n} changed after enable");
            }
            level[n] = high;
        }
        let addr = |base: usize| {
            (0..4)
                .map(|b| usize::from(level[base + b]) << b)
                .sum::<usize>()
        };
        assert_eq!((addr(0), addr(5)), (3, 11));
        assert!(level[4] && level[9]);
        assert_eq!(*delays.borrow(), [8_000]);
        // Same injection again: nothing switches, no settle.
        mux.route(inj).unwrap();
        assert_eq!(delays.borrow().len(), 1);
        let far = Injection {
            source: ElectrodeId(16),
            sink: ElectrodeId(0),
        };
        assert!(matches!(mux.route(far), Err(MuxError::Range(_))));
    }

    #[test]
    fn adc_scale_rails_and_volts() {
        let s = AdcScale::bipolar_16bit(5.0, 1);
        assert!(s.is_valid());
        assert!(s.at_rail(0) && s.at_rail(65_535) && !s.at_rail(1) && !s.at_rail(65_534));
        assert!((s.volts_per_code - 152.6e-6).abs() < 0.1e-6);
        assert_eq!(s.volts(32_768.0), 0.0);
        let s12 = AdcScale {
            bits: 12,
            zero_code: 2048.0,
            volts_per_code: 1e-3,
        };
        assert_eq!(s12.max_code(), 4095);
        assert!(s12.at_rail(4095) && s12.at_rail(5000));
        assert!(!AdcScale { bits: 0, ..s12 }.is_valid());
        assert!(
            !AdcScale {
                volts_per_code: f32::NAN,
                ..s12
            }
            .is_valid()
        );
    }

    /// Interleaved codes of 3 channels over `scans` scans: channel c reads `base[c] + i`.
    fn interleaved(base: [u16; 3], scans: usize) -> std::vec::Vec<u16> {
        (0..scans)
            .flat_map(|i| base.map(|b| b + i as u16))
            .collect()
    }

    #[test]
    fn parallel_bursts_give_differences_on_their_scale() {
        let codes = interleaved([2000, 1500, 3000], 4);
        let burst = ParallelBurst::new(&codes, 3, 12).unwrap();
        assert_eq!(burst.scans(), 4);
        let mut out = [0u16; 4];
        burst.difference(0, 1, &mut out).unwrap();
        assert_eq!(out, [4096 + 500; 4]);
        burst.difference(1, 2, &mut out).unwrap();
        assert_eq!(out, [4096 - 1500; 4]);
        let scale = difference_scale(12, 3.3 / 4096.0);
        assert!((scale.volts(f32::from(out[0])) - (-1500.0 * 3.3 / 4096.0)).abs() < 1e-6);
        assert_eq!(scale.max_code(), 8191);
        // Rails of either input become rails of the difference, with the right sign.
        let codes = [4095, 10, 2000, 0, 2000, 2000, 100, 4095, 7];
        let burst = ParallelBurst::new(&codes, 3, 12).unwrap();
        let mut out = [0u16; 3];
        // Scans: [4095, 10, 2000], [0, 2000, 2000], [100, 4095, 7].
        burst.difference(0, 2, &mut out).unwrap();
        assert_eq!(out, [8191, 0, 4096 + 93]);
        assert_eq!(out.map(|c| scale.at_rail(c)), [true, true, false]);
        burst.difference(2, 1, &mut out).unwrap();
        assert_eq!(out, [4096 + 1990, 4096, 0], "q high: the negative rail");
        burst.difference(1, 0, &mut out).unwrap();
        assert_eq!(out, [0, 8191, 8191], "q high, q low, p high");
        // Shapes.
        assert_eq!(
            ParallelBurst::new(&codes[..8], 3, 12).err(),
            Some(BurstError::Shape)
        );
        assert_eq!(
            ParallelBurst::new(&codes, 0, 12).err(),
            Some(BurstError::Shape)
        );
        assert_eq!(
            ParallelBurst::new(&codes, 3, 16).err(),
            Some(BurstError::Shape)
        );
        assert_eq!(burst.difference(3, 0, &mut out), Err(BurstError::Channel));
        assert_eq!(
            burst.difference(0, 1, &mut out[..2]),
            Err(BurstError::Output)
        );
    }

    #[test]
    fn no_difference_of_inputs_off_the_rails_lands_on_a_rail() {
        let bits = 6u8;
        let top = (1u16 << bits) - 1;
        for a in 1..top {
            for b in 1..top {
                let codes = [a, b];
                let mut out = [0u16; 1];
                ParallelBurst::new(&codes, 2, bits)
                    .unwrap()
                    .difference(0, 1, &mut out)
                    .unwrap();
                assert!(!difference_scale(bits, 1.0).at_rail(out[0]), "{a} {b}");
                assert_eq!(i32::from(out[0]) - 64, i32::from(a) - i32::from(b));
            }
        }
    }
}
