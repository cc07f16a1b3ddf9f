//! The data-collection procedure of docs/method.md §9 (Algorithms 2-3), on the simulator.
//!
//! The sheet is divided into a grid of classes. The grid is visited T times; at each visit
//! every class is pressed for S_num scans while the pressure is varied by hand (a random
//! pressure per scan between `pressure_pa`), the finger landing anywhere in the class's target
//! (`target_radius`) with a contact radius that differs from press to press (`radius_spread`).
//! The fabric still holds part of each press at the next (`creep`), and the front end drifts
//! during a visit (`drift`). Each scan's kept samples are cut into S_sub sub-sections whose medians
//! each give one observation, so a class collects n_c = T S_num S_sub observations. The
//! features are the frame values named by `feature_index` (the opposite protocol's
//! reciprocity-halved set by default: p = L (L - 4) / 2).

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use et_core::extract::Extracted;
use et_core::protocol::Halving;
use et_core::rng::Rng;
use et_core::{ScanConfig, Scanner};
use et_sim::frontend::{FrontendSpec, Hand, SetState, SimFrontend};
use et_sim::sheet::{SheetSpec, SimulatedSheet, Unevenness};
use et_sim::touch::{Footprint, Touch};
use nalgebra::DMatrix;

use crate::dataset::Dataset;

mod error;
mod size;
mod visits;
pub use error::CollectError;
pub use size::collection_bytes;
pub use visits::collect_visits;

/// Class centres on a rows x cols grid over the sheet's bounding box, inset by `margin` m
/// (cell centres, row-major from the lower left).
#[must_use]
pub fn grid(spec: &SheetSpec, rows: usize, cols: usize, margin: f64) -> Vec<[f64; 2]> {
    let [x0, y0, x1, y1] = spec.physical.shape.bounds();
    let (w, h) = (
        (x1 - x0 - 2.0 * margin) / cols as f64,
        (y1 - y0 - 2.0 * margin) / rows as f64,
    );
    (0..rows)
        .flat_map(|r| {
            (0..cols).map(move |c| {
                [
                    x0 + margin + (c as f64 + 0.5) * w,
                    y0 + margin + (r as f64 + 0.5) * h,
                ]
            })
        })
        .filter(|p| spec.physical.shape.contains(*p, 0.0))
        .collect()
}

/// The scan settings of docs/method.md §9's training scans, on top of `base` (electrodes, current,
/// gain): the opposite protocol, S = 3 200 samples per scan at 10 kHz (3 200 / L per step, a
/// fifth of each dropped as settling).
#[must_use]
pub fn training_config(base: ScanConfig) -> ScanConfig {
    let samples = (3_200 / u16::from(base.electrodes.max(1))).max(2);
    ScanConfig {
        protocol: et_core::ProtocolKind::Opposite,
        samples_per_step: samples,
        settle_samples: samples / 5,
        sample_rate_hz: 10_000,
        ..base
    }
}

