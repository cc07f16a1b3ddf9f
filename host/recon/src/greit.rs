//! GREIT, the consensus linear reconstruction of 2D EIT (Adler et al., "GREIT: a unified
//! approach to 2D linear EIT reconstruction of lung images", Physiol. Meas. 30 (2009) S35),
//! beside one-step Gauss-Newton (docs/method.md §6.6).
//!
//! GREIT asks for the one matrix R (pixels x K) that maps the data of small targets anywhere
//! on the sheet closest to their *desired images*, under noise: it minimises the expected
//! error E |D x - R (J x + n)|^2 over targets x with covariance Sigma_x and noise n with
//! covariance Sigma_n, whose solution is
//!
//! ```text
//! R = D Sigma_x J^T (J Sigma_x J^T + lambda Sigma_n)^-1.
//! ```
//!
//! Here (the "distribution" form of the consensus method, with every triangle a target):
//!
//! - Sigma_x = diag(area of each triangle): the sheet's conductivity changes independently per
//!   unit area, so the mesh's grading towards the electrodes does not weight them more;
//! - D (pixels x T) is the desired image: the change of each triangle blurred over a disc of
//!   radius r (an anti-aliased disc, one pixel of ramp, its integral the triangle's area), so
//!   the desired image of a touch is the touch's conductivity change blurred by r, in the same
//!   units as a Gauss-Newton image (S per square) and centred on it;
//! - Sigma_n = I (the front end's noise is the same on every channel, the ADC's);
//! - lambda is set by the *noise figure* NF = SNR_in / SNR_out of a target at the centre of
//!   area (the consensus choice is NF = 0.5), or given as alpha (lambda = alpha^2 tr(A) / K,
//!   as [`crate::onestep`]).
//!
//! R = D R_x with R_x = Sigma_x J^T (J Sigma_x J^T + lambda I)^-1, the one-step solution with
//! the prior Sigma_x^-1 ([`crate::onestep::DataSpace`], factored over the transfer
//! impedances): GREIT is that solution's image blurred into the desired one, with its own
//! prior and its own rule for lambda. The rule is solved over A = J Sigma_x J^T = U diag(e)
//! U^T (from the r x r problem): with E = D Sigma_x J^T U (pixels x q), each lambda tried
//! costs pixels x q.

use faer::Mat;

use crate::fem::TransferJacobian;
use crate::imager::Imager;
use crate::onestep::{DataSpace, OneStep, ReconError, map_columns, product};
use crate::operator::FrameOperator;
use crate::pixels::PixelGrid;

/// The area of each of `imager`'s triangles, m^2 (GREIT's prior S_x), once `jac` is checked
/// to be of the same mesh.
fn triangle_areas(imager: &Imager, jac: &TransferJacobian) -> Result<Vec<f64>, ReconError> {
    let mesh = imager.forward.mesh();
    let t_n = mesh.triangles.len();
    if jac.g.ncols() != t_n {
        return Err(ReconError::Size {
            what: "the Jacobian's triangles",
            got: jac.g.ncols(),
            expected: t_n,
        });
    }
    Ok((0..t_n).map(|t| 0.5 * mesh.double_area(t)).collect())
}

/// The consensus noise figure (Adler et al. 2009).
pub const NOISE_FIGURE: f64 = 0.5;

/// The desired image's radius as a share of the sheet's longer side (GREIT's targets are 5 %
/// of the medium's diameter; a fingertip, 7.5 mm, is 6 % of a 13 cm sheet).
pub const RADIUS_SHARE: f64 = 0.05;

/// How GREIT's lambda is set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Regularisation {
    /// lambda such that a target at the centre of area has this noise figure
    /// (SNR_in / SNR_out; larger: sharper, noisier images).
    NoiseFigure(f64),
    /// lambda = alpha^2 tr(A) / K, as one-step Gauss-Newton's alpha.
    Alpha(f64),
}

