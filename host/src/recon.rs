//! Difference imaging by one-step linearised Gauss-Newton (SPEC §6) and the image metrics of
//! SPEC §7.
//!
//! With J the Jacobian at the background sigma_0 (K x T, [`crate::fem::Forward::jacobian`]) and
//! the NOSER prior P = diag(J^T J)^s [3.9], the Tikhonov solution [3.8]
//!
//! ```text
//! d_sigma = (J^T J + lambda P)^-1 J^T dV = P^-1 J^T (J P^-1 J^T + lambda I)^-1 dV
//! ```
//!
//! is computed in its data-space form on the right (P is diagonal, so only a K x K system is
//! factorised). **Normalisation of alpha:** lambda = alpha^2 tr(J P^-1 J^T) / K, so alpha is
//! dimensionless and means the same for any mesh, current or protocol (alpha = 1: the
//! regularisation is as large as the average data-space eigenvalue). The reconstruction matrix
//! R (T x K) is built once; each frame then costs one matrix-vector product, onto the mesh or
//! (cheaper) onto a pixel grid ([`PixelGrid`]).

use nalgebra::{DMatrix, DVector};

use crate::mesh::Mesh;

/// Why a reconstruction could not be set up or run.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ReconError {
    /// A parameter out of range (alpha not finite or <= 0, s outside [0, 1], wrong lengths).
    Parameter(String),
    /// The data-space system is not positive definite (a Jacobian with NaN, or all zero).
    Singular,
    /// A frame holds NaN or infinite values.
    NonFinite,
}

impl std::fmt::Display for ReconError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReconError::Parameter(why) => write!(f, "reconstruction: {why}"),
            ReconError::Singular => write!(f, "reconstruction: the regularised system is singular"),
            ReconError::NonFinite => write!(f, "reconstruction: a frame value is NaN or infinite"),
        }
    }
}

impl std::error::Error for ReconError {}

/// The one-step Gauss-Newton reconstruction matrix of one (mesh, protocol, alpha, s).
#[derive(Clone, Debug)]
pub struct OneStep {
    /// T x K: d_sigma = R dV.
    pub matrix: DMatrix<f64>,
    /// The alpha it was built with.
    pub alpha: f64,
    /// The NOSER exponent s.
    pub s: f64,
}