/// How to collect.
#[derive(Clone, Debug)]
pub struct Plan {
    /// T: visits of the whole grid.
    pub visits: usize,
    /// S_num: scans per class per visit.
    pub scans: usize,
    /// S_sub: observations per scan.
    pub subsections: usize,
    /// Pressure range while pressing, Pa (docs/method.md §9: from below 10 kPa up).
    pub pressure_pa: (f64, f64),
    /// Finger contact radius, m (the median over presses).
    pub radius: f64,
    /// Relative rms of the contact radius from press to press (log-normal): fingers differ,
    /// and a finger pressed flatter or harder touches more fabric.
    pub radius_spread: f64,
    /// Radius of the target the finger's centre lands in, uniformly, m (the marked spot of a
    /// class: docs/method.md §9's 15 mm target for 49 classes is 7.5 mm).
    pub target_radius: f64,
    /// Fraction of a press's pressure the fabric still holds where it was pressed when the
    /// next press comes (slow elastic return, hysteresis), 0 to 1.
    pub creep: f64,
    /// How far the front end's state (junction potentials, conductance) moves during one
    /// visit, as a fraction of the spread between measurement sets: 0 = constant within a
    /// visit; 1 = by the visit's end as far as another set.
    pub drift: f64,
    /// Rms electrode movement along the outline between visits, m, were the clips put back
    /// between them (default none: the sheet stays mounted, as the front end's calibration
    /// between sets assumes, `et_sim::frontend::CALIBRATION_MOVEMENT_M`). Each visit is also a
    /// measurement set of the front end's `sets` (junction potentials, conductance).
    pub electrode_movement: f64,
    /// Electrode poses per visit: each press finds the electrodes in one of `poses` positions
    /// (drawn once per visit around the visit's positions), since pressing a frameless sheet
    /// pulls on its clips. 1 = the electrodes stay put within a visit.
    pub poses: usize,
    /// Rms movement of each pose around the visit's electrode positions, m.
    pub press_movement: f64,
    /// Rms change of each electrode's junction potential at every press, V: pressing a
    /// frameless sheet tugs on its clips, and a clip's contact potential moves with its
    /// contact pressure.
    pub press_junction: f64,
    /// Rms of each mode of the fabric's uneven conductance ([`et_sim::sheet::Unevenness`]),
    /// drawn anew at every visit (a measurement set): the fabric relaxes unevenly and
    /// temperature and humidity vary across it. 0 = uniform.
    pub unevenness: f64,
    /// Relative rms of the hand's force about each press's pressure while it scans
    /// ([`et_sim::frontend::Hand`]): docs/method.md §9's presses are held by hand, so a scan's
    /// injections see the touch at different strengths.
    pub wobble: f64,
    /// Correlation time of the hand's force, s.
    pub wobble_s: f64,
    /// Largest elongation of the contact ([`Footprint`]): each press's is drawn uniformly
    /// between 1 (the finger straight down) and this (the finger at its flattest). 1 = every
    /// contact a disc.
    pub elongation: f64,
    /// Direction the finger points on the sheet, rad from +x (pi / 2: the hand comes from the
    /// -y edge), and its rms from press to press, rad. Used when `elongation` > 1.
    pub finger_angle: (f64, f64),
    /// Seed of the session (electrode movement, placement, pressure, noise).
    pub seed: u64,
}

impl Default for Plan {
    /// docs/method.md §9's collection: T = 6 visits x S_num = 20 scans x S_sub = 20 observations,
    /// pressed from 5 to 60 kPa with a 7.5 mm finger (15 % spread) landing anywhere in its
    /// 15 mm target, the hand's force wandering 20 % rms over 0.1 s, each press moving the
    /// clips' junction potentials 15 uV rms, a tenth of each press's pressure still held at
    /// the next, the front end drifting half a set's spread during a visit, the sheet staying
    /// mounted; seed 1. docs/calibration.md says why (the wobble and the press junction were
    /// fitted to the reference's accuracies there).
    fn default() -> Self {
        Self {
            visits: 6,
            scans: 20,
            subsections: 20,
            pressure_pa: (5e3, 60e3),
            radius: 0.0075,
            radius_spread: 0.15,
            target_radius: 0.0075,
            creep: 0.1,
            drift: 0.5,
            electrode_movement: et_sim::frontend::CALIBRATION_MOVEMENT_M,
            poses: 1,
            press_movement: 0.0,
            press_junction: 15e-6,
            unevenness: 0.0,
            wobble: 0.2,
            wobble_s: 0.1,
            elongation: 1.0,
            finger_angle: (std::f64::consts::FRAC_PI_2, 0.35),
            seed: 1,
        }
    }
}

impl Plan {
    /// Checks the plan's lengths against the sheet (its bounding box's shorter side S): a
    /// finger of radius under S / 4 (so there is room to place it away from the outline), a
    /// target under S / 2 around each class centre, electrode movements under S / 4.
    ///
    /// # Errors
    /// [`CollectError::Plan`] naming the length, in mm, and the sheet's.
    pub fn fits(&self, shape: &et_core::sheet::Shape) -> Result<(), CollectError> {
        let [x0, y0, x1, y1] = shape.bounds();
        let side = (x1 - x0).min(y1 - y0);
        for (name, value, share) in [
            ("--radius-mm (the finger's radius)", self.radius, 0.25),
            (
                "--target-mm (the target around each class centre)",
                self.target_radius,
                0.5,
            ),
            (
                "--movement-mm (electrodes between visits)",
                self.electrode_movement,
                0.25,
            ),
            (
                "--press-movement-mm (electrodes between presses)",
                self.press_movement,
                0.25,
            ),
        ] {
            if !(value.is_finite() && value >= 0.0 && value <= share * side) {
                return Err(CollectError::Plan {
                    name,
                    value,
                    side,
                    limit: share * side,
                });
            }
        }
        Ok(())
    }