/// GREIT's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GreitOptions {
    /// The desired image's radius, m; None: [`RADIUS_SHARE`] of the sheet's longer side.
    pub radius: Option<f64>,
    /// How lambda is set.
    pub regularisation: Regularisation,
}

impl Default for GreitOptions {
    /// The consensus noise figure 0.5, radius 5 % of the sheet.
    fn default() -> Self {
        Self {
            radius: None,
            regularisation: Regularisation::NoiseFigure(NOISE_FIGURE),
        }
    }
}

/// GREIT's reconstruction matrix for one (mesh, protocol, options), onto the pixels inside
/// the sheet, kept factored as D R_x with R_x = Sigma_x J^T (A + lambda I)^-1 (a
/// [`OneStep`] whose "triangles" are the pixels).
#[derive(Clone, Debug)]
pub struct Greit {
    /// The grid's pixel indices inside the sheet (R's rows), and the grid's length.
    inside: Vec<usize>,
    grid_len: usize,
    /// R, factored.
    recon: OneStep,
    /// R as a frame meets it (f32, packed thin factors).
    operator: FrameOperator,
    /// The desired image's radius, m (at least one pixel).
    pub radius: f64,
    /// lambda, V^2 per (S/sq)^2.
    pub lambda: f64,
    /// alpha = sqrt(lambda K / tr(A)) (as one-step Gauss-Newton's).
    pub alpha: f64,
    /// The noise figure of R (a target of the radius at the centre of area).
    pub noise_figure: f64,
}

impl Greit {
    /// GREIT for the factored Jacobian `jac` of `imager`'s mesh (at its background) onto
    /// `imager`'s pixel grid.
    ///
    /// # Errors
    /// [`ReconError::OutOfRange`] (or [`ReconError::RadiusTooLarge`]) for a radius not finite and > 0, a noise figure or alpha not
    /// finite and > 0, or a Jacobian of another mesh; [`ReconError::Singular`] when the data
    /// space has no eigendecomposition or cannot be factorised.
    pub fn new(
        imager: &Imager,
        jac: &TransferJacobian,
        options: &GreitOptions,
    ) -> Result<Self, ReconError> {
        let area = triangle_areas(imager, jac)?;
        let grid = &imager.grid;
        let extent = grid.size * grid.width.max(grid.height) as f64;
        let radius = options.radius.unwrap_or(RADIUS_SHARE * extent);
        if !(radius.is_finite() && radius > 0.0) {
            return Err(ReconError::OutOfRange {
                name: "a desired image's radius (m)",
                value: radius,
                range: "finite and > 0",
            });
        }
        if radius > 0.5 * extent {
            return Err(ReconError::RadiusTooLarge {
                radius,
                across: extent,
            });
        }
        let radius = radius.max(grid.size);
        match options.regularisation {
            Regularisation::NoiseFigure(v) | Regularisation::Alpha(v)
                if !(v.is_finite() && v > 0.0) =>
            {
                let (name, value) = match options.regularisation {
                    Regularisation::NoiseFigure(v) => ("GREIT's noise figure", v),
                    Regularisation::Alpha(v) => ("GREIT's alpha", v),
                };
                return Err(ReconError::OutOfRange {
                    name,
                    value,
                    range: "finite and > 0",
                });
            }
            _ => {}
        }
        let space = DataSpace::factored_with_prior(jac, &area)?;
        let (inside, d) = desired(grid, imager, radius);
        // Z^T = (D Sigma_x G^T)^T, r x pixels: R = Z M^T (A + lambda I)^-1.
        let zt = map_columns(space.gp(), &d);
        let h = centre_target(imager, jac, radius);
        let scale = space.lambda_scale();
        let lambda = match options.regularisation {
            Regularisation::Alpha(alpha) => alpha * alpha * scale,
            Regularisation::NoiseFigure(nf) => {
                // Over A's spectrum: E = Z M^T U (pixels x q), c = U^T h.
                let (e, u) = space.eigenpairs()?;
                let q = e.len();
                let mut mtu = Mat::<f64>::zeros(zt.nrows(), q);
                for j in 0..q {
                    let col: Vec<f64> = u.col(j).iter().copied().collect();
                    for (i, v) in space.m_transpose(&col).into_iter().enumerate() {
                        mtu[(i, j)] = v;
                    }
                }
                let e_mat = product(zt.transpose(), mtu.as_ref());
                let c: Vec<f64> = (0..q)
                    .map(|j| u.col(j).iter().zip(&h).map(|(a, b)| a * b).sum())
                    .collect();
                let snr_in = h.iter().map(|v| v * v).sum::<f64>() / h.len().max(1) as f64;
                let figure = |lambda: f64| snr_in / snr_out(&e_mat, &e, &c, lambda);
                solve_noise_figure(&figure, nf, scale)
            }
        };
        let alpha = (lambda / scale).sqrt();
        let recon = space.at_lambda(lambda, alpha)?.with_columns(zt);
        // The noise figure of the matrix made (by its definition, on R itself).
        let measured = noise_figure(
            &h,
            &recon.reconstruct(&h)?,
            &recon.noise_sd(&vec![1.0; h.len()])?,
        );
        Ok(Self {
            operator: FrameOperator::of(&recon),
            inside,
            grid_len: grid.triangle.len(),
            recon,
            radius,
            lambda,
            alpha,
            noise_figure: measured,
        })
    }

