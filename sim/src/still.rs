//! A still scene's frames, as imaging and its tests use them: V_0 averaged over untouched
//! frames (as captured at set-up), the noise of dV from their spread, and one frame with
//! every touch of the scene pressed.

use std::sync::Arc;

use et_core::ScanConfig;
use et_core::stats::{self, StatsError};

use crate::frontend::{SimError, SimFrontend};
use crate::scene::{Scene, TouchEvent};
use crate::sheet::{SheetError, SimulatedSheet};
use crate::touch::Touch;

/// Why a still scene's frames could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StillError {
    /// The sheet could not be built.
    #[error("simulated sheet: {0}")]
    Sheet(#[from] SheetError),
    /// The front end refused the configuration.
    #[error("simulated front end: {0}")]
    Frontend(#[from] SimError),
    /// The reference frames could not be averaged (non-finite values).
    #[error("reference frames: {0}")]
    Stats(#[from] StatsError),
}

/// A touch's centre (m) and radius (m).
pub type Truth = ([f64; 2], f64);

/// The simulator's frames of a still scene.
#[derive(Clone, Debug)]
pub struct SceneFrames {
    /// V_0: the untouched sheet, mean of the reference frames, V.
    pub v0: Vec<f64>,
    /// V_1: one frame with the scene's touches, V.
    pub v1: Vec<f32>,
    /// The noise of dV per channel, from the reference frames' spread
    /// ([`et_core::stats::dv_variance`]) and at least the ADC's rounding (q^2 / 6 for a code
    /// of q volts: V_1's and V_0's uniform rounding errors), V^2.
    pub var: Vec<f64>,
    /// The touches.
    pub truth: Vec<Truth>,
}

impl SceneFrames {
    /// dV = V_1 - V_0, V.
    #[must_use]
    pub fn dv(&self) -> Vec<f64> {
        self.v1
            .iter()
            .zip(&self.v0)
            .map(|(a, b)| f64::from(*a) - b)
            .collect()
    }
}

/// Noisy frames of `scene` scanned with `config`: V_0 the mean of `reference` untouched
/// frames (as captured at set-up), V_1 one frame with every touch of the scene pressed at
/// once (their start and end times ignored).
///
/// # Errors
/// [`StillError`] if the sheet cannot be built or the configuration is invalid.
pub fn scene_frames(
    scene: &Scene,
    config: &ScanConfig,
    reference: usize,
) -> Result<SceneFrames, StillError> {
    scene_frames_on(&simulated_sheet(scene)?, scene, config, reference)
}

/// The scene's sheet as the simulator's resistor network (the expensive part of
/// [`scene_frames`], shared by scenes with the same sheet).
///
/// # Errors
/// [`StillError`] if the sheet cannot be built.
pub fn simulated_sheet(scene: &Scene) -> Result<Arc<SimulatedSheet>, StillError> {
    scene.check_touches_resolved()?;
    // The sheet a recording of the scene measures: its electrodes moved as the seed draws
    // them, its shorted pairs shorted (both were left out here, so a still scene's frames
    // were of a perfect sheet).
    let offsets = scene.electrode_offsets();
    Ok(Arc::new(SimulatedSheet::with_shorts(
        &scene.sheet,
        &offsets,
        &scene.shorts(),
    )?))
}

/// [`scene_frames`] on a sheet already built by [`simulated_sheet`] (from a scene with the
/// same sheet).
///
/// # Errors
/// [`StillError`] if the configuration is invalid.
pub fn scene_frames_on(
    sheet: &Arc<SimulatedSheet>,
    scene: &Scene,
    config: &ScanConfig,
    reference: usize,
) -> Result<SceneFrames, StillError> {
    let mut sim = SimFrontend::new(Arc::clone(sheet), scene.frontend, scene.seed)?;
    let n = reference.max(1);
    let mut frames = Vec::with_capacity(n);
    for _ in 0..n {
        let frame = sim.fast_frame(config)?;
        frames.push(frame);
    }
    let k = frames[0].len();
    let (mut v0, mut var) = (vec![0.0; k], vec![0.0; k]);
    stats::reference(&frames, &mut v0)?;
    stats::dv_variance(&frames, &mut var)?;
    // At least the ADC's rounding: V_1 and V_0 each off by a uniform error of one code, so
    // frames without noise (identical reference frames) still carry their quantisation.
    let q = f64::from(scene.frontend.scale(config.gain).volts_per_code);
    for v in &mut var {
        *v = v.max(q * q / 6.0);
    }
    let touches: Vec<Touch> = scene.touches.iter().map(TouchEvent::touch).collect();
    sim.set_touches(&touches)?;
    Ok(SceneFrames {
        v0,
        v1: sim.fast_frame(config)?,
        var,
        truth: touches.iter().map(|t| (t.position, t.radius)).collect(),
    })
}
