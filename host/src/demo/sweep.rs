//! The demo's third stage: mesh size against forward error, position error and time.

use super::*;
use et_recon::reconstructor::{median_seconds, onto_triangles};

/// The headline numbers of the sweep.
pub(super) struct SweepKey {
    /// (triangles, set-up s, live frame us) of the mesh nearest 8 000 triangles.
    pub(super) at_8k: Option<(usize, f64, f64)>,
}

/// One mesh of the sweep.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// Triangles.
    pub triangles: usize,
    /// Largest difference of the untouched frame from the reference mesh's, relative to the
    /// largest voltage.
    pub forward_error: f64,
    /// Mesh + forward model + Jacobian + one-step matrix, s.
    pub setup_s: f64,
    /// One live frame onto the mesh, drawn on the pixels (f32, the packed factors), median
    /// of 100 as `et reconstruct` reports it, us.
    pub live_frame_us: f64,
    /// PE of the one-step image.
    pub pe_one_step: f64,
    /// PE and time (s) of 4 iterative Gauss-Newton steps, where run.
    pub iterative: Option<(f64, f64)>,
}

/// The speed/accuracy sweep of imaging on docs/method.md §7's disc with the target at x = 0.5:
/// adjacent protocol, complete electrode model, noiseless simulator frames, alpha 0.03,
/// s = 0.5. Forward error against a mesh of `reference` triangles; the iterative
/// Gauss-Newton (4 steps) on meshes up to `iterative_up_to`. `tick` is called after each mesh.
///
/// # Errors
/// When a mesh, solve or reconstruction fails.
pub fn mesh_sweep(
    triangles: &[usize],
    reference: usize,
    iterative_up_to: usize,
    mut tick: impl FnMut(&SweepRow),
) -> Result<Vec<SweepRow>> {
    let scene = load(REFERENCE_SCENES[1])?;
    let protocol = Protocol::new(
        ProtocolKind::Adjacent,
        scene.sheet.physical.electrodes.count,
    )?;
    let amps = 32e-6;
    let schedule = protocol.schedule(amps)?;
    let t = &scene.touches[0];
    let sheet = simulated_sheet(&scene)?;
    let mut sim = et_sim::frontend::SimFrontend::new(sheet, scene.frontend, 1)?;
    let v0 = sim.ideal_frame(&protocol, amps);
    sim.set_touches(&[t.touch()])?;
    let dv: Vec<f64> = sim
        .ideal_frame(&protocol, amps)
        .iter()
        .zip(&v0)
        .map(|(a, b)| a - b)
        .collect();
    let fine = Imager::new(
        &scene.sheet.physical,
        Mesh::with_about(&scene.sheet.physical, reference)?,
        8,
    )?;
    let v_ref = fine.forward.frame(&fine.background(), &schedule)?;
    let scale = v_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let pe = |imager: &Imager, d: &[f64]| {
        let rois = regions(&imager.grid, &imager.grid.image(d), 0.1);
        let extent = imager.grid.width.max(imager.grid.height) as f64 * imager.grid.size;
        rois.first().map_or(1.0, |r| {
            (r.centroid[0] - t.position[0]).hypot(r.centroid[1] - t.position[1]) / extent
        })
    };
    let mut rows = Vec::new();
    for &target in triangles {
        let started = Instant::now();
        let imager = Imager::new(
            &scene.sheet.physical,
            Mesh::with_about(&scene.sheet.physical, target)?,
            64,
        )?;
        let jac = imager
            .forward
            .transfer_jacobian(&imager.background(), &schedule)?;
        let one = et_recon::DataSpace::factored(&jac, 0.5)?.one_step(0.03)?;
        let v = jac.frame;
        let setup_s = started.elapsed().as_secs_f64();
        let forward_error = v
            .iter()
            .zip(&v_ref)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / scale;
        let image = one.reconstruct(&dv)?;
        // The live frame as `et reconstruct` times it: the median of 100 applications, in f32
        // onto the triangles and drawn on the pixels.
        let operator = et_recon::FrameOperator::of(&one);
        let live_us = 1e6
            * median_seconds(100, || onto_triangles(&imager.grid, &operator, &dv).ok())
                .ok_or(et_recon::ReconError::NonFinite)?;
        let iterative = if imager.triangles() <= iterative_up_to {
            let t0 = Instant::now();
            let its = et_recon::gauss_newton(
                &imager.forward,
                &schedule,
                &imager.background(),
                Data::Difference(&dv),
                GaussNewton {
                    alpha: 0.03,
                    s: 0.5,
                    iterations: 4,
                },
                &[],
            )?;
            let last = its
                .iterates
                .last()
                .ok_or(DemoError::Scenes("the iterative fit returned no iterate"))?;
            let d: Vec<f64> = last.sigma.iter().map(|v| v - imager.sigma0).collect();
            Some((pe(&imager, &d), t0.elapsed().as_secs_f64()))
        } else {
            None
        };
        let row = SweepRow {
            triangles: imager.triangles(),
            forward_error,
            setup_s,
            live_frame_us: live_us,
            pe_one_step: pe(&imager, &image),
            iterative,
        };
        tick(&row);
        rows.push(row);
    }
    Ok(rows)
}