    /// alpha for GREIT chosen by the frame rather than by the noise figure: generalised
    /// cross-validation on GREIT's own data space (the area prior), never fitting `dv` closer
    /// than its noise `var_dv` ([`DataSpace::choose_alpha`] over
    /// [`crate::default_alphas`]). Pass it as [`Regularisation::Alpha`]. The noise figure
    /// holds one lambda for every frame; a touch where the protocol sees little (the centre,
    /// for adjacent drive) then may not stand above its noise, where a frame-chosen lambda
    /// smooths more and finds it (docs/measurements.md, "GREIT").
    ///
    /// # Errors
    /// As [`DataSpace::choose_alpha`]; [`ReconError::Size`] for a Jacobian of another
    /// mesh.
    pub fn choose_alpha(
        imager: &Imager,
        jac: &TransferJacobian,
        dv: &[f64],
        var_dv: &[f64],
    ) -> Result<f64, ReconError> {
        DataSpace::factored_with_prior(jac, &triangle_areas(imager, jac)?)?.choose_alpha(
            dv,
            var_dv,
            &crate::default_alphas(),
        )
    }

    /// K, the frame length.
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.recon.frame_len()
    }

    /// R (pixels inside the sheet x K, in [`PixelGrid::project`]'s order) as the
    /// [`FrameOperator`] a live frame is imaged with.
    #[must_use]
    pub fn projection(&self) -> FrameOperator {
        self.operator.clone()
    }

    /// The image of the frame difference `dv` (K values, V) on the grid, S per square (None
    /// outside the sheet).
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for a wrong length, [`ReconError::NonFinite`] for NaN/inf.
    pub fn image(&self, dv: &[f64]) -> Result<Vec<Option<f64>>, ReconError> {
        let inside: Vec<f64> = self
            .operator
            .image(dv)?
            .into_iter()
            .map(f64::from)
            .collect();
        Ok(self.spread(&inside))
    }

    /// The standard deviation of each pixel's value when dV carries independent noise of
    /// variance `var_dv` per channel (V^2), on the grid (None outside), as
    /// [`OneStep::noise_sd`].
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for a wrong length.
    pub fn noise_sd(&self, var_dv: &[f64]) -> Result<Vec<Option<f64>>, ReconError> {
        Ok(self.spread(&self.recon.noise_sd(var_dv)?))
    }

    fn spread(&self, inside: &[f64]) -> Vec<Option<f64>> {
        let mut out = vec![None; self.grid_len];
        for (&p, &v) in self.inside.iter().zip(inside) {
            out[p] = Some(v);
        }
        out
    }
}

