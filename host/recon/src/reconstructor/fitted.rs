//! The background a Reconstructor images about: fitted to the reference frame, or the
//! sheet's given values, and how far a reference is from the model's frame of it.

use crate::background::BackgroundFit;
use crate::imager::Imager;

use super::{ImagingError, Reconstructor, mismatch_and_weights};

impl Reconstructor {
    /// The background fitted to the reference frame `v0` (K values, V; [`crate::background`]):
    /// the sheet resistance and contact with which this mesh's model reproduces it best, then
    /// the forward model, Jacobian and matrix made again about it (the mesh kept).
    ///
    /// # Errors
    /// [`crate::background::BackgroundError`] for a reference of the wrong length, NaN, all
    /// zero, or running against the model; as [`super::Spec::set_up`] for the new model.
    pub fn fit_background(&mut self, v0: &[f64]) -> Result<BackgroundFit, ImagingError> {
        let mesh = self.imager.forward.mesh();
        let mut fit = crate::background::fit(&self.sheet, mesh, &self.schedule, v0)?;
        let sheet = fit.apply(&self.sheet);
        self.imager = Imager::new(&sheet, mesh.clone(), self.pixels)?;
        self.sheet = sheet;
        self.jac = self.imager.transfer_jacobian(&self.schedule)?;
        self.redundancy = std::sync::OnceLock::new();
        let (mismatch, weights) =
            mismatch_and_weights(self.schedule.rows(), v0, &self.jac.frame, self.weighting);
        fit.misfit_on_drive = mismatch.on_drive;
        fit.misfit_off_drive = mismatch.off_drive;
        fit.worst_electrode = self.electrode_misfit(v0);
        self.mismatch = Some(mismatch.shares);
        self.weights = weights;
        self.prepare()?;
        Ok(fit)
    }

    /// Whether the background was fitted to measured frames
    /// ([`Reconstructor::fit_background`]); if not, the sheet's given resistances are imaged
    /// about.
    #[must_use]
    pub fn background_fitted(&self) -> bool {
        self.mismatch.is_some()
    }

    /// How many times the model's frame of the untouched sheet the untouched frame `v0` (K
    /// values, V) is: the least-squares s of v0 = s V_m, V_m the frame at the background.
    /// About 1 when the sheet's resistances are the frames' (a fitted background, or frames
    /// simulated from the same values); frames s times the model's come from a sheet of s
    /// times its resistance (or s times its current), and the images' values (Delta sigma /
    /// sigma_0, the peaks, z) come out about s times theirs until the background is fitted.
    /// None when the model's frame is zero.
    #[must_use]
    pub fn scale_of(&self, v0: &[f64]) -> Option<f64> {
        let model = &self.jac.frame;
        let zero = model.iter().all(|m| *m == 0.0);
        (!zero).then(|| crate::background::best_scale(model, v0).0)
    }
}