impl OneStep {
    /// Builds R from the Jacobian `jac` (K x T).
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for alpha not in (0, inf) or s not in [0, 1];
    /// [`ReconError::Singular`] when the system cannot be factorised.
    pub fn new(jac: &DMatrix<f64>, alpha: f64, s: f64) -> Result<Self, ReconError> {
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(ReconError::Parameter(format!(
                "alpha = {alpha}: must be finite and > 0"
            )));
        }
        if !(0.0..=1.0).contains(&s) {
            return Err(ReconError::Parameter(format!("s = {s}: must be in [0, 1]")));
        }
        if jac.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        let (jp, a) = data_space(jac, s)?;
        let chol = regularised(a, alpha)?;
        // R = P^-1 J^T (A + lambda I)^-1 = ((A + lambda I)^-1 J P^-1)^T.
        let x = chol.solve(&jp);
        let matrix = x.transpose();
        if matrix.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        Ok(Self { matrix, alpha, s })
    }

    /// d_sigma on the mesh's triangles for the frame difference `dv` = V_1 - V_0 (K values).
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for a wrong length, [`ReconError::NonFinite`] for NaN/inf.
    pub fn reconstruct(&self, dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        if dv.len() != self.matrix.ncols() {
            return Err(ReconError::Parameter(format!(
                "{} values, the protocol has K = {}",
                dv.len(),
                self.matrix.ncols()
            )));
        }
        if dv.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite);
        }
        Ok((&self.matrix * DVector::from_column_slice(dv))
            .as_slice()
            .to_vec())
    }

    /// The standard deviation of each triangle's value when dV carries independent noise of
    /// variance `var_dv` per channel (V^2): sqrt(sum_k R_tk^2 var_k). Same units as an image.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for a wrong length.
    pub fn noise_sd(&self, var_dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        if var_dv.len() != self.matrix.ncols() {
            return Err(ReconError::Parameter(format!(
                "{} variances, the protocol has K = {}",
                var_dv.len(),
                self.matrix.ncols()
            )));
        }
        Ok(self
            .matrix
            .row_iter()
            .map(|row| {
                row.iter()
                    .zip(var_dv)
                    .map(|(r, v)| r * r * v.max(0.0))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect())
    }
}

/// Iterative Gauss-Newton for when accuracy matters more than speed. Minimises
/// |r(sigma)|^2 + lambda |sigma - sigma_0|^2_P, P = diag(J^T J)^s at each iterate, with the
/// residual r = dV - (F(sigma) - F(sigma_0)) for difference data (`dv` = V_1 - V_0: model
/// errors common to both frames cancel) or r = V - F(sigma) for absolute data
/// ([`Data::Absolute`]). Each step, in data-space form with d = sigma - sigma_0:
/// sigma += P^-1 J^T (J P^-1 J^T + lambda I)^-1 (r + J d) - d, the conductivity kept above
/// 1e-3 sigma_0. Returns the iterates' conductivities (per triangle) and residual norms.
///
/// # Errors
/// [`ReconError`] for bad parameters, or a failed forward solve.
pub fn gauss_newton(
    forward: &crate::fem::Forward,
    protocol: &et_core::protocol::Protocol,
    amps: f64,
    sigma_0: &[f64],
    data: Data<'_>,
    options: GaussNewton,
) -> Result<Vec<(Vec<f64>, f64)>, ReconError> {
    let GaussNewton {
        alpha,
        s,
        iterations,
    } = options;
    if !(alpha.is_finite() && alpha > 0.0 && (0.0..=1.0).contains(&s)) {
        return Err(ReconError::Parameter(format!(
            "alpha = {alpha} (> 0), s = {s} (in [0, 1])"
        )));
    }
    let fem = |e: crate::fem::FemError| ReconError::Parameter(e.to_string());
    // One factorisation per iterate: the Jacobian solve also gives the frame.
    let (v0, jac0) = forward.jacobian(sigma_0, protocol, amps).map_err(fem)?;
    let target: Vec<f64> = match data {
        Data::Difference(dv) => dv.iter().zip(&v0).map(|(d, v)| d + v).collect(),
        Data::Absolute(v) => v.to_vec(),
    };
    if target.len() != v0.len() {
        return Err(ReconError::Parameter(format!(
            "{} values, K = {}",
            target.len(),
            v0.len()
        )));
    }
    if target.iter().any(|v| !v.is_finite()) {
        return Err(ReconError::NonFinite);
    }
    // For difference data the model is F(sigma) - F(sigma_0) + V_0(measured); the
    // target above already is V_0(model) + dV, so both cases compare F(sigma) with target.
    let mut sigma = sigma_0.to_vec();
    let mut out = Vec::with_capacity(iterations);
    let (mut v, mut jac) = (v0, jac0);
    for it in 0..iterations {
        let r: Vec<f64> = target.iter().zip(&v).map(|(t, v)| t - v).collect();
        let d: Vec<f64> = sigma.iter().zip(sigma_0).map(|(a, b)| a - b).collect();
        let (jp, a) = data_space(&jac, s)?;
        let rhs = DVector::from_vec(r) + &jac * DVector::from_column_slice(&d);
        let y = regularised(a, alpha)?.solve(&rhs);
        let step = jp.transpose() * y;
        for (i, sg) in sigma.iter_mut().enumerate() {
            *sg = (sigma_0[i] + step[i]).max(1e-3 * sigma_0[i]);
        }
        // The next step needs the Jacobian here; the last one only the frame.
        if it + 1 < iterations {
            (v, jac) = forward.jacobian(&sigma, protocol, amps).map_err(fem)?;
        } else {
            v = forward.frame(&sigma, protocol, amps).map_err(fem)?;
        }
        let norm = target
            .iter()
            .zip(&v)
            .map(|(t, v)| (t - v).powi(2))
            .sum::<f64>()
            .sqrt();
        out.push((sigma.clone(), norm));
    }
    Ok(out)
}

/// Settings of [`gauss_newton`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussNewton {
    /// Regularisation, normalised as [`OneStep`]'s.
    pub alpha: f64,
    /// NOSER exponent in [0, 1].
    pub s: f64,
    /// Iterations.
    pub iterations: usize,
}

