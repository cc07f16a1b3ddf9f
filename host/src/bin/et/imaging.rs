//! `et forward` and `et reconstruct`: the finite elements and one-step imaging of a scene.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, bail};
use et_host::recording;
use et_recon::Method;
use et_recon::background::poor_fit_said;
use et_sim::scene::Scene;

use crate::domain::count;

mod batch;
mod frames;
use batch::each_frame;
use frames::{frames, table_frames};
mod method;
use method::method_and_alpha;
mod mesh;
use mesh::mesh_plan;

/// How a command gets its mesh.
#[derive(Debug, clap::Args)]
pub(crate) struct MeshArgs {
    /// About how many triangles to mesh the sheet with.
    #[arg(long, default_value_t = 8_000, value_parser = crate::domain::within(et_recon::limits::TRIANGLES))]
    triangles: usize,
    /// Use this mesh instead of meshing the scene's sheet: a Gmsh 2.2 ASCII `.msh` (one
    /// physical line per electrode), or `nodes.csv,triangles.csv,electrodes.csv`.
    #[arg(long, value_name = "FILE")]
    mesh: Option<String>,
    /// Mesh a disc of the sheet finer: centre x, y and radius R in mm, edges of R/6 inside
    /// (repeat for several; the triangle budget stays the same). `et forward` refines at the
    /// scene's touches by itself.
    #[arg(long, value_name = "X,Y,R", allow_hyphen_values = true)]
    refine: Vec<String>,
}

#[derive(Debug, clap::Args)]
pub(crate) struct ForwardArgs {
    /// Scene file.
    #[arg(long)]
    scene: PathBuf,
    #[command(flatten)]
    mesh: MeshArgs,
    /// Print JSON (all K values of V_0 and V_1, in volts).
    #[arg(long)]
    json: bool,
}

/// `et reconstruct --background`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Background {
    /// Fitted to the reference frame.
    Fit,
    /// The scene's sheet resistance and contact.
    Scene,
}

