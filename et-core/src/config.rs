//! Scan configuration: one value type the host sends to the firmware
//! ([`Command::Configure`](crate::wire::Command::Configure)) and every frame carries.

use serde::{Deserialize, Serialize};

use crate::protocol::{Protocol, ProtocolError, ProtocolKind};

/// Longest burst one step may acquire (samples per injection, S / L in docs/method.md §3).
pub const SAMPLES_PER_STEP_MAX: u16 = 4096;
/// Largest current the Howland source is asked for, in nA (docs/method.md §2 uses 10 000 to 32 000).
pub const CURRENT_NA_MAX: u32 = 1_000_000;

/// How one scan is acquired (docs/method.md §3, Algorithm 1).
///
/// The reference operating point ([`ScanConfig::REFERENCE`]) is L = 16, adjacent, 62.5 kS/s per
/// channel, 50 samples per injection of which t_s = 25 are dropped, 32 uA: 78 Hz.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanConfig {
    /// Electrode count L (even, 4 to 32).
    #[serde(deserialize_with = "crate::whole::whole")]
    pub electrodes: u8,
    /// Injection / measurement protocol (docs/method.md §4).
    pub protocol: ProtocolKind,
    /// Samples acquired per step, S / L (docs/method.md §3), `1..=SAMPLES_PER_STEP_MAX`.
    #[serde(deserialize_with = "crate::whole::whole")]
    pub samples_per_step: u16,
    /// t_s: samples dropped at the start of each step while the front end settles.
    /// Must leave at least one sample: `settle_samples < samples_per_step`.
    #[serde(deserialize_with = "crate::whole::whole")]
    pub settle_samples: u16,
    /// Injected current I in nA (10 000 to 32 000 in docs/method.md §2), `1..=CURRENT_NA_MAX`.
    #[serde(deserialize_with = "crate::whole::whole")]
    pub current_na: u32,
    /// ADC sample rate per channel in Hz (62 500 at the reference point).
    #[serde(deserialize_with = "crate::whole::whole")]
    pub sample_rate_hz: u32,
    /// Programmable gain of the instrumentation amplifier (1 = unity), at least 1.
    #[serde(deserialize_with = "crate::whole::whole")]
    pub gain: u8,
}

impl ScanConfig {
    /// The reference operating point of docs/method.md §3: 78 Hz at L = 16.
    pub const REFERENCE: ScanConfig = ScanConfig {
        electrodes: 16,
        protocol: ProtocolKind::Adjacent,
        samples_per_step: 50,
        settle_samples: 25,
        current_na: 32_000,
        sample_rate_hz: 62_500,
        gain: 1,
    };

    /// Checks every field and builds the protocol tables.
    ///
    /// # Errors
    /// [`ConfigError`] naming the first field that is out of range.
    pub fn validate(&self) -> Result<Protocol, ConfigError> {
        let protocol =
            Protocol::new(self.protocol, self.electrodes).map_err(ConfigError::Protocol)?;
        if self.samples_per_step == 0 || self.samples_per_step > SAMPLES_PER_STEP_MAX {
            return Err(ConfigError::SamplesPerStep {
                samples_per_step: self.samples_per_step,
            });
        }
        if self.settle_samples >= self.samples_per_step {
            return Err(ConfigError::Settle {
                settle_samples: self.settle_samples,
                samples_per_step: self.samples_per_step,
            });
        }
        if self.current_na == 0 || self.current_na > CURRENT_NA_MAX {
            return Err(ConfigError::Current {
                current_na: self.current_na,
            });
        }
        if self.sample_rate_hz == 0 {
            return Err(ConfigError::SampleRate);
        }
        if self.gain == 0 {
            return Err(ConfigError::Gain);
        }
        Ok(protocol)
    }

    /// Samples kept per step after dropping t_s.
    #[must_use]
    pub fn kept_samples(&self) -> u16 {
        self.samples_per_step.saturating_sub(self.settle_samples)
    }

    /// Frames per second when every channel of an injection is sampled in parallel:
    /// `sample_rate / (samples_per_step * L)` (78.1 Hz at the reference point).
    #[must_use]
    pub fn frame_rate_hz(&self) -> f32 {
        self.sample_rate_hz as f32 / (f32::from(self.samples_per_step) * f32::from(self.electrodes))
    }

    /// The current in amperes.
    #[must_use]
    pub fn current_amps(&self) -> f32 {
        self.current_na as f32 * 1e-9
    }
}

impl Default for ScanConfig {
    fn default() -> Self {
        Self::REFERENCE
    }
}

/// Why a [`ScanConfig`] is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// `electrodes` / `protocol` do not make a protocol.
    #[error("protocol: {0}")]
    Protocol(ProtocolError),
    /// `samples_per_step` is 0 or above [`SAMPLES_PER_STEP_MAX`].
    #[error("samples_per_step = {samples_per_step}: use 1 to {SAMPLES_PER_STEP_MAX}")]
    SamplesPerStep {
        /// The value given.
        samples_per_step: u16,
    },
    /// `settle_samples` leaves no sample to take the median of.
    #[error(
        "settle_samples = {settle_samples} leaves nothing of {samples_per_step} samples per step: make it smaller"
    )]
    Settle {
        /// t_s given.
        settle_samples: u16,
        /// Samples per step given.
        samples_per_step: u16,
    },
    /// `current_na` is 0 or above [`CURRENT_NA_MAX`].
    #[error("current_na = {current_na}: use 1 to {CURRENT_NA_MAX} nA")]
    Current {
        /// The value given.
        current_na: u32,
    },
    /// `sample_rate_hz` is 0.
    #[error("sample_rate_hz must be positive")]
    SampleRate,
    /// `gain` is 0.
    #[error("gain must be at least 1")]
    Gain,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_point_is_78_hz_and_valid() {
        let p = ScanConfig::REFERENCE.validate().unwrap();
        assert_eq!(p.frame_len(), 208);
        assert!((ScanConfig::REFERENCE.frame_rate_hz() - 78.125).abs() < 1e-3);
        let l8 = ScanConfig {
            electrodes: 8,
            ..ScanConfig::REFERENCE
        };
        assert!((l8.frame_rate_hz() - 156.25).abs() < 1e-3);
        assert_eq!(ScanConfig::REFERENCE.kept_samples(), 25);
    }

    #[test]
    fn each_bad_field_is_named() {
        let r = ScanConfig::REFERENCE;
        let bad = |c: ScanConfig| c.validate().unwrap_err();
        assert!(matches!(
            bad(ScanConfig { electrodes: 7, ..r }),
            ConfigError::Protocol(_)
        ));
        assert_eq!(
            bad(ScanConfig {
                samples_per_step: 0,
                ..r
            }),
            ConfigError::SamplesPerStep {
                samples_per_step: 0
            }
        );
        assert_eq!(
            bad(ScanConfig {
                samples_per_step: 5000,
                ..r
            }),
            ConfigError::SamplesPerStep {
                samples_per_step: 5000
            }
        );
        assert_eq!(
            bad(ScanConfig {
                settle_samples: 50,
                ..r
            }),
            ConfigError::Settle {
                settle_samples: 50,
                samples_per_step: 50
            }
        );
        assert_eq!(
            bad(ScanConfig { current_na: 0, ..r }),
            ConfigError::Current { current_na: 0 }
        );
        assert_eq!(
            bad(ScanConfig {
                sample_rate_hz: 0,
                ..r
            }),
            ConfigError::SampleRate
        );
        assert_eq!(bad(ScanConfig { gain: 0, ..r }), ConfigError::Gain);
    }
}
