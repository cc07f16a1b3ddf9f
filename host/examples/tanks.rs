//! et's imaging rules on two real saline tanks measured by other labs' instruments
//! (`../shared/data/tanks/`: the KIT4 archive of Hauptmann et al. 2017, arXiv:1704.01178, and
//! the Kuopio Tomography Challenge 2023's training data): each tank as a user gives it to
//! `et reconstruct` (a scene, a protocol file, the reference frame), the background fitted to
//! the reference as `et reconstruct --frames` does, then every case with known targets imaged
//! under each rule: the median distance from the strongest object to the nearest target,
//! how often its sign is that target's, how often the object count is within one, and the
//! alphas chosen.
//!
//! Run: `cargo run --release -p et-host --example tanks` (ET_TANKS_RULES picks rules by name,
//! `;` between; ET_TANKS_LEVELS the segmentation's shares; ET_LINEAR=1 prints the
//! linearisation's misfit at each rule's images, `Reconstructor::linearisation_misfit`;
//! ET_TANKS_WRITE=dir writes each tank's scene, protocol and frames there and stops;
//! ET_TANKS_ELECTRODES=1 prints the electrode each tank's fitted model explains worst, as
//! measured and with electrode 7 detached in five ways, the worst in its case frames as
//! measured and with electrode 7 detached, and electrodes 7 and 12 detached at once, and
//! stops).

#[path = "../tests/support/tanks.rs"]
mod tanks;

use et_recon::gcv::Criterion;
use et_recon::reconstructor::{MISMATCH_FACTOR, Weighting};
use et_recon::{AlphaRule, Image, Method, Reconstructor, Reference, Spec};
use et_sim::scene::Scene;
use tanks::{Case, CaseScore, Found, Tank};

/// A rule: its name, the model's error (None: the constant shares of before), the
/// weighting, the method and alpha's rule.
type Rule = (String, Option<f64>, Weighting, Method, AlphaRule);

