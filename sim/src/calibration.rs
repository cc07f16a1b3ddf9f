//! The calibration of the simulated front end's two noise layers to the reference hardware
//! (docs/calibration.md, docs/method.md §3): the measurements, the reference's figures, and the
//! searches that fit the parameters. `cargo run --release -p et-sim --example calibrate` runs
//! them; the `calibration` tests check the defaults against the figures.
//!
//! The operating point: the 13 x 13 cm, 16-electrode sheet, untouched, adjacent protocol at the
//! reference scan settings and PGIA gain [`CALIBRATION_GAIN`].

use std::sync::Arc;

use et_core::ScanConfig;
use et_core::rng::Rng;
use et_core::stats::{mad, snr};

use crate::frontend::{CALIBRATION_GAIN, FrontendSpec, SetSpread, SimError, SimFrontend};
use crate::sheet::{SheetError, SheetSpec, SimulatedSheet};

/// The reference's frame-to-frame SNR, dB, at 32 uA and 10 uA.
pub const SNR_DB: [(u32, f64); 2] = [(32_000, 55.0), (10_000, 49.0)];
/// The reference's MAD between measurement sets, V, at 32 uA and 10 uA.
pub const MAD_V: [(u32, f64); 2] = [(32_000, 0.5e-3), (10_000, 0.4e-3)];

/// The sheet of the calibration.
#[must_use]
pub fn sheet_spec() -> SheetSpec {
    SheetSpec::rectangle(0.13, 0.13, 16)
}

/// The scan settings of the calibration at `current_na`.
#[must_use]
pub fn config(current_na: u32) -> ScanConfig {
    ScanConfig {
        current_na,
        gain: CALIBRATION_GAIN,
        ..ScanConfig::REFERENCE
    }
}

/// Why a measurement failed (a spec or configuration the simulator refuses).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CalibrationError {
    /// The sheet or the front end's spec.
    #[error(transparent)]
    Sheet(#[from] SheetError),
    /// The simulated front end.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The statistics (too few frames, non-finite values).
    #[error("statistics: {0}")]
    Stats(#[from] et_core::stats::StatsError),
}

/// K, the frame length of `config`.
fn frame_len(config: &ScanConfig) -> Result<usize, CalibrationError> {
    Ok(config.validate().map_err(SimError::Config)?.frame_len())
}

/// `frames` frames of one measurement set, flattened (fast path).
fn frames_of(
    fe: &mut SimFrontend,
    config: &ScanConfig,
    frames: usize,
) -> Result<Vec<f32>, CalibrationError> {
    let mut out = Vec::new();
    for _ in 0..frames {
        out.extend(fe.fast_frame(config)?);
    }
    Ok(out)
}

/// The mean SNR, dB, over channels of `frames` repeated frames of one set (docs/method.md §3).
///
/// # Errors
/// [`CalibrationError`] for a spec the simulator refuses or fewer than 2 frames.
pub fn frame_snr(
    sheet: &Arc<SimulatedSheet>,
    spec: FrontendSpec,
    current_na: u32,
    frames: usize,
    seed: u64,
) -> Result<f64, CalibrationError> {
    let config = config(current_na);
    let mut fe = SimFrontend::new(sheet.clone(), spec, seed)?;
    let k = frame_len(&config)?;
    let all = frames_of(&mut fe, &config, frames)?;
    Ok(f64::from(snr(&all, k)?.mean_db))
}

/// `count` sheets of `spec` whose electrodes were put down again, each `movement` m rms off
/// its place along the outline (drawn from `seed`); with no movement, one sheet `count` times
/// (the sheet stayed mounted).
///
/// # Errors
/// [`SheetError`] if a sheet cannot be built.
pub fn replaced_sheets(
    spec: &SheetSpec,
    movement: f64,
    count: usize,
    seed: u64,
) -> Result<Vec<Arc<SimulatedSheet>>, SheetError> {
    if movement == 0.0 {
        let sheet = Arc::new(SimulatedSheet::new(spec, &[])?);
        return Ok(vec![sheet; count]);
    }
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| {
            let offsets: Vec<f64> = (0..spec.physical.electrodes.count)
                .map(|_| movement * rng.normal())
                .collect();
            SimulatedSheet::new(spec, &offsets).map(Arc::new)
        })
        .collect()
}

