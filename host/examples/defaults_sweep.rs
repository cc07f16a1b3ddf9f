//! The default alpha against fixed alphas on another system's frames: two saline tanks as
//! other labs build them, measured by the simulator's resistor network (not the
//! reconstruction's finite elements) through [`et_sim::foreign`]'s laboratory instrument
//! (noise, gain drift), with a true sheet resistance and contact impedance other than the ones
//! the user's scene guesses; one reference frame (the empty tank), as real data sets give.
//! Each case holds 1 to 3 rods, metal (conductivity x 10) or plastic (x 0.01), 2 to 3 cm
//! across, anywhere within 70 % of the radius.
//!
//! The background is fitted to the reference frame first, as `et reconstruct --frames` does.
//! For each rule: the median distance from the strongest object to the nearest rod, how often
//! its sign is that rod's, how often the object count is within one of the rods', and the
//! alphas chosen.
//!
//! Run: `cargo run --release -p et-host --example defaults_sweep` (ET_SWEEP_RULES and
//! ET_SWEEP_INSTRUMENTS pick rows by name, `;` between; ET_SWEEP_MISMATCH sets the real
//! tank's mismatch; ET_LINEAR=1 prints the linearisation's misfit at each rule's images).

use et_core::rng::Rng;
use et_core::schedule::Schedule;
use et_recon::{AlphaRule, Method, Reference, Spec};
use et_sim::foreign::{self, Instrument, Mismatch};
use et_sim::scene::Scene;
use et_sim::sheet::SimulatedSheet;
use et_sim::touch::{Footprint, Inclusion};

/// A tank: the user's scene, the truth the simulator measures, and the protocol.
struct Tank {
    name: &'static str,
    scene: Scene,
    truth: Scene,
    schedule: Schedule,
    radius: f64,
}

/// A disc tank of `radius` with `electrodes` (`extra` TOML keys), the user's guesses of
/// 200 ohm/sq and 20 ohm contacts; the truth 230 ohm/sq and 60 ohm.
fn tank(name: &'static str, radius: f64, electrodes: &str, schedule: Schedule) -> Tank {
    let scene = |rs: f64, contact: f64| {
        let text = format!(
            "[sheet]\nshape = {{ kind = \"disc\", radius = {radius} }}\nsheet_resistance = {rs}\n\
             electrodes = {{ {electrodes}, contact_ohm = {contact} }}\n"
        );
        Scene::parse(&text, name).expect("a valid scene")
    };
    Tank {
        name,
        scene: scene(200.0, 20.0),
        truth: scene(230.0, 60.0),
        schedule,
        radius,
    }
}

/// The 16-electrode tank: adjacent, skip 1, 2, 3 and all against electrode 0 (79
/// injections, 1 264 values); the 32-electrode tank: injections between odd electrodes only,
/// 1 to 4 odd electrodes apart and opposite (72 injections, 2 304 values).
fn tanks() -> Vec<Tank> {
    let mut pairs16: Vec<(u16, u16)> = (0..4)
        .flat_map(|skip| (0..16).map(move |i| (i, (i + skip + 1) % 16)))
        .collect();
    pairs16.extend((1..16).map(|i| (i, 0)));
    let odd = |i: u16| (2 * i + 1) % 32;
    let mut pairs32: Vec<(u16, u16)> = (1..=4)
        .flat_map(|d| (0..16).map(move |i| (odd(i), odd(i + d))))
        .collect();
    pairs32.extend((0..8).map(|i| (odd(i), odd(i + 8))));
    vec![
        tank(
            "16 electrodes, 79 injections",
            0.14,
            "count = 16, width = 0.025, first_deg = 90, direction = \"cw\"",
            Schedule::adjacent_pairs_under(16, &pairs16, 1.4142e-3).expect("a schedule"),
        ),
        tank(
            "32 electrodes, odd injections",
            0.15,
            "count = 32, width = 0.01, first_deg = 0, direction = \"ccw\"",
            Schedule::adjacent_pairs_under(32, &pairs32, 1e-3).expect("a schedule"),
        ),
    ]
}