/// The data an iterative reconstruction fits.
#[derive(Clone, Copy, Debug)]
pub enum Data<'a> {
    /// V_1 - V_0 (difference imaging).
    Difference(&'a [f64]),
    /// V (absolute imaging: the model must match the hardware's absolute voltages).
    Absolute(&'a [f64]),
}

/// J P^-1 (K x T) and A = J P^-1 J^T (K x K) for the NOSER prior of exponent `s`.
fn data_space(jac: &DMatrix<f64>, s: f64) -> Result<(DMatrix<f64>, DMatrix<f64>), ReconError> {
    let p_inv = noser_inverse(jac, s).ok_or(ReconError::Singular)?;
    let jp = DMatrix::from_fn(jac.nrows(), jac.ncols(), |r, c| jac[(r, c)] * p_inv[c]);
    let a = &jp * jac.transpose();
    Ok((jp, a))
}

/// The Cholesky factor of A + lambda I, lambda = alpha^2 tr(A) / K (the module's
/// normalisation).
fn regularised(
    mut a: DMatrix<f64>,
    alpha: f64,
) -> Result<nalgebra::Cholesky<f64, nalgebra::Dyn>, ReconError> {
    let k = a.nrows();
    let lambda = alpha * alpha * a.trace() / k as f64;
    for i in 0..k {
        a[(i, i)] += lambda;
    }
    a.cholesky().ok_or(ReconError::Singular)
}

/// The NOSER weights P^-1 = diag(J^T J)^-s (a column that sees nothing gets the smallest
/// positive weight's), or None when every column is zero.
fn noser_inverse(jac: &DMatrix<f64>, s: f64) -> Option<Vec<f64>> {
    let diag: Vec<f64> = (0..jac.ncols())
        .map(|c| jac.column(c).norm_squared())
        .collect();
    let floor = diag
        .iter()
        .copied()
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    floor
        .is_finite()
        .then(|| diag.iter().map(|d| d.max(floor).powf(-s)).collect())
}

/// Generalised cross-validation of alpha for the frame difference `dv`: with A = J P^-1 J^T
/// = U diag(e) U^T and c = U^T dv, GCV(lambda) = K sum_i (lambda c_i / (e_i + lambda))^2 /
/// (sum_i lambda / (e_i + lambda))^2, lambda = alpha^2 tr(A) / K (this module's
/// normalisation). Returns the candidate with the smallest GCV and every (alpha, GCV).
///
/// # Errors
/// [`ReconError`] for bad parameters, a zero Jacobian or a non-finite frame.
pub fn gcv_alpha(
    jac: &DMatrix<f64>,
    s: f64,
    dv: &[f64],
    candidates: &[f64],
) -> Result<(f64, Vec<(f64, f64)>), ReconError> {
    if !(0.0..=1.0).contains(&s) || dv.len() != jac.nrows() || candidates.is_empty() {
        return Err(ReconError::Parameter(
            "s in [0, 1], K frame values, candidates".into(),
        ));
    }
    if dv.iter().any(|v| !v.is_finite()) {
        return Err(ReconError::NonFinite);
    }
    let (_, a) = data_space(jac, s)?;
    let k = a.nrows() as f64;
    let trace = a.trace();
    let eig = a.symmetric_eigen();
    let c = eig.eigenvectors.transpose() * DVector::from_column_slice(dv);
    let scores: Vec<(f64, f64)> = candidates
        .iter()
        .map(|&alpha| {
            let lambda = alpha * alpha * trace / k;
            let (mut num, mut den) = (0.0, 0.0);
            for (e, ci) in eig.eigenvalues.iter().zip(c.iter()) {
                let w = lambda / (e.max(0.0) + lambda);
                num += (w * ci).powi(2);
                den += w;
            }
            (alpha, k * num / (den * den).max(f64::MIN_POSITIVE))
        })
        .collect();
    let best = scores
        .iter()
        .copied()
        .filter(|s| s.1.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .ok_or(ReconError::Singular)?;
    Ok((best.0, scores))
}

/// A pixel grid over a mesh: which triangle each pixel centre lies in.
#[derive(Clone, Debug)]
pub struct PixelGrid {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// Lower-left corner and pixel size, m: pixel (i, j) (column i, row j from the bottom)
    /// is centred at (x0 + (i + 1/2) size, y0 + (j + 1/2) size).
    pub origin: [f64; 2],
    /// Pixel size, m.
    pub size: f64,
    /// Triangle under each pixel (row-major from the bottom row), None outside the sheet.
    pub triangle: Vec<Option<usize>>,
}

impl PixelGrid {
    /// A grid `pixels` across the mesh's longer side.
    #[must_use]
    pub fn new(mesh: &Mesh, pixels: usize) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &mesh.nodes {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]) / pixels.max(1) as f64;
        let width = ((hi[0] - lo[0]) / size).round().max(1.0) as usize;
        let height = ((hi[1] - lo[1]) / size).round().max(1.0) as usize;
        let mut triangle = vec![None; width * height];
        // Each triangle claims the pixel centres inside it (barycentric test on its box).
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = tri.map(|i| mesh.nodes[i]);
            let bx = |d: usize, f: fn(f64, f64) -> f64| f(f(p[0][d], p[1][d]), p[2][d]);
            let i0 = (((bx(0, f64::min) - lo[0]) / size - 0.5).ceil().max(0.0)) as usize;
            let i1 = (((bx(0, f64::max) - lo[0]) / size - 0.5).floor().max(-1.0) + 1.0) as usize;
            let j0 = (((bx(1, f64::min) - lo[1]) / size - 0.5).ceil().max(0.0)) as usize;
            let j1 = (((bx(1, f64::max) - lo[1]) / size - 0.5).floor().max(-1.0) + 1.0) as usize;
            let area2 = mesh.double_area(t);
            for j in j0..j1.min(height) {
                for i in i0..i1.min(width) {
                    let c = [
                        lo[0] + (i as f64 + 0.5) * size,
                        lo[1] + (j as f64 + 0.5) * size,
                    ];
                    let w = |a: [f64; 2], b: [f64; 2]| {
                        ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])) / area2
                    };
                    let eps = -1e-12;
                    if w(p[0], p[1]) >= eps && w(p[1], p[2]) >= eps && w(p[2], p[0]) >= eps {
                        triangle[j * width + i].get_or_insert(t);
                    }
                }
            }
        }
        Self {
            width,
            height,
            origin: lo,
            size,
            triangle,
        }
    }

    /// Centre of pixel `index`, m.
    #[must_use]
    pub fn centre(&self, index: usize) -> [f64; 2] {
        let (i, j) = (index % self.width, index / self.width);
        [
            self.origin[0] + (i as f64 + 0.5) * self.size,
            self.origin[1] + (j as f64 + 0.5) * self.size,
        ]
    }

    /// The 4 neighbours of pixel `index` (left, right, below, above; None off the grid).
    #[must_use]
    pub fn neighbours(&self, index: usize) -> [Option<usize>; 4] {
        let (i, j) = (index % self.width, index / self.width);
        [
            (i > 0).then(|| index - 1),
            (i + 1 < self.width).then(|| index + 1),
            (j > 0).then(|| index - self.width),
            (j + 1 < self.height).then(|| index + self.width),
        ]
    }

    /// Mean of the centres of `pixels`, m ([0, 0] for none).
    #[must_use]
    pub fn centroid(&self, pixels: &[usize]) -> [f64; 2] {
        let n = pixels.len().max(1) as f64;
        pixels.iter().fold([0.0; 2], |c, &p| {
            let x = self.centre(p);
            [c[0] + x[0] / n, c[1] + x[1] / n]
        })
    }

    /// The reconstruction matrix onto the pixels (one row per pixel inside the sheet, in
    /// pixel order): a live frame then costs pixels x K multiply-adds.
    #[must_use]
    pub fn project(&self, r: &OneStep) -> DMatrix<f32> {
        let inside: Vec<usize> = self.triangle.iter().filter_map(|t| *t).collect();
        DMatrix::from_fn(inside.len(), r.matrix.ncols(), |p, k| {
            r.matrix[(inside[p], k)] as f32
        })
    }

    /// Spreads per-triangle values onto the grid (None outside the sheet).
    #[must_use]
    pub fn image(&self, per_triangle: &[f64]) -> Vec<Option<f64>> {
        self.triangle
            .iter()
            .map(|t| t.map(|t| per_triangle[t]))
            .collect()
    }
}