/// The noise figure NF = SNR_in / SNR_out of a linear reconstruction (the consensus
/// definition, as EIDORS' `calc_noise_figure`, with white noise of one variance on every
/// channel): SNR_in = mean_k h_k^2, SNR_out = sum_p img_p^2 / sum_p sd_p^2, for the target's
/// data `h` ([`centre_target`]), its image `image` (per pixel of equal area, or the
/// reconstruction's own values) and each value's noise `sd` under unit-variance noise.
#[must_use]
pub fn noise_figure(h: &[f64], image: &[f64], sd: &[f64]) -> f64 {
    let snr_in = h.iter().map(|v| v * v).sum::<f64>() / h.len().max(1) as f64;
    let snr_out = image.iter().map(|v| v * v).sum::<f64>() / sd.iter().map(|v| v * v).sum::<f64>();
    snr_in / snr_out
}

/// The noise figure's target data h = J x (K values, V): x = 1 S per square on the triangles
/// within `radius` (m) of the sheet's centre of area (the nearest triangle if none).
#[must_use]
pub fn centre_target(imager: &Imager, jac: &TransferJacobian, radius: f64) -> Vec<f64> {
    let mesh = imager.forward.mesh();
    let t_n = mesh.triangles.len();
    let area: Vec<f64> = (0..t_n).map(|t| 0.5 * mesh.double_area(t)).collect();
    let total: f64 = area.iter().sum();
    let centre = (0..t_n).fold([0.0; 2], |c, t| {
        let m = mesh.centroid(t);
        [c[0] + m[0] * area[t] / total, c[1] + m[1] * area[t] / total]
    });
    let dist = |t: usize| {
        let m = mesh.centroid(t);
        (m[0] - centre[0]).hypot(m[1] - centre[1])
    };
    let mut picked: Vec<usize> = (0..t_n).filter(|&t| dist(t) <= radius).collect();
    if picked.is_empty() {
        picked.extend((0..t_n).min_by(|&a, &b| dist(a).total_cmp(&dist(b))));
    }
    linear_data(jac, &picked)
}

/// J x for x = 1 S per square on the triangles `picked`, 0 elsewhere: M (G x), K values.
fn linear_data(jac: &TransferJacobian, picked: &[usize]) -> Vec<f64> {
    let gx: Vec<f64> = (0..jac.g.nrows())
        .map(|p| picked.iter().map(|&t| jac.g[(p, t)]).sum())
        .collect();
    jac.combination
        .iter()
        .map(|row| row.iter().map(|&(p, c)| c * gx[p]).sum())
        .collect()
}

/// GREIT's figures of merit over a grid of targets, summarised (docs/method.md §6.6).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeritSummary {
    /// Targets imaged.
    pub targets: usize,
    /// Amplitude response: mean, and its coefficient of variation (sd / mean; GREIT wants it
    /// small: a touch's strength should not depend on where it is).
    pub amplitude_mean: f64,
    /// Amplitude response's sd / mean.
    pub amplitude_cv: f64,
    /// Position error, mean and sd over the targets, m.
    pub position_error_mean: f64,
    /// Position error's sd, m.
    pub position_error_sd: f64,
    /// Resolution, mean (sqrt of the quarter set's share of the sheet; smaller is sharper).
    pub resolution_mean: f64,
    /// Resolution's sd / mean.
    pub resolution_cv: f64,
    /// Shape deformation, mean.
    pub shape_deformation_mean: f64,
    /// Ringing, mean.
    pub ringing_mean: f64,
}

/// A linear reconstruction as [`figures_of_merit`] takes it: the frame difference (K values,
/// V) to an image on the grid (None outside the sheet).
pub type ImageOf<'a> = dyn Fn(&[f64]) -> Result<Vec<Option<f64>>, ReconError> + 'a;

/// One target's centre (m) and the figures of merit of its image.
pub type TargetMerit = ([f64; 2], crate::metrics::Merit);

