//! The fast frame: a whole frame at once from the settled voltages and the noise's
//! statistics, without the sample-by-sample scan (the scan engine's result, not its timing).

use super::*;

impl SimFrontend {
    /// One whole frame with the statistics of the scan engine's output, without the settling
    /// transient: per step the settled voltage (with this injection's current jitter), the
    /// mains value mid-step, and the median of the kept samples' noise (white and ADC), each
    /// sample quantised. Rounding is monotone, so the median of the codes is the rounded
    /// median of the noisy values (the mean of the two middle ones for an even count): the
    /// kept samples are drawn, the middle picked, then rounded. The clock advances as a real
    /// scan would.
    ///
    /// # Errors
    /// [`SimError::Config`] for an invalid configuration, [`SimError::Electrodes`] for one of
    /// another electrode count.
    pub fn fast_frame(&mut self, config: &ScanConfig) -> Result<Vec<f32>, SimError> {
        Ok(self.fast_frame_with_report(config)?.0)
    }

    /// [`SimFrontend::fast_frame`] with the scan engine's report: a measurement whose value
    /// lands on an ADC rail is flagged in `rail`, as the sample path flags it, with all its
    /// kept samples counted in `rail_samples` (the median is on the rail only when most of
    /// them are); measurements whose injection drove the source into compliance are counted
    /// in `compliance_steps`.
    ///
    /// # Errors
    /// [`SimError::Config`] for an invalid configuration, [`SimError::Electrodes`] for one of
    /// another electrode count.
    pub fn fast_frame_with_report(
        &mut self,
        config: &ScanConfig,
    ) -> Result<(Vec<f32>, et_core::ScanReport), SimError> {
        let protocol = config.validate().map_err(SimError::Config)?;
        self.check_electrodes(config)?;
        let scale = self.spec.scale(config.gain);
        let dt = 1.0 / f64::from(config.sample_rate_hz);
        let kept = f64::from(config.kept_samples());
        let spp = f64::from(config.samples_per_step);
        let sigma = self.spec.sample_noise_v(config.gain);
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
                self.start_injection(config);
            }
            let mid = self.time + dt * (f64::from(config.settle_samples) + kept / 2.0);
            let (v, compliance) = self.faulty(
                step.injection,
                step.measurement,
                amps * self.jitter,
                config.gain,
            );
            report.compliance_steps += u32::from(compliance);
            let v = v + self.mains(mid);
            let max = f64::from(scale.max_code());
            let to_code = |x: f64| ((v + x) / lsb + f64::from(scale.zero_code)).round();
            let code = match self.median_noise(config.kept_samples(), sigma) {
                (lo, None) => to_code(lo),
                (lo, Some(hi)) => (to_code(lo) + to_code(hi)) / 2.0,
            };
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

    /// The middle of `n` draws of N(0, sigma^2): the median for odd `n`, the two middle values
    /// for even `n`.
    pub(super) fn median_noise(&mut self, n: u16, sigma: f64) -> (f64, Option<f64>) {
        let n = usize::from(n.max(1));
        self.burst.clear();
        for _ in 0..n {
            self.burst.push(sigma * self.rng.normal());
        }
        let half = n / 2;
        let (below, mid, _) = self.burst.select_nth_unstable_by(half, f64::total_cmp);
        let mid = *mid;
        if n % 2 == 1 {
            (mid, None)
        } else {
            let lo = below.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo, Some(mid))
        }
    }

    pub(super) fn check_electrodes(&self, config: &ScanConfig) -> Result<(), SimError> {
        if usize::from(config.electrodes) != self.sheet.electrodes() {
            return Err(SimError::Electrodes {
                configured: config.electrodes,
                sheet: self.sheet.electrodes(),
            });
        }
        Ok(())
    }
}
