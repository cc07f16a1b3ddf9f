//! Imaging from Python: [`Reconstructor`] over [`et_recon::Reconstructor`].

use crate::batch::{FRAMES_AT_ONCE, frames_f32, in_run, reference_of, single};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use et_recon::touches::ObjectSummary;
use et_recon::{AlphaRule, MeshPlan, Method, Reference, Spec};

use crate::{array2, json, matrix, refused, slice, usage};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    crate::sheets::register(m)?;
    m.add_class::<Reconstructor>()?;
    m.add(
        "FRAME_SCALE_SAID",
        et_recon::reconstructor::FRAME_SCALE_SAID,
    )?;
    Ok(())
}

/// One frame's image as the Python side receives it: the summary (JSON) and the arrays.
type ImageParts<'py> = (
    String,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Option<Bound<'py, PyArray1<f64>>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// A frame's pixels alone: the pixels (rows x cols), dV (K) and the alpha.
type PixelParts<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>, f64);

/// A batch's pixels alone: the pixels (n * rows * cols), dV (n x K) and the alphas (n).
type BatchParts<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// One frame's objects and touches (`objects_batch`), as `image`'s summary names them.
#[derive(serde::Serialize)]
struct FoundSummary {
    objects: Vec<ObjectSummary>,
    touches: Vec<ObjectSummary>,
}

/// What `image` reports besides the arrays (the `et reconstruct --json` names).
#[derive(serde::Serialize)]
struct ImageSummary<'a> {
    alpha: f64,
    threshold: f64,
    noise: et_recon::FrameNoise,
    noise_figure: Option<f64>,
    radius_m: Option<f64>,
    objects: Vec<ObjectSummary>,
    touches: Vec<ObjectSummary>,
    regions: Vec<ObjectSummary>,
    iterations: Option<usize>,
    timings_s: &'a Timings,
}

/// What a frame took, s.
#[derive(serde::Serialize)]
struct Timings {
    matrix: Option<f64>,
    frame: f64,
}

/// A reconstruction set up once for a sheet, a protocol, a mesh and a method, that images
/// every frame against a reference ([`et_recon::Reconstructor`]).
#[pyclass(module = "et_touch._native")]
pub(crate) struct Reconstructor {
    inner: et_recon::Reconstructor,
}