#[derive(Debug, clap::Args)]
pub(crate) struct ReconstructArgs {
    /// Scene file: the sheet, its electrodes, the scan protocol and the touches.
    #[arg(long)]
    scene: PathBuf,
    #[command(flatten)]
    mesh: MeshArgs,
    /// Gauss-Newton iterations: 1 is the one-step reconstruction; more refit the data
    /// (slower, for when accuracy matters more than speed).
    #[arg(long, default_value_t = 1, value_parser = crate::domain::within(et_recon::limits::ITERATIONS))]
    iterations: usize,
    /// The reconstruction: gn, one-step (or iterative) Gauss-Newton with the NOSER prior,
    /// or greit, the consensus linear reconstruction (GREIT: desired images of small targets
    /// over the sheet, lambda set by the noise figure). docs/method.md §6.
    #[arg(long, value_enum, default_value_t = Method::default())]
    method: Method,
    /// Regularisation alpha (dimensionless: lambda = alpha^2 tr(J P^-1 J^T) / K), or a rule
    /// that chooses it on each frame. For gn, "auto" (or "corner") takes the L-curve's corner
    /// (where fitting the frame closer costs the image most: the error the frame itself
    /// shows, noise and the model's mismatch with a real sheet), never below what generalised
    /// cross-validation takes above the frame's noise and 1 % of its change; "gcv" takes
    /// GCV's choice above the noise and the fitted background's misfit (twice the share of
    /// V_0 left unexplained, per kind of value: smoother); "discrepancy", "lcurve" and
    /// "quasi-optimality" those criteria alone (docs/measurements.md compares them all on
    /// two real tanks). For greit "auto" sets it by --noise-figure (one lambda for every
    /// frame, the consensus rule) and "gcv" by cross-validation on this frame (finds touches
    /// where the protocol sees little, as the centre for adjacent drive; places others less
    /// closely).
    #[arg(long, default_value = "auto")]
    alpha: String,
    /// GREIT: the noise figure that sets lambda under --alpha auto (SNR in / SNR out of a
    /// target at the centre; larger is sharper and noisier; default 0.5, the consensus
    /// value). Refused beside --method gn or another --alpha, which it would not change.
    #[arg(long, value_parser = crate::domain::above(0.0, et_recon::limits::MAX_NOISE_FIGURE))]
    noise_figure: Option<f64>,
    /// GREIT: the radius of the desired image of a small target, mm (default: 5 % of the
    /// sheet's longer side; at least one pixel). Refused beside --method gn.
    #[arg(long, value_parser = crate::domain::above(0.0, 1_000.0))]
    radius_mm: Option<f64>,
    /// Gauss-Newton: the NOSER exponent s in [0, 1] (prior diag(J^T J)^s; default 0.5).
    /// Refused beside --method greit, which has no prior.
    #[arg(long, value_parser = crate::domain::real(0.0, 1.0))]
    s: Option<f64>,
    /// ROI threshold f (keep pixels >= f max); default per protocol as docs/method.md §6: adjacent
    /// 0.10, pseudo-polar 0.08, PP-PP 0.05, others 0.10.
    #[arg(long, value_parser = crate::domain::real(0.0, 1.0))]
    threshold: Option<f64>,
    /// Pixels across the image (4 to 512).
    #[arg(long, default_value_t = 64, value_parser = crate::domain::within(et_recon::limits::PIXELS))]
    pixels: usize,
    /// Image measured frames instead of simulating the scene's touches; the scene gives the
    /// sheet, the electrodes and the protocol (a built-in one, or any system's as a file).
    /// An et recording (.jsonl, from `et sim` or `et record`), or any system's frames in
    /// volts: a CSV with one frame per row (header optional; `,` `;`, tab or spaces; LabVIEW's
    /// .lvm), a NumPy .npy (2-D, frames as rows), an .npz array (FILE.npz:NAME) or a MATLAB
    /// .mat variable (version 5 or 7: FILE.mat:VARIABLE, or a struct's field as EIDORS keeps
    /// its data, FILE.mat:vi.meas), or a JSON array of frames (json.dump(F.tolist())). A
    /// matrix whose columns are the frames (MATLAB's habit) is read transposed.
    #[arg(long, value_name = "FILE")]
    frames: Option<PathBuf>,
    /// With --frames: average the first N frames as the untouched reference V_0 (as
    /// `et stream` and `et view` do; record them with the sheet untouched).
    #[arg(long, default_value_t = 20, requires = "frames", value_parser = count(1, 10_000_000))]
    reference: usize,
    /// The untouched reference V_0 from another file (one or more frames, averaged; any
    /// format --frames reads); then --frame counts every frame of --frames.
    #[arg(
        long,
        value_name = "FILE",
        requires = "frames",
        conflicts_with = "reference"
    )]
    reference_file: Option<PathBuf>,
    /// The background the image is made about: fit (the sheet resistance and one contact
    /// resistance with which the model reproduces the reference frame best, least squares;
    /// the contact only when the protocol measures on drive electrodes) or scene (the
    /// scene's values). Default: fit for measured --frames, scene for a simulated scene.
    #[arg(long, value_enum)]
    background: Option<Background>,
    /// How the frame's values are weighted in the fit: alike (the default), kind (values on
    /// drive electrodes and off them each by the inverse of what the fitted background leaves
    /// of them in V_0) or normalised (by 1 / V_0^2: the normalised difference dV / V_0, as
    /// EIDORS offers it). Needs the fitted background. docs/measurements.md measures them.
    #[arg(long, default_value = "alike", value_parser = ["alike", "kind", "normalised"])]
    weights: String,
    /// With --frames: leave out every value these electrodes drive or measure (a detached or
    /// broken electrode, which the background fit names when its values stand out), counted
    /// as the scene's protocol file counts them (from 1 with `base = 1`), else from 0.
    /// Several: 3,7.
    #[arg(long, value_name = "E,...", value_delimiter = ',',
          value_parser = crate::domain::electrode, requires = "frames")]
    skip_electrodes: Vec<u16>,
    /// With --frames: which frame to image (0-based; default the last).
    #[arg(long, requires = "frames", conflicts_with_all = ["all", "range"],
          value_parser = crate::domain::frame_index())]
    frame: Option<usize>,
    /// With --frames: image every frame after the reference, set up once: each frame's
    /// objects and touches as a JSON line on standard output (`frame`, `alpha`, `noise`,
    /// `objects`, `found_touches`, as --json names them); --out draws the last, --image-out and
    /// --segment write every frame's pixels and classes (frames x rows x cols).
    #[arg(long, requires = "frames", conflicts_with_all = ["json"])]
    all: bool,
    /// With --frames: as --all, for frames A..B only (0-based, B excluded and at most the
    /// count of frames; A.. to the end).
    #[arg(long, value_name = "A..B", allow_hyphen_values = true, requires = "frames", conflicts_with_all = ["all", "json"])]
    range: Option<et_learn::tabular::RowRange>,
    /// Where to write the image (PNG); it may be left out where --json, --image-out,
    /// --segment, --all or --range give what was found.
    #[arg(long, required_unless_present_any = ["json", "image_out", "segment", "all", "range"])]
    out: Option<PathBuf>,
    /// Print a JSON summary (regions, metrics, timings).
    #[arg(long)]
    json: bool,
    /// Also write the pixel image as a NumPy .npy: Delta sigma / sigma_0 (no unit), NaN
    /// outside the sheet, the top row first (`plt.imshow(numpy.load(F))` shows it upright);
    /// --json gives its grid (`image`: lower-left corner and pixel size, m).
    #[arg(long, value_name = "NPY")]
    image_out: Option<PathBuf>,
    /// Also write the three-class picture as a NumPy .npy: 0 background, 1 resistive (the
    /// conductivity fell), 2 conductive (it rose), NaN outside the sheet, top row first, on
    /// --image-out's grid. Each object's pixels at or above half its own peak take its
    /// class, so a kind of target the image does not show stays empty (the picture
    /// tomography challenges score; docs/method.md §6.5). With --all or --range, every
    /// frame's (frames x rows x cols).
    #[arg(long, value_name = "NPY")]
    segment: Option<PathBuf>,
}

