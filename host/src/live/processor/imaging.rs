//! One frame imaged: the reconstruction, projection, noise and classifier made current for
//! its configuration, then the frame's pixels, touches and event.

use super::*;

/// What imaging one frame reads, made current for its configuration and settings: the
/// reconstruction, the projection, the reference's noise and the classifier.
pub(super) struct Imaging<'a> {
    pub(super) recon: &'a Reconstructor,
    /// The grid's pixels inside the sheet, in the projection's row order.
    pub(super) inside: &'a [usize],
    /// Each grid pixel's row in the projection (None outside the sheet).
    pub(super) inside_index: &'a [Option<usize>],
    pub(super) touch_factor: f64,
    pub(super) projection: &'a Projection,
    pub(super) noise: &'a Noise,
    pub(super) classifier: Option<&'a Board>,
}

impl Imaging<'_> {
    /// `frame` imaged against the reference, its touches found and, when touched, its event.
    pub(super) fn frame(&self, frame: LiveFrame, threshold: f64) -> Result<Output, LiveError> {
        let Noise {
            var_dv, inverse_sd, ..
        } = self.noise;
        let dv = self.noise.dv(&self.projection.at, &frame.voltages);
        let values = self.projection.matrix.image(&dv)?;
        // The strongest pixel in units of its own noise (a touch raises the conductivity).
        let intensity = f64::from(
            values
                .iter()
                .zip(inverse_sd)
                .map(|(v, inverse)| v * inverse)
                .fold(0.0f32, f32::max),
        );
        let mut image = vec![None; self.recon.grid().triangle.len()];
        for (&p, v) in self.inside.iter().zip(values.iter()) {
            image[p] = Some(f64::from(*v));
        }
        let regions = if intensity > self.touch_factor {
            self.touches(&image, &values, &dv, threshold)
        } else {
            Vec::new()
        };
        let touches = et_recon::select::significant(
            &regions,
            &et_recon::select::Settings::new([0.0, 0.0], 1.0),
        );
        let event =
            (!regions.is_empty()).then(|| self.event(&frame, &regions, touches.len(), intensity));
        let volts: Vec<f64> = frame.voltages.iter().map(|v| f64::from(*v)).collect();
        let electrode_off = (self.recon)
            .electrode_misfit(&self.projection.at.keep(&volts))
            .filter(ElectrodeMisfit::stands_out);
        Ok(Output {
            referencing: None,
            image,
            regions,
            touches,
            bvc: stats::bvc_dv(&dv),
            noise: var_dv.iter().sum::<f64>().sqrt(),
            event,
            threshold,
            electrode_off,
            frame,
        })
    }

    /// The touches by `et reconstruct`'s rule (et_recon::touches::touch_rule) in a frame's
    /// `image` (grid pixels; `values` its inside pixels, `dv` its K changes, V): regions split
    /// at their saddles, each reaching the touch factor times its pixels' noise somewhere, that
    /// noise what the Reconstructor's images carry (the frames' and the model's own error, a
    /// share of dV) made for the regions' pixels alone. Called for a frame whose strongest
    /// pixel reaches the factor over the reference's noise alone, which is smaller: one that
    /// does not has no touch, and no region is searched.
    pub(super) fn touches(
        &self,
        image: &[Option<f64>],
        values: &[f32],
        dv: &[f64],
        threshold: f64,
    ) -> Vec<Region> {
        let var: Vec<f32> = self
            .recon
            .imaging_variance(&self.noise.var_dv, dv)
            .iter()
            .map(|&v| v as f32)
            .collect();
        touch_rule(
            self.recon.grid(),
            image,
            threshold,
            self.touch_factor,
            RegionNoise {
                imaging: self,
                values,
                var: &var,
            },
        )
    }

    /// A touched frame's event: the classifier's class, position and posterior when there is
    /// one, else the board's class and the strongest region's centroid.
    pub(super) fn event(
        &self,
        frame: &LiveFrame,
        regions: &[Region],
        touches: usize,
        intensity: f64,
    ) -> TouchEvent {
        let model = self
            .classifier
            .and_then(|c| c.classify(&frame.config, &frame.voltages, &self.noise.v0));
        let chip = frame.chip_class.map(|c| c.class);
        let image_position = regions.first().map_or([f64::NAN; 2], |r| {
            [r.centroid[0] * 1e3, r.centroid[1] * 1e3]
        });
        TouchEvent {
            t_us: frame.t_us,
            seq: frame.seq,
            class: chip.or(model.map(|m| m.class)),
            position_mm: model.map_or(image_position, |m| [m.centre[0] * 1e3, m.centre[1] * 1e3]),
            intensity,
            confidence: model.map(|m| m.posterior),
            regions: touches,
        }
    }
}

/// A touched frame's pixel noise for the touch rule: the reference's alone (its floor, held
/// per pixel), and the images' own (the frames' and the model's error, a dot product over
/// the channels) made only for pixels the rule asks.
struct RegionNoise<'a, 'b> {
    imaging: &'a Imaging<'b>,
    /// The frame's inside pixels.
    values: &'a [f32],
    /// Each channel's variance, V^2 (K values).
    var: &'a [f32],
}

impl RegionNoise<'_, '_> {
    /// Pixel p's row and its reference noise's inverse.
    fn inverse(&self, p: usize) -> Option<(usize, f32)> {
        let i = (*self.imaging.inside_index.get(p)?)?;
        Some((i, *self.imaging.noise.inverse_sd.get(i)?))
    }
}

impl et_recon::PixelNoise for RegionNoise<'_, '_> {
    fn sd(&mut self, p: usize) -> Option<f64> {
        let (i, inverse) = self.inverse(p)?;
        // A pixel below the factor over the reference's noise alone is below it over the
        // larger noise too: its noise need not be made (the reference's, which it is given,
        // keeps it below the factor; a region's z is its largest pixel's).
        let factor = self.imaging.touch_factor as f32;
        if self.values.get(i).is_some_and(|v| v * inverse < factor) && inverse > 0.0 {
            return Some(f64::from(1.0 / inverse));
        }
        self.imaging.projection.squares.sd(i, self.var)
    }

    fn floor(&mut self, p: usize) -> Option<f64> {
        // The reference's noise, less a thousandth: it and the images' own noise are summed
        // in other precisions (f64 at set-up, f32 here), so it stays below it when the
        // model's error adds almost nothing.
        let (_, inverse) = self.inverse(p)?;
        (inverse > 0.0).then(|| 0.999 * f64::from(1.0 / inverse))
    }
}
