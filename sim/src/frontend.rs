//! The simulated acquisition chain (docs/method.md §2-3), as an [`et_core::Frontend`]: the real scan
//! engine runs against it sample by sample.
//!
//! Noise comes in two layers (docs/calibration.md):
//!
//! - **Frame to frame**, within one measurement set. Per step the Howland source drives the
//!   injection (the readings see a small relative jitter of its current from one injection to
//!   the next: the source and the ADC share one voltage reference, so the ratiometric reading
//!   cancels most of the source's own jitter; it saturates at its compliance); the
//!   instrumentation amplifier sees the measurement pair's voltage, reached through a
//!   first-order switching transient from whatever it showed before; the amplifier's white
//!   noise and the mains hum its common-mode rejection lets through add on; the PGIA gain
//!   scales it; the ADC adds its own transition noise (a fraction of a code, the dither that
//!   keeps a median of codes unbiased), quantises, and clips at its rails.
//! - **Between measurement sets** ([`SetSpread`], drawn by [`SetSpread::draw`] and applied by
//!   [`SimFrontend::set_state`]): each electrode's DC junction potential (clip on PPy) and the
//!   sheet's conductance (temperature, humidity) differ from one set to the next. Electrode
//!   re-placement, were the sheet taken off between sets, is the sheet's
//!   (`et_sim::sheet::SimulatedSheet::new`'s offsets); the calibration keeps it mounted.
//!
//! [`SimFrontend::fast_frame`] gives whole frames with the same statistics without the
//! settling transient: per step the settled value, the current jitter, the mains value
//! mid-step, and the median of the step's kept samples, each with its white and ADC noise and
//! quantised (drawn sample by sample, so that the median of codes is the scan engine's).

use std::f64::consts::PI;
use std::sync::Arc;

use et_core::ScanConfig;
use et_core::frontend::{AdcScale, Frontend};
use et_core::protocol::{Injection, Measurement, Protocol};
use serde::{Deserialize, Serialize};

use crate::network::Transfer;
use crate::sheet::{SheetError, SimulatedSheet, Source};
use crate::touch::Touch;
use et_core::rng::Rng;

/// The front end's parameters. Defaults are the calibrated reference hardware
/// (docs/calibration.md).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrontendSpec {
    /// Current source and multiplexers.
    pub source: Source,
    /// ADC resolution, bits.
    pub adc_bits: u8,
    /// ADC input range, +- V (at unity gain).
    pub adc_range_v: f64,
    /// White noise per sample at the amplifier input, V rms.
    pub white_noise_v: f64,
    /// The ADC's own noise per sample (transition and reference noise), codes rms: the dither
    /// that keeps the median of a burst from sticking to one code.
    pub adc_noise_codes: f64,
    /// Relative rms jitter of the current from one injection to the next, as the readings
    /// see it (what the ratiometric measurement leaves of the source's jitter).
    pub current_noise: f64,
    /// Mains hum amplitude at the amplifier input, V (what the amplifier's common-mode
    /// rejection lets through).
    pub mains_v: f64,
    /// Mains frequency, Hz.
    pub mains_hz: f64,
    /// Time constant of the settling transient after each switch, us.
    pub settle_tau_us: f64,
    /// How one measurement set differs from the next.
    pub sets: SetSpread,
}

impl Default for FrontendSpec {
    fn default() -> Self {
        Self {
            source: Source::default(),
            adc_bits: 16,
            adc_range_v: 5.0,
            white_noise_v: CALIBRATED_WHITE_NOISE_V,
            adc_noise_codes: ADC_NOISE_CODES,
            current_noise: CALIBRATED_CURRENT_NOISE,
            mains_v: MAINS_V,
            mains_hz: 50.0,
            settle_tau_us: 50.0,
            sets: SetSpread::default(),
        }
    }
}

