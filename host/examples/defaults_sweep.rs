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

use et_recon::gcv::Criterion;
use et_recon::reconstructor::MISMATCH_FACTOR;
use et_recon::{AlphaRule, Method, Reconstructor, Reference, Spec};
use et_sim::foreign::{self, Instrument, Mismatch};
use et_sim::sheet::SimulatedSheet;
use et_sim::touch::Inclusion;

#[path = "../tests/support/stand_in.rs"]
mod stand_in;
use stand_in::{Score, Tank, cases, median, tanks};

/// A rule: its name, alpha's rule, the model's error counted (None: the constant shares of
/// before).
type Rule = (&'static str, AlphaRule, Option<f64>);

/// An instrument, and the tank's departures from its model (None: the network as drawn).
type Setting = (&'static str, Instrument, Option<Mismatch>);

/// The real tank's mismatch: [`Mismatch::tank`] (its draw seeded by ET_SWEEP_SEED, default
/// 5), or ET_SWEEP_MISMATCH="position, width, contact spread, contact drift, unevenness" to
/// try others.
fn mismatch() -> Mismatch {
    let seed = std::env::var("ET_SWEEP_SEED").map_or(5, |s| s.parse().unwrap_or(5));
    let mut m = Mismatch::tank(seed);
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
    let mut rules = rules();
    let only = std::env::var("ET_SWEEP_RULES").unwrap_or_default();
    rules.retain(|r| only.is_empty() || only.split(';').any(|o| r.0.contains(o)));
    let n = 24;
    println!(
        "| tank | instrument | alpha | strongest object to nearest rod, median | its sign right | count within one | objects, median | alpha chosen (min, median, max) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut instruments = instruments();
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
                "{}, {instrument_name}: background {:.1} ohm/sq (truth 230), contact {:.1} ohm (truth 60; the models' electrodes differ), residual {:.2} % ({:.2} % on drive electrodes, {:.2} % off them; the scene's guess: {:.1} %); worst electrode {}",
                tank.name,
                fit.sheet_resistance,
                fit.contact_ohm,
                100.0 * fit.residual,
                100.0 * fit.misfit_on_drive.unwrap_or(f64::NAN),
                100.0 * fit.misfit_off_drive.unwrap_or(f64::NAN),
                100.0 * fit.scene_residual,
                fit.worst_electrode.map_or("none".into(), |w| format!(
                    "{} (0-based): its values {:.1} % off the model, the rest {:.1} %{}",
                    w.electrode,
                    100.0 * w.own,
                    100.0 * w.rest,
                    if w.stands_out() { ", named" } else { "" }
                ))
            );
            for &rule in &rules {
                let run = Run {
                    tank: &tank,
                    instrument_name,
                    cases: &cases,
                    frames: &frames,
                    reference: &reference,
                };
                run.row(&mut recon, rule)?;
            }
        }
    }
    Ok(())
}

/// Every rule the table compares, the defaults of before and now among them.
fn rules() -> Vec<Rule> {
    vec![
        ("before (GCV above noise + 1 % of dV)", AlphaRule::Gcv, None),
        (
            "GCV above noise + 2 x misfit (the default before the corner)",
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
            "default: the corner above GCV's (noise + 1 % of dV)",
            AlphaRule::Chosen(Criterion::CornerAboveFloor),
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
        ("fixed 3", AlphaRule::Fixed(3.0), Some(MISMATCH_FACTOR)),
    ]
}

/// The instruments the frames are measured by, and the tank's mismatch beside the last.
fn instruments() -> Vec<Setting> {
    vec![
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
            "very noisy",
            Instrument {
                noise: 1e-2,
                proportional: 1e-2,
                ..Instrument::laboratory(11)
            },
            None,
        ),
        (
            "laboratory, a real tank's mismatch",
            Instrument::laboratory(11),
            Some(mismatch()),
        ),
    ]
}

/// One tank's frames under one instrument, as every rule images them.
struct Run<'a> {
    tank: &'a Tank,
    instrument_name: &'a str,
    /// The cases' rods, and each frame (the reference's first).
    cases: &'a [Vec<Inclusion>],
    frames: &'a [Vec<f64>],
    reference: &'a Reference,
}

impl Run<'_> {
    /// Every case imaged under `rule`: its table row.
    fn row(&self, recon: &mut Reconstructor, (name, rule, factor): Rule) -> anyhow::Result<()> {
        let Run {
            tank,
            instrument_name,
            cases,
            frames,
            reference,
        } = *self;
        let n = cases.len();
        recon.set_mismatch_factor(factor);
        recon.set_method(Method::default(), rule)?;
        // The linearisation's misfit at each case's image (ET_LINEAR).
        let mut linear: Vec<f64> = Vec::new();
        let want_linear = std::env::var_os("ET_LINEAR").is_some();
        let mut score = Score::of(
            recon,
            reference,
            cases,
            &frames[1..],
            want_linear.then_some(&mut linear),
        )?;
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
        Ok(())
    }
}
