//! One sheet's imaging set-up, shared by every caller: the forward model about the
//! background conductivity and the pixel grid images are drawn on.

use et_core::schedule::Schedule;
use et_core::sheet::Sheet;
use nalgebra::DMatrix;

use crate::fem::{Electrodes, FemError, Forward};
use crate::mesh::Mesh;
use crate::pixels::PixelGrid;

/// The forward model of one sheet about its background conductivity, and the pixel grid
/// images are drawn on. One `Imager` serves every protocol (a Jacobian per protocol).
pub struct Imager {
    /// Finite elements with the sheet's electrode model (docs/method.md §5).
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

/// The most pixels across an image: 512 x 512 cells, whose live projection (cells x K in
/// f32) stays under half a gigabyte for every protocol on 16 electrodes.
pub const MAX_PIXELS: usize = 512;

impl Imager {
    /// The forward model of `sheet` on `mesh` with the sheet's electrode model
    /// ([`Electrodes::of_sheet`]: complete with z = contact resistance x electrode width,
    /// ohm m, point or shunt), a grid `pixels` across.
    ///
    /// # Errors
    /// [`FemError::Pixels`] for `pixels` outside 4 to [`MAX_PIXELS`]; [`FemError`] if the
    /// forward model cannot be built.
    pub fn new(sheet: &Sheet, mesh: Mesh, pixels: usize) -> Result<Self, FemError> {
        if !(4..=MAX_PIXELS).contains(&pixels) {
            return Err(FemError::Pixels {
                pixels,
                max: MAX_PIXELS,
            });
        }
        let grid = PixelGrid::new(&mesh, pixels);
        Ok(Self {
            forward: Forward::new(mesh, Electrodes::of_sheet(sheet)?)?,
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

    /// The Jacobian of `schedule`'s frame at the background in factored form (J = M G over
    /// the transfer impedances, [`crate::fem::TransferJacobian`]): what
    /// [`crate::onestep::DataSpace::factored`] takes.
    ///
    /// # Errors
    /// [`FemError`] if the solve fails.
    pub fn transfer_jacobian(
        &self,
        schedule: &Schedule,
    ) -> Result<crate::fem::TransferJacobian, FemError> {
        self.forward.transfer_jacobian(&self.background(), schedule)
    }

    /// The K x T Jacobian of `schedule`'s frame at the background (V per S per square).
    ///
    /// # Errors
    /// [`FemError`] if the solve fails.
    pub fn jacobian(&self, schedule: &Schedule) -> Result<DMatrix<f64>, FemError> {
        Ok(self.forward.jacobian(&self.background(), schedule)?.1)
    }
}