#[pymethods]
impl Reconstructor {
    #[new]
    #[pyo3(signature = (sheet_json, electrodes, protocol, current_a, rows, currents, triangles,
        method, alpha, pixels, threshold, s, iterations, noise_figure, radius_m))]
    fn new(
        py: Python<'_>,
        sheet_json: &str,
        electrodes: u64,
        protocol: Option<&str>,
        current_a: f64,
        rows: Option<PyReadonlyArray2<'_, i64>>,
        currents: Option<PyReadonlyArray1<'_, f64>>,
        triangles: usize,
        method: &str,
        alpha: &str,
        pixels: usize,
        threshold: Option<f64>,
        s: f64,
        iterations: usize,
        noise_figure: Option<f64>,
        radius_m: Option<f64>,
    ) -> PyResult<Self> {
        let sheet = crate::sheets::sheet_of(sheet_json)?;
        let schedule = crate::sheets::schedule(electrodes, protocol, current_a, rows, currents)?;
        let method = match Method::from_name(method) {
            Some(Method::GaussNewton { .. }) => Method::GaussNewton { s, iterations },
            Some(Method::Greit { .. }) => Method::Greit { radius: radius_m },
            None => return Err(usage(format!("method '{method}': gn or greit"))),
        };
        let noise_figure = noise_figure.unwrap_or(et_recon::greit::NOISE_FIGURE);
        let alpha = AlphaRule::from_text(alpha, &method, noise_figure).map_err(|e| refused(&e))?;
        let spec = Spec {
            mesh: MeshPlan::About {
                triangles,
                refine: Vec::new(),
            },
            method,
            alpha,
            pixels,
            threshold,
            ..Spec::new(sheet, schedule)
        };
        let inner = crate::interruptible(py, move |stop| spec.set_up_until(stop))?
            .map_err(|e| refused(&e))?;
        Ok(Self { inner })
    }

    /// Images `frame` (K values, V) against the untouched `reference` frames (n x K, V; their
    /// mean is V_0, their spread the noise of dV), or against those set by `set_reference`
    /// when None: the summary (JSON), the pixels and their
    /// noise (rows from the top, Delta sigma / sigma_0, NaN outside), the values on the
    /// triangles (Delta sigma / sigma_0; None for GREIT), dV and the three-class picture
    /// (0 background, 1 resistive, 2 conductive, NaN outside; [`et_recon::segment`]).
    #[pyo3(signature = (frame, reference=None))]
    fn image<'py>(
        &mut self,
        py: Python<'py>,
        frame: PyReadonlyArray1<'_, f64>,
        reference: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<ImageParts<'py>> {
        // As et's frames are: single precision (the board's, and every reader's).
        let frame = slice(&frame, "v")?;
        let frame = single(frame, frame.len(), "v")?;
        let reference = reference.as_ref().map(reference_of).transpose()?;
        let inner = &mut self.inner;
        let image = py
            .detach(|| match &reference {
                Some(reference) => inner.image(&frame, reference),
                None => inner.image_frame(&frame),
            })
            .map_err(|e| refused(&e))?;
        let (grid, sigma0) = (self.inner.grid(), self.inner.imager().sigma0);
        let found = |regions: &[et_recon::Region]| {
            (regions.iter())
                .map(|r| ObjectSummary::of_region(r, 1, sigma0))
                .collect()
        };
        let objects = self.inner.objects(&image);
        let classes = et_recon::segment::as_values(&et_recon::segment(
            &image.pixels,
            &objects,
            et_recon::SEGMENT_LEVEL,
        ));
        let summary = ImageSummary {
            alpha: image.alpha,
            threshold: image.threshold,
            noise: image.noise,
            noise_figure: image.greit.map(|g| g.0),
            radius_m: image.greit.map(|g| g.1),
            objects: (objects.iter())
                .map(|o| ObjectSummary::of(o, sigma0))
                .collect(),
            touches: found(&image.touches),
            regions: found(&image.regions),
            iterations: image.iterations.as_ref().map(|i| i.completed),
            timings_s: &Timings {
                matrix: image.timings.matrix,
                frame: image.timings.frame,
            },
        };
        let (w, h) = (grid.width, grid.height);
        let pixels = array2(py, grid.top_first(&image.pixels, 1.0 / sigma0), h, w)?;
        let noise = array2(py, grid.top_first(&image.noise_sd, 1.0 / sigma0), h, w)?;
        let classes = array2(py, grid.top_first(&classes, 1.0), h, w)?;
        let mesh_values = image
            .mesh_values
            .as_ref()
            .map(|v| PyArray1::from_vec(py, v.iter().map(|x| x / sigma0).collect()));
        Ok((
            json(&summary)?,
            pixels,
            noise,
            mesh_values,
            PyArray1::from_vec(py, image.dv),
            classes,
        ))
    }

    /// The pixels of `frame` (K values, V) against the reference `set_reference` set, and no
    /// more (rows x cols, Delta sigma / sigma_0, top row first, NaN outside), with dV and the
    /// alpha: what `image` makes first, the rest (noise, objects) when first read.
    fn pixels<'py>(
        &mut self,
        py: Python<'py>,
        frame: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<PixelParts<'py>> {
        let frame = slice(&frame, "v")?;
        let frame = single(frame, frame.len(), "v")?;
        let inner = &mut self.inner;
        let (w, h) = (inner.grid().width, inner.grid().height);
        let sigma0 = inner.imager().sigma0;
        let mut picture = vec![f64::NAN; w * h];
        let (dv, alpha) = py
            .detach(|| inner.frame_picture(&frame, 1.0 / sigma0, &mut picture))
            .map_err(|e| refused(&e))?;
        Ok((
            array2(py, picture, h, w)?,
            PyArray1::from_vec(py, dv),
            alpha,
        ))
    }

    /// The pixels of each of `frames` (n x K, V) against the reference set, as `pixels` does
    /// frame by frame, in one call without the GIL: the pixels stacked (n * rows * cols, top
    /// row first), dV (n * K) and each frame's alpha.
    fn pixels_batch<'py>(
        &mut self,
        py: Python<'py>,
        frames: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<BatchParts<'py>> {
        let (w, h) = (self.inner.grid().width, self.inner.grid().height);
        crate::batch::check_fits(frames.as_array().nrows(), w * h).map_err(usage)?;
        let (frames, n, k) = frames_f32(&frames)?;
        let inner = &mut self.inner;
        let (grid, sigma0) = (inner.grid().clone(), inner.imager().sigma0);
        // The stack in NumPy's own memory: it asks the kernel for huge pages for large
        // arrays, where a Rust Vec's fresh pages cost a fault each 4 kB (8 a 64 x 64 frame,
        // as much as the frame itself at 750 triangles).
        let stack = numpy::PyArray1::<f64>::zeros(py, n * w * h, false);
        let mut dv = Vec::with_capacity(n * k);
        let mut alpha = Vec::with_capacity(n);
        {
            let mut stack = stack.readwrite();
            let pixels = stack.as_slice_mut().map_err(|e| refused(&e))?;
            py.detach(|| {
                let frames: Vec<&[f32]> = frames.iter().map(Vec::as_slice).collect();
                let mut out = pixels.chunks_mut((w * h).max(1));
                // In runs: each run's images are held until copied out; Ctrl-C between.
                for (r, run) in frames.chunks(FRAMES_AT_ONCE).enumerate() {
                    crate::interrupted()?;
                    let imaged =
                        (inner.image_frames(run, false)).map_err(|e| refused(&in_run(e, r)))?;
                    for (m, to) in imaged.into_iter().zip(&mut out) {
                        grid.top_first_onto(&m.pixels.pixels, 1.0 / sigma0, to);
                        dv.extend(m.pixels.dv);
                        alpha.push(m.pixels.alpha);
                    }
                }
                PyResult::Ok(())
            })?;
        }
        Ok((stack, array2(py, dv, n, k)?, PyArray1::from_vec(py, alpha)))
    }

    /// The objects and touches of each of `frames` (n x K, V) against the reference set, as
    /// `image` finds them (each object's pixels' noise made for them alone), over every
    /// core: JSON, a list with one {"objects": [...], "touches": [...]} per frame.
    fn objects_batch(
        &mut self,
        py: Python<'_>,
        frames: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<String> {
        let (frames, _, _) = frames_f32(&frames)?;
        let inner = &mut self.inner;
        let sigma0 = inner.imager().sigma0;
        let imaged = py.detach(|| {
            let frames: Vec<&[f32]> = frames.iter().map(Vec::as_slice).collect();
            let mut imaged = Vec::with_capacity(frames.len());
            for (r, run) in frames.chunks(FRAMES_AT_ONCE).enumerate() {
                crate::interrupted()?;
                // Each frame's objects kept, its pixels dropped.
                let found = (inner.image_frames(run, true))
                    .map_err(|e| refused(&in_run(e, r)))?
                    .into_iter()
                    .map(|m| m.found);
                imaged.extend(found);
            }
            PyResult::Ok(imaged)
        })?;
        let found: Vec<FoundSummary> = imaged
            .iter()
            .map(|found| {
                let found = found.as_ref();
                FoundSummary {
                    objects: (found.map_or(&[][..], |f| &f.objects).iter())
                        .map(|o| ObjectSummary::of(o, sigma0))
                        .collect(),
                    touches: (found.map_or(&[][..], |f| &f.touches).iter())
                        .map(|r| ObjectSummary::of_region(r, 1, sigma0))
                        .collect(),
                }
            })
            .collect();
        json(&found)
    }

    /// Sets the untouched `reference` frames (n x K, V) every later frame is imaged against
    /// when `image` is given none.
    fn set_reference(&mut self, reference: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        let reference = reference_of(&reference)?;
        self.inner.set_reference(reference).map_err(|e| refused(&e))
    }

    /// Whether the background was fitted (`fit_background`).
    #[getter]
    fn background_fitted(&self) -> bool {
        self.inner.background_fitted()
    }

    /// How many times the model's frame of the untouched sheet the mean of the untouched
    /// `reference` frames (n x K, V) is (least squares); None when the model's frame is zero.
    fn scale_of(&self, reference: PyReadonlyArray2<'_, f64>) -> PyResult<Option<f64>> {
        let v0 = reference_of(&reference)?.v0;
        Ok(self.inner.scale_of(&v0))
    }

    /// What is said when the model's frame of the untouched sheet leaves more than
    /// `et_recon::background::POOR_FIT` of the mean of the untouched `reference` frames
    /// (n x K, V) unexplained, at its best scale; None within it.
    fn poor_fit(&self, reference: PyReadonlyArray2<'_, f64>) -> PyResult<Option<String>> {
        let v0 = reference_of(&reference)?.v0;
        Ok(et_recon::background::poor_fit_said(
            self.inner.unexplained(&v0),
        ))
    }

    /// What is said when one electrode's values in the mean of the untouched `reference`
    /// frames (n x K, V) stand out from the model's frame as a detached or broken
    /// electrode's (`et_recon::background::ElectrodeMisfit::stands_out`, numbered from 0);
    /// None otherwise.
    fn electrode_off(&self, reference: PyReadonlyArray2<'_, f64>) -> PyResult<Option<String>> {
        let v0 = reference_of(&reference)?.v0;
        let detached = self.inner.detached_electrodes(&v0);
        Ok(
            et_recon::background::detached_said(&detached, 0).map(|(said, numbers)| {
                let numbers = numbers.replace(',', ", ");
                let whose = if detached.len() == 1 { "its" } else { "their" };
                format!("{said} Protocol.without([{numbers}]) leaves {whose} values out")
            }),
        )
    }

    /// Each of `frames`' (n x K, V) scale to the reference `v0` (K, V): the median of its
    /// values' ratios, `et_recon::Reference::scale_of`, the rule `et reconstruct` warns with;
    /// NaN where there is none (V_0 zero).
    fn frame_scales(
        &self,
        frames: PyReadonlyArray2<'_, f64>,
        v0: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Vec<f64>> {
        let reference = Reference {
            v0: slice(&v0, "v0")?.to_vec(),
            var_dv: Vec::new(),
        };
        let (values, n, k) = matrix(&frames, "V")?;
        Ok((values.chunks(k.max(1)).take(n))
            .map(|f| {
                let f: Vec<f32> = f.iter().map(|&v| v as f32).collect();
                reference.scale_of(&f).unwrap_or(f64::NAN)
            })
            .collect())
    }

    /// What is said when one electrode's values stand out as a detached or broken
    /// electrode's in frames to image (n x K, V, numbered from 0), not in the mean of the
    /// untouched `reference` frames (n x K): a clip that came off during the recording
    /// (`et_recon::Reconstructor::came_off`, as `et reconstruct` says it); None otherwise.
    fn came_off(
        &self,
        frames: PyReadonlyArray2<'_, f64>,
        reference: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Option<String>> {
        let v0 = reference_of(&reference)?.v0;
        let named: Vec<u16> = (self.inner.detached_electrodes(&v0).iter())
            .map(|m| m.electrode)
            .collect();
        let (values, n, k) = matrix(&frames, "V")?;
        let frames: Vec<(usize, Vec<f32>)> = single(values, k, "V")?
            .chunks(k.max(1))
            .take(n)
            .map(<[f32]>::to_vec)
            .enumerate()
            .collect();
        let leave_out = |n| format!("Protocol.without([{n}]) leaves them out");
        Ok(self
            .inner
            .came_off(&frames, &named)
            .map(|off| off.said(0, leave_out)))
    }

    /// What is said when the mean of the untouched `reference` frames (n x K) passes
    /// `et_recon::background::VOLTS_MOST`: frames in another unit than volts; None within.
    fn not_volts(&self, reference: PyReadonlyArray2<'_, f64>) -> PyResult<Option<String>> {
        Ok(et_recon::background::not_volts_said(
            &reference_of(&reference)?.v0,
        ))
    }

    /// What is said when one of the untouched `reference` frames (n x K, V) differs from
    /// their mean as a change of the sheet does, past
    /// `et_recon::background::REFERENCE_CHANGE_SAID`; None within it or for one frame.
    fn reference_changed(&self, reference: PyReadonlyArray2<'_, f64>) -> PyResult<Option<String>> {
        let view = reference.as_array();
        let frames: Vec<Vec<f32>> = (view.rows().into_iter())
            .map(|r| r.iter().map(|&v| v as f32).collect())
            .collect();
        Ok(self.inner.reference_changes(&frames).and_then(|c| {
            et_recon::background::reference_changes_said(
                c,
                Some(|n| format!("the reference's first {n} rows, v0[:{n}]")),
            )
        }))
    }

    /// Fits the background (sheet resistance, contact) to the untouched `reference` frames
    /// (n x K, V) and images about it from then on; the fit as JSON.
    fn fit_background(
        &mut self,
        py: Python<'_>,
        reference: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<String> {
        let v0 = reference_of(&reference)?.v0;
        let inner = &mut self.inner;
        let fit = py
            .detach(|| inner.fit_background(&v0))
            .map_err(|e| refused(&e))?;
        json(&fit)
    }

    /// The frame (K values, V) the finite-element model gives for conductivity `sigma` (one
    /// per triangle, S per square).
    fn forward<'py>(
        &self,
        py: Python<'py>,
        sigma: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let sigma = slice(&sigma, "sigma")?;
        let t = self.inner.imager().triangles();
        if sigma.len() != t {
            return Err(usage(format!(
                "sigma: {} values for {t} triangles",
                sigma.len()
            )));
        }
        // The conductivities of the sheets a scene takes (their resistances' range): outside
        // it a frame underflows to zeros or overflows single precision.
        let (low, high) = et_core::sheet::SHEET_SIGMA_RANGE;
        let (low_ohm, high_ohm) = et_core::sheet::SHEET_OHM_RANGE;
        if let Some((i, s)) = sigma
            .iter()
            .enumerate()
            .find(|(_, s)| s.is_finite() && **s > 0.0 && !(low..=high).contains(*s))
        {
            return Err(usage(format!(
                "sigma[{i}] = {s:e} S per square: et models sheets of {low:e} to {high:e} S per \
                 square (sheet resistances {low_ohm:e} to {high_ohm:e} ohm/sq); in other units?"
            )));
        }
        let (imager, schedule) = (self.inner.imager(), self.inner.schedule());
        let frame = py
            .detach(|| imager.forward.frame(sigma, schedule))
            .map_err(|e| refused(&e))?;
        Ok(PyArray1::from_vec(py, frame))
    }

    /// The Jacobian of the frame at the background, K x T (V per S/sq).
    fn jacobian<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let j = self.inner.jacobian().dense();
        let (k, t) = j.shape();
        // nalgebra is column-major: its transpose's storage is J row by row.
        array2(py, j.transpose().as_slice().to_vec(), k, t)
    }

    /// The mesh's nodes, n x 2 (m).
    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let nodes = &self.inner.imager().forward.mesh().nodes;
        array2(
            py,
            nodes.iter().flatten().copied().collect(),
            nodes.len(),
            2,
        )
    }

    /// The mesh's triangles, T x 3 node indices (counter-clockwise).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let tris = &self.inner.imager().forward.mesh().triangles;
        let flat = tris.iter().flatten().map(|&i| i as i64).collect();
        array2(py, flat, tris.len(), 3)
    }

    /// Each electrode's centre, L x 2 (m), in electrode order.
    #[getter]
    fn electrodes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let sheet = self.inner.sheet();
        let c = sheet.electrodes.centres(&sheet.shape);
        array2(py, c.iter().flatten().copied().collect(), c.len(), 2)
    }

    /// The protocol's rows (K x 4) and currents (K, A).
    #[getter]
    fn protocol<'py>(&self, py: Python<'py>) -> PyResult<crate::sheets::Table<'py>> {
        crate::sheets::schedule_table(py, self.inner.schedule())
    }

    /// The pixel grid: (rows, cols, x0_m, y0_m, pixel_m), the lower-left corner of the
    /// lower-left pixel and a pixel's side.
    #[getter]
    fn grid(&self) -> (usize, usize, f64, f64, f64) {
        let g = self.inner.grid();
        (g.height, g.width, g.origin[0], g.origin[1], g.size)
    }

    /// The background conductivity sigma_0, S per square.
    #[getter]
    fn sigma0(&self) -> f64 {
        self.inner.imager().sigma0
    }

    /// The sheet imaged (JSON; after `fit_background`, with the fitted values).
    #[getter]
    fn sheet_json(&self) -> PyResult<String> {
        json(self.inner.sheet())
    }

    /// What the set-up took, s: (mesh, forward_jacobian, matrix).
    #[getter]
    fn set_up_s(&self) -> (f64, f64, f64) {
        let t = self.inner.set_up_timings;
        (t.mesh, t.forward_jacobian, t.matrix)
    }

    /// The median time of `repeats` warm applications of the last frame's reconstruction to
    /// `dv` (s; `et reconstruct`'s `timings_s.frame`), None when it has none.
    fn frame_median(&self, dv: PyReadonlyArray1<'_, f64>, repeats: usize) -> PyResult<Option<f64>> {
        et_recon::limits::count("repeats", repeats, &et_recon::limits::REPEATS)
            .map_err(|e| refused(&e))?;
        let dv = slice(&dv, "dv")?;
        // A frame that cannot be imaged is refused, not timed as None.
        let k = self.inner.schedule().frame_len();
        if dv.len() != k {
            return Err(usage(format!(
                "dv: {} values, where the protocol's frame has K = {k}",
                dv.len()
            )));
        }
        if let Some((i, v)) = dv.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(usage(format!("dv[{i}] = {v}: a finite number")));
        }
        Ok(self.inner.frame_median(dv, repeats))
    }
}
