//! What et reconstruct and et forward print and write: the stage lines, the metrics and the JSON
//! summaries.

use super::*;

/// `et reconstruct`'s picture, JSON and lines: the image against the truth where known.
pub(super) fn report(
    args: &ReconstructArgs,
    recon: &et_recon::Reconstructor,
    image: &et_recon::Image,
    truth: &[et_sim::still::Truth],
    background: Option<et_recon::background::BackgroundFit>,
    timings_s: Timings,
    started: Instant,
) -> Result<()> {
    let grid = recon.grid();
    let f = image.threshold;
    let (rois, found) = (&image.regions, &image.touches);
    // docs/method.md §7's metrics are for one object; with several, each true touch is
    // matched to its nearest found touch instead.
    let m = (truth.len() == 1)
        .then(|| truth[0])
        .map(|(centre, radius)| {
            et_recon::metrics(
                grid,
                &image.pixels,
                f,
                &image.dv,
                centre,
                std::f64::consts::PI * radius * radius,
            )
        });
    let matches = et_recon::match_touches(grid, found, truth);
    let sigma0 = recon.imager().sigma0;
    // --all and --range wrote every frame's pixels already.
    let batch = args.all || args.range.is_some();
    let image_grid = match args.image_out.as_ref().filter(|_| !batch) {
        Some(path) => Some(write_pixels(
            path,
            grid,
            &image.pixels,
            1.0 / sigma0,
            "Delta sigma / sigma_0",
        )?),
        None => None,
    };
    let objects = recon.objects(image);
    let segment = match args.segment.as_ref().filter(|_| !batch) {
        Some(path) => Some(write_segment(path, grid, image, &objects)?),
        None => None,
    };
    let picture = args.out.as_deref().map(|out| {
        crate::output::write(out, |partial| {
            et_host::plot::sheet_image(
                recon.imager(),
                partial,
                &format!(
                    "{}: {} found (f = {f})",
                    args.scene
                        .file_name()
                        .map_or(String::new(), |n| n.to_string_lossy().into_owned()),
                    et_host::plot::touches(found.len())
                ),
                &image.pixels,
                &et_host::plot::SheetMarks {
                    truth: truth.to_vec(),
                    found: found.iter().map(|g| g.centroid).collect(),
                    roi: rois.iter().flat_map(|g| g.pixels.iter().copied()).collect(),
                    half_range: None,
                },
            )
        })
    });
    picture.transpose()?;
    let summary = ReconstructSummary {
        out: args.out.as_deref(),
        triangles: recon.imager().triangles(),
        protocol: recon
            .schedule()
            .kind()
            .map_or_else(|| "custom".to_string(), |k| k.to_string()),
        method: args.method.name(),
        alpha: image.alpha,
        noise: image.noise,
        background,
        noise_figure: image.greit.map(|g| g.0),
        s: args.s.unwrap_or(super::method::NOSER_S),
        threshold: f,
        regions: rois.iter().map(RegionSummary::of).collect(),
        found_touches: found.iter().map(RegionSummary::of).collect(),
        image: image_grid,
        segment,
        objects: objects
            .iter()
            .map(|o| et_recon::touches::ObjectSummary::of(o, sigma0))
            .collect(),
        touches_mm: truth
            .iter()
            .map(|(c, _)| [c[0] * 1e3, c[1] * 1e3])
            .collect(),
        metrics: m.as_ref(),
        touch_matches: matches
            .iter()
            .map(|t| TouchMatchSummary {
                truth_mm: [t.truth[0] * 1e3, t.truth[1] * 1e3],
                found: t.found,
                pe: t.pe,
                se: t.se,
            })
            .collect(),
        timings_s,
        seconds: started.elapsed().as_secs_f64(),
    };
    if args.json {
        out!("{}", serde_json::to_string(&summary)?);
        return Ok(());
    }
    say_found(rois, found, m.as_ref(), truth.len(), &matches);
    if let Some(out) = &args.out {
        say!("wrote {}", out.display());
    }
    Ok(())
}