/// Images `n` x `n` targets over the sheet (disc targets of radius `target_radius`, m, whose
/// disc lies inside the sheet: the triangles whose centroid is within the radius, contrast 1
/// S per square, data J x from the linearised model) with `image_of` (the frame difference
/// to an image on `imager`'s grid) and summarises their figures of merit
/// ([`crate::metrics::merit`]). Also returns each target's centre and merit.
///
/// # Errors
/// What `image_of` returns; [`ReconError::OutOfRange`] when no target fits on the sheet.
pub fn figures_of_merit(
    imager: &Imager,
    jac: &TransferJacobian,
    n: usize,
    target_radius: f64,
    image_of: &ImageOf<'_>,
) -> Result<(MeritSummary, Vec<TargetMerit>), ReconError> {
    let mesh = imager.forward.mesh();
    let grid = &imager.grid;
    let (w, h) = (
        grid.width as f64 * grid.size,
        grid.height as f64 * grid.size,
    );
    let on_sheet = |x: [f64; 2]| {
        let i = ((x[0] - grid.origin[0]) / grid.size).floor();
        let j = ((x[1] - grid.origin[1]) / grid.size).floor();
        i >= 0.0
            && j >= 0.0
            && (i as usize) < grid.width
            && (j as usize) < grid.height
            && grid.triangle[j as usize * grid.width + i as usize].is_some()
    };
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let centre = [
                grid.origin[0] + (i as f64 + 0.5) * w / n as f64,
                grid.origin[1] + (j as f64 + 0.5) * h / n as f64,
            ];
            let fits = (0..16).all(|a| {
                let phi = a as f64 * std::f64::consts::TAU / 16.0;
                on_sheet([
                    centre[0] + 1.5 * target_radius * phi.cos(),
                    centre[1] + 1.5 * target_radius * phi.sin(),
                ])
            }) && on_sheet(centre);
            if !fits {
                continue;
            }
            let picked: Vec<usize> = (0..mesh.triangles.len())
                .filter(|&t| {
                    let c = mesh.centroid(t);
                    (c[0] - centre[0]).hypot(c[1] - centre[1]) <= target_radius
                })
                .collect();
            if picked.is_empty() {
                continue;
            }
            let area: f64 = picked.iter().map(|&t| 0.5 * mesh.double_area(t)).sum();
            let dv = linear_data(jac, &picked);
            let image = image_of(&dv)?;
            if let Some(m) = crate::metrics::merit(grid, &image, centre, 1.0, area) {
                out.push((centre, m));
            }
        }
    }
    if out.is_empty() {
        return Err(ReconError::OutOfRange {
            name: "the targets' radius (m)",
            value: target_radius,
            range: "small enough for a target to fit on the sheet",
        });
    }
    let stats = |f: fn(&crate::metrics::Merit) -> f64| {
        let n = out.len() as f64;
        let mean = out.iter().map(|(_, m)| f(m)).sum::<f64>() / n;
        let var = out.iter().map(|(_, m)| (f(m) - mean).powi(2)).sum::<f64>() / n;
        (mean, var.sqrt())
    };
    let (a, a_sd) = stats(|m| m.amplitude);
    let (pe, pe_sd) = stats(|m| m.position_error);
    let (res, res_sd) = stats(|m| m.resolution);
    Ok((
        MeritSummary {
            targets: out.len(),
            amplitude_mean: a,
            amplitude_cv: a_sd / a.abs().max(f64::MIN_POSITIVE),
            position_error_mean: pe,
            position_error_sd: pe_sd,
            resolution_mean: res,
            resolution_cv: res_sd / res.max(f64::MIN_POSITIVE),
            shape_deformation_mean: stats(|m| m.shape_deformation).0,
            ringing_mean: stats(|m| m.ringing).0,
        },
        out,
    ))
}

