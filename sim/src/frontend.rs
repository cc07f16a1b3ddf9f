//! The simulated acquisition chain (docs/method.md §2-3), as an [`et_core::Frontend`]: the real scan
//! engine runs against it sample by sample.
//!
//! Per step: the Howland source drives the injection (its current jitters a little from one
//! injection to the next, and it saturates at its compliance); the instrumentation amplifier
//! sees the measurement pair's voltage, reached through a first-order switching transient
//! from whatever it showed before; white noise and mains hum add on; the PGIA gain scales it;
//! the ADC quantises and clips at its rails.
//!
//! [`SimFrontend::fast_frame`] gives whole frames with the same statistics without the sample
//! detail: the settled value, the median's share of the white noise, the mains value at the
//! step, the current jitter, and the quantisation.

use std::f64::consts::PI;
use std::sync::Arc;

use et_core::ScanConfig;
use et_core::frontend::{AdcScale, Frontend};
use et_core::protocol::{Injection, Measurement, Protocol};
use serde::{Deserialize, Serialize};

use crate::network::Transfer;
use crate::sheet::{Sheet, SheetError, Source};
use crate::touch::Touch;
use et_core::rng::Rng;

/// The front end's parameters. Defaults are the calibrated reference hardware (see
/// `README.md`, "Calibration").
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
    /// Relative rms jitter of the injected current from one injection to the next.
    pub current_noise: f64,
    /// Mains hum amplitude at the amplifier input, V.
    pub mains_v: f64,
    /// Mains frequency, Hz.
    pub mains_hz: f64,
    /// Time constant of the settling transient after each switch, us.
    pub settle_tau_us: f64,
}

impl Default for FrontendSpec {
    fn default() -> Self {
        Self {
            source: Source::default(),
            adc_bits: 16,
            adc_range_v: 5.0,
            white_noise_v: CALIBRATED_WHITE_NOISE_V,
            current_noise: CALIBRATED_CURRENT_NOISE,
            mains_v: CALIBRATED_MAINS_V,
            mains_hz: 50.0,
            settle_tau_us: 50.0,
        }
    }
}

/// Calibrated white noise per sample, V rms: with [`CALIBRATED_CURRENT_NOISE`] and
/// [`CALIBRATED_MAINS_V`] the adjacent protocol on the 13 x 13 cm, 16-electrode sheet shows
/// the reference MAD of 0.50 mV at 32 uA and 0.40 mV at 10 uA (docs/method.md §3). Fitted by
/// `cargo run --release -p et-sim --example calibrate`; checked by the `calibration` test.
pub const CALIBRATED_WHITE_NOISE_V: f64 = 1.7e-3;
/// Calibrated relative current jitter between injections (see [`CALIBRATED_WHITE_NOISE_V`]).
pub const CALIBRATED_CURRENT_NOISE: f64 = 8.5e-3;
/// Calibrated mains hum amplitude, V (fixed, not fitted: typical pickup of a fabric sheet).
pub const CALIBRATED_MAINS_V: f64 = 0.3e-3;

impl FrontendSpec {
    /// Checks every field.
    ///
    /// # Errors
    /// [`SheetError::Field`] naming the field.
    pub fn validate(&self) -> Result<(), SheetError> {
        let bad = |field, why: &str| {
            Err(SheetError::Field {
                field,
                why: why.into(),
            })
        };
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        if !(1..=16).contains(&self.adc_bits) {
            return bad("frontend.adc_bits", "use 1 to 16 bits");
        }
        if !(self.adc_range_v.is_finite() && self.adc_range_v > 0.0) {
            return bad("frontend.adc_range_v", "must be a positive voltage");
        }
        if !(nonneg(self.white_noise_v) && nonneg(self.current_noise) && nonneg(self.mains_v)) {
            return bad(
                "frontend noise",
                "white_noise_v, current_noise and mains_v must be >= 0",
            );
        }
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
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SimError {
    /// `acquire` before `configure` and `select`.
    NotSelected,
    /// An electrode the sheet does not have.
    Electrode(u8),
    /// The configuration asks for something the front end cannot do.
    Config(String),
}

impl std::fmt::Display for SimError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SimError::NotSelected => write!(f, "acquire called before configure/select"),
            SimError::Electrode(e) => write!(f, "electrode {e} does not exist on this sheet"),
            SimError::Config(why) => write!(f, "configuration: {why}"),
        }
    }
}

impl std::error::Error for SimError {}

/// The simulated sensor: a sheet in some touch state behind the acquisition chain.
#[derive(Debug)]
pub struct SimFrontend {
    sheet: Arc<Sheet>,
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
    /// Amplifier input at the end of the last sample, V (where the next transient starts).
    last: f64,
    /// Per electrode, the chance that its contact is open at a step (1 = disconnected).
    open: Vec<f64>,
    /// The sheet's conductance relative to when it was built (temperature drift).
    conductance_scale: f64,
}