/// Calibrated white noise per sample at the amplifier input, V rms. With
/// [`CALIBRATED_CURRENT_NOISE`] it gives the reference's frame-to-frame SNR on the adjacent
/// protocol of the 13 x 13 cm, 16-electrode sheet: 55 dB at 32 uA, 49 dB at 10 uA
/// (docs/method.md §3, at PGIA gain [`CALIBRATION_GAIN`]). Fitted by
/// `cargo run --release -p et-sim --example calibrate`; checked by the `calibration` tests.
pub const CALIBRATED_WHITE_NOISE_V: f64 = 49e-6;
/// Calibrated relative current jitter between injections, as the readings see it (see
/// [`CALIBRATED_WHITE_NOISE_V`]).
pub const CALIBRATED_CURRENT_NOISE: f64 = 1.08e-3;
/// The ADC's transition noise, codes rms (not fitted: typical of a 16-bit SAR converter).
pub const ADC_NOISE_CODES: f64 = 0.5;
/// Mains hum at the amplifier input, V (not fitted: about 0.3 V of common-mode hum on a
/// body-worn sheet, rejected by an instrumentation amplifier's 90 dB).
pub const MAINS_V: f64 = 10e-6;
/// The PGIA gain the calibration is read at: the adjacent protocol's largest reading at
/// 32 uA (0.3 V on the 13 cm sheet) then uses about half the ADC's range. At gain 1 a code
/// (153 uV) is five times the reference's frame noise, and a median of codes cannot resolve
/// below it.
pub const CALIBRATION_GAIN: u8 = 8;
/// Calibrated rms of each electrode's DC junction potential between measurement sets, V:
/// with [`CALIBRATED_SET_CONDUCTANCE`] (and no re-placement, [`CALIBRATION_MOVEMENT_M`]) it
/// gives the reference's MAD between sets, 0.5 mV at 32 uA and 0.4 mV at 10 uA
/// (docs/method.md §3).
pub const CALIBRATED_CONTACT_POTENTIAL_V: f64 = 0.333e-3;
/// Electrode re-placement between measurement sets the set layer is calibrated with, m rms
/// along the outline: none, the sheet stays mounted from one set to the next (clips put back
/// 0.13 mm off would alone give the reference's whole MAD at 32 uA, and 0.1 mm makes
/// next-day classification fall far below the reference's: docs/calibration.md).
pub const CALIBRATION_MOVEMENT_M: f64 = 0.0;
/// Calibrated relative rms of the sheet's conductance between measurement sets (see
/// [`CALIBRATED_CONTACT_POTENTIAL_V`]).
pub const CALIBRATED_SET_CONDUCTANCE: f64 = 0.80e-2;

/// How one measurement set differs from the next (sets taken at different times, the sheet
/// put down again): the part of the reference's MAD "among different measurement sets" that
/// the front end and the sheet's state own. Electrode re-placement is the sheet's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SetSpread {
    /// Rms of each electrode's DC junction potential (clip on PPy fabric), V: it adds to
    /// every reading of a pair, whatever the current.
    pub contact_potential_v: f64,
    /// Relative rms of the sheet's conductance (temperature, humidity): every voltage of a
    /// set scales by one factor.
    pub conductance: f64,
}

impl Default for SetSpread {
    fn default() -> Self {
        Self {
            contact_potential_v: CALIBRATED_CONTACT_POTENTIAL_V,
            conductance: CALIBRATED_SET_CONDUCTANCE,
        }
    }
}

/// One measurement set's state: what [`SetSpread::draw`] drew.
#[derive(Clone, Debug, PartialEq)]
pub struct SetState {
    /// Each electrode's DC junction potential, V.
    pub contact_potentials_v: Vec<f64>,
    /// The sheet's conductance relative to nominal.
    pub conductance_scale: f64,
}

impl SetSpread {
    /// Draws a set for a sheet of `electrodes` (the conductance log-normal, so positive).
    #[must_use]
    pub fn draw(&self, electrodes: usize, rng: &mut Rng) -> SetState {
        SetState {
            contact_potentials_v: (0..electrodes)
                .map(|_| self.contact_potential_v * rng.normal())
                .collect(),
            conductance_scale: (self.conductance * rng.normal()).exp(),
        }
    }

    fn validate(&self) -> Result<(), SheetError> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if !(ok(self.contact_potential_v) && ok(self.conductance) && self.conductance <= 1.0) {
            return Err(SheetError::rule(
                "frontend.sets",
                "contact_potential_v must be >= 0 V and conductance between 0 and 1",
            ));
        }
        Ok(())
    }
}