fn main() -> anyhow::Result<()> {
    let Some(all) = tanks::both() else {
        anyhow::bail!("no ../shared/data/tanks beside the project");
    };
    // ET_TANKS_WRITE=dir: each tank's scene, protocol and frames as a user writes them, for
    // `et reconstruct` by hand (dir/kit4-2017/scene.toml, protocol.csv, frames.csv; the same for
    // ktc2023-training).
    if let Some(dir) = std::env::var_os("ET_TANKS_WRITE") {
        for tank in &all {
            let folder = tank.name.split(' ').next().unwrap_or(tank.name);
            let (scene, frames) = tank.write(&std::path::Path::new(&dir).join(folder));
            println!("{}: {} {}", tank.name, scene.display(), frames.display());
        }
        return Ok(());
    }
    if std::env::var_os("ET_TANKS_ELECTRODES").is_some() {
        return worst_electrodes(&all);
    }
    let only = std::env::var("ET_TANKS_RULES").unwrap_or_default();
    let mut all_rules = rules();
    all_rules.retain(|r| only.is_empty() || only.split(';').any(|o| r.0.contains(o)));
    // The segmentations' levels scored beside Otsu's (a share of each object's peak).
    let levels: Vec<f64> = std::env::var("ET_TANKS_LEVELS")
        .unwrap_or_else(|_| et_recon::SEGMENT_LEVEL.to_string())
        .split(',')
        .filter_map(|l| l.trim().parse().ok())
        .collect();
    println!(
        "| tank | rule | strongest object, median miss | sign right | count within one | alpha (min, median, max) | challenge score (Otsu / objects at each level) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    let work = std::env::temp_dir().join(format!("et-tanks-{}", std::process::id()));
    for tank in &all {
        let dir = work.join(tank.name.split(' ').next().unwrap_or("tank"));
        let (scene_path, _) = tank.write(&dir);
        let scene = Scene::load(&scene_path)?;
        let mut recon = Spec::new(scene.sheet.physical.clone(), scene.schedule()?).set_up()?;
        let reference = Reference::from_frames(std::slice::from_ref(&tank.reference))?;
        let fit = recon.fit_background(&reference.v0)?;
        eprintln!(
            "{}: background {:.4} ohm/sq, contact {:.3} ohm, residual {:.2} %",
            tank.name,
            fit.sheet_resistance,
            fit.contact_ohm,
            100.0 * fit.residual
        );
        let mut weighting = Weighting::Alike;
        for rule in &all_rules {
            if rule.2 != weighting {
                weighting = rule.2;
                recon.set_weighting(weighting);
                recon.fit_background(&reference.v0)?;
            }
            score_rule(tank, &mut recon, &reference, rule, &levels)?;
        }
    }
    std::fs::remove_dir_all(&work).ok();
    Ok(())
}

/// Every rule the table compares, the defaults of before and now among them.
fn rules() -> Vec<Rule> {
    let gn = Method::default();
    let d = Some(MISMATCH_FACTOR);
    let mut all_rules: Vec<Rule> = vec![(
        "before: GCV above noise + 1 % of dV".into(),
        None,
        Weighting::Alike,
        gn,
        AlphaRule::Gcv,
    )];
    for factor in [1.0, 1.5, 2.0, 3.0] {
        all_rules.push((
            format!(
                "GCV above noise + {factor} x V_0's misfit of dV{}",
                if factor == MISMATCH_FACTOR {
                    " (the default before the corner)"
                } else {
                    ""
                }
            ),
            Some(factor),
            Weighting::Alike,
            gn,
            AlphaRule::Gcv,
        ));
    }
    for (name, c) in [
        ("discrepancy", Criterion::Discrepancy),
        ("L-curve", Criterion::LCurve),
        ("quasi-optimality", Criterion::QuasiOptimality),
        (
            "default: the corner above GCV's (noise + 1 % of dV)",
            Criterion::CornerAboveFloor,
        ),
    ] {
        all_rules.push((
            format!("{name}, noise + 2 x misfit"),
            d,
            Weighting::Alike,
            gn,
            AlphaRule::Chosen(c),
        ));
    }
    for a in [0.1, 0.3, 1.0] {
        all_rules.push((
            format!("fixed alpha {a}"),
            d,
            Weighting::Alike,
            gn,
            AlphaRule::Fixed(a),
        ));
    }
    all_rules.push((
        "GREIT, noise figure 0.5".into(),
        d,
        Weighting::Alike,
        Method::Greit { radius: None },
        AlphaRule::NoiseFigure(0.5),
    ));
    for (name, w) in [
        ("weighted by kind", Weighting::PerKind),
        ("normalised dV / V_0", Weighting::Normalised),
    ] {
        all_rules.push((
            format!("default, {name}"),
            d,
            w,
            gn,
            AlphaRule::Chosen(Criterion::CornerAboveFloor),
        ));
        all_rules.push((
            format!("fixed alpha 1, {name}"),
            d,
            w,
            gn,
            AlphaRule::Fixed(1.0),
        ));
    }
    all_rules
}

/// Every case of `tank` imaged under `rule` (the weighting already set): its table row.
fn score_rule(
    tank: &Tank,
    recon: &mut Reconstructor,
    reference: &Reference,
    (name, factor, _, method, alpha_rule): &Rule,
    levels: &[f64],
) -> anyhow::Result<()> {
    recon.set_mismatch_factor(*factor);
    recon.set_method(*method, *alpha_rule)?;
    let mut scores = Vec::new();
    let mut alphas = Vec::new();
    let mut challenge = (vec![0.0; 1 + levels.len()], 0);
    // The linearisation's misfit at each case's image (ET_LINEAR).
    let mut linear: Vec<f64> = Vec::new();
    for case in &tank.cases {
        let image = recon.image(&case.values, reference)?;
        let objects: Vec<Found> = recon
            .objects(&image)
            .iter()
            .map(|o| Found {
                centre: o.region.centroid,
                sign: o.sign,
            })
            .collect();
        let score = CaseScore::of(case, &objects);
        add_challenge(tank, case, recon, &image, levels, &mut challenge.0);
        challenge.1 += 1;
        if std::env::var("ET_TANKS_CASE").is_ok_and(|c| c == case.id) {
            say_case(name, case, recon, &image);
        }
        if std::env::var_os("ET_TANKS_VERBOSE").is_some() {
            eprintln!(
                "  {name} {}: alpha {:.2e}, miss {:.1} mm, sign {}, {} objects of {}",
                case.id,
                image.alpha,
                1e3 * score.miss.unwrap_or(f64::NAN),
                score.sign_right,
                score.found,
                score.targets
            );
        }
        if std::env::var_os("ET_LINEAR").is_some()
            && let Some(m) = recon.linearisation_misfit(&image)?
        {
            linear.push(m);
        }
        scores.push(score);
        alphas.push(image.alpha);
    }
    alphas.sort_by(f64::total_cmp);
    if !linear.is_empty() {
        linear.sort_by(f64::total_cmp);
        eprintln!(
            "{} {name}: the linearisation's misfit at the images, of |dV|: min {:.3}, median {:.3}, max {:.3}",
            tank.name,
            linear[0],
            linear[linear.len() / 2],
            linear[linear.len() - 1]
        );
    }
    let s = tanks::summary(&scores);
    let (sums, n) = challenge;
    let challenge = if n == 0 {
        "-".to_string()
    } else {
        sums.iter()
            .map(|s| format!("{s:.2}"))
            .collect::<Vec<_>>()
            .join(" / ")
            + &format!(" of {n}")
    };
    println!(
        "| {} | {name} | {:.1} mm | {}/{} | {}/{} | {:.2e}, {:.2e}, {:.2e} | {challenge} |",
        tank.name,
        1e3 * s.median_miss,
        s.sign_right,
        s.cases,
        s.count_within_one,
        s.cases,
        alphas[0],
        alphas[alphas.len() / 2],
        alphas[alphas.len() - 1],
    );
    Ok(())
}

/// Adds `case`'s challenge scores to `sums`: Otsu's segmentation first, then the objects'
/// segmentation at each of `levels`.
fn add_challenge(
    tank: &Tank,
    case: &Case,
    recon: &Reconstructor,
    image: &Image,
    levels: &[f64],
    sums: &mut [f64],
) {
    let truth = tanks::truth_mask(tank, case);
    let grid = recon.grid();
    let sampled = tanks::on_score_grid(tank, grid, &image.pixels);
    sums[0] += tanks::challenge_score(&truth, &tanks::otsu_segmentation(&sampled));
    let found = recon.objects(image);
    for (k, level) in levels.iter().enumerate() {
        let classes = et_recon::segment(&image.pixels, &found, *level);
        let seg: Vec<u8> = tanks::on_score_grid(tank, grid, &classes)
            .iter()
            .map(|c| c.map_or(0, |c| c as u8))
            .collect();
        sums[1 + k] += tanks::challenge_score(&truth, &seg);
    }
}

/// Every object of `case`'s image and every target (ET_TANKS_CASE), to standard error.
fn say_case(name: &str, case: &Case, recon: &Reconstructor, image: &Image) {
    let all = recon.objects(image);
    let top = all.first().map_or(1.0, |o| o.region.peak);
    for o in &all {
        eprintln!(
            "    {name} {}: sign {} at ({:.0}, {:.0}) mm, peak {:.2} of the top, z {:.1}, area {:.0} mm2, {} px",
            case.id,
            o.sign,
            1e3 * o.region.centroid[0],
            1e3 * o.region.centroid[1],
            o.region.peak / top,
            o.region.z.unwrap_or(f64::NAN),
            1e6 * o.region.area,
            o.region.pixels.len()
        );
    }
    for t in &case.targets {
        eprintln!(
            "    target {} at ({:.0}, {:.0}) mm, r {:.0} mm",
            if t.conductive { "+" } else { "-" },
            1e3 * t.centre[0],
            1e3 * t.centre[1],
            1e3 * t.radius
        );
    }
}

/// A fault of one value: its row's electrodes (source, sink, positive, negative; 0-based), its
/// value as measured (V) and a generator of noise give the value the fault leaves.
type Fault = fn(&[u16; 4], f64, &mut et_core::rng::Rng) -> f64;

/// Each tank's worst electrode ([`et_recon::background::electrode_misfit`], counted from 1 as
/// the tanks' protocol files count) after the background fit to its reference as measured,
/// and to the reference with electrode 7 detached: reading noise of 0.5 V rms (a floating
/// input), reading 0 V, driving no current (its injections' values 10 uV of noise), or reading
/// 50 or 90 % of its potential (a poor contact).
fn worst_electrodes(all: &[Tank]) -> anyhow::Result<()> {
    println!(
        "| tank | electrode 7 | worst electrode | its values off the model (own) | the rest | stands out |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    let work = std::env::temp_dir().join(format!("et-tanks-{}", std::process::id()));
    let mut rng = et_core::rng::Rng::new(7);
    for tank in all {
        let dir = work.join(tank.name.split(' ').next().unwrap_or("tank"));
        let (scene_path, _) = tank.write(&dir);
        let scene = Scene::load(&scene_path)?;
        let schedule = scene.schedule()?;
        let measured: Vec<f64> = tank.reference.iter().map(|v| f64::from(*v)).collect();
        let faults: [(&str, Fault); 6] = [
            ("as measured", |_, v, _| v),
            ("reads noise (0.5 V rms)", |r, v, rng| {
                if r[2..].contains(&6) {
                    0.5 * rng.normal()
                } else {
                    v
                }
            }),
            (
                "reads 0 V",
                |r, v, _| {
                    if r[2..].contains(&6) { 0.0 } else { v }
                },
            ),
            ("drives no current", |r, v, rng| {
                if r[..2].contains(&6) {
                    1e-5 * rng.normal()
                } else {
                    v
                }
            }),
            (
                "reads 50 %",
                |r, v, _| {
                    if r[2..].contains(&6) { 0.5 * v } else { v }
                },
            ),
            (
                "reads 90 %",
                |r, v, _| {
                    if r[2..].contains(&6) { 0.9 * v } else { v }
                },
            ),
        ];
        for (name, fault) in faults {
            let v0: Vec<f64> = (schedule.rows().iter().zip(&measured))
                .map(|(r, v)| fault(&[r.source, r.sink, r.positive, r.negative], *v, &mut rng))
                .collect();
            let mut recon = Spec::new(scene.sheet.physical.clone(), schedule.clone()).set_up()?;
            let fit = recon.fit_background(&v0)?;
            let Some(w) = fit.worst_electrode else {
                continue;
            };
            println!(
                "| {} | {name} | {} ({} values) | {:.1} % | {:.1} % | {} |",
                tank.name,
                w.electrode + 1,
                w.values,
                100.0 * w.own,
                100.0 * w.rest,
                if w.stands_out() { "yes" } else { "no" }
            );
        }
        detached_in_frames(tank, &scene, &mut rng)?;
    }
    std::fs::remove_dir_all(&work).ok();
    Ok(())
}

/// Of `tank`'s case frames (their targets in the tank) against the model fitted to its
/// reference, as `et reconstruct` weighs the frames it images: the worst electrode as measured
/// and with electrode 7 detached (reading noise, driving no current; from 1 as the protocol
/// file counts), and electrodes 7 and 12 detached at once in the reference.
fn detached_in_frames(
    tank: &Tank,
    scene: &Scene,
    rng: &mut et_core::rng::Rng,
) -> anyhow::Result<()> {
    let schedule = scene.schedule()?;
    let rows = schedule.rows();
    let mut detach = |v: &[f32], electrodes: &[u16]| -> Vec<f64> {
        (rows.iter().zip(v))
            .map(|(r, v)| {
                if electrodes
                    .iter()
                    .any(|e| [r.positive, r.negative].contains(e))
                {
                    0.5 * rng.normal()
                } else if electrodes.iter().any(|e| [r.source, r.sink].contains(e)) {
                    1e-5 * rng.normal()
                } else {
                    f64::from(*v)
                }
            })
            .collect()
    };
    let mut recon = Spec::new(scene.sheet.physical.clone(), schedule.clone()).set_up()?;
    let reference: Vec<f64> = tank.reference.iter().map(|v| f64::from(*v)).collect();
    recon.fit_background(&reference)?;
    // (own, rest, electrode from 1) of each frame's worst electrode: the largest own, and
    // the smallest with electrode 7 detached.
    let mut sound = (0.0f64, 0.0f64, 0u16);
    let mut off = (f64::INFINITY, 0.0f64, 0u16);
    for case in &tank.cases {
        let frame: Vec<f64> = case.values.iter().map(|v| f64::from(*v)).collect();
        if let Some(w) = recon.electrode_misfit(&frame).filter(|w| w.own > sound.0) {
            sound = (w.own, w.rest, w.electrode + 1);
        }
        if let Some(w) = recon.electrode_misfit(&detach(&case.values, &[6])) {
            if !w.stands_out() || w.electrode != 6 {
                println!(
                    "{}: {}: electrode 7 detached not named: {w:?}",
                    tank.name, case.id
                );
            }
            off = if w.own < off.0 {
                (w.own, w.rest, w.electrode + 1)
            } else {
                off
            };
        }
    }
    println!(
        "{}: its {} case frames as measured: the worst electrode at most {:.1} % off (electrode \
         {}, the rest {:.1} %); electrode 7 detached in them: at least {:.1} % off (electrode {}, \
         the rest {:.1} %)",
        tank.name,
        tank.cases.len(),
        100.0 * sound.0,
        sound.2,
        100.0 * sound.1,
        100.0 * off.0,
        off.2,
        100.0 * off.1
    );
    let both = detach(&tank.reference, &[6, 11]);
    let mut recon = Spec::new(scene.sheet.physical.clone(), schedule.clone()).set_up()?;
    let fit = recon.fit_background(&both)?;
    let named: Vec<String> = (recon.detached_electrodes(&both).iter())
        .map(|m| {
            format!(
                "{} ({:.1} %, the rest {:.1} %)",
                m.electrode + 1,
                100.0 * m.own,
                100.0 * m.rest
            )
        })
        .collect();
    let worst = fit.worst_electrode.map_or("none".into(), |w| {
        format!(
            "electrode {}, {:.1} %, the rest {:.1} %",
            w.electrode + 1,
            100.0 * w.own,
            100.0 * w.rest
        )
    });
    let named = if named.is_empty() {
        "none".to_string()
    } else {
        named.join(", ")
    };
    println!(
        "{}: electrodes 7 and 12 detached in the reference: {named} named; the worst weighed \
         beside all the rest: {worst}",
        tank.name,
    );
    Ok(())
}
