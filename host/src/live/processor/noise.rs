//! The untouched reference's noise: V_0, each channel's variance of dV, and each pixel's
//! noise through the projection.

use super::*;

/// V_0, the noise of dV per channel, and each pixel's noise through the projection built
/// with (method, alpha) and its electrodes left out.
#[derive(Clone, Debug)]
pub(super) struct Noise {
    pub(super) method: Method,
    pub(super) alpha: f64,
    /// The electrodes left out of the projection it was made through.
    left_out: Vec<u16>,
    /// V_0, the configuration's K values, V (the classifier's whole frame).
    pub(super) v0: Vec<f64>,
    /// The variance of each value imaged (those the electrodes left out do not involve), V^2.
    pub(super) var_dv: Vec<f64>,
    /// 1 / each pixel's noise (0 where the noise is 0), for the frames' z-scores.
    pub(super) inverse_sd: Vec<f32>,
    /// A reference of one frame carries no noise: `var_dv` is then 0 and `inverse_sd` is for
    /// a variance of 1 V^2 on every channel, and each frame's noise is estimated from its own
    /// dV ([`Noise::of_frame`]), as `et reconstruct` images such frames.
    pub(super) per_frame: bool,
}

impl Noise {
    /// The noise in `slot` if it was made for `(method, alpha)` through a projection leaving
    /// out `projection`'s electrodes, else one made from the
    /// reference `frames` (each K values, V) through `projection` and put there, their V_0
    /// checked against `recon`'s model of the untouched sheet as a reconstruction's reference
    /// is (negated or unsigned frames imaged every touch in the wrong place).
    pub(super) fn current<'n>(
        slot: &'n mut Option<Noise>,
        frames: &[Vec<f32>],
        (recon, projection): (&Reconstructor, &Projection),
        (method, alpha): (Method, f64),
    ) -> Result<&'n Noise, LiveError> {
        let at = &projection.at;
        if let Some(kept) = slot
            .take()
            .filter(|n| n.method == method && n.alpha == alpha && n.left_out == at.left_out)
        {
            return Ok(slot.insert(kept));
        }
        // V_0 and the channel variances of an untouched frame's dV.
        let k = frames.first().map_or(0, Vec::len);
        let (mut v0, mut var_dv) = (vec![0.0; k], vec![0.0; k]);
        stats::reference(frames, &mut v0)?;
        recon.runs_with_the_model(&at.keep(&v0))?;
        stats::dv_variance(frames, &mut var_dv)?;
        let var_dv = at.keep(&var_dv);
        let per_frame = frames.len() < 2;
        // The image's own noise level, E|P n|^2 = sum_p sum_k P_pk^2 var_k: the image filters
        // the noise the data carry, so a touch stands out better here than in |dV|.
        let pixel_sd = if per_frame {
            projection.matrix.noise_sd(&vec![1.0; var_dv.len()])?
        } else {
            projection.matrix.noise_sd(&var_dv)?
        };
        let inverse_sd = pixel_sd
            .iter()
            .map(|&sd| if sd > 0.0 { (1.0 / sd) as f32 } else { 0.0 })
            .collect();
        Ok(slot.insert(Noise {
            method,
            alpha,
            left_out: at.left_out.clone(),
            v0,
            var_dv,
            inverse_sd,
            per_frame,
        }))
    }

    /// For a reference of one frame ([`Noise::per_frame`]): this noise with each channel's
    /// variance estimated from the frame's own dV (the part no conductivity change can make,
    /// [`Reconstructor::redundancy_noise`]); None for a reference of two or more frames,
    /// whose noise is measured.
    ///
    /// # Errors
    /// [`LiveError::UnknownNoise`] when the protocol has too little redundancy to tell noise
    /// from a change.
    pub(super) fn of_frame(
        &self,
        (recon, at): (&Reconstructor, &At),
        frame: &LiveFrame,
    ) -> Result<Option<Noise>, LiveError> {
        if !self.per_frame {
            return Ok(None);
        }
        let dv = self.dv(at, &frame.voltages);
        let variance = recon
            .redundancy_noise(&dv)
            .map(|n| n.variance)
            .ok_or(LiveError::UnknownNoise { seq: frame.seq })?;
        // A frame equal to V_0 has no noise to see and nothing to image: no touch.
        let scale = if variance > 0.0 {
            (1.0 / variance.sqrt()) as f32
        } else {
            0.0
        };
        Ok(Some(Noise {
            method: self.method,
            alpha: self.alpha,
            left_out: self.left_out.clone(),
            v0: self.v0.clone(),
            var_dv: vec![variance; dv.len()],
            inverse_sd: self.inverse_sd.iter().map(|i| i * scale).collect(),
            per_frame: false,
        }))
    }

    /// A frame's change from V_0 (`voltages`: its K values, V), of the values `at` images.
    pub(super) fn dv(&self, at: &At, voltages: &[f32]) -> Vec<f64> {
        let dv: Vec<f64> = (voltages.iter().zip(&self.v0))
            .map(|(a, b)| f64::from(*a) - b)
            .collect();
        match &at.kept {
            Some(_) => at.keep(&dv),
            None => dv,
        }
    }
}
