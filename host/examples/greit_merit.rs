//! One-step Gauss-Newton (NOSER prior, s = 0.5) against GREIT, two ways:
//!
//! 1. GREIT's figures of merit over a 9 x 9 grid of small targets (radius 2.5 % of the
//!    sheet's longer side, data from the linearised model), both methods at the same noise
//!    figure (0.5, the consensus value: GN's alpha is solved for it), on the 22 cm disc and the
//!    13 cm square, 16 electrodes, adjacent protocol, about 8 000 triangles, 64 pixels.
//! 2. The reference scenes (the simulator's resistor network, its noisy frames: V_0 the mean
//!    of 10): touches found and each true touch's distance to its match, GN with alpha by GCV
//!    as `et reconstruct`, GREIT at noise figure 0.5.
//!
//! Run: `cargo run --release -p et-host --example greit_merit`

use std::time::Instant;

use et_core::protocol::ProtocolKind;
use et_recon::greit::NOISE_FIGURE;
use et_recon::greit::{MeritSummary, centre_target, figures_of_merit, noise_figure};
use et_recon::{AlphaRule, DataSpace, ReconError, match_touches};
use et_sim::scene::Scene;

fn scene(name: &str) -> Scene {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim/scenes");
    Scene::load(&root.join(name)).expect("a reference scene")
}

