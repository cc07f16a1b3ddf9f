//! Imaging a sheet end to end, as `et reconstruct`, `et demo` and the viewer do it: the set-up
//! (mesh, forward model, Jacobian at the background conductivity, pixel grid), the simulator's
//! frames of a still scene, and the picture with its colour bar.
//!
//! The pieces are [`crate::mesh`], [`crate::fem`] and [`crate::recon`]; this module only
//! strings them together so every caller does it the same way.

use std::path::Path;
use std::sync::Arc;

use et_core::ScanConfig;
use et_core::protocol::Protocol;
use et_sim::scene::{Scene, TouchEvent};
use et_sim::sheet::{Sheet, SheetSpec};
use et_sim::touch::Touch;
use nalgebra::DMatrix;

use crate::fem::{Electrodes, FemError, Forward};
use crate::mesh::{Mesh, MeshError};
use crate::plot::{self, PlotError};
use crate::recon::{PixelGrid, ReconError};

/// Why imaging could not be set up or run.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ImagingError {
    /// The mesh.
    Mesh(MeshError),
    /// The forward model.
    Fem(FemError),
    /// The reconstruction.
    Recon(ReconError),
    /// The simulated sheet (its own message).
    Sim(String),
}

impl std::fmt::Display for ImagingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ImagingError::Mesh(e) => e.fmt(f),
            ImagingError::Fem(e) => e.fmt(f),
            ImagingError::Recon(e) => e.fmt(f),
            ImagingError::Sim(why) => write!(f, "simulated sheet: {why}"),
        }
    }
}

impl std::error::Error for ImagingError {}

impl From<MeshError> for ImagingError {
    fn from(e: MeshError) -> Self {
        Self::Mesh(e)
    }
}

impl From<FemError> for ImagingError {
    fn from(e: FemError) -> Self {
        Self::Fem(e)
    }
}

impl From<ReconError> for ImagingError {
    fn from(e: ReconError) -> Self {
        Self::Recon(e)
    }
}

fn sim_error(e: impl std::fmt::Display) -> ImagingError {
    ImagingError::Sim(e.to_string())
}

/// The forward model of one sheet about its background conductivity, and the pixel grid
/// images are drawn on. One `Imager` serves every protocol (a Jacobian per protocol).
pub struct Imager {
    /// Finite elements with the complete electrode model (SPEC §5).
    pub forward: Forward,
    /// The pixels images are drawn on.
    pub grid: PixelGrid,
    /// Background conductivity sigma_0 = 1 / sheet resistance, S per square.
    pub sigma0: f64,
}

impl std::fmt::Debug for Imager {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Imager")
            .field("triangles", &self.triangles())
            .field("grid", &(self.grid.width, self.grid.height))
            .field("sigma0", &self.sigma0)
            .finish_non_exhaustive()
    }
}

impl Imager {
    /// The complete electrode model of `sheet` on `mesh` (contact impedance z = contact
    /// resistance x electrode width, ohm m), a grid `pixels` across.
    ///
    /// # Errors
    /// [`ImagingError::Fem`] if the forward model cannot be built.
    pub fn new(sheet: &SheetSpec, mesh: Mesh, pixels: usize) -> Result<Self, ImagingError> {
        let grid = PixelGrid::new(&mesh, pixels.max(4));
        let e = &sheet.electrodes;
        let z = vec![e.contact_ohm * e.width; usize::from(e.count)];
        Ok(Self {
            forward: Forward::new(mesh, Electrodes::Complete(z))?,
            grid,
            sigma0: 1.0 / sheet.sheet_resistance,
        })
    }

    /// Triangles of the mesh.
    #[must_use]
    pub fn triangles(&self) -> usize {
        self.forward.mesh().triangles.len()
    }

    /// The background conductivity on every triangle.
    #[must_use]
    pub fn background(&self) -> Vec<f64> {
        vec![self.sigma0; self.triangles()]
    }