/// The largest value of an image when it is positive and finite.
fn positive_max(image: &[Option<f64>]) -> Option<f64> {
    let max = image
        .iter()
        .flatten()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    (max.is_finite() && max > 0.0).then_some(max)
}

/// The ROI threshold f of SPEC §6 [3.10] the reference study used for a protocol: 0.10 for
/// adjacent (and opposite, which it did not report), 0.08 for pseudo-polar, 0.05 for PP-PP.
#[must_use]
pub fn default_threshold(kind: et_core::protocol::ProtocolKind) -> f64 {
    use et_core::protocol::ProtocolKind;
    match kind {
        ProtocolKind::PseudoPolar => 0.08,
        ProtocolKind::PpPp => 0.05,
        _ => 0.10,
    }
}

/// One connected region of an image above threshold.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Region {
    /// Centroid of its pixels, m.
    pub centroid: [f64; 2],
    /// Area, m^2.
    pub area: f64,
    /// Largest value in it.
    pub peak: f64,
    /// The pixel (index into the image) where it peaks.
    pub peak_pixel: usize,
    /// Its largest value over its pixel's noise, where [`touches`] was given the noise.
    pub z: Option<f64>,
}

impl Region {
    /// The mesh refinement this region asks for: a disc of its area, widened as
    /// [`Refinement::touch`] widens a touch (to re-mesh where an image found something).
    ///
    /// [`Refinement::touch`]: crate::mesh::Refinement::touch
    #[must_use]
    pub fn refinement(&self) -> crate::mesh::Refinement {
        crate::mesh::Refinement::touch(self.centroid, (self.area / std::f64::consts::PI).sqrt())
    }
}