impl FrontendSpec {
    /// Checks every field.
    ///
    /// # Errors
    /// [`SheetError::field`] naming the field.
    pub fn validate(&self) -> Result<(), SheetError> {
        let bad = |field, rule| Err(SheetError::rule(field, rule));
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        if !(1..=16).contains(&self.adc_bits) {
            return bad("frontend.adc_bits", "use 1 to 16 bits");
        }
        if !(self.adc_range_v.is_finite() && self.adc_range_v > 0.0) {
            return bad("frontend.adc_range_v", "a positive voltage");
        }
        if !(nonneg(self.white_noise_v)
            && nonneg(self.adc_noise_codes)
            && nonneg(self.current_noise)
            && nonneg(self.mains_v))
        {
            return bad(
                "frontend noise",
                "white_noise_v, adc_noise_codes, current_noise and mains_v must be >= 0",
            );
        }
        self.sets.validate()?;
        if !(nonneg(self.mains_hz) && nonneg(self.settle_tau_us)) {
            return bad("frontend", "mains_hz and settle_tau_us must be >= 0");
        }
        if !(self.source.v_out_max.is_finite()
            && self.source.v_out_max > 0.0
            && nonneg(self.source.mux_on_ohm))
        {
            return bad(
                "frontend.source",
                "v_out_max must be positive, mux_on_ohm >= 0",
            );
        }
        Ok(())
    }

    /// This front end without noise of either layer (no white, ADC, current or mains noise, no
    /// junction potentials, nominal conductance): what tests compare against exact values.
    #[must_use]
    pub fn without_noise(self) -> Self {
        Self {
            white_noise_v: 0.0,
            adc_noise_codes: 0.0,
            current_noise: 0.0,
            mains_v: 0.0,
            sets: SetSpread {
                contact_potential_v: 0.0,
                conductance: 0.0,
            },
            ..self
        }
    }

    /// The noise of one sample at PGIA gain `gain`, referred to the amplifier input, V rms:
    /// the amplifier's white noise and the ADC's, a code being smaller at higher gain.
    #[must_use]
    pub fn sample_noise_v(&self, gain: u8) -> f64 {
        let lsb = f64::from(self.scale(gain).volts_per_code);
        self.white_noise_v.hypot(self.adc_noise_codes * lsb)
    }

    /// The ADC scale at PGIA gain `gain`.
    #[must_use]
    pub fn scale(&self, gain: u8) -> AdcScale {
        let codes = f64::from(1u32 << self.adc_bits);
        AdcScale {
            bits: self.adc_bits,
            zero_code: (codes / 2.0) as f32,
            volts_per_code: (2.0 * self.adc_range_v / codes / f64::from(gain.max(1))) as f32,
        }
    }
}

/// What can go wrong in the simulated front end.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// `acquire` before `configure` and `select`.
    #[error("acquire called before configure/select")]
    NotSelected,
    /// An electrode the sheet does not have.
    #[error("electrode {0} does not exist on this sheet")]
    Electrode(u8),
    /// A scan configuration that is not valid.
    #[error("configuration: {0}")]
    Config(#[source] et_core::config::ConfigError),
    /// A configuration for another electrode count than the sheet's.
    #[error("configuration: {configured} electrodes configured, the sheet has {sheet}")]
    Electrodes {
        /// The configuration's.
        configured: u8,
        /// The sheet's.
        sheet: usize,
    },
    /// A hand with a negative wobble or a correlation time that is not positive.
    #[error(
        "configuration: a hand needs a wobble >= 0 and a positive correlation time (got \
         {wobble} and {correlation_s} s)"
    )]
    Hand {
        /// Its wobble.
        wobble: f64,
        /// Its correlation time, s.
        correlation_s: f64,
    },
    /// A probability outside [0, 1].
    #[error("configuration: open probability {0} is not in [0, 1]")]
    Probability(f64),
    /// A conductance scale that is not finite and positive.
    #[error("configuration: conductance scale {0} must be positive")]
    ConductanceScale(f64),
    /// A measurement set with a potential per electrode of another count, a non-finite
    /// potential or a conductance that is not finite and positive.
    #[error(
        "configuration: a measurement set needs {electrodes} finite junction potentials and a \
         positive conductance"
    )]
    Set {
        /// The sheet's electrodes.
        electrodes: usize,
    },
}