pub(super) fn sweep(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Section<SweepKey>> {
    let bar = steps.bar(sizes.sweep.len(), "speed/accuracy sweep (meshes)");
    let rows = mesh_sweep(
        sizes.sweep,
        sizes.sweep_reference,
        sizes.iterative_up_to,
        |_| bar.inc(1),
    )?;
    steps.done(&bar, "swept mesh sizes");
    charts(&out.join("sweep"), &rows)?;
    let mut md = String::from("## 3. Speed against accuracy (imaging)\n\n");
    let _ = writeln!(
        md,
        "22 cm disc, adjacent protocol, complete electrode model, the target at x = 0.5; \
         noiseless simulator frames so that only the mesh matters; alpha = 0.03, s = 0.5. \
         Forward error: the largest difference of the untouched frame from a {}-triangle \
         mesh's, over the largest voltage. Times on one core of the machine above (the live \
         frame is the median of 100 applications, as `et reconstruct --json` reports it).\n\n\
         | triangles | forward error | set-up | live frame | PE one-step | PE iterative (4 steps) | iterative time |\n\
         | --- | --- | --- | --- | --- | --- | --- |",
        sizes.sweep_reference
    );
    for r in &rows {
        let _ = writeln!(
            md,
            "| {} | {:.2} % | {:.3} s | {:.0} us | {:.3} | {} | {} |",
            r.triangles,
            100.0 * r.forward_error,
            r.setup_s,
            r.live_frame_us,
            r.pe_one_step,
            r.iterative.map_or("-".into(), |i| format!("{:.3}", i.0)),
            r.iterative.map_or("-".into(), |i| format!("{:.2} s", i.1)),
        );
    }
    let _ = writeln!(
        md,
        "\n![accuracy](sweep/accuracy.png)\n\n\
         How to read this: one point per mesh (the lines only join them); lower is better. PE \
         is the distance from the true centre to the ROI's centroid over the sheet's largest \
         extent (22 cm: 1 % is 2.2 mm). The frames are noiseless, so what is left is the mesh's \
         and the method's own error.\n\n\
         ![forward error](sweep/forward-error.png)\n\n\
         How to read this: how far the host's finite-element voltages on the untouched sheet \
         are from a {}-triangle mesh's, as a share of the largest voltage. It falls as the \
         mesh refines, though not at every step: each mesh places its nodes anew.\n\n\
         ![time](sweep/time.png)\n\n\
         How to read this: the set-up is paid once per mesh, protocol and alpha; the iterative \
         fit is paid per frame. A live one-step frame (the table) is microseconds at every \
         size.\n\n\
         The one-step matrix is built once per (mesh, protocol, alpha); a live frame is one \
         matrix-vector product. The iterative Gauss-Newton refits the nonlinear model and costs \
         a Jacobian per step: use it offline, when accuracy matters more than speed.\n",
        sizes.sweep_reference
    );
    let at_8k = rows
        .iter()
        .min_by_key(|r| r.triangles.abs_diff(8_000))
        .map(|r| (r.triangles, r.setup_s, r.live_frame_us));
    Ok(Section {
        markdown: md,
        json: serde_json::to_value(SweepSummary {
            reference_triangles: sizes.sweep_reference,
            rows: &rows,
        })?,
        key: SweepKey { at_8k },
    })
}

/// The sweep's three charts in `dir`: mesh size against position error, against the forward
/// model's error, and against time.
fn charts(dir: &Path, rows: &[SweepRow]) -> Result<()> {
    let xs = |f: fn(&SweepRow) -> Option<f64>| -> Vec<(f64, f64)> {
        rows.iter()
            .filter_map(|r| Some((r.triangles as f64, f(r)?)))
            .collect()
    };
    plot::chart(
        &dir.join("accuracy.png"),
        plot::Labels {
            title: "mesh size against position error (AD, CEM, target at x = 0.5)",
            x: "triangles",
            y: "position error PE (% of the sheet's extent)",
            legend: plot::Legend::UpperRight,
        },
        &[
            plot::Series {
                label: "PE one-step, % of the sheet".into(),
                points: xs(|r| Some(100.0 * r.pe_one_step)),
                scatter: false,
            },
            plot::Series {
                label: "PE iterative (4 steps), % of the sheet".into(),
                points: xs(|r| r.iterative.map(|i| 100.0 * i.0)),
                scatter: false,
            },
        ],
    )?;
    plot::chart(
        &dir.join("forward-error.png"),
        plot::Labels {
            title: "mesh size against the forward model's error (untouched sheet)",
            x: "triangles",
            y: "largest voltage difference (% of the largest voltage)",
            legend: plot::Legend::UpperRight,
        },
        &[plot::Series {
            label: String::new(),
            points: xs(|r| Some(100.0 * r.forward_error)),
            scatter: false,
        }],
    )?;
    plot::chart(
        &dir.join("time.png"),
        plot::Labels {
            title: "mesh size against time",
            x: "triangles",
            y: "seconds",
            legend: plot::Legend::UpperLeft,
        },
        &[
            plot::Series {
                label: "set-up: mesh + forward + Jacobian + one-step matrix".into(),
                points: xs(|r| Some(r.setup_s)),
                scatter: false,
            },
            plot::Series {
                label: "iterative Gauss-Newton, 4 steps".into(),
                points: xs(|r| r.iterative.map(|i| i.1)),
                scatter: false,
            },
        ],
    )?;
    Ok(())
}

/// `summary.json`'s "sweep".
#[derive(Serialize)]
struct SweepSummary<'a> {
    /// The fine mesh the others are measured against.
    reference_triangles: usize,
    rows: &'a [SweepRow],
}
