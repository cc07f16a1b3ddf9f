//! One reading as the chain makes it: the source's compliance, the settling transient, open
//! electrodes and mains hum.

use super::*;

impl SimFrontend {
    /// Whether the source cannot drive `amps` through injection `inj`'s load (compliance).
    pub(super) fn limited(&self, inj: Injection, amps: f64) -> bool {
        let (a, b) = (usize::from(inj.source.0), usize::from(inj.sink.0));
        let c = self.conductance_scale * self.set.conductance_scale;
        self.spec.source.current(amps, self.transfer.load(a, b) / c) < amps
    }

    pub(super) fn settled(&self, inj: Injection, meas: Measurement, amps: f64) -> f64 {
        let (a, b) = (usize::from(inj.source.0), usize::from(inj.sink.0));
        let (p, q) = (usize::from(meas.positive.0), usize::from(meas.negative.0));
        let c = self.conductance_scale * self.set.conductance_scale;
        let i = self.spec.source.current(amps, self.transfer.load(a, b) / c);
        let e = &self.set.contact_potentials_v;
        let junction = e.get(p).copied().unwrap_or(0.0) - e.get(q).copied().unwrap_or(0.0);
        let mut v = self.transfer.voltage(a, b, p, q, i);
        if self.wobble != 0.0 {
            let v0 = self.untouched.voltage(a, b, p, q, i);
            // A hand lifting off leaves no touch, never a negative one.
            v = v0 + (v - v0) * (1.0 + self.wobble).max(0.0);
        }
        v / c + junction
    }

    /// Whether electrode `e`'s contact is open at this step (draws only for faulty ones).
    pub(super) fn is_open(&mut self, e: u8) -> bool {
        match self.open.get(usize::from(e)).copied().unwrap_or(0.0) {
            p if p >= 1.0 => true,
            p if p > 0.0 => self.rng.uniform() < p,
            _ => false,
        }
    }

    /// The step's settled input with the contact faults of this step applied, and whether the
    /// source is in compliance (its load too high, or a drive contact open: an infinite load).
    pub(super) fn faulty(
        &mut self,
        inj: Injection,
        meas: Measurement,
        amps: f64,
        gain: u8,
    ) -> (f64, bool) {
        let drive_open = self.is_open(inj.source.0) | self.is_open(inj.sink.0);
        let probe_open = self.is_open(meas.positive.0) | self.is_open(meas.negative.0);
        let compliance = drive_open || self.limited(inj, amps);
        let v = if probe_open {
            // A floating input drifts beyond the positive rail.
            1.5 * self.spec.adc_range_v / f64::from(gain.max(1))
        } else if drive_open {
            0.0
        } else {
            self.settled(inj, meas, amps)
        };
        (v, compliance)
    }

    pub(super) fn mains(&self, t: f64) -> f64 {
        self.spec.mains_v * (2.0 * PI * self.spec.mains_hz * t).sin()
    }
}