    /// The K x T Jacobian of `protocol`'s frame at the background, `amps` injected (V per
    /// S per square).
    ///
    /// # Errors
    /// [`ImagingError::Fem`] if the solve fails.
    pub fn jacobian(&self, protocol: &Protocol, amps: f64) -> Result<DMatrix<f64>, ImagingError> {
        Ok(self.forward.jacobian(&self.background(), protocol, amps)?.1)
    }

    /// Writes `image` (one value per pixel, None outside the sheet, S per square) as a PNG in
    /// units of the background, with a symmetric colour bar and axes in mm.
    ///
    /// # Errors
    /// [`PlotError`] naming the file.
    pub fn write_png(
        &self,
        path: &Path,
        title: &str,
        image: &[Option<f64>],
    ) -> Result<(), PlotError> {
        let grid = &self.grid;
        // Row 0 at the top.
        let rows: Vec<f64> = (0..grid.height)
            .rev()
            .flat_map(|j| (0..grid.width).map(move |i| j * grid.width + i))
            .map(|p| image[p].map_or(f64::NAN, |v| v / self.sigma0))
            .collect();
        let hi = rows
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let mm = |v: f64| v * 1e3;
        let extent = plot::Extent {
            x: (
                mm(grid.origin[0]),
                mm(grid.origin[0] + grid.width as f64 * grid.size),
            ),
            y: (
                mm(grid.origin[1] + grid.height as f64 * grid.size),
                mm(grid.origin[1]),
            ),
        };
        plot::heatmap_over(
            path,
            plot::Labels {
                title,
                x: "x (mm)",
                y: "y (mm)",
                legend: plot::Legend::UpperLeft,
            },
            &rows,
            (grid.height, grid.width),
            extent,
            (-hi, hi.max(f64::MIN_POSITIVE)),
            "conductivity change / background",
        )
    }
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
    /// ([`crate::recon::dv_variance`]), V^2.
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
/// [`ImagingError::Sim`] if the sheet cannot be built or the configuration is invalid.
pub fn scene_frames(
    scene: &Scene,
    config: &ScanConfig,
    reference: usize,
) -> Result<SceneFrames, ImagingError> {
    scene_frames_on(&simulated_sheet(scene)?, scene, config, reference)
}

/// The scene's sheet as the simulator's resistor network (the expensive part of
/// [`scene_frames`], shared by scenes with the same sheet).
///
/// # Errors
/// [`ImagingError::Sim`] if the sheet cannot be built.
pub fn simulated_sheet(scene: &Scene) -> Result<Arc<Sheet>, ImagingError> {
    Ok(Arc::new(Sheet::new(&scene.sheet, &[]).map_err(sim_error)?))
}

/// [`scene_frames`] on a sheet already built by [`simulated_sheet`] (from a scene with the
/// same sheet).
///
/// # Errors
/// [`ImagingError::Sim`] if the configuration is invalid.
pub fn scene_frames_on(
    sheet: &Arc<Sheet>,
    scene: &Scene,
    config: &ScanConfig,
    reference: usize,
) -> Result<SceneFrames, ImagingError> {
    let mut sim = et_sim::frontend::SimFrontend::new(Arc::clone(sheet), scene.frontend, scene.seed)
        .map_err(sim_error)?;
    let n = reference.max(1);
    let mut frames = Vec::with_capacity(n);
    for _ in 0..n {
        let frame = sim.fast_frame(config).map_err(sim_error)?;
        frames.push(frame.into_iter().map(f64::from).collect::<Vec<f64>>());
    }
    let k = frames[0].len();
    let v0: Vec<f64> = (0..k)
        .map(|c| frames.iter().map(|f| f[c]).sum::<f64>() / n as f64)
        .collect();
    let var = crate::recon::dv_variance(&frames);
    let touches: Vec<Touch> = scene.touches.iter().map(TouchEvent::touch).collect();
    sim.set_touches(&touches).map_err(sim_error)?;
    Ok(SceneFrames {
        v0,
        v1: sim.fast_frame(config).map_err(sim_error)?,
        var,
        truth: touches.iter().map(|t| (t.position, t.radius)).collect(),
    })
}
