//! The scan engine (docs/method.md §3, Algorithm 1): one scan of a protocol through a [`Frontend`].
//!
//! For every step k of the protocol: select the injection and measurement, acquire
//! `samples_per_step` samples, drop the first t_s, take the median of the rest, convert it to
//! volts and write V_m\[k]. Rail hits are counted per step and reported in a [`RailMask`], never
//! silently averaged in. The same loop with sub-section medians builds training observations
//! (Algorithms 2-3).
//!
//! The caller owns every buffer: the burst scratch (`samples_per_step` codes) and V_m (K
//! values), so the engine runs on the microcontroller without allocation.

use crate::config::{ConfigError, ScanConfig};
use crate::extract::{Extracted, settle_median, subsection_medians};
use crate::frontend::{AdcScale, Frontend};
use crate::protocol::{K_MAX, Protocol};

/// Which measurements of a frame had samples on an ADC rail (bit k = V_m\[k]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RailMask([u32; K_MAX / 32]);

impl Default for RailMask {
    fn default() -> Self {
        Self([0; K_MAX / 32])
    }
}

impl RailMask {
    /// Marks measurement `k`.
    pub fn set(&mut self, k: usize) {
        if let Some(w) = self.0.get_mut(k / 32) {
            *w |= 1 << (k % 32);
        }
    }

    /// Whether measurement `k` had rail samples.
    #[must_use]
    pub fn get(&self, k: usize) -> bool {
        self.0.get(k / 32).is_some_and(|w| w & (1 << (k % 32)) != 0)
    }

    /// How many measurements had rail samples.
    #[must_use]
    pub fn count(&self) -> usize {
        self.0.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// The flagged measurement indices, ascending.
    pub fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        (0..K_MAX).filter(|&k| self.get(k))
    }
}

/// What a scan saw besides the voltages.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanReport {
    /// Measurements with at least one kept sample on a rail.
    pub rail: RailMask,
    /// Kept samples on a rail, over the whole scan.
    pub rail_samples: u32,
    /// Samples acquired (`K * samples_per_step`).
    pub samples: u32,
    /// Samples dropped as settling transient (`K * t_s`).
    pub settle_dropped: u32,
    /// Measurements taken while the current source was in compliance
    /// ([`Frontend::in_compliance`]): their readings are too small.
    pub compliance_steps: u32,
}

/// Why a scan failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ScanError<E> {
    /// The configuration was refused before anything was switched.
    #[error("scan configuration refused: {0}")]
    Config(ConfigError),
    /// The front end reported an error (given back as is).
    #[error("front end error: {0:?}")]
    Frontend(E),
    /// The front end's [`AdcScale`] is not usable (bits, zero or step invalid).
    #[error("the front end reported an unusable ADC scale")]
    Scale,
    /// A caller buffer is shorter than the scan needs.
    #[error("buffer holds {given} elements, the scan needs {needed}")]
    Buffer {
        /// Elements needed.
        needed: usize,
        /// Elements given.
        given: usize,
    },
    /// More sub-sections than samples kept after t_s (`subsections == 0` is refused too).
    #[error("{subsections} sub-sections do not fit the {kept} samples kept per step")]
    Subsections {
        /// Sub-sections asked for.
        subsections: usize,
        /// Samples kept per step.
        kept: usize,
    },
}

/// A configured scan: the validated [`ScanConfig`], its protocol tables and the front end's
/// ADC scale. Build it with [`Scanner::new`] on the front end it will scan with.
#[derive(Clone, Copy, Debug)]
pub struct Scanner {
    config: ScanConfig,
    protocol: Protocol,
    scale: AdcScale,
}

impl Scanner {
    /// Validates `config` and configures `frontend` with it.
    ///
    /// # Errors
    /// [`ScanError::Config`] for a bad configuration (the front end is not touched),
    /// [`ScanError::Frontend`] if the front end refuses it, [`ScanError::Scale`] if it answers
    /// with an unusable ADC scale.
    pub fn new<F: Frontend>(
        config: ScanConfig,
        frontend: &mut F,
    ) -> Result<Self, ScanError<F::Error>> {
        let protocol = config.validate().map_err(ScanError::Config)?;
        let scale = frontend.configure(&config).map_err(ScanError::Frontend)?;
        if !scale.is_valid() {
            return Err(ScanError::Scale);
        }
        Ok(Self {
            config,
            protocol,
            scale,
        })
    }