/// The segmentation of `image` by its `objects` (0 background, 1 resistive, 2 conductive)
/// written to `path` as pixels.
fn write_segment(
    path: &std::path::Path,
    grid: &et_recon::PixelGrid,
    image: &et_recon::Image,
    objects: &[et_recon::Object],
) -> Result<ImageGrid> {
    let classes = et_recon::segment::as_values(&et_recon::segment(
        &image.pixels,
        objects,
        et_recon::SEGMENT_LEVEL,
    ));
    write_pixels(
        path,
        grid,
        &classes,
        1.0,
        "class: 0 background, 1 resistive, 2 conductive",
    )
}

/// The regions and touches found, the metrics against a single true touch, and each of
/// `truths` true touches' match when there are several, said on standard error.
fn say_found(
    rois: &[et_recon::Region],
    found: &[et_recon::Region],
    m: Option<&et_recon::Metrics>,
    truths: usize,
    matches: &[et_recon::TouchMatch],
) {
    for (i, r) in rois.iter().enumerate().take(5) {
        say!(
            "region {i}: centroid ({:.1}, {:.1}) mm, area {:.0} mm^2",
            r.centroid[0] * 1e3,
            r.centroid[1] * 1e3,
            r.area * 1e6
        );
    }
    if found.is_empty() {
        say!(
            "no touch: no region reaches {} times its pixels' noise (the untouched sheet, or \
             frames of noise)",
            et_recon::TOUCH_Z
        );
    }
    for (i, r) in found.iter().enumerate() {
        say!(
            "touch {i}: at ({:.1}, {:.1}) mm{}",
            r.centroid[0] * 1e3,
            r.centroid[1] * 1e3,
            r.z.map_or(String::new(), |z| format!(", {z:.1} x its noise"))
        );
    }
    if let Some(m) = m {
        say!(
            "PE {:.3}, SE {:.3}, RNG {:.3}, BVC {:.3e} V",
            m.pe,
            m.se,
            m.rng,
            m.bvc
        );
    }
    if truths > 1 {
        for t in matches {
            say!(
                "true touch at ({:.1}, {:.1}) mm: {}, PE {:.3}, SE {:.3}",
                t.truth[0] * 1e3,
                t.truth[1] * 1e3,
                t.found.map_or("not found".into(), |i| format!("touch {i}")),
                t.pe,
                t.se
            );
        }
    }
}

/// `et forward --json`.
#[derive(serde::Serialize)]
pub(super) struct ForwardSummary<'a> {
    pub(super) triangles: usize,
    pub(super) protocol: String,
    /// The current every row drives, A (the scene's, or its protocol file's); None where the
    /// file's rows drive different currents, then given in `currents_a`.
    pub(super) current_a: Option<f64>,
    /// Each row's current, A (K values), where they differ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) currents_a: Option<Vec<f64>>,
    /// Each electrode's centre, m, in electrode order (where `first_deg` and `direction`
    /// put them).
    pub(super) electrodes_m: Vec<[f64; 2]>,
    /// The untouched frame, V (K values).
    pub(super) v0: &'a [f64],
    /// The touched frame, V.
    pub(super) v1: &'a [f64],
    /// |V_1 - V_0|, V.
    pub(super) bvc: f64,
    pub(super) seconds: f64,
}

/// `et reconstruct --json`.
#[derive(serde::Serialize)]
pub(super) struct ReconstructSummary<'a> {
    /// The picture's path (None: none drawn).
    out: Option<&'a std::path::Path>,
    triangles: usize,
    protocol: String,
    /// "gn" or "greit".
    method: &'static str,
    alpha: f64,
    /// The noise of dV the image was made against.
    noise: et_recon::FrameNoise,
    /// The background fitted to the reference frame (null: the scene's).
    background: Option<et_recon::background::BackgroundFit>,
    /// GREIT's noise figure of the matrix made; null for gn.
    noise_figure: Option<f64>,
    s: f64,
    threshold: f64,
    /// Every region above the threshold.
    regions: Vec<RegionSummary>,
    /// The touches: regions split at their saddles, above TOUCH_Z times their noise.
    found_touches: Vec<RegionSummary>,
    /// The pixel image written by --image-out, and its grid.
    image: Option<ImageGrid>,
    /// The three-class picture written by --segment, and its grid.
    segment: Option<ImageGrid>,
    /// Objects of both signs, strongest (|peak|) first: conductive (+1) and resistive (-1)
    /// targets of a tank, presses of a sheet. Field names fixed: scripts rely on them.
    objects: Vec<et_recon::touches::ObjectSummary>,
    /// The scene's touches, mm.
    touches_mm: Vec<[f64; 2]>,
    /// docs/method.md §7's PE, SE, RNG and BVC, for a scene with one touch (null otherwise).
    metrics: Option<&'a et_recon::metrics::Metrics>,
    /// Each true touch and the found touch nearest it, with its own PE and SE.
    touch_matches: Vec<TouchMatchSummary>,
    timings_s: Timings,
    /// Wall time of the whole command, s.
    seconds: f64,
}