/// The regions of interest (SPEC §6 [3.10]): pixels >= f max(image) (for a touch, which
/// raises the conductivity), grouped into 4-connected regions, largest peak first.
#[must_use]
pub fn regions(grid: &PixelGrid, image: &[Option<f64>], f: f64) -> Vec<Region> {
    let Some(max) = positive_max(image) else {
        return Vec::new();
    };
    let keep: Vec<bool> = image
        .iter()
        .map(|v| v.is_some_and(|v| v >= f * max))
        .collect();
    let mut seen = vec![false; keep.len()];
    let mut out = Vec::new();
    for start in 0..keep.len() {
        if !keep[start] || seen[start] {
            continue;
        }
        let (mut stack, mut members) = (vec![start], Vec::new());
        seen[start] = true;
        while let Some(p) = stack.pop() {
            members.push(p);
            for q in grid.neighbours(p).into_iter().flatten() {
                if keep[q] && !seen[q] {
                    seen[q] = true;
                    stack.push(q);
                }
            }
        }
        let (peak_pixel, peak) = members.iter().filter_map(|&m| Some((m, image[m]?))).fold(
            (start, f64::NEG_INFINITY),
            |a, b| if b.1 > a.1 { b } else { a },
        );
        out.push(Region {
            centroid: grid.centroid(&members),
            area: members.len() as f64 * grid.size * grid.size,
            peak,
            peak_pixel,
            z: None,
        });
    }
    out.sort_by(|a, b| b.peak.total_cmp(&a.peak));
    out
}