fn row(name: &str, alpha: f64, nf: f64, m: &MeritSummary, setup: f64) {
    println!(
        "| {name} | {alpha:.3} | {nf:.3} | {:.3} | {:.3} | {:.1} +- {:.1} | {:.3} | {:.3} | {:.3} | {:.3} | {setup:.3} |",
        m.amplitude_mean,
        m.amplitude_cv,
        m.position_error_mean * 1e3,
        m.position_error_sd * 1e3,
        m.resolution_mean,
        m.resolution_cv,
        m.shape_deformation_mean,
        m.ringing_mean,
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("## Figures of merit, both at noise figure 0.5\n");
    println!(
        "| sheet, method | alpha | NF | AR mean | AR sd/mean | PE mean +- sd, mm | RES mean | RES sd/mean | SD | RNG | set-up, s |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for name in ["disc-ref-x050.toml", "square-13cm-16.toml"] {
        merit_rows(name)?;
    }
    println!(
        "\n(GN's set-up includes the bisection for its alpha: 40 one-step matrices.)\n\n## The reference scenes (simulator, noisy frames)\n"
    );
    println!(
        "| scene | protocol | method | alpha | touches found / true | distance to each true touch, mm |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for (name, kind) in [
        ("disc-ref-x000.toml", ProtocolKind::Adjacent),
        ("disc-ref-x025.toml", ProtocolKind::Adjacent),
        ("disc-ref-x050.toml", ProtocolKind::Adjacent),
        ("disc-ref-x075.toml", ProtocolKind::Adjacent),
        ("disc-ref-two.toml", ProtocolKind::PpPp),
    ] {
        scene_rows(name, kind)?;
    }
    Ok(())
}

/// The figures of merit of GREIT and of one-step Gauss-Newton, both at the noise figure 0.5,
/// on scene `name`'s sheet: two table rows.
fn merit_rows(name: &str) -> Result<(), Box<dyn std::error::Error>> {
    let sc = scene(name);
    let protocol = et_core::protocol::Protocol::new(ProtocolKind::Adjacent, 16)?;
    // GREIT at the consensus noise figure, about 8 000 triangles, 64 pixels.
    let recon = et_recon::Spec {
        method: et_recon::Method::Greit { radius: None },
        alpha: AlphaRule::NoiseFigure(NOISE_FIGURE),
        ..et_recon::Spec::new(sc.sheet.physical.clone(), protocol.schedule(32e-6)?)
    }
    .set_up()?;
    let (imager, jac) = (recon.imager(), recon.jacobian());
    let grid = &imager.grid;
    let extent = grid.size * grid.width.max(grid.height) as f64;
    let target = 0.025 * extent;
    let sheet = format!("{name} ({} triangles)", imager.triangles());
    // GREIT: its matrix's time is the set-up's.
    let greit = recon
        .greit()
        .ok_or("GREIT at a noise figure keeps its matrix")?;
    let setup = recon.set_up_timings.matrix;
    let (m, _) = figures_of_merit(imager, jac, 9, target, &|dv| greit.image(dv))?;
    row(
        &format!("{sheet}, GREIT"),
        greit.alpha,
        greit.noise_figure,
        &m,
        setup,
    );
    // GN at the same noise figure: alpha by bisection (NF falls as alpha grows).
    let t = Instant::now();
    let space = DataSpace::factored(jac, 0.5)?;
    let h = centre_target(imager, jac, greit.radius);
    let ones = vec![1.0; h.len()];
    let nf_of = |alpha: f64| -> Result<f64, ReconError> {
        let r = space.one_step(alpha)?;
        let img: Vec<f64> = grid
            .image(&r.reconstruct(&h)?)
            .into_iter()
            .flatten()
            .collect();
        let sd: Vec<f64> = grid
            .image(&r.noise_sd(&ones)?)
            .into_iter()
            .flatten()
            .collect();
        Ok(noise_figure(&h, &img, &sd))
    };
    let (mut lo, mut hi) = (1e-4f64.ln(), 1e2f64.ln());
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if nf_of(mid.exp())? > 0.5 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let alpha = (0.5 * (lo + hi)).exp();
    let gn = space.one_step(alpha)?;
    let setup = t.elapsed().as_secs_f64();
    let (m, _) = figures_of_merit(imager, jac, 9, target, &|dv| {
        Ok(grid.image(&gn.reconstruct(dv)?))
    })?;
    row(
        &format!("{sheet}, one-step GN"),
        alpha,
        nf_of(alpha)?,
        &m,
        setup,
    );
    Ok(())
}

/// Scene `name`'s noisy frames under protocol `kind` imaged by each method: one row each.
fn scene_rows(name: &str, kind: ProtocolKind) -> Result<(), Box<dyn std::error::Error>> {
    let sc = scene(name);
    let config = et_core::config::ScanConfig {
        protocol: kind,
        ..sc.scan_config()?
    };
    let protocol = config.validate()?;
    let amps = f64::from(config.current_amps());
    let f = et_sim::still::scene_frames(&sc, &config, 10)?;
    let reference = et_recon::Reference {
        v0: f.v0.clone(),
        var_dv: f.var.clone(),
    };
    let mut recon =
        et_recon::Spec::new(sc.sheet.physical.clone(), protocol.schedule(amps)?).set_up()?;
    let greit = et_recon::Method::Greit { radius: None };
    let mut methods = Vec::new();
    for (method, rule, what) in [
        (et_recon::Method::default(), AlphaRule::Gcv, "one-step GN"),
        (greit, AlphaRule::NoiseFigure(NOISE_FIGURE), "GREIT"),
        (greit, AlphaRule::Gcv, "GREIT, alpha by GCV"),
    ] {
        recon.set_method(method, rule)?;
        methods.push((what, recon.image(&f.v1, &reference)?));
    }
    let grid = recon.grid();
    for (method, image) in methods {
        let (alpha, found) = (image.alpha, image.touches);
        let matches = match_touches(grid, &found, &f.truth);
        let distances: Vec<String> = matches
            .iter()
            .map(|m| match m.found {
                Some(i) => {
                    let c = found[i].centroid;
                    format!("{:.1}", (c[0] - m.truth[0]).hypot(c[1] - m.truth[1]) * 1e3)
                }
                None => "none".into(),
            })
            .collect();
        println!(
            "| {name} | {kind} | {method} | {alpha:.3} | {} / {} | {} |",
            found.len(),
            f.truth.len(),
            distances.join(", ")
        );
    }
    Ok(())
}
