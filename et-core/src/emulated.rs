//! A sheet compiled into the firmware image: the [`Frontend`] the QEMU build scans, since QEMU
//! has no ADC (docs/design.md, "QEMU runs the real firmware image").
//!
//! The sheet is described by transfer impedances, one L x L matrix per touch state, that the
//! simulator's resistor network computes at build time (`et_sim::emulated`). A sheet is linear,
//! so for current I entering at electrode a and leaving at b, the voltage between probes p
//! and q is
//!
//! ```text
//! V = I (Z[p][a] - Z[p][b] - Z[q][a] + Z[q][b])
//! ```
//!
//! The front end adds white noise per sample and quantises to the reference board's 16-bit
//! ADC over +-5 V ([`AdcScale::bipolar_16bit`]), so everything after it (settle, median, frame,
//! classifier) is the production code path.

use crate::config::ScanConfig;
use crate::frontend::{AdcScale, Frontend};
use crate::protocol::{Injection, Measurement};
use crate::rng::Rng;

/// ADC input range of the emulated board, +-V at unity gain (the reference board's).
pub const RANGE_V: f32 = 5.0;

/// sqrt(3): the sum of four uniforms on [-1/2, 1/2) has variance 1/3.
const SQRT_3: f32 = 1.732_050_8;

/// Why the emulated sheet refused a call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EmulatedError {
    /// The tables are empty or not a whole number of L x L matrices.
    Tables,
    /// The configuration's electrode count is not the sheet's.
    Electrodes,
    /// An electrode index outside the sheet.
    Electrode,
    /// `acquire` before `configure` and `select`.
    NotSelected,
}

/// The emulated sheet (see the module docs).
#[derive(Debug, Clone)]
pub struct EmulatedSheet<'t> {
    electrodes: usize,
    /// Transfer impedances, ohms: `states` matrices of L x L, row-major, state-major.
    z: &'t [f32],
    state: usize,
    noise_v: f32,
    rng: Rng,
    amps: f32,
    scale: Option<AdcScale>,
    volts: Option<f32>,
}

impl<'t> EmulatedSheet<'t> {
    /// A sheet of `electrodes` electrodes with touch states `z` (each L x L, ohms), white noise
    /// of `noise_v` V rms per sample, pseudo-random from `seed`.
    ///
    /// # Errors
    /// [`EmulatedError::Tables`] unless `z` holds at least one whole L x L matrix.
    pub fn new(
        electrodes: u8,
        z: &'t [f32],
        noise_v: f32,
        seed: u64,
    ) -> Result<Self, EmulatedError> {
        let l = usize::from(electrodes);
        if l == 0 || z.is_empty() || !z.len().is_multiple_of(l * l) {
            return Err(EmulatedError::Tables);
        }
        Ok(Self {
            electrodes: l,
            z,
            state: 0,
            noise_v,
            rng: Rng::new(seed),
            amps: 0.0,
            scale: None,
            volts: None,
        })
    }

    /// Number of touch states.
    #[must_use]
    pub fn states(&self) -> usize {
        self.z.len() / (self.electrodes * self.electrodes)
    }

    /// Selects touch state `state` (modulo [`states`](Self::states)) from the next `select` on.
    pub fn set_state(&mut self, state: usize) {
        self.state = state % self.states();
    }

    fn at(&self, e: usize, f: usize) -> f32 {
        let l = self.electrodes;
        self.z[self.state * l * l + e * l + f]
    }

    /// A uniform draw in [-0.5, 0.5).
    fn uniform(&mut self) -> f32 {
        self.rng.uniform_f32() - 0.5
    }
}

impl Frontend for EmulatedSheet<'_> {
    type Error = EmulatedError;

    fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, EmulatedError> {
        if usize::from(config.electrodes) != self.electrodes {
            return Err(EmulatedError::Electrodes);
        }
        self.amps = config.current_amps();
        let scale = AdcScale::bipolar_16bit(RANGE_V, config.gain);
        self.scale = Some(scale);
        self.volts = None;
        Ok(scale)
    }

    fn select(
        &mut self,
        injection: Injection,
        measurement: Measurement,
    ) -> Result<(), EmulatedError> {
        let [a, b, p, q] = [
            injection.source.0,
            injection.sink.0,
            measurement.positive.0,
            measurement.negative.0,
        ]
        .map(usize::from);
        if [a, b, p, q].iter().any(|&e| e >= self.electrodes) {
            return Err(EmulatedError::Electrode);
        }
        let z = self.at(p, a) - self.at(p, b) - self.at(q, a) + self.at(q, b);
        self.volts = Some(self.amps * z);
        Ok(())
    }

    fn acquire(&mut self, samples: &mut [u16]) -> Result<(), EmulatedError> {
        let (Some(scale), Some(volts)) = (self.scale, self.volts) else {
            return Err(EmulatedError::NotSelected);
        };
        // The sum of four uniforms has variance 4/12: scale it to noise_v rms.
        let sigma = self.noise_v * SQRT_3;
        let max = f32::from(scale.max_code());
        for s in samples.iter_mut() {
            let noise = sigma * (self.uniform() + self.uniform() + self.uniform() + self.uniform());
            let code = (volts + noise) / scale.volts_per_code + scale.zero_code;
            *s = round_half_away(code).clamp(0.0, max) as u16;
        }
        Ok(())
    }
}