/// The MAD, V, between measurement sets: one set per sheet of `sets` (each in its own
/// [`SetSpread::draw`] of `spec.sets`), each set's mean of `frames_per_set` frames against the
/// mean over sets, averaged over channels and sets. Set `s` draws from `seed + s`, so two
/// specs are compared on the same draws.
///
/// # Errors
/// [`CalibrationError`] for a spec the simulator refuses or fewer than 2 sets.
pub fn set_mad(
    sets: &[Arc<SimulatedSheet>],
    spec: FrontendSpec,
    current_na: u32,
    frames_per_set: usize,
    seed: u64,
) -> Result<f64, CalibrationError> {
    let config = config(current_na);
    let k = frame_len(&config)?;
    let mut means = Vec::with_capacity(sets.len() * k);
    for (s, sheet) in sets.iter().enumerate() {
        let mut rng = Rng::new(seed.wrapping_add(s as u64));
        let state = spec.sets.draw(sheet.electrodes(), &mut rng);
        let mut fe = SimFrontend::new(sheet.clone(), spec, rng.next_u64())?;
        fe.set_state(&state)?;
        let all = frames_of(&mut fe, &config, frames_per_set)?;
        let mut mean = vec![0.0f64; k];
        for f in all.chunks(k) {
            for (m, v) in mean.iter_mut().zip(f) {
                *m += f64::from(*v) / frames_per_set as f64;
            }
        }
        means.extend(mean.iter().map(|&m| m as f32));
    }
    Ok(f64::from(mad(&means, k)?))
}

/// The x in [lo, hi] where the increasing `f` crosses `target` (`halvings` steps).
fn bisect(
    mut lo: f64,
    mut hi: f64,
    halvings: usize,
    target: f64,
    mut f: impl FnMut(f64) -> Result<f64, CalibrationError>,
) -> Result<f64, CalibrationError> {
    for _ in 0..halvings {
        let mid = 0.5 * (lo + hi);
        if f(mid)? < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Fits the frame layer (white noise, current jitter) of `base` to [`SNR_DB`], `frames`
/// frames per SNR: the floor independent of the current sets the 10 uA SNR, the jitter caps
/// the 32 uA one. Nested bisections: the jitter on [0, 1 %], and for each jitter the white
/// noise on [0, 0.5 mV] that gives 49 dB at 10 uA.
///
/// # Errors
/// [`CalibrationError`] as [`frame_snr`].
pub fn fit_frame_layer(
    sheet: &Arc<SimulatedSheet>,
    base: FrontendSpec,
    frames: usize,
) -> Result<FrontendSpec, CalibrationError> {
    let [(hi_na, hi_db), (lo_na, lo_db)] = SNR_DB;
    let with_jitter = |j: f64| -> Result<FrontendSpec, CalibrationError> {
        let with = |w: f64| FrontendSpec {
            white_noise_v: w,
            current_noise: j,
            ..base
        };
        let w = bisect(0.0, 0.5e-3, 20, -lo_db, |w| {
            Ok(-frame_snr(sheet, with(w), lo_na, frames, 42)?)
        })?;
        Ok(with(w))
    };
    let j = bisect(0.0, 0.01, 14, -hi_db, |j| {
        Ok(-frame_snr(sheet, with_jitter(j)?, hi_na, frames, 42)?)
    })?;
    with_jitter(j)
}

/// Fits the set layer (junction potentials, conductance) of `base` to [`MAD_V`] on `sets`
/// (one sheet per set: the same sheet when it stays mounted, or re-placed ones): the junction potentials, independent of the current, set the 10 uA
/// MAD; the conductance adds to the 32 uA one in proportion to the current. Nested
/// bisections: the conductance on [0, 5 %], and for each the junction potential on
/// [0, 2 mV] that gives 0.4 mV at 10 uA. When re-placement alone exceeds a MAD, the
/// corresponding parameter ends at 0.
///
/// # Errors
/// [`CalibrationError`] as [`set_mad`].
pub fn fit_set_layer(
    sets: &[Arc<SimulatedSheet>],
    base: FrontendSpec,
    frames_per_set: usize,
) -> Result<FrontendSpec, CalibrationError> {
    let [(hi_na, hi_v), (lo_na, lo_v)] = MAD_V;
    let with_conductance = |g: f64| -> Result<FrontendSpec, CalibrationError> {
        let with = |c: f64| FrontendSpec {
            sets: SetSpread {
                contact_potential_v: c,
                conductance: g,
            },
            ..base
        };
        let c = bisect(0.0, 2e-3, 20, lo_v, |c| {
            set_mad(sets, with(c), lo_na, frames_per_set, 1_000)
        })?;
        Ok(with(c))
    };
    let g = bisect(0.0, 0.05, 14, hi_v, |g| {
        set_mad(sets, with_conductance(g)?, hi_na, frames_per_set, 1_000)
    })?;
    with_conductance(g)
}
