//! Many frames against the reference set at once, over every core: each frame's pixels and,
//! when asked, its objects (with the noise of the pixels they stand on, made for those
//! pixels alone).

use super::{FrameNoise, ImagingError, Reconstructor};
use crate::onestep::ReconError;
use crate::pixels::PixelGrid;
use crate::reconstructor::spec::Method;
use crate::reconstructor::stream::FramePixels;
use crate::touches::{
    OBJECT_FRACTION, Object, PixelNoise, Region, TOUCH_Z, objects_with, touch_rule,
};

/// One frame of [`Reconstructor::image_frames`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrameObjects {
    /// Its pixels, dV and alpha.
    pub pixels: FramePixels,
    /// Its noise, as [`super::Image::noise`].
    pub noise: FrameNoise,
    /// Its objects, strongest first ([`Reconstructor::objects`]), and its touches (as
    /// [`super::Image::touches`]), when asked for.
    pub found: Option<Found>,
}

/// A frame's objects and touches ([`Reconstructor::image_frames`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    /// Objects of either sign, strongest first ([`Reconstructor::objects`]).
    pub objects: Vec<Object>,
    /// The touches ([`crate::touch_rule`] at [`TOUCH_Z`]).
    pub touches: Vec<Region>,
}

/// A frame made ready for its matrix: dV, alpha and (for its objects) the channels'
/// variances as the images see them.
struct Ready {
    dv: Vec<f64>,
    alpha: f64,
    var: Vec<f64>,
    noise: FrameNoise,
}

impl Reconstructor {
    /// `frames` (each K values, V) against the reference set ([`Reconstructor::set_reference`]),
    /// as [`Reconstructor::frame_pixels`] images each, and each frame's objects when `objects`
    /// (as [`Reconstructor::objects`] finds them in the whole image, each object's pixels'
    /// noise made for them alone). One-step Gauss-Newton runs over every core: each frame's
    /// dV and alpha, then the frames of each alpha through its matrix (made once, its f32
    /// operator onto the pixels when two frames or more share it). GREIT and the iterative
    /// fit image each frame whole, in turn.
    ///
    /// # Errors
    /// [`ImagingError::Frame`] naming the first frame that fails (a wrong length, NaN) and
    /// why; [`ImagingError::NoReference`] when none was set.
    pub fn image_frames(
        &mut self,
        frames: &[&[f32]],
        objects: bool,
    ) -> Result<Vec<FrameObjects>, ImagingError> {
        let in_frame = |index: usize| {
            move |e: ImagingError| ImagingError::Frame {
                index,
                source: Box::new(e),
            }
        };
        let Method::GaussNewton {
            iterations: 0 | 1, ..
        } = self.method
        else {
            return (frames.iter().enumerate())
                .map(|(i, f)| {
                    let image = self.image_frame(f).map_err(in_frame(i))?;
                    let found = objects.then(|| Found {
                        objects: self.objects(&image),
                        touches: image.touches.clone(),
                    });
                    Ok(FrameObjects {
                        pixels: FramePixels {
                            dv: image.dv,
                            alpha: image.alpha,
                            pixels: image.pixels,
                        },
                        noise: image.noise,
                        found,
                    })
                })
                .collect();
        };
        let reference = self.reference.as_ref().ok_or(ImagingError::NoReference)?;
        // Each frame's dV, alpha and variances (the alpha rules read a data space shared by
        // every thread).
        let this = &*self;
        let ready: Vec<Result<Ready, ImagingError>> = on_every_core(frames, |f| {
            let dv = this.difference(f, reference)?;
            let (var_dv, noise) = this.frame_noise(&dv, &reference.var_dv);
            let var = this.imaging_variance(&var_dv, &dv);
            let alpha = this.gauss_newton_alpha(&dv, &var_dv, &var)?;
            Ok(Ready {
                dv,
                alpha,
                var,
                noise,
            })
        });
        let ready = (ready.into_iter().enumerate())
            .map(|(i, r)| r.map_err(in_frame(i)))
            .collect::<Result<Vec<Ready>, _>>()?;
        // The alphas chosen, in the order first met; each one's frames through its matrix.
        let mut alphas: Vec<f64> = Vec::new();
        for r in &ready {
            if !alphas.contains(&r.alpha) {
                alphas.push(r.alpha);
            }
        }
        let f = self.threshold();
        let mut out: Vec<Option<FrameObjects>> = vec![None; ready.len()];
        for alpha in alphas {
            let group: Vec<(usize, &Ready)> = (ready.iter().enumerate())
                .filter(|(_, r)| r.alpha == alpha)
                .collect();
            self.matrix_at(alpha)?;
            let grid = &self.imager.grid;
            let matrix = self.one_step.as_mut().ok_or(ReconError::Singular)?;
            matrix.frames += group.len();
            let through_operator = matrix.frames > 1;
            let matrix = &*matrix;
            let imaged = on_every_core(&group, |&(i, r)| {
                let (pixels, found) = if through_operator {
                    let operator = matrix.pixel_operator(grid);
                    let pixels = operator.image(&r.dv)?;
                    let found = objects.then(|| found(grid, &pixels, f, operator.noise(&r.var)));
                    (pixels, found)
                } else {
                    let pixels = grid.image(&matrix.recon.reconstruct(&r.dv)?);
                    let found = match objects {
                        true => {
                            let sd = grid.noise_sd(&matrix.recon, &r.var)?;
                            let sd = |p: usize| sd.get(p).copied().flatten();
                            Some(found(grid, &pixels, f, sd))
                        }
                        false => None,
                    };
                    (pixels, found)
                };
                Ok::<_, ImagingError>((i, pixels, found))
            });
            for (k, result) in imaged.into_iter().enumerate() {
                let (i, pixels, found) = result.map_err(in_frame(group[k].0))?;
                out[i] = Some(FrameObjects {
                    pixels: FramePixels {
                        dv: ready[i].dv.clone(),
                        alpha,
                        pixels,
                    },
                    noise: ready[i].noise,
                    found,
                });
            }
        }
        Ok(out.into_iter().flatten().collect())
    }
}

/// The objects and touches of `pixels` (the image's values, S per square) with threshold
/// `f`, each pixel's noise from `sd`.
fn found(grid: &PixelGrid, pixels: &[Option<f64>], f: f64, mut sd: impl PixelNoise) -> Found {
    Found {
        objects: objects_with(grid, pixels, |p| sd.sd(p), OBJECT_FRACTION, TOUCH_Z),
        touches: touch_rule(grid, pixels, f, TOUCH_Z, |p| sd.sd(p)),
    }
}

/// `f` of each item, the items shared out in equal runs over the machine's cores, in order.
fn on_every_core<T: Sync, U: Send>(items: &[T], f: impl Fn(&T) -> U + Sync) -> Vec<U> {
    if items.len() <= 1 {
        return items.iter().map(f).collect();
    }
    // Asked once: the answer reads the control group's files each time.
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    let cores = *CORES
        .get_or_init(|| std::thread::available_parallelism().map_or(1, std::num::NonZero::get));
    let threads = cores.min(items.len());
    if threads <= 1 {
        return items.iter().map(f).collect();
    }
    let run = items.len().div_ceil(threads);
    let f = &f;
    std::thread::scope(|scope| {
        let handles: Vec<_> = items
            .chunks(run)
            .map(|chunk| scope.spawn(move || chunk.iter().map(f).collect::<Vec<U>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}