/// How deep the dip below the lower of two peaks must be, as a share of the image's
/// largest value, for [`touches`] to keep them apart.
pub const PROMINENCE: f64 = 0.25;

/// The touches in an image: the regions of interest of [`regions`] (pixels >= f max, SPEC
/// §6 [3.10]), each split at its saddles into one region per peak that stands out.
///
/// A threshold alone answers SPEC §8's "several ROIs" only when the image dips below it
/// between the touches; under noise the alpha that suits the data often joins two touches
/// over a saddle far above f max. Here the pixels are flooded from the top (a watershed):
/// when two rising regions meet at a pixel of value v, the lower one (peak h) stays a touch
/// of its own when its prominence h - v is at least `prominence` x max(image), else it joins
/// the higher one (so ripples and noise on a touch's flank stay part of it). Later pixels
/// join their highest-peaked neighbouring region. Each touch's area is its share of the
/// region of interest; its centroid is that of its pixels at or above half its peak, so the
/// flank it shares with a neighbour does not pull it over. With `sd`, the standard deviation
/// of each pixel's noise ([`OneStep::noise_sd`] on the grid; empty when unknown), each touch
/// also gets its largest value over noise, `z`, for [`above_noise`]. Largest peak first.
#[must_use]
pub fn touches(
    grid: &PixelGrid,
    image: &[Option<f64>],
    sd: &[Option<f64>],
    f: f64,
    prominence: f64,
) -> Vec<Region> {
    let Some(max) = positive_max(image) else {
        return Vec::new();
    };
    let mut order: Vec<(usize, f64)> = image
        .iter()
        .enumerate()
        .filter_map(|(p, v)| v.filter(|&v| v >= f * max).map(|v| (p, v)))
        .collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1));
    // Union-find over pixels; a root's peak is its region's highest value.
    let mut parent: Vec<usize> = (0..image.len()).collect();
    let mut peak = vec![f64::NAN; image.len()];
    let mut flooded = vec![false; image.len()];
    fn root(parent: &mut [usize], mut p: usize) -> usize {
        while parent[p] != p {
            parent[p] = parent[parent[p]];
            p = parent[p];
        }
        p
    }
    // Pairs of regions already found to be separate touches (by root).
    let mut apart: Vec<(usize, usize)> = Vec::new();
    for &(p, v) in &order {
        let mut near: Vec<usize> = Vec::with_capacity(4);
        for q in grid.neighbours(p).into_iter().flatten() {
            if flooded[q] {
                let r = root(&mut parent, q);
                if !near.contains(&r) {
                    near.push(r);
                }
            }
        }
        flooded[p] = true;
        near.sort_by(|&a, &b| peak[b].total_cmp(&peak[a]));
        let Some(&top) = near.first() else {
            peak[p] = v;
            continue;
        };
        parent[p] = top;
        for &r in &near[1..] {
            let separate = apart
                .iter()
                .any(|&(a, b)| (a, b) == (r, top) || (a, b) == (top, r))
                || peak[r] - v >= prominence * max;
            if separate {
                if !apart.contains(&(r, top)) {
                    apart.push((r, top));
                }
            } else {
                parent[r] = top;
                // What was apart from r is now apart from top.
                for pair in &mut apart {
                    for end in [&mut pair.0, &mut pair.1] {
                        if *end == r {
                            *end = top;
                        }
                    }
                }
            }
        }
    }
    // Each region's pixels, by root (a noisy image has many small regions).
    let mut slot = vec![usize::MAX; image.len()];
    let mut members: Vec<(usize, Vec<usize>)> = Vec::new();
    for &(p, _) in &order {
        let r = root(&mut parent, p);
        if slot[r] == usize::MAX {
            slot[r] = members.len();
            members.push((r, Vec::new()));
        }
        members[slot[r]].1.push(p);
    }
    let mut out: Vec<Region> = members
        .into_iter()
        .map(|(r, m)| {
            let core: Vec<usize> = m
                .iter()
                .copied()
                .filter(|&q| image[q].is_some_and(|v| v >= 0.5 * peak[r]))
                .collect();
            Region {
                centroid: grid.centroid(&core),
                area: m.len() as f64 * grid.size * grid.size,
                peak: peak[r],
                peak_pixel: r,
                z: m.iter()
                    .filter_map(|&q| {
                        let sd = sd.get(q).copied().flatten().filter(|&sd| sd > 0.0)?;
                        Some(image[q]? / sd)
                    })
                    .reduce(f64::max),
            }
        })
        .collect();
    out.sort_by(|a, b| b.peak.total_cmp(&a.peak));
    out
}