    /// One press's contact shape: a disc when `elongation` is 1 (drawing nothing, so that
    /// sessions without footprints keep their random streams), else an ellipse of elongation
    /// uniform in [1, `elongation`] along the finger's direction.
    #[must_use]
    pub fn footprint(&self, rng: &mut Rng) -> Footprint {
        if self.elongation <= 1.0 {
            return Footprint::ROUND;
        }
        let (direction, spread) = self.finger_angle;
        Footprint {
            elongation: 1.0
                + (self.elongation.min(et_sim::touch::MAX_ELONGATION) - 1.0) * rng.uniform(),
            angle: direction + spread * rng.normal(),
        }
    }
}

/// One press of the sheet: its label and its touches (the first touch's position and
/// pressure are what the dataset records).
#[derive(Clone, Debug)]
pub struct Press {
    /// Class (or, for touch-count sets, the number of touches).
    pub label: u16,
    /// The touches, at least one.
    pub touches: Vec<Touch>,
}

/// Runs the procedure on a simulated sheet. Every visit draws its own electrode positions from
/// `plan.seed`, so a second call with another seed is a "next day" test set.
///
/// # Errors
/// [`CollectError`] if the sheet cannot be built or a scan fails.
pub fn collect(
    spec: &SheetSpec,
    frontend: FrontendSpec,
    config: ScanConfig,
    centres: &[[f64; 2]],
    plan: &Plan,
) -> Result<Dataset, CollectError> {
    let pressed = AtomicUsize::new(0);
    collect_counting(spec, frontend, config, centres, plan, &pressed)
}

/// [`collect`], adding one to `pressed` after each press is scanned.
fn collect_counting(
    spec: &SheetSpec,
    frontend: FrontendSpec,
    config: ScanConfig,
    centres: &[[f64; 2]],
    plan: &Plan,
    pressed: &AtomicUsize,
) -> Result<Dataset, CollectError> {
    let grid_visit = |rng: &mut Rng| {
        let mut presses = Vec::with_capacity(centres.len() * plan.scans);
        for (c, centre) in centres.iter().enumerate() {
            for _ in 0..plan.scans {
                // Uniform over the target disc: radius sqrt(u), angle uniform.
                let (rho, phi) = (
                    plan.target_radius * rng.uniform().sqrt(),
                    std::f64::consts::TAU * rng.uniform(),
                );
                let (lo, hi) = plan.pressure_pa;
                presses.push(Press {
                    label: c as u16,
                    touches: vec![Touch {
                        position: [centre[0] + rho * phi.cos(), centre[1] + rho * phi.sin()],
                        radius: plan.radius * (plan.radius_spread * rng.normal()).exp(),
                        pressure: lo + (hi - lo) * rng.uniform(),
                        footprint: plan.footprint(rng),
                    }],
                });
            }
        }
        presses
    };
    let halving = Halving::Reciprocity;
    collect_presses_counted(
        spec,
        (frontend, config),
        centres,
        plan,
        halving,
        grid_visit,
        pressed,
    )
}

/// `count` presses of `touches` fingers each, anywhere on the sheet (uniform over the outline
/// kept `plan.radius` inside it), pressure uniform in `plan.pressure_pa`, contact radius
/// spread by `plan.radius_spread`; labelled with the
/// number of touches. For regression (continuous position, pressure) and touch counting.
pub fn random_presses(
    spec: &SheetSpec,
    plan: &Plan,
    count: usize,
    touches: usize,
) -> impl FnMut(&mut Rng) -> Vec<Press> {
    let shape = spec.physical.shape.clone();
    let [x0, y0, x1, y1] = shape.bounds();
    let (radius, spread, (lo, hi)) = (plan.radius, plan.radius_spread, plan.pressure_pa);
    let plan = plan.clone();
    move |rng: &mut Rng| {
        (0..count)
            .map(|_| Press {
                label: touches as u16,
                touches: (0..touches)
                    .map(|_| {
                        // Rejection sampling, bounded: a sheet with no room for the finger
                        // anywhere (a thin strip) gets presses at its bounding box's centre.
                        let position = (0..100_000)
                            .map(|_| {
                                [
                                    x0 + (x1 - x0) * rng.uniform(),
                                    y0 + (y1 - y0) * rng.uniform(),
                                ]
                            })
                            .find(|&p| shape.contains(p, radius))
                            .unwrap_or([0.5 * (x0 + x1), 0.5 * (y0 + y1)]);
                        Touch {
                            position,
                            radius: radius * (spread * rng.normal()).exp(),
                            pressure: lo + (hi - lo) * rng.uniform(),
                            footprint: plan.footprint(rng),
                        }
                    })
                    .collect(),
            })
            .collect()
    }
}

