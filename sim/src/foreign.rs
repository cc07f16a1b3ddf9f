//! Another lab's instrument, as the simulator stands in for it: any schedule (a protocol file
//! of any system: its numbering, its families of injections, measurements on drive
//! electrodes, milliampere currents) measured on the resistor network, with the noise and
//! drift a real instrument adds. Frames come out in volts, one `Vec` per frame, the empty
//! sheet's first, as other systems write them (`et reconstruct --frames` reads them from CSV,
//! .npy, .npz or .mat).
//!
//! The noise of real systems is not et's front end: each value carries white noise of
//! `noise` times the frame's rms (the amplifier and ADC floor) and `proportional` times its own
//! magnitude (the current source's and gain's jitter, largest on the drive electrodes'
//! values); the instrument's gain drifts by `gain_drift` per frame (temperature, a slowly
//! discharging reference), so a frame taken long after its reference is off by a common
//! factor.

use et_core::rng::Rng;
use et_core::schedule::Schedule;

use crate::sheet::{SheetError, SimulatedSheet};
use crate::touch::Inclusion;

/// A foreign instrument's imperfections (all dimensionless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instrument {
    /// White noise per value, as a share of the empty sheet's rms value.
    pub noise: f64,
    /// Noise proportional to each value, as a share of it.
    pub proportional: f64,
    /// The gain's change per frame (frame i is scaled by 1 + i gain_drift).
    pub gain_drift: f64,
    /// The noise's seed.
    pub seed: u64,
}

impl Instrument {
    /// An instrument with no noise and no drift.
    #[must_use]
    pub fn ideal() -> Self {
        Self {
            noise: 0.0,
            proportional: 0.0,
            gain_drift: 0.0,
            seed: 0,
        }
    }

    /// A good laboratory system: 0.05 % of the rms white, 0.05 % proportional, 0.01 % gain
    /// drift per frame (signal-to-noise about 66 dB on an average channel).
    #[must_use]
    pub fn laboratory(seed: u64) -> Self {
        Self {
            noise: 5e-4,
            proportional: 5e-4,
            gain_drift: 1e-4,
            seed,
        }
    }
}

/// Why frames could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ForeignError {
    /// The sheet's network could not be solved with the inclusions.
    #[error("simulated sheet: {0}")]
    Sheet(#[from] SheetError),
    /// The schedule is for another number of electrodes than the sheet's.
    #[error("the protocol is for {protocol} electrodes, the sheet has {sheet}")]
    Electrodes {
        /// The schedule's electrodes.
        protocol: usize,
        /// The sheet's.
        sheet: usize,
    },
}

/// The frames `instrument` measures on `sheet` under `schedule`: the empty sheet's first, then
/// one per entry of `scenes` (the inclusions present in that frame), V (K values each).
///
/// # Errors
/// [`ForeignError`] when the network cannot be solved or the schedule has another electrode
/// count.
pub fn frames(
    sheet: &SimulatedSheet,
    schedule: &Schedule,
    scenes: &[Vec<Inclusion>],
    instrument: &Instrument,
) -> Result<Vec<Vec<f64>>, ForeignError> {
    let ideal = |inclusions: &[Inclusion]| -> Result<Vec<f64>, ForeignError> {
        sheet
            .transfer_inclusions(inclusions)?
            .frame_of(schedule)
            .ok_or(ForeignError::Electrodes {
                protocol: schedule.electrodes(),
                sheet: sheet.electrodes(),
            })
    };
    let empty = ideal(&[])?;
    let rms = (empty.iter().map(|v| v * v).sum::<f64>() / empty.len().max(1) as f64).sqrt();
    let mut rng = Rng::new(instrument.seed);
    let mut measure = |i: usize, v: Vec<f64>| -> Vec<f64> {
        let gain = 1.0 + i as f64 * instrument.gain_drift;
        v.into_iter()
            .map(|x| {
                let sd = (instrument.noise * rms).hypot(instrument.proportional * x);
                gain * x + sd * rng.normal()
            })
            .collect()
    };
    let mut out = vec![measure(0, empty)];
    for (i, inclusions) in scenes.iter().enumerate() {
        out.push(measure(i + 1, ideal(inclusions)?));
    }
    Ok(out)
}