/// A touch stands out of the noise when its peak is at least this many times the noise of
/// its pixel (see [`above_noise`]; noise alone stays below about 3.5 on the simulator).
pub const TOUCH_Z: f64 = 5.0;

/// The regions that reach at least `z` times their pixels' noise somewhere (their `z`, from
/// [`touches`]); a region whose noise is unknown is kept.
#[must_use]
pub fn above_noise(regions: &[Region], z: f64) -> Vec<Region> {
    regions
        .iter()
        .filter(|r| r.z.is_none_or(|v| v >= z))
        .cloned()
        .collect()
}

/// Variance of each channel of dV = V_1 - V_0 when V_0 is the mean of `frames` (untouched,
/// V) and V_1 one more frame: the sample variance x (1 + 1/n). Zero with fewer than two.
#[must_use]
pub fn dv_variance(frames: &[Vec<f64>]) -> Vec<f64> {
    let n = frames.len();
    let k = frames.first().map_or(0, Vec::len);
    if n < 2 {
        return vec![0.0; k];
    }
    let nf = n as f64;
    (0..k)
        .map(|c| {
            let mean = frames.iter().map(|f| f[c]).sum::<f64>() / nf;
            let ss: f64 = frames.iter().map(|f| (f[c] - mean).powi(2)).sum();
            ss / (nf - 1.0) * (1.0 + 1.0 / nf)
        })
        .collect()
}

/// SPEC §7's metrics of one image against the truth.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// BVC = |V_1 - V_0|, V.
    pub bvc: f64,
    /// PE = |r_real - r_detected| / sheet size (largest extent).
    pub pe: f64,
    /// SE = |detected size - real size| / sheet area.
    pub se: f64,
    /// RNG = area of opposite-sign ringing / (sheet area - detected size).
    pub rng: f64,
}

/// Metrics of `image` for a single object of area `object_area` (m^2) centred at `truth`,
/// with ROI threshold `f`.
#[must_use]
pub fn metrics(
    grid: &PixelGrid,
    image: &[Option<f64>],
    f: f64,
    dv: &[f64],
    truth: [f64; 2],
    object_area: f64,
) -> Metrics {
    let bvc = dv.iter().map(|v| v * v).sum::<f64>().sqrt();
    let pixel = grid.size * grid.size;
    let sheet_area = image.iter().flatten().count() as f64 * pixel;
    let extent = grid.width.max(grid.height) as f64 * grid.size;
    let rois = regions(grid, image, f);
    let detected: f64 = rois.iter().map(|r| r.area).sum();
    let pe = rois.first().map_or(1.0, |r| {
        (r.centroid[0] - truth[0]).hypot(r.centroid[1] - truth[1]) / extent
    });
    let max = image.iter().flatten().copied().fold(0.0f64, f64::max);
    let ringing = image.iter().flatten().filter(|&&v| v <= -f * max).count() as f64 * pixel;
    Metrics {
        bvc,
        pe,
        se: (detected - object_area).abs() / sheet_area,
        rng: if sheet_area > detected {
            ringing / (sheet_area - detected)
        } else {
            0.0
        },
    }
}

#[cfg(test)]
mod tests;