/// The collection loop under [`collect`]: `plan.visits` visits (electrodes moved by
/// `plan.electrode_movement`, an untouched frame first, then the presses `visit` draws, each
/// scanned into `plan.subsections` observations, in one of `plan.poses` electrode poses).
///
/// # Errors
/// [`CollectError`] if the sheet cannot be built or a scan fails.
pub fn collect_presses(
    spec: &SheetSpec,
    frontend: FrontendSpec,
    config: ScanConfig,
    centres: &[[f64; 2]],
    plan: &Plan,
    visit_presses: impl FnMut(&mut Rng) -> Vec<Press>,
) -> Result<Dataset, CollectError> {
    collect_presses_with(
        spec,
        frontend,
        config,
        centres,
        plan,
        Halving::Reciprocity,
        visit_presses,
    )
}

/// [`collect_presses`] keeping the frame values `halving` names (all of them with
/// [`Halving::None`]: 192 for 16 electrodes opposite, as a board that reads both polarities
/// records them).
///
/// # Errors
/// [`CollectError`] if the sheet cannot be built or a scan fails.
pub fn collect_presses_with(
    spec: &SheetSpec,
    frontend: FrontendSpec,
    config: ScanConfig,
    centres: &[[f64; 2]],
    plan: &Plan,
    halving: Halving,
    visit_presses: impl FnMut(&mut Rng) -> Vec<Press>,
) -> Result<Dataset, CollectError> {
    let pressed = AtomicUsize::new(0);
    let scan = (frontend, config);
    collect_presses_counted(spec, scan, centres, plan, halving, visit_presses, &pressed)
}

/// [`collect_presses_with`] (the front end and its scan configuration as `scan`), adding
/// one to `pressed` after each press is scanned.
fn collect_presses_counted(
    spec: &SheetSpec,
    (frontend, config): (FrontendSpec, ScanConfig),
    centres: &[[f64; 2]],
    plan: &Plan,
    halving: Halving,
    mut visit_presses: impl FnMut(&mut Rng) -> Vec<Press>,
    pressed: &AtomicUsize,
) -> Result<Dataset, CollectError> {
    let protocol = config.validate()?;
    plan.fits(&spec.physical.shape)?;
    let feature_index: Vec<u16> = protocol.features(halving).map(|k| k as u16).collect();
    let mut rng = Rng::new(plan.seed);
    let k = protocol.frame_len();
    let s_sub = plan.subsections;
    let mut burst = vec![0u16; usize::from(config.samples_per_step)];
    let mut scratch = vec![
        Extracted {
            median_code: 0.0,
            rail_samples: 0
        };
        s_sub
    ];
    let mut obs = vec![0.0f32; s_sub * k];
    let mut rows = Rows::default();
    let mut baselines = Vec::new();
    let electrodes = usize::from(spec.physical.electrodes.count);
    let hand = Hand {
        wobble: plan.wobble,
        correlation_s: plan.wobble_s,
    };
    for v in 0..plan.visits {
        // A frameless sheet is handled between visits: its electrodes sit somewhere else
        // within their movement each time.
        let offsets: Vec<f64> = (0..electrodes)
            .map(|_| plan.electrode_movement * rng.normal())
            .collect();
        let field = (plan.unevenness > 0.0).then(|| Unevenness::draw(plan.unevenness, &mut rng));
        let build = |offsets: &[f64]| match &field {
            Some(f) => SimulatedSheet::uneven(spec, offsets, f),
            None => SimulatedSheet::new(spec, offsets),
        };
        // Each visit is a measurement set: the junction potentials and the sheet's
        // conductance differ from the last.
        let set = frontend.sets.draw(electrodes, &mut rng);
        let held = |sheet, seed| posed(sheet, frontend, &set, hand, seed, config);
        let (mut fe, scanner) = held(build(&offsets)?, rng.next_u64())?;
        // The untouched frame, as the sheet lies before the first press.
        scanner.scan_subsections(&mut fe, &mut burst, s_sub, &mut scratch, &mut obs)?;
        let untouched: Vec<&[f32]> = obs.chunks(k).collect();
        let mut v0 = vec![0.0; k];
        et_core::stats::reference(&untouched, &mut v0)?;
        baselines.extend(feature_index.iter().map(|&i| v0[usize::from(i)]));
        let mut poses = vec![fe];
        for _ in 1..plan.poses {
            let moved: Vec<f64> = offsets
                .iter()
                .map(|o| o + plan.press_movement * rng.normal())
                .collect();
            poses.push(held(build(&moved)?, rng.next_u64())?.0);
        }
        // Where the front end's state heads during the visit (a fraction `drift` of the way
        // to another set by its end).
        let heading = frontend.sets.draw(electrodes, &mut rng);
        let presses = visit_presses(&mut rng);
        let count = presses.len().max(1) as f64;
        let mut remnants: Vec<Touch> = Vec::new();
        for (i, press) in presses.into_iter().enumerate() {
            let Some(first) = press.touches.first().copied() else {
                return Err(CollectError::EmptyPress { label: press.label });
            };
            let pose = (rng.uniform() * poses.len() as f64) as usize % poses.len();
            let fe = &mut poses[pose];
            let mut state = drifted(&set, &heading, plan.drift * i as f64 / count);
            for e in &mut state.contact_potentials_v {
                *e += plan.press_junction * rng.normal();
            }
            fe.set_state(&state).map_err(CollectError::Sim)?;
            // The fabric still holds part of the last press where it was.
            let mut touches = press.touches.clone();
            touches.extend(remnants.iter().copied());
            fe.set_touches(&touches)?;
            remnants = press
                .touches
                .iter()
                .filter(|_| plan.creep > 0.0)
                .map(|t| Touch {
                    pressure: plan.creep * t.pressure,
                    ..*t
                })
                .collect();
            scanner.scan_subsections(fe, &mut burst, s_sub, &mut scratch, &mut obs)?;
            rows.push(&obs, k, &feature_index, (press.label, first, v as u16));
            pressed.fetch_add(1, Ordering::Relaxed);
        }
    }
    Ok(Dataset {
        x: DMatrix::from_row_slice(rows.y.len(), feature_index.len(), &rows.x),
        y: rows.y,
        positions: rows.positions,
        pressure: rows.pressures,
        electrodes: (spec.physical.electrodes).centres(&spec.physical.shape),
        centres: centres.to_vec(),
        visit: rows.visit,
        baselines: DMatrix::from_row_slice(plan.visits, feature_index.len(), &baselines),
        feature_index,
        config,
    })
}