/// The simulated sensor: a sheet in some touch state behind the acquisition chain.
#[derive(Debug)]
pub struct SimFrontend {
    sheet: Arc<SimulatedSheet>,
    spec: FrontendSpec,
    transfer: Transfer,
    rng: Rng,
    config: Option<ScanConfig>,
    /// Device clock, s (advances one sample period per sample).
    time: f64,
    /// Current multiplier of the injection in progress (1 + jitter).
    jitter: f64,
    injection: Option<Injection>,
    /// Settled voltage of the selected step, V at the input.
    target: Option<f64>,
    /// Whether the source is in compliance at the selected step.
    compliance: bool,
    /// Amplifier input at the end of the last sample, V (where the next transient starts).
    last: f64,
    /// Per electrode, the chance that its contact is open at a step (1 = disconnected).
    open: Vec<f64>,
    /// The sheet's conductance relative to when it was built (temperature drift).
    conductance_scale: f64,
    /// This measurement set's state (junction potentials, conductance).
    set: SetState,
    /// The kept samples of one step (fast path).
    burst: Vec<f64>,
    /// The untouched sheet's transfer (what a touch's change is measured from).
    untouched: Transfer,
    /// How the hand holds its presses.
    hand: Hand,
    /// The hand's force now, relative to the press's nominal (0 = nominal).
    wobble: f64,
    /// Whether `wobble` has been drawn (the first draw is from the stationary spread).
    wobble_drawn: bool,
}

/// How a hand holds a press: its force wanders about the press's nominal pressure, so the
/// injections of one scan (tens of ms apart) see the touch at different strengths. Modelled
/// as an Ornstein-Uhlenbeck process: relative rms `wobble`, correlation time `correlation_s`;
/// the touch's change of every reading scales by 1 + the process's value at its injection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hand {
    /// Relative rms of the force about the nominal (0 = a steady press).
    pub wobble: f64,
    /// Correlation time of the force's wandering, s.
    pub correlation_s: f64,
}

impl Default for Hand {
    /// A steady press.
    fn default() -> Self {
        Self {
            wobble: 0.0,
            correlation_s: 0.1,
        }
    }
}

impl SimFrontend {
    /// An untouched sheet behind `spec`, with noise from `seed`.
    ///
    /// # Errors
    /// [`SheetError::field`] for an invalid spec.
    pub fn new(
        sheet: Arc<SimulatedSheet>,
        spec: FrontendSpec,
        seed: u64,
    ) -> Result<Self, SheetError> {
        spec.validate()?;
        let transfer = sheet.transfer(&[])?;
        let untouched = transfer.clone();
        let electrodes = sheet.electrodes();
        Ok(Self {
            sheet,
            spec,
            transfer,
            rng: Rng::new(seed),
            config: None,
            time: 0.0,
            jitter: 1.0,
            injection: None,
            target: None,
            compliance: false,
            last: 0.0,
            open: vec![0.0; electrodes],
            conductance_scale: 1.0,
            set: SetState {
                contact_potentials_v: vec![0.0; electrodes],
                conductance_scale: 1.0,
            },
            burst: Vec::new(),
            untouched,
            hand: Hand::default(),
            wobble: 0.0,
            wobble_drawn: false,
        })
    }

    /// How the hand holds its presses from now on ([`Hand`]).
    ///
    /// # Errors
    /// [`SimError::Hand`] for a negative or non-finite wobble or a correlation time that is
    /// not positive.
    pub fn set_hand(&mut self, hand: Hand) -> Result<(), SimError> {
        if !(hand.wobble.is_finite()
            && hand.wobble >= 0.0
            && hand.correlation_s.is_finite()
            && hand.correlation_s > 0.0)
        {
            return Err(SimError::Hand {
                wobble: hand.wobble,
                correlation_s: hand.correlation_s,
            });
        }
        self.hand = hand;
        if hand.wobble == 0.0 {
            (self.wobble, self.wobble_drawn) = (0.0, false);
        }
        Ok(())
    }