/// Rounds half away from zero (`f32::round` is not in `core`).
fn round_half_away(x: f32) -> f32 {
    let t = x as i64 as f32;
    if x - t >= 0.5 {
        t + 1.0
    } else if t - x >= 0.5 {
        t - 1.0
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{ElectrodeId, ProtocolKind};
    use crate::scan::Scanner;

    /// A 4-electrode "sheet" of one resistor R between every pair of electrodes: Z from the
    /// pseudo-inverse of the Laplacian with electrode 0 grounded.
    fn ring(r: f32) -> [f32; 16] {
        // Laplacian of K4 with conductance g: 3g on the diagonal, -g off it. Ground 0 and
        // invert the 3 x 3 block [[3,-1,-1],[-1,3,-1],[-1,-1,3]] g: inverse = (1/4g)[[2,1,1],[1,2,1],[1,1,2]].
        let mut z = [0.0; 16];
        for e in 1..4 {
            for f in 1..4 {
                z[e * 4 + f] = r / 4.0 * if e == f { 2.0 } else { 1.0 };
            }
        }
        z
    }

    #[test]
    fn voltages_follow_the_transfer_impedances() {
        let z = ring(1000.0);
        let mut sheet = EmulatedSheet::new(4, &z, 0.0, 1).unwrap();
        let config = ScanConfig {
            electrodes: 4,
            protocol: ProtocolKind::Adjacent,
            ..ScanConfig::REFERENCE
        };
        let scanner = Scanner::new(config, &mut sheet).unwrap();
        let mut burst = [0u16; 64];
        let mut v = [0.0f32; 8];
        scanner.scan(&mut sheet, &mut burst, &mut v).unwrap();
        // Every step is the module docs' formula, to within one ADC code.
        let amps = config.current_amps();
        for (step, got) in scanner.protocol().steps().zip(v) {
            let [a, b, p, q] = [
                step.injection.source.0,
                step.injection.sink.0,
                step.measurement.positive.0,
                step.measurement.negative.0,
            ]
            .map(usize::from);
            let at = |e: usize, f: usize| z[e * 4 + f];
            let want = amps * (at(p, a) - at(p, b) - at(q, a) + at(q, b));
            let lsb = AdcScale::bipolar_16bit(RANGE_V, 1).volts_per_code;
            assert!((got - want).abs() <= lsb, "{got} vs {want}");
        }
    }

    #[test]
    fn noise_has_the_asked_rms_and_states_switch() {
        let mut z = [0.0f32; 32];
        z[5] = 100.0; // state 0: Z[1][1] = 100 ohm
        z[16 + 5] = 300.0; // state 1
        let mut sheet = EmulatedSheet::new(4, &z, 2e-3, 7).unwrap();
        assert_eq!(sheet.states(), 2);
        let config = ScanConfig {
            electrodes: 4,
            current_na: 1_000_000,
            ..ScanConfig::REFERENCE
        };
        let scale = sheet.configure(&config).unwrap();
        let inj = Injection {
            source: ElectrodeId(1),
            sink: ElectrodeId(0),
        };
        let meas = Measurement {
            positive: ElectrodeId(1),
            negative: ElectrodeId(0),
        };
        for (state, volts) in [(0, 0.1f32), (1, 0.3)] {
            sheet.set_state(state);
            sheet.select(inj, meas).unwrap();
            let mut s = [0u16; 4000];
            sheet.acquire(&mut s).unwrap();
            let v: std::vec::Vec<f32> = s.iter().map(|&c| scale.volts(f32::from(c))).collect();
            let mean = v.iter().sum::<f32>() / v.len() as f32;
            let rms = (v.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / v.len() as f32).sqrt();
            assert!((mean - volts).abs() < 2e-4, "state {state}: mean {mean}");
            assert!((rms - 2e-3).abs() < 2e-4, "rms {rms}");
        }
        assert_eq!(
            EmulatedSheet::new(4, &z[..15], 0.0, 1).err(),
            Some(EmulatedError::Tables)
        );
        let mut other = EmulatedSheet::new(4, &z, 0.0, 1).unwrap();
        assert_eq!(
            other.configure(&ScanConfig::REFERENCE),
            Err(EmulatedError::Electrodes)
        );
        assert_eq!(other.acquire(&mut [0; 4]), Err(EmulatedError::NotSelected));
    }
}