/// Where `--image-out`'s or `--segment`'s pixels are: row 0 is the top row.
#[derive(serde::Serialize)]
pub(super) struct ImageGrid {
    file: PathBuf,
    rows: usize,
    cols: usize,
    /// The lower-left corner of the lower-left pixel, m.
    x0_m: f64,
    /// The lower-left corner of the lower-left pixel, m.
    y0_m: f64,
    /// A pixel's side, m.
    pixel_m: f64,
    /// What each value is.
    unit: &'static str,
}

/// Writes pixels on `grid` (times `scale`, NaN outside, top row first) as .npy.
fn write_pixels(
    path: &std::path::Path,
    grid: &et_recon::PixelGrid,
    pixels: &[Option<f64>],
    scale: f64,
    unit: &'static str,
) -> Result<ImageGrid> {
    let top_first = grid.top_first(pixels, scale);
    let m = nalgebra::DMatrix::from_row_slice(grid.height, grid.width, &top_first);
    let bytes = et_learn::npz::npy_of_matrix(&m);
    crate::output::write(path, |partial| std::fs::write(partial, &bytes))?;
    Ok(ImageGrid {
        file: path.to_path_buf(),
        rows: grid.height,
        cols: grid.width,
        x0_m: grid.origin[0],
        y0_m: grid.origin[1],
        pixel_m: grid.size,
        unit,
    })
}

/// A true touch matched to the nearest found one.
#[derive(serde::Serialize)]
pub(super) struct TouchMatchSummary {
    truth_mm: [f64; 2],
    /// Index into `found_touches`; null when none was found.
    found: Option<usize>,
    pe: f64,
    se: f64,
}

/// `et reconstruct`'s stage times, s.
#[derive(serde::Serialize)]
pub(super) struct Timings {
    /// Meshing the sheet (or reading --mesh).
    pub(super) mesh: f64,
    /// The forward model, its factorisation, the frame and the Jacobian at the background.
    pub(super) forward_jacobian: f64,
    /// The reconstruction matrix: one-step Gauss-Newton's (with GCV's eigendecomposition
    /// under --alpha auto) or GREIT's (with its noise-figure search); null with --iterations
    /// above 1, which builds no matrix.
    pub(super) one_step: Option<f64>,
    /// mesh + forward_jacobian + one_step: what a live session pays once.
    pub(super) setup: f64,
    /// Imaging one frame as a live session does, the matrix warm in cache: the median of
    /// 100 applications of the reconstruction to this frame's dV (in f32 onto the triangles
    /// and drawn on the pixels; GREIT onto the pixels). With --iterations above 1, the whole
    /// iterative fit, once.
    pub(super) frame: f64,
    /// The image's own application (the one-step matrix's f64 factors, GREIT's operator), or
    /// the iterative fit.
    pub(super) frame_first: f64,
}

/// A region of the image, in mm.
#[derive(serde::Serialize)]
pub(super) struct RegionSummary {
    centroid_mm: [f64; 2],
    area_mm2: f64,
    peak: f64,
    /// Its peak over its pixels' noise (a z-score); null when the noise is not known.
    z: Option<f64>,
}

impl RegionSummary {
    pub(super) fn of(r: &et_recon::Region) -> Self {
        Self {
            centroid_mm: [r.centroid[0] * 1e3, r.centroid[1] * 1e3],
            area_mm2: r.area * 1e6,
            peak: r.peak,
            z: r.z,
        }
    }
}