/// The rows a collection gathers, one per scan: the features (row-major), then each row's
/// label, first touch's position (m) and pressure (Pa), and visit.
#[derive(Default)]
struct Rows {
    x: Vec<f64>,
    y: Vec<u16>,
    positions: Vec<[f64; 2]>,
    pressures: Vec<f64>,
    visit: Vec<u16>,
}

impl Rows {
    /// One row per frame of `obs` (frames of `k` values): the features `feature_index` reads,
    /// with the press's label, its first touch's position and pressure, and the visit.
    fn push(&mut self, obs: &[f32], k: usize, feature_index: &[u16], of: (u16, Touch, u16)) {
        let (label, first, visit) = of;
        for o in obs.chunks(k) {
            self.x
                .extend(feature_index.iter().map(|&i| f64::from(o[usize::from(i)])));
            self.y.push(label);
            self.positions.push(first.position);
            self.pressures.push(first.pressure);
            self.visit.push(visit);
        }
    }
}

/// A simulated front end on `sheet` (its noise drawn from `seed`) in the measurement set
/// `set`, held by `hand`, with the scanner for `config` set up on it.
fn posed(
    sheet: SimulatedSheet,
    frontend: FrontendSpec,
    set: &SetState,
    hand: Hand,
    seed: u64,
    config: ScanConfig,
) -> Result<(SimFrontend, Scanner), CollectError> {
    let mut fe = SimFrontend::new(Arc::new(sheet), frontend, seed)?;
    fe.set_state(set).map_err(CollectError::Sim)?;
    fe.set_hand(hand).map_err(CollectError::Sim)?;
    let scanner = Scanner::new(config, &mut fe)?;
    Ok((fe, scanner))
}

/// The set `start` moved a fraction `f` of the way to `heading`'s deviation from nominal:
/// junction potentials add `f` of `heading`'s, the conductance multiplies by its `f`th power.
fn drifted(start: &SetState, heading: &SetState, f: f64) -> SetState {
    SetState {
        contact_potentials_v: start
            .contact_potentials_v
            .iter()
            .zip(&heading.contact_potentials_v)
            .map(|(a, d)| a + f * d)
            .collect(),
        conductance_scale: start.conductance_scale * heading.conductance_scale.powf(f),
    }
}