impl SimFrontend {
    /// An untouched sheet behind `spec`, with noise from `seed`.
    ///
    /// # Errors
    /// [`SheetError::Field`] for an invalid spec.
    pub fn new(sheet: Arc<Sheet>, spec: FrontendSpec, seed: u64) -> Result<Self, SheetError> {
        spec.validate()?;
        let transfer = sheet.transfer(&[])?;
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
            last: 0.0,
            open: vec![0.0; electrodes],
            conductance_scale: 1.0,
        })
    }

    /// Makes electrode `e`'s contact open at each step with probability `p` (1 = disconnected,
    /// between 0 and 1 = intermittent, 0 = sound). An open drive electrode stops the current;
    /// an open measurement electrode leaves the amplifier input floating to a rail.
    ///
    /// # Errors
    /// [`SimError::Electrode`] for an electrode the sheet does not have, [`SimError::Config`]
    /// for p outside [0, 1].
    pub fn set_open(&mut self, e: u8, p: f64) -> Result<(), SimError> {
        let slot = self
            .open
            .get_mut(usize::from(e))
            .ok_or(SimError::Electrode(e))?;
        if !(0.0..=1.0).contains(&p) {
            return Err(SimError::Config(format!(
                "open probability {p} is not in [0, 1]"
            )));
        }
        *slot = p;
        Ok(())
    }

    /// Scales the sheet's conductance (temperature drift): every voltage divides by `c`.
    ///
    /// # Errors
    /// [`SimError::Config`] unless `c` is finite and positive.
    pub fn set_conductance_scale(&mut self, c: f64) -> Result<(), SimError> {
        if !(c.is_finite() && c > 0.0) {
            return Err(SimError::Config(format!(
                "conductance scale {c} must be positive"
            )));
        }
        self.conductance_scale = c;
        Ok(())
    }

    /// The sheet.
    #[must_use]
    pub fn sheet(&self) -> &Arc<Sheet> {
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

    /// The noiseless, settled frame of `protocol` at `amps` for the current touch state (V).
    #[must_use]
    pub fn ideal_frame(&self, protocol: &Protocol, amps: f64) -> Vec<f64> {
        crate::sheet::frame(&self.transfer, protocol, amps, &self.spec.source)
    }

    fn settled(&self, inj: Injection, meas: Measurement, amps: f64) -> f64 {
        let (a, b) = (usize::from(inj.source.0), usize::from(inj.sink.0));
        let (p, q) = (usize::from(meas.positive.0), usize::from(meas.negative.0));
        let c = self.conductance_scale;
        let i = self.spec.source.current(amps, self.transfer.load(a, b) / c);
        self.transfer.voltage(a, b, p, q, i) / c
    }

    /// Whether electrode `e`'s contact is open at this step (draws only for faulty ones).
    fn is_open(&mut self, e: u8) -> bool {
        match self.open.get(usize::from(e)).copied().unwrap_or(0.0) {
            p if p >= 1.0 => true,
            p if p > 0.0 => self.rng.uniform() < p,
            _ => false,
        }
    }

    /// The step's settled input with the contact faults of this step applied.
    fn faulty(&mut self, inj: Injection, meas: Measurement, amps: f64, gain: u8) -> f64 {
        let drive_open = self.is_open(inj.source.0) | self.is_open(inj.sink.0);
        let probe_open = self.is_open(meas.positive.0) | self.is_open(meas.negative.0);
        if probe_open {
            // A floating input drifts beyond the positive rail.
            1.5 * self.spec.adc_range_v / f64::from(gain.max(1))
        } else if drive_open {
            0.0
        } else {
            self.settled(inj, meas, amps)
        }
    }

    fn mains(&self, t: f64) -> f64 {
        self.spec.mains_v * (2.0 * PI * self.spec.mains_hz * t).sin()
    }

    /// One whole frame with the statistics of the scan engine's output, without simulating
    /// samples: per step the settled voltage (with this injection's current jitter), the
    /// median's share of the white noise (sqrt(pi/2) sigma / sqrt(kept) for a median of
    /// Gaussian samples), the mains value mid-step, and quantisation to half an ADC code (the
    /// median of an even count can end in .5). The clock advances as a real scan would.
    ///
    /// # Errors
    /// [`SimError::Config`] for an invalid configuration.
    pub fn fast_frame(&mut self, config: &ScanConfig) -> Result<Vec<f32>, SimError> {
        Ok(self.fast_frame_with_report(config)?.0)
    }

    /// [`SimFrontend::fast_frame`] with the scan engine's report: a measurement whose value
    /// lands on an ADC rail is flagged in `rail`, as the sample path flags it, with all its
    /// kept samples counted in `rail_samples` (the median is on the rail only when most of
    /// them are).
    ///
    /// # Errors
    /// [`SimError::Config`] for an invalid configuration.
    pub fn fast_frame_with_report(
        &mut self,
        config: &ScanConfig,
    ) -> Result<(Vec<f32>, et_core::ScanReport), SimError> {
        let protocol = config
            .validate()
            .map_err(|e| SimError::Config(e.to_string()))?;
        self.check_electrodes(config)?;
        let scale = self.spec.scale(config.gain);
        let dt = 1.0 / f64::from(config.sample_rate_hz);
        let kept = f64::from(config.kept_samples());
        let spp = f64::from(config.samples_per_step);
        let median_sigma = self.spec.white_noise_v * (PI / 2.0).sqrt() / kept.sqrt();
        let amps = f64::from(config.current_amps());
        let lsb = f64::from(scale.volts_per_code);
        let mut out = Vec::with_capacity(protocol.frame_len());
        let mut report = et_core::ScanReport::default();
        let k = protocol.frame_len() as u32;
        report.samples = k * u32::from(config.samples_per_step);
        report.settle_dropped = k * u32::from(config.settle_samples);
        let mut injection = None;
        for (i, step) in protocol.steps().enumerate() {
            if injection != Some(step.injection) {
                injection = Some(step.injection);
                self.jitter = 1.0 + self.spec.current_noise * self.rng.normal();
            }
            let mid = self.time + dt * (f64::from(config.settle_samples) + kept / 2.0);
            let v = self.faulty(
                step.injection,
                step.measurement,
                amps * self.jitter,
                config.gain,
            ) + median_sigma * self.rng.normal()
                + self.mains(mid);
            let code = (v / lsb * 2.0).round() / 2.0 + f64::from(scale.zero_code);
            let max = f64::from(scale.max_code());
            if !(code > 0.0 && code < max) {
                report.rail.set(i);
                report.rail_samples += u32::from(config.kept_samples());
            }
            let code = code.clamp(0.0, max);
            out.push(scale.volts(code as f32));
            self.time += dt * spp;
        }
        Ok((out, report))
    }

    fn check_electrodes(&self, config: &ScanConfig) -> Result<(), SimError> {
        if usize::from(config.electrodes) != self.sheet.electrodes() {
            return Err(SimError::Config(format!(
                "{} electrodes configured, the sheet has {}",
                config.electrodes,
                self.sheet.electrodes()
            )));
        }
        Ok(())
    }
}

