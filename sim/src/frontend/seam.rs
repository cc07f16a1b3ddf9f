//! The simulated front end as et-core's one hardware seam: what the scan engine drives.

use super::*;

impl Frontend for SimFrontend {
    type Error = SimError;

    fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, SimError> {
        config.validate().map_err(SimError::Config)?;
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
            self.start_injection(&config);
        }
        let amps = f64::from(config.current_amps()) * self.jitter;
        let (v, compliance) = self.faulty(injection, measurement, amps, config.gain);
        (self.target, self.compliance) = (Some(v), compliance);
        Ok(())
    }

    fn in_compliance(&self) -> bool {
        self.compliance
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
        let sigma = self.spec.sample_noise_v(config.gain);
        let mut gap = self.last - target;
        for s in samples.iter_mut() {
            self.time += dt;
            gap *= decay;
            let v = target + gap + sigma * self.rng.normal() + self.mains(self.time);
            *s = (v / lsb + zero).round().clamp(0.0, top) as u16;
        }
        self.last = target + gap;
        Ok(())
    }
}