pub(crate) fn forward_cmd(args: &ForwardArgs) -> Result<()> {
    let scene = Scene::load(&args.scene)?;
    let schedule = scene.schedule()?;
    let protocol = schedule
        .kind()
        .map_or_else(|| "from its file".to_string(), |k| k.to_string());
    let started = Instant::now();
    // The mesh and forward model `et reconstruct` images with, refined at the touches.
    let imager = et_recon::Spec {
        mesh: mesh_plan(&scene, &args.mesh, true)?,
        ..et_recon::Spec::new(scene.sheet.physical.clone(), schedule.clone())
    }
    .imager()?;
    let (fwd, sigma0) = (&imager.forward, imager.background());
    let mesh = fwd.mesh();
    // Each touch multiplies the conductivity of the triangles whose centroid it covers.
    let sigma1: Vec<f64> = (sigma0.iter().enumerate())
        .map(|(t, &s0)| {
            let c = mesh.centroid(t);
            scene.touches.iter().fold(s0, |s, touch| {
                let inside =
                    (c[0] - touch.position[0]).hypot(c[1] - touch.position[1]) <= touch.radius;
                if inside {
                    s * scene.sheet.piezo.multiplier(touch.pressure)
                } else {
                    s
                }
            })
        })
        .collect();
    let t_n = mesh.triangles.len();
    // The rows' currents: the scene's, or the protocol file's own (one per row).
    let currents: Vec<f64> = schedule.rows().iter().map(|r| r.current_a).collect();
    let one_current = currents
        .first()
        .copied()
        .filter(|&first| currents.iter().all(|&c| c == first));
    let v0 = fwd.frame(&sigma0, &schedule)?;
    let v1 = fwd.frame(&sigma1, &schedule)?;
    let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
    let bvc = et_core::stats::bvc_dv(&dv);
    if args.json {
        let summary = ForwardSummary {
            triangles: t_n,
            protocol,
            current_a: one_current,
            currents_a: one_current.is_none().then(|| currents.clone()),
            electrodes_m: scene
                .sheet
                .physical
                .electrodes
                .centres(&scene.sheet.physical.shape),
            v0: &v0,
            v1: &v1,
            bvc,
            seconds: started.elapsed().as_secs_f64(),
        };
        out!("{}", serde_json::to_string(&summary)?);
    } else {
        let least = currents.iter().copied().fold(f64::INFINITY, f64::min);
        let most = currents.iter().copied().fold(0.0, f64::max);
        let current = match one_current {
            Some(a) => format!("{:.1} uA", a * 1e6),
            None => format!(
                "{:.1} to {:.1} uA (each row its own)",
                least * 1e6,
                most * 1e6
            ),
        };
        out!(
            "{} triangles, {} protocol, K = {}, {current}",
            t_n,
            protocol,
            v0.len(),
        );
        out!("    k        V_0 (V)        V_1 (V)     V_1 - V_0 (V)");
        for (k, (a, b)) in v0.iter().zip(&v1).enumerate() {
            out!("{k:5} {a:14.6e} {b:14.6e} {:14.6e}", b - a);
        }
        out!(
            "BVC |V_1 - V_0| = {bvc:.4e} V ({:.2} s)",
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

pub(crate) fn reconstruct_cmd(args: &ReconstructArgs, force: bool) -> Result<()> {
    let scene = Scene::load(&args.scene)?;
    frames::check_paths(args, &scene, force)?;
    let table = args
        .frames
        .as_deref()
        .filter(|f| et_host::frames::reads_as_table(f));
    let recording = match (&args.frames, table) {
        (Some(f), None) => Some(recording::read(f)?),
        _ => None,
    };
    for note in recording.iter().flat_map(recording::Recording::notes) {
        say!(
            "note: {}: {note}",
            args.frames.as_deref().unwrap_or(Path::new("")).display()
        );
    }
    let sheet = &scene.sheet.physical;
    if let Some(other) = recording
        .as_ref()
        .and_then(|r| r.made_on_another_sheet(sheet))
    {
        say!(
            "warning: {}: {other}",
            args.frames.as_deref().unwrap_or(Path::new("")).display()
        );
    }
    let (schedule, config) = match &recording {
        Some(r) => {
            if r.header.config.electrodes != sheet.electrodes.count {
                bail!(
                    "the frames are of {} electrodes, the scene's sheet has {}",
                    r.header.config.electrodes,
                    sheet.electrodes.count
                );
            }
            (r.header.config.schedule()?, Some(r.header.config))
        }
        // Another system's frames: the scene's protocol (any schedule, any current).
        None if table.is_some() => (scene.schedule()?, None),
        None => {
            let config = scene.board_config()?;
            (config.schedule()?, Some(config))
        }
    };
    let started = Instant::now();
    let (method, alpha) = method_and_alpha(args)?;
    let mut spec = et_recon::Spec {
        mesh: mesh_plan(&scene, &args.mesh, false)?,
        method,
        alpha,
        pixels: args.pixels,
        threshold: args.threshold,
        ..et_recon::Spec::new(sheet.clone(), schedule)
    };
    let stage = |what: &str, dt: f64| match dt < 0.01 {
        true => say!("{what:<44} {:>8.1} us", dt * 1e6),
        false => say!("{what:<44} {dt:>8.3} s"),
    };
    let clock = Instant::now();
    let mut chosen = match (table, config) {
        (Some(path), _) => table_frames(args, path, spec.schedule.frame_len())?,
        (None, Some(config)) => frames(args, &scene, recording.as_ref(), &config)?,
        (None, None) => bail!("no frames to image"),
    };
    drop(recording);
    let base = scene.electrode_base();
    // A built-in protocol without an electrode is still of its family: its threshold kept.
    if !args.skip_electrodes.is_empty() {
        let kind = spec.schedule.kind();
        spec.threshold = spec.threshold.or(kind.map(et_recon::default_threshold));
    }
    frames::skip_electrodes(&args.skip_electrodes, base, &mut spec.schedule, &mut chosen)?;
    let frames::Chosen {
        reference,
        reference_frames,
        frames: chosen,
        truth,
        skipped,
    } = chosen;
    let Some((_, v1)) = chosen.last() else {
        bail!("no frames to image");
    };
    frames::say_unlike_frames(&reference, &chosen);
    stage("frames", clock.elapsed().as_secs_f64());
    let (mut recon, background) = set_up(args, spec, &reference, stage)?;
    let in_reference = recon.detached_electrodes(&reference.v0);
    if let Some((said, numbers)) = et_recon::background::detached_said(&in_reference, base) {
        let whose = if in_reference.len() == 1 {
            "its"
        } else {
            "their"
        };
        say!("warning: {said} --skip-electrodes {numbers} leaves {whose} values out");
    }
    let named: Vec<u16> = in_reference.iter().map(|m| m.electrode).collect();
    frames::say_detached_in_frames(&recon, base, &chosen, &named);
    // Reference frames of which one differs as a touch or a drift does: every frame is
    // imaged against them.
    if let Some(said) = (recon.reference_changes(&reference_frames)).and_then(|c| {
        et_recon::background::reference_changes_said(c, Some(|n| format!("--reference {n}")))
    }) {
        say!("warning: {said}");
    }
    let set_up = recon.set_up_timings;
    if args.all || args.range.is_some() {
        let image = each_frame(args, &mut recon, reference, &chosen, &skipped)?;
        let timings_s = frame_stages(args, &image, &set_up, (0.0, None), |_, _| ());
        return report(args, &recon, &image, &truth, background, timings_s, started);
    }
    let imaging = crate::spinner::Spinner::new("imaging the frame");
    let image = recon.image(v1, &reference)?;
    // The warm frames' figure is the live pipeline's: through the f32 operator, made here if
    // this one frame did not need it.
    imaging.say("timing warm frames: the f32 operator, 100 frames");
    let operator = recon.prepare_frames();
    let frame_median = recon.frame_median(&image.dv, 100);
    drop(imaging);
    let timings_s = frame_stages(args, &image, &set_up, (operator, frame_median), stage);
    report(args, &recon, &image, &truth, background, timings_s, started)
}

/// The Reconstructor for `spec`, about the background fitted to `reference` (the default
/// for measured frames) or the scene's, its stages said as they end (a spinner while they
/// run); the fit, when made.
fn set_up(
    args: &ReconstructArgs,
    spec: et_recon::Spec,
    reference: &et_recon::Reference,
    stage: impl Fn(&str, f64),
) -> Result<(
    et_recon::Reconstructor,
    Option<et_recon::background::BackgroundFit>,
)> {
    let fit_background = args.background.unwrap_or(if args.frames.is_some() {
        Background::Fit
    } else {
        Background::Scene
    }) == Background::Fit;
    let weighting = et_recon::reconstructor::Weighting::from_text(&args.weights)?;
    if weighting != et_recon::reconstructor::Weighting::Alike && !fit_background {
        bail!(
            "--weights {}: needs the fitted background (--background fit)",
            args.weights
        );
    }
    // With a fitted background the Jacobian and matrix are made once, about the fit.
    let clock = Instant::now();
    let setting_up = crate::spinner::Spinner::new(if fit_background {
        "setting up: mesh, background fit, Jacobian"
    } else {
        "setting up: mesh, forward model, Jacobian"
    });
    let (recon, fit) = if fit_background {
        let (recon, fit) = spec.set_up_fitted(&reference.v0, weighting)?;
        (recon, Some(fit))
    } else {
        (spec.set_up()?, None)
    };
    drop(setting_up);
    let set_up = recon.set_up_timings;
    let t_n = recon.imager().triangles();
    stage(&format!("mesh ({t_n} triangles)"), set_up.mesh);
    let jacobian = format!(
        "(K = {}, r = {})",
        recon.jacobian().frame.len(),
        recon.jacobian().pairs()
    );
    let not_volts = et_recon::background::not_volts_said(&reference.v0);
    match &fit {
        Some(fit) => {
            let took = clock.elapsed().as_secs_f64() - set_up.mesh - set_up.matrix;
            say_background(fit, &jacobian, took, stage);
        }
        None => {
            stage(
                &format!("forward + Jacobian {jacobian}"),
                set_up.forward_jacobian,
            );
            // Measured frames at the scene's values: the model's frame at its best scale.
            let residual = recon.unexplained(&reference.v0);
            if let (Some(said), Some(_)) = (poor_fit_said(residual), &args.frames) {
                say!("warning: {said}");
            }
        }
    }
    if let Some(said) = not_volts {
        say!("note: {said}");
    }
    Ok((recon, fit))
}

/// The fitted background said on standard error: the fit's stage time (`took`, s, with
/// the forward model and `jacobian`'s sizes), its values and misfit, and the model error the
/// objects' noise counts.
fn say_background(
    fit: &et_recon::background::BackgroundFit,
    jacobian: &str,
    took: f64,
    stage: impl Fn(&str, f64),
) {
    stage(
        &format!(
            "background fit ({} solves), forward + Jacobian {jacobian}",
            fit.solves
        ),
        took,
    );
    say!(
        "background: {:.4} ohm/sq, contact {:.4} ohm{}; the model leaves {:.2} % of V_0 \
         unexplained (the scene's values: {:.2} %)",
        fit.sheet_resistance,
        fit.contact_ohm,
        if fit.contact_fitted {
            ""
        } else {
            " (not fitted: kept at the scene's ratio)"
        },
        100.0 * fit.residual,
        100.0 * fit.scene_residual
    );
    let share =
        |s: Option<f64>| s.map_or("none measured".into(), |s| format!("{:.2} %", 100.0 * s));
    say!(
        "model error: it leaves {} of V_0 on drive electrodes, {} off them; the objects' \
         noise counts {} times that share of each change as the model's error",
        share(fit.misfit_on_drive),
        share(fit.misfit_off_drive),
        et_recon::reconstructor::MISMATCH_FACTOR
    );
    if let Some(said) = poor_fit_said(fit.residual) {
        say!("warning: {said}");
    }
}

/// Prints the matrix's and the frame's stages of `image` (stderr) and returns every stage's
/// time for `--json`.
fn frame_stages(
    args: &ReconstructArgs,
    image: &et_recon::Image,
    set_up: &et_recon::reconstructor::SetUpTimings,
    (operator, frame_median): (f64, Option<f64>),
    stage: impl Fn(&str, f64),
) -> Timings {
    // The reconstruction matrix: made at set-up, or for this frame (GCV's choice).
    let t_matrix = image
        .timings
        .matrix
        .map_or(set_up.matrix, |m| m + set_up.matrix);
    let t_one_step = match (&image.iterations, image.greit) {
        (Some(_), _) => None,
        (None, Some((nf, radius))) => {
            stage(
                &format!(
                    "GREIT matrix (alpha {:.3e}, noise figure {nf:.3}, radius {:.1} mm)",
                    image.alpha,
                    radius * 1e3
                ),
                t_matrix,
            );
            Some(t_matrix)
        }
        (None, None) => {
            stage(
                &format!("one-step matrix (alpha {:.3e})", image.alpha),
                t_matrix,
            );
            Some(t_matrix)
        }
    };
    use et_recon::NoiseSource as S;
    say!(
        "noise of dV: {:.2e} V rms, {}",
        image.noise.rms_v,
        match image.noise.source {
            S::ReferenceFrames => "from the reference frames' spread".to_string(),
            S::Redundancy { dof } =>
                format!("from the protocol's {dof} redundant values (one reference frame)"),
            S::Unknown => "unknown (one reference frame, no redundant values): taken as 0".into(),
        }
    );
    match &image.iterations {
        None => {
            stage("one frame imaged (first)", image.timings.frame);
            if operator > 0.0 {
                stage("f32 operator for the warm frames", operator);
            }
            if let Some(t) = frame_median {
                stage("one frame imaged (median of 100, warm)", t);
            }
        }
        Some(it) => {
            let steps: Vec<String> = it.steps.iter().map(|s| format!("{s}")).collect();
            stage(
                &format!(
                    "{} Gauss-Newton steps (alpha {:.3e}, residual {:.3e} V, step lengths {})",
                    it.completed,
                    image.alpha,
                    it.residual,
                    steps.join(" ")
                ),
                image.timings.frame,
            );
            if let et_recon::gauss_newton::Stop::NoDescent { iteration } = it.stop {
                say!(
                    "note: stopped at iteration {iteration} of {}: no step lowered the misfit \
                 (the image is the last iterate that did; a larger --alpha may fit further)",
                    args.iterations
                );
            }
        }
    }
    Timings {
        mesh: set_up.mesh,
        forward_jacobian: set_up.forward_jacobian,
        one_step: t_one_step,
        setup: set_up.mesh + set_up.forward_jacobian + t_one_step.unwrap_or(0.0),
        frame: frame_median.unwrap_or(image.timings.frame),
        frame_first: image.timings.frame,
    }
}

mod report;
use report::*;