    /// What changes when a new injection starts (both frame paths): the current's jitter is
    /// drawn anew and the hand's force moves on by one injection of `config`: S/L samples,
    /// the time a front end that samples every electrode at once (as the reference's does)
    /// spends on an injection, whatever order this simulator steps the measurements in.
    fn start_injection(&mut self, config: &ScanConfig) {
        self.jitter = 1.0 + self.spec.current_noise * self.rng.normal();
        let w = self.hand.wobble;
        if w == 0.0 {
            return;
        }
        let dt = f64::from(config.samples_per_step) / f64::from(config.sample_rate_hz);
        let r = if self.wobble_drawn {
            (-dt / self.hand.correlation_s).exp()
        } else {
            0.0
        };
        self.wobble = r * self.wobble + (1.0 - r * r).sqrt() * w * self.rng.normal();
        self.wobble_drawn = true;
    }

    /// Makes electrode `e`'s contact open at each step with probability `p` (1 = disconnected,
    /// between 0 and 1 = intermittent, 0 = sound). An open drive electrode stops the current;
    /// an open measurement electrode leaves the amplifier input floating to a rail.
    ///
    /// # Errors
    /// [`SimError::Electrode`] for an electrode the sheet does not have, [`SimError::Probability`]
    /// for p outside [0, 1].
    pub fn set_open(&mut self, e: u8, p: f64) -> Result<(), SimError> {
        let slot = self
            .open
            .get_mut(usize::from(e))
            .ok_or(SimError::Electrode(e))?;
        if !(0.0..=1.0).contains(&p) {
            return Err(SimError::Probability(p));
        }
        *slot = p;
        Ok(())
    }

    /// Scales the sheet's conductance (temperature drift): every voltage divides by `c`.
    ///
    /// # Errors
    /// [`SimError::ConductanceScale`] unless `c` is finite and positive.
    pub fn set_conductance_scale(&mut self, c: f64) -> Result<(), SimError> {
        if !(c.is_finite() && c > 0.0) {
            return Err(SimError::ConductanceScale(c));
        }
        self.conductance_scale = c;
        Ok(())
    }

    /// Puts the front end in measurement set `set` (junction potentials and conductance, see
    /// [`SetSpread::draw`]); a new front end starts in the nominal set (no junction
    /// potentials, nominal conductance).
    ///
    /// # Errors
    /// [`SimError::Set`] for a potential per electrode of another count, a non-finite
    /// potential or a conductance that is not finite and positive.
    pub fn set_state(&mut self, set: &SetState) -> Result<(), SimError> {
        if set.contact_potentials_v.len() != self.open.len()
            || set.contact_potentials_v.iter().any(|v| !v.is_finite())
            || !(set.conductance_scale.is_finite() && set.conductance_scale > 0.0)
        {
            return Err(SimError::Set {
                electrodes: self.open.len(),
            });
        }
        self.set = set.clone();
        Ok(())
    }

    /// The sheet.
    #[must_use]
    pub fn sheet(&self) -> &Arc<SimulatedSheet> {
        &self.sheet
    }

    /// Puts `touches` on the sheet (replacing the previous ones).
    ///
    /// # Errors
    /// [`SheetError`] if the touch update fails (non-finite values).
    pub fn set_touches(&mut self, touches: &[Touch]) -> Result<(), SheetError> {
        self.transfer = self.sheet.transfer(touches)?;
        Ok(())
    }

    /// The device clock, s.
    #[must_use]
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The noiseless, settled frame of `protocol` at `amps` for the current touch state and
    /// measurement set (V).
    #[must_use]
    pub fn ideal_frame(&self, protocol: &Protocol, amps: f64) -> Vec<f64> {
        protocol
            .steps()
            .map(|s| self.settled(s.injection, s.measurement, amps))
            .collect()
    }
}

mod fast;
mod reading;
mod seam;

#[cfg(test)]
mod tests;