impl Frontend for SimFrontend {
    type Error = SimError;

    fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, SimError> {
        config
            .validate()
            .map_err(|e| SimError::Config(e.to_string()))?;
        self.check_electrodes(config)?;
        self.config = Some(*config);
        self.injection = None;
        self.target = None;
        Ok(self.spec.scale(config.gain))
    }

    fn select(&mut self, injection: Injection, measurement: Measurement) -> Result<(), SimError> {
        let config = self.config.ok_or(SimError::NotSelected)?;
        let l = config.electrodes;
        for e in [
            injection.source,
            injection.sink,
            measurement.positive,
            measurement.negative,
        ] {
            if e.0 >= l {
                return Err(SimError::Electrode(e.0));
            }
        }
        if self.injection != Some(injection) {
            self.injection = Some(injection);
            self.jitter = 1.0 + self.spec.current_noise * self.rng.normal();
        }
        let amps = f64::from(config.current_amps()) * self.jitter;
        self.target = Some(self.faulty(injection, measurement, amps, config.gain));
        Ok(())
    }

    fn acquire(&mut self, samples: &mut [u16]) -> Result<(), SimError> {
        let (config, target) = (
            self.config.ok_or(SimError::NotSelected)?,
            self.target.ok_or(SimError::NotSelected)?,
        );
        let scale = self.spec.scale(config.gain);
        let (lsb, zero, top) = (
            f64::from(scale.volts_per_code),
            f64::from(scale.zero_code),
            f64::from(scale.max_code()),
        );
        let dt = 1.0 / f64::from(config.sample_rate_hz);
        let decay = if self.spec.settle_tau_us > 0.0 {
            (-dt / (self.spec.settle_tau_us * 1e-6)).exp()
        } else {
            0.0
        };
        let mut gap = self.last - target;
        for s in samples.iter_mut() {
            self.time += dt;
            gap *= decay;
            let v =
                target + gap + self.spec.white_noise_v * self.rng.normal() + self.mains(self.time);
            *s = (v / lsb + zero).round().clamp(0.0, top) as u16;
        }
        self.last = target + gap;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