/// The pixels inside the sheet (as [`PixelGrid::project`]) and D's rows for them:
/// (triangle, weight) with weight = area_t ramp(d) / sum over the whole pixel lattice of
/// ramp(d) h^2, where ramp is 1 within r - h/2 and 0 beyond r + h/2 (d: pixel centre to the
/// triangle's centroid, h: the pixel's size). Each triangle's desired image integrates to its
/// area, less what falls off the sheet.
#[must_use]
pub fn desired(
    grid: &PixelGrid,
    imager: &Imager,
    radius: f64,
) -> (Vec<usize>, Vec<Vec<(usize, f64)>>) {
    let mesh = imager.forward.mesh();
    let inside: Vec<usize> = (0..grid.triangle.len())
        .filter(|&p| grid.triangle[p].is_some())
        .collect();
    let mut row_of = vec![usize::MAX; grid.triangle.len()];
    for (row, &p) in inside.iter().enumerate() {
        row_of[p] = row;
    }
    let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); inside.len()];
    let h = grid.size;
    let reach = radius + 0.5 * h;
    let mut near: Vec<(usize, f64)> = Vec::new();
    for t in 0..mesh.triangles.len() {
        let c = mesh.centroid(t);
        let area = 0.5 * mesh.double_area(t);
        // Lattice indices (unbounded) of the pixel centres within reach.
        let lo = |d: usize| ((c[d] - reach - grid.origin[d]) / h - 0.5).ceil() as i64;
        let hi = |d: usize| ((c[d] + reach - grid.origin[d]) / h - 0.5).floor() as i64;
        let (mut norm, mut kept) = (0.0, 0usize);
        near.clear();
        for j in lo(1)..=hi(1) {
            for i in lo(0)..=hi(0) {
                let x = grid.origin[0] + (i as f64 + 0.5) * h;
                let y = grid.origin[1] + (j as f64 + 0.5) * h;
                let ramp = ((radius - (x - c[0]).hypot(y - c[1])) / h + 0.5).clamp(0.0, 1.0);
                norm += ramp * h * h;
                let on_grid =
                    i >= 0 && j >= 0 && (i as usize) < grid.width && (j as usize) < grid.height;
                if ramp > 0.0 && on_grid {
                    let p = j as usize * grid.width + i as usize;
                    if row_of[p] != usize::MAX {
                        near.push((row_of[p], ramp));
                        kept += 1;
                    }
                }
            }
        }
        if kept > 0 && norm > 0.0 {
            for &(row, ramp) in &near {
                rows[row].push((t, area * ramp / norm));
            }
        }
    }
    (inside, rows)
}

/// SNR_out(lambda) = sum_p img_p^2 / sum_p sd_p^2 (the consensus definition, as EIDORS'
/// `calc_noise_figure`: powers, pixels of equal area) for the target's c = U^T h under white
/// unit noise: img = E diag(1 / (e + lambda)) c, sd_p^2 = sum_j E_pj^2 / (e_j + lambda)^2.
/// (A's directions below 1e-12 of its largest eigenvalue are left out here; the matrix made
/// keeps them, and its noise figure is measured on it.)
fn snr_out(e_mat: &Mat<f64>, e: &[f64], c: &[f64], lambda: f64) -> f64 {
    let w: Vec<f64> = e.iter().map(|v| 1.0 / (v.max(0.0) + lambda)).collect();
    let (mut signal, mut noise) = (0.0, 0.0);
    for p in 0..e_mat.nrows() {
        let (mut img, mut var) = (0.0, 0.0);
        for j in 0..w.len() {
            let v = e_mat[(p, j)] * w[j];
            img += v * c[j];
            var += v * v;
        }
        signal += img * img;
        noise += var;
    }
    signal / noise
}

/// lambda with noise figure `target`: bisection in log lambda over alpha 1e-5 to 1e3 (lambda
/// = alpha^2 `scale`); the noise figure falls as lambda grows, so a target outside the range
/// gets the nearer end.
fn solve_noise_figure(figure: &dyn Fn(f64) -> f64, target: f64, scale: f64) -> f64 {
    let (mut lo, mut hi) = ((1e-10 * scale).ln(), (1e6 * scale).ln());
    if figure(hi.exp()) >= target {
        return hi.exp();
    }
    if figure(lo.exp()) <= target {
        return lo.exp();
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if figure(mid.exp()) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)).exp()
}
