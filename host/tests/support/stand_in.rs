//! Simulated saline tanks as other labs build them, measured by the simulator's resistor
//! network (not the reconstruction's finite elements), and the score of a rule on them: the
//! strongest object's distance to the nearest rod, its sign, the object count.
//!
//! Shared by the stand-in's regression test (`host/tests/stand_in.rs`) and the sweep's example
//! (`host/examples/defaults_sweep.rs`).

#![allow(dead_code)]

use et_core::rng::Rng;
use et_core::schedule::Schedule;
use et_recon::{Reconstructor, Reference};
use et_sim::scene::Scene;
use et_sim::touch::{Footprint, Inclusion};

/// A tank: the user's scene, the truth the simulator measures, and the protocol.
pub struct Tank {
    pub name: &'static str,
    pub scene: Scene,
    pub truth: Scene,
    pub schedule: Schedule,
    pub radius: f64,
}

/// A disc tank of `radius` with `electrodes` (`extra` TOML keys), the user's guesses of
/// 200 ohm/sq and 20 ohm contacts; the truth 230 ohm/sq and 60 ohm.
pub fn tank(name: &'static str, radius: f64, electrodes: &str, schedule: Schedule) -> Tank {
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
pub fn tanks() -> Vec<Tank> {
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
pub fn cases(radius: f64, n: usize, seed: u64, [metal, plastic]: [f64; 2]) -> Vec<Vec<Inclusion>> {
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
pub struct Score {
    /// The strongest object's distance to the nearest rod, mm (infinite: no object).
    pub miss_mm: Vec<f64>,
    /// Cases whose strongest object has the nearest rod's sign.
    pub sign_right: usize,
    /// Cases whose object count is within one of the rods'.
    pub count_within_one: usize,
    /// The alpha each case was imaged at.
    pub alphas: Vec<f64>,
    /// Each case's object count.
    pub objects: Vec<usize>,
}

pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

impl Score {
    /// `recon`'s images of `frames` (one a case, V) against `reference`, scored against each
    /// case's `rods`; `linear` collects each image's linearisation misfit when given.
    ///
    /// # Errors
    /// A failed image.
    pub fn of(
        recon: &mut Reconstructor,
        reference: &Reference,
        cases: &[Vec<Inclusion>],
        frames: &[Vec<f64>],
        mut linear: Option<&mut Vec<f64>>,
    ) -> anyhow::Result<Self> {
        let mut score = Score::default();
        for (rods, frame) in cases.iter().zip(frames) {
            let frame: Vec<f32> = frame.iter().map(|&v| v as f32).collect();
            let image = recon.image(&frame, reference)?;
            if let Some(linear) = linear.as_deref_mut()
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
            let d = |o: &Inclusion| (o.position[0] - c[0]).hypot(o.position[1] - c[1]);
            let nearest = rods
                .iter()
                .min_by(|a, b| d(a).total_cmp(&d(b)))
                .expect("a rod");
            score.miss_mm.push(1e3 * d(nearest));
            if (first.sign > 0) == (nearest.multiplier > 1.0) {
                score.sign_right += 1;
            }
        }
        Ok(score)
    }

    /// The median distance from the strongest object to the nearest rod, mm.
    #[must_use]
    pub fn median_miss_mm(&self) -> f64 {
        median(&mut self.miss_mm.clone())
    }

    /// The median of `values`.
    #[must_use]
    pub fn median_of(values: &[f64]) -> f64 {
        median(&mut values.to_vec())
    }
}