    /// The configuration this scanner runs.
    #[must_use]
    pub fn config(&self) -> &ScanConfig {
        &self.config
    }

    /// The protocol tables.
    #[must_use]
    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }

    /// The ADC scale the front end reported.
    #[must_use]
    pub fn scale(&self) -> &AdcScale {
        &self.scale
    }

    /// Frame length K.
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.protocol.frame_len()
    }

    fn check_len<E>(needed: usize, given: usize) -> Result<(), ScanError<E>> {
        if given < needed {
            Err(ScanError::Buffer { needed, given })
        } else {
            Ok(())
        }
    }

    /// The loop both scans share: for every step, select, acquire a burst of
    /// `samples_per_step` codes, hand it to `extract` (which returns the step's rail count),
    /// and account for it in the report.
    fn walk<F: Frontend>(
        &self,
        frontend: &mut F,
        burst: &mut [u16],
        mut extract: impl FnMut(usize, &mut [u16]) -> Option<u16>,
    ) -> Result<ScanReport, ScanError<F::Error>> {
        let spp = usize::from(self.config.samples_per_step);
        let settle = usize::from(self.config.settle_samples);
        Self::check_len(spp, burst.len())?;
        let mut report = ScanReport::default();
        for step in self.protocol.steps() {
            let k = usize::from(step.k);
            frontend
                .select(step.injection, step.measurement)
                .map_err(ScanError::Frontend)?;
            let burst = &mut burst[..spp];
            frontend.acquire(burst).map_err(ScanError::Frontend)?;
            // ScanConfig::validate guarantees settle < spp, and the callers check their
            // sub-section counts, so this only fails on a broken invariant.
            let rails = extract(k, burst).ok_or(ScanError::Subsections {
                subsections: 1,
                kept: spp - settle,
            })?;
            if rails > 0 {
                report.rail.set(k);
            }
            report.rail_samples += u32::from(rails);
            report.compliance_steps += u32::from(frontend.in_compliance());
            report.samples += spp as u32;
            report.settle_dropped += settle as u32;
        }
        Ok(report)
    }

    /// Runs one scan (Algorithm 1) and writes V_m (volts, K values) into `v_m[..K]`.
    /// `burst` is scratch for one step's samples (at least `samples_per_step` codes).
    ///
    /// # Errors
    /// [`ScanError::Buffer`] if `burst` or `v_m` is too short (checked before anything is
    /// switched); [`ScanError::Frontend`] as soon as the front end fails (V_m is then partial).
    pub fn scan<F: Frontend>(
        &self,
        frontend: &mut F,
        burst: &mut [u16],
        v_m: &mut [f32],
    ) -> Result<ScanReport, ScanError<F::Error>> {
        let settle = usize::from(self.config.settle_samples);
        Self::check_len(self.frame_len(), v_m.len())?;
        self.walk(frontend, burst, |k, burst| {
            let e = settle_median(burst, settle, &self.scale)?;
            v_m[k] = self.scale.volts(e.median_code);
            Some(e.rail_samples)
        })
    }

    /// Runs one scan and cuts every step's kept samples into `subsections` sub-sections whose
    /// medians each give one observation (Algorithms 2-3). Observation `s` is written to
    /// `observations[s * K .. (s + 1) * K]` (observation-major, volts). `scratch` holds one
    /// [`Extracted`] per sub-section.
    ///
    /// # Errors
    /// [`ScanError::Subsections`] if `subsections` is 0 or larger than the kept samples,
    /// [`ScanError::Buffer`] for short buffers, [`ScanError::Frontend`] from the front end.
    pub fn scan_subsections<F: Frontend>(
        &self,
        frontend: &mut F,
        burst: &mut [u16],
        subsections: usize,
        scratch: &mut [Extracted],
        observations: &mut [f32],
    ) -> Result<ScanReport, ScanError<F::Error>> {
        let settle = usize::from(self.config.settle_samples);
        let kept = usize::from(self.config.kept_samples());
        if subsections == 0 || subsections > kept {
            return Err(ScanError::Subsections { subsections, kept });
        }
        let k_len = self.frame_len();
        Self::check_len(subsections, scratch.len())?;
        Self::check_len(subsections * k_len, observations.len())?;
        let scratch = &mut scratch[..subsections];
        self.walk(frontend, burst, |k, burst| {
            let rails = subsection_medians(burst, settle, &self.scale, scratch)?;
            for (s, e) in scratch.iter().enumerate() {
                observations[s * k_len + k] = self.scale.volts(e.median_code);
            }
            Some(rails)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{Injection, Measurement, ProtocolKind};
    use std::vec;
    use std::vec::Vec;

    /// A scripted front end: the "true" voltage of a step is a known function of its
    /// electrodes; every burst starts with a transient of t_s samples far off the value,
    /// carries spikes at fixed places, and optionally hits a rail. It logs every call.
    struct Scripted {
        scale: AdcScale,
        settle: usize,
        selected: Option<(Injection, Measurement)>,
        selects: usize,
        acquired: Vec<usize>,
        rail_on: Option<(Injection, Measurement)>,
        fail_after: Option<usize>,
    }

    impl Scripted {
        fn new(settle: usize) -> Self {
            Self {
                scale: AdcScale::bipolar_16bit(5.0, 1),
                settle,
                selected: None,
                selects: 0,
                acquired: Vec::new(),
                rail_on: None,
                fail_after: None,
            }
        }
        /// The code a step should read: distinct for every (injection, measurement).
        fn truth(inj: Injection, m: Measurement) -> u16 {
            30_000
                + 97 * u16::from(inj.source.0)
                + 31 * u16::from(inj.sink.0)
                + 7 * u16::from(m.positive.0)
                + u16::from(m.negative.0)
        }
    }

    impl Frontend for Scripted {
        type Error = &'static str;
        fn configure(&mut self, c: &ScanConfig) -> Result<AdcScale, Self::Error> {
            self.scale = AdcScale::bipolar_16bit(5.0, c.gain);
            Ok(self.scale)
        }
        fn select(&mut self, i: Injection, m: Measurement) -> Result<(), Self::Error> {
            self.selects += 1;
            if self.fail_after == Some(self.selects) {
                return Err("mux stuck");
            }
            self.selected = Some((i, m));
            Ok(())
        }
        fn acquire(&mut self, out: &mut [u16]) -> Result<(), Self::Error> {
            let (i, m) = self.selected.ok_or("acquire before select")?;
            self.acquired.push(out.len());
            let v = Self::truth(i, m);
            for (n, s) in out.iter_mut().enumerate() {
                *s = if n < self.settle {
                    // Transient: far above the plateau, decaying.
                    v.saturating_add(20_000 - 500 * n as u16)
                } else if n % 7 == 3 {
                    v.saturating_sub(9_000) // spike
                } else {
                    v + (n % 3) as u16 - 1 // +-1 code of "noise" around v
                };
            }
            if self.rail_on == Some((i, m)) {
                out[out.len() - 1] = self.scale.max_code();
            }
            Ok(())
        }
    }

    #[test]
    fn scan_returns_the_medians_with_the_configured_counts() {
        for kind in ProtocolKind::NAMED {
            let config = ScanConfig {
                protocol: kind,
                electrodes: 8,
                ..ScanConfig::REFERENCE
            };
            let mut fe = Scripted::new(usize::from(config.settle_samples));
            let scanner = Scanner::new(config, &mut fe).unwrap();
            let k = scanner.frame_len();
            let mut burst = vec![0u16; 64];
            let mut v_m = vec![f32::NAN; k];
            let report = scanner.scan(&mut fe, &mut burst, &mut v_m).unwrap();
            for step in scanner.protocol().steps() {
                let want = fe
                    .scale
                    .volts(f32::from(Scripted::truth(step.injection, step.measurement)));
                assert!(
                    (v_m[usize::from(step.k)] - want).abs() <= fe.scale.volts_per_code,
                    "{kind:?} k={} got {} want {want}",
                    step.k,
                    v_m[usize::from(step.k)]
                );
            }
            assert_eq!(fe.selects, k);
            assert_eq!(
                fe.acquired,
                vec![50; k],
                "every burst is samples_per_step long"
            );
            assert_eq!(report.samples, 50 * k as u32);
            assert_eq!(report.settle_dropped, 25 * k as u32);
            assert_eq!(report.rail.count(), 0);
        }
    }

    #[test]
    fn without_settling_the_transient_biases_the_median() {
        // The same script, t_s = 0 and a transient over 30 of 50 samples: the median moves,
        // which is why t_s exists.
        let config = ScanConfig {
            settle_samples: 0,
            ..ScanConfig::REFERENCE
        };
        let mut fe = Scripted::new(30);
        let scanner = Scanner::new(config, &mut fe).unwrap();
        let mut burst = vec![0u16; 50];
        let mut v_m = vec![0.0; scanner.frame_len()];
        scanner.scan(&mut fe, &mut burst, &mut v_m).unwrap();
        let step = scanner.protocol().step(0).unwrap();
        let want = fe
            .scale
            .volts(f32::from(Scripted::truth(step.injection, step.measurement)));
        assert!((v_m[0] - want).abs() > 100.0 * fe.scale.volts_per_code);
    }

    #[test]
    fn rail_hits_are_flagged_on_their_step() {
        let config = ScanConfig::REFERENCE;
        let mut fe = Scripted::new(25);
        let scanner = Scanner::new(config, &mut fe).unwrap();
        let target = scanner.protocol().step(17).unwrap();
        fe.rail_on = Some((target.injection, target.measurement));
        let mut burst = vec![0u16; 50];
        let mut v_m = vec![0.0; scanner.frame_len()];
        let report = scanner.scan(&mut fe, &mut burst, &mut v_m).unwrap();
        assert_eq!(report.rail.iter().collect::<Vec<_>>(), vec![17]);
        assert_eq!(report.rail_samples, 1);
    }

    #[test]
    fn subsections_give_one_observation_each() {
        let config = ScanConfig {
            samples_per_step: 200,
            settle_samples: 40,
            ..ScanConfig::REFERENCE
        };
        let mut fe = Scripted::new(40);
        let scanner = Scanner::new(config, &mut fe).unwrap();
        let k = scanner.frame_len();
        let mut burst = vec![0u16; 200];
        let mut scratch = [Extracted {
            median_code: 0.0,
            rail_samples: 0,
        }; 4];
        let mut obs = vec![f32::NAN; 4 * k];
        scanner
            .scan_subsections(&mut fe, &mut burst, 4, &mut scratch, &mut obs)
            .unwrap();
        for s in 0..4 {
            for step in scanner.protocol().steps() {
                let want = fe
                    .scale
                    .volts(f32::from(Scripted::truth(step.injection, step.measurement)));
                let got = obs[s * k + usize::from(step.k)];
                assert!(
                    (got - want).abs() <= fe.scale.volts_per_code,
                    "s={s} k={}",
                    step.k
                );
            }
        }
        let e = scanner.scan_subsections(&mut fe, &mut burst, 161, &mut scratch, &mut obs);
        assert_eq!(
            e,
            Err(ScanError::Subsections {
                subsections: 161,
                kept: 160
            })
        );
        let e = scanner.scan_subsections(&mut fe, &mut burst, 0, &mut scratch, &mut obs);
        assert!(matches!(
            e,
            Err(ScanError::Subsections { subsections: 0, .. })
        ));
    }

    #[test]
    fn errors_are_typed_and_early() {
        let mut fe = Scripted::new(25);
        let bad = ScanConfig {
            settle_samples: 60,
            ..ScanConfig::REFERENCE
        };
        assert!(matches!(
            Scanner::new(bad, &mut fe),
            Err(ScanError::Config(_))
        ));
        let scanner = Scanner::new(ScanConfig::REFERENCE, &mut fe).unwrap();
        let mut short = vec![0u16; 10];
        let mut v_m = vec![0.0; 208];
        assert_eq!(
            scanner.scan(&mut fe, &mut short, &mut v_m),
            Err(ScanError::Buffer {
                needed: 50,
                given: 10
            })
        );
        assert_eq!(
            fe.selects, 0,
            "nothing switched before the buffers were checked"
        );
        let mut burst = vec![0u16; 50];
        assert_eq!(
            scanner.scan(&mut fe, &mut burst, &mut v_m[..100]),
            Err(ScanError::Buffer {
                needed: 208,
                given: 100
            })
        );
        fe.fail_after = Some(5);
        assert_eq!(
            scanner.scan(&mut fe, &mut burst, &mut v_m),
            Err(ScanError::Frontend("mux stuck"))
        );
    }
}