/// `n` cases of 1 to 3 rods (centre m, radius m, multiplier: metal's or plastic's of
/// `[metal, plastic]`) within 70 % of `radius`, at least 4 cm apart edge to edge.
fn cases(radius: f64, n: usize, seed: u64, [metal, plastic]: [f64; 2]) -> Vec<Vec<Inclusion>> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|i| {
            let count = 1 + i % 3;
            let mut rods: Vec<Inclusion> = Vec::new();
            while rods.len() < count {
                let r = 0.7 * radius * rng.uniform().sqrt();
                let a = std::f64::consts::TAU * rng.uniform();
                let position = [r * a.cos(), r * a.sin()];
                let size = 0.01 + 0.005 * rng.uniform();
                let clear = rods.iter().all(|o| {
                    (o.position[0] - position[0]).hypot(o.position[1] - position[1])
                        > o.radius + size + 0.04
                });
                if clear {
                    rods.push(Inclusion {
                        position,
                        radius: size,
                        multiplier: if rng.uniform() < 0.5 { metal } else { plastic },
                        footprint: Footprint::default(),
                    });
                }
            }
            rods
        })
        .collect()
}

/// One rule's results over the cases.
#[derive(Default)]
struct Score {
    miss_mm: Vec<f64>,
    sign_right: usize,
    count_within_one: usize,
    alphas: Vec<f64>,
    objects: Vec<usize>,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

/// The real tank's mismatch: [`Mismatch::tank`], or ET_SWEEP_MISMATCH="position, width,
/// contact spread, contact drift, unevenness" to try others.
fn mismatch() -> Mismatch {
    let mut m = Mismatch::tank(5);
    if let Ok(text) = std::env::var("ET_SWEEP_MISMATCH") {
        let v: Vec<f64> = text
            .split(',')
            .filter_map(|x| x.trim().parse().ok())
            .collect();
        if let [position, width, contact_spread, contact_drift, unevenness] = v[..] {
            m = Mismatch {
                position,
                width,
                contact_spread,
                contact_drift,
                unevenness,
                ..m
            };
        }
    }
    m
}

fn main() -> anyhow::Result<()> {
    use et_recon::gcv::Criterion;
    use et_recon::reconstructor::MISMATCH_FACTOR;
    // name, alpha's rule, the model's error counted (None: the constant shares of before).
    let mut rules = vec![
        ("before (GCV above noise + 1 % of dV)", AlphaRule::Gcv, None),
        (
            "default (GCV above noise + 2 x misfit)",
            AlphaRule::Gcv,
            Some(MISMATCH_FACTOR),
        ),
        ("GCV above noise + 1 x misfit", AlphaRule::Gcv, Some(1.0)),
        ("GCV above noise + 0.5 x misfit", AlphaRule::Gcv, Some(0.5)),
        (
            "L-curve above noise + 1 % of dV",
            AlphaRule::Chosen(Criterion::LCurve),
            None,
        ),
        (
            "L-curve above noise + 2 x misfit",
            AlphaRule::Chosen(Criterion::LCurve),
            Some(MISMATCH_FACTOR),
        ),
        (
            "quasi-optimality above noise + 1 % of dV",
            AlphaRule::Chosen(Criterion::QuasiOptimality),
            None,
        ),
        ("fixed 0.01", AlphaRule::Fixed(0.01), Some(MISMATCH_FACTOR)),
        ("fixed 0.03", AlphaRule::Fixed(0.03), Some(MISMATCH_FACTOR)),
        ("fixed 0.1", AlphaRule::Fixed(0.1), Some(MISMATCH_FACTOR)),
        ("fixed 0.3", AlphaRule::Fixed(0.3), Some(MISMATCH_FACTOR)),
        ("fixed 1", AlphaRule::Fixed(1.0), Some(MISMATCH_FACTOR)),
    ];
    let only = std::env::var("ET_SWEEP_RULES").unwrap_or_default();
    rules.retain(|r| only.is_empty() || only.split(';').any(|o| r.0.contains(o)));
    let n = 24;
    println!(
        "| tank | instrument | alpha | strongest object to nearest rod, median | its sign right | count within one | objects, median | alpha chosen (min, median, max) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    // The instrument, and the tank's departures from its model (None: the network as drawn).
    let mut instruments = vec![
        ("ideal", Instrument::ideal(), None),
        ("laboratory", Instrument::laboratory(11), None),
        (
            "noisy",
            Instrument {
                noise: 2e-3,
                proportional: 2e-3,
                ..Instrument::laboratory(11)
            },
            None,
        ),
        (
            "laboratory, a real tank's mismatch",
            Instrument::laboratory(11),
            Some(mismatch()),
        ),
    ];
    let only = std::env::var("ET_SWEEP_INSTRUMENTS").unwrap_or_default();
    instruments.retain(|i| only.is_empty() || only.split(';').any(|o| i.0.contains(o)));
    for (instrument_name, instrument, mismatch) in instruments {
        for tank in tanks() {
            // Metal (x 10) and plastic (x 0.01) as before; metal and plastic as real
            // tanks' rods are (x 1e3, x 1e-3) beside a real tank's mismatch.
            let contrast = if mismatch.is_some() {
                [1e3, 1e-3]
            } else {
                [10.0, 0.01]
            };
            let cases = cases(tank.radius, n, 7, contrast);
            let frames = if let Some(m) = mismatch {
                let (reference, later) = m.sheets(&tank.truth.sheet)?;
                foreign::frames_between(&reference, &later, &tank.schedule, &cases, &instrument)?
            } else {
                let sheet = SimulatedSheet::new(&tank.truth.sheet, &[])?;
                foreign::frames(&sheet, &tank.schedule, &cases, &instrument)?
            };
            let as_f32 = |f: &[f64]| f.iter().map(|&v| v as f32).collect::<Vec<f32>>();
            let reference = Reference::from_frames(&[as_f32(&frames[0])])?;
            let mut recon =
                Spec::new(tank.scene.sheet.physical.clone(), tank.schedule.clone()).set_up()?;
            // As `et reconstruct --frames` does by default.
            let fit = recon.fit_background(&reference.v0)?;
            eprintln!(
                "{}, {instrument_name}: background {:.1} ohm/sq (truth 230), contact {:.1} ohm (truth 60; the models' electrodes differ), residual {:.2} % ({:.2} % on drive electrodes, {:.2} % off them; the scene's guess: {:.1} %)",
                tank.name,
                fit.sheet_resistance,
                fit.contact_ohm,
                100.0 * fit.residual,
                100.0 * fit.misfit_on_drive.unwrap_or(f64::NAN),
                100.0 * fit.misfit_off_drive.unwrap_or(f64::NAN),
                100.0 * fit.scene_residual
            );
            for &(name, rule, factor) in &rules {
                recon.set_mismatch_factor(factor);
                recon.set_method(Method::default(), rule)?;
                let mut score = Score::default();
                // The linearisation's misfit at each case's image (ET_LINEAR).
                let mut linear: Vec<f64> = Vec::new();
                for (rods, frame) in cases.iter().zip(&frames[1..]) {
                    let image = recon.image(&as_f32(frame), &reference)?;
                    if std::env::var_os("ET_LINEAR").is_some()
                        && let Some(m) = recon.linearisation_misfit(&image)?
                    {
                        linear.push(m);
                    }
                    let objects = recon.objects(&image);
                    score.alphas.push(image.alpha);
                    score.objects.push(objects.len());
                    if objects.len().abs_diff(rods.len()) <= 1 {
                        score.count_within_one += 1;
                    }
                    let Some(first) = objects.first() else {
                        score.miss_mm.push(f64::INFINITY);
                        continue;
                    };
                    let c = first.region.centroid;
                    let nearest = rods
                        .iter()
                        .min_by(|a, b| {
                            let d =
                                |o: &Inclusion| (o.position[0] - c[0]).hypot(o.position[1] - c[1]);
                            d(a).total_cmp(&d(b))
                        })
                        .expect("a rod");
                    score
                        .miss_mm
                        .push(1e3 * (nearest.position[0] - c[0]).hypot(nearest.position[1] - c[1]));
                    if (first.sign > 0) == (nearest.multiplier > 1.0) {
                        score.sign_right += 1;
                    }
                }
                if !linear.is_empty() {
                    let m = median(&mut linear);
                    eprintln!(
                        "{}, {instrument_name}, {name}: the linearisation's misfit at the images, of |dV|: median {m:.3}, max {:.3}",
                        tank.name,
                        linear[linear.len() - 1]
                    );
                }
                let mut objects: Vec<f64> = score.objects.iter().map(|&o| o as f64).collect();
                let mut alphas = score.alphas.clone();
                let (lo, hi) = alphas
                    .iter()
                    .fold((f64::INFINITY, 0.0f64), |(l, h), a| (l.min(*a), h.max(*a)));
                let none = score.miss_mm.iter().filter(|m| m.is_infinite()).count();
                let miss = median(&mut score.miss_mm);
                let miss = if miss.is_finite() {
                    format!("{miss:.1} mm")
                } else {
                    format!("no object in {none} of {n}")
                };
                println!(
                    "| {} | {instrument_name} | {name} | {miss} | {} of {n} | {} % | {} | {lo:.2e}, {:.2e}, {hi:.2e} |",
                    tank.name,
                    score.sign_right,
                    100 * score.count_within_one / n,
                    median(&mut objects),
                    median(&mut alphas),
                );
            }
        }
    }
    Ok(())
}
