//! A stand-in for another lab's sensor, in that lab's file format, made on the simulated
//! sheet: what `et train --features F.csv --targets T.csv` is tested on and what the
//! comparison with scikit-learn runs.
//!
//! The shape follows a published kind of e-skin data set: 16 electrodes, the opposite
//! protocol read in both polarities without reciprocity halving (16 x 12 = 192 values per
//! row), each row one press anywhere in an 80 mm disc, the values pressed minus unpressed in
//! board units (ADC codes); the targets x, y, z in metres in a robot's frame (the sheet lies
//! at z = 50 mm, centred at (350, -120) mm; z falls with the press's depth) in a second file.
//! Both files start with a UTF-8 byte-order mark and have no header row. Rows are in time
//! order: several sessions, the electrodes moved between sessions and a little from press to
//! press, the unpressed frame taken once per session (so drift is in the data), pressure
//! uniform from 5 to 60 kPa, fingertips of 6 to 9 mm radius.

use std::io::Write as _;
use std::path::Path;

use et_core::protocol::Halving;
use et_core::rng::Rng;
use et_sim::scene::Scene;
use et_sim::touch::Touch;
use nalgebra::DMatrix;

use super::collect::{CollectError, Plan, Press, collect_presses_with, training_config};

/// The sheet: a 100 mm disc of the 30 kOhm fabric with 16 clip electrodes.
const SCENE: &str = r#"
description = "stand-in e-skin: 100 mm disc, 16 electrodes, opposite protocol"
[sheet]
shape = { kind = "disc", radius = 0.05 }
sheet_resistance = 30e3
electrodes = { count = 16, width = 0.004, contact_ohm = 1000 }
[scan]
protocol = "opposite"
current_ua = 32
"#;

/// Where the sheet sits in the robot's frame, m.
pub const SHEET_ORIGIN_M: [f64; 3] = [0.35, -0.12, 0.05];
/// Presses land uniformly in a disc of this radius, m.
pub const PRESS_DISC_RADIUS_M: f64 = 0.04;
/// Board units: ADC codes per volt (16 bits over +-5 V).
pub const CODES_PER_VOLT: f64 = 65_536.0 / 10.0;

/// The stand-in data: features in board units and targets in metres, rows in time order.
#[derive(Clone, Debug)]
pub struct StandIn {
    /// n x 192 pressed-minus-unpressed values, ADC codes.
    pub features: DMatrix<f64>,
    /// x, y, z in metres in the robot's frame.
    pub targets_m: Vec<[f64; 3]>,
    /// The session of each row (0-based).
    pub session: Vec<u16>,
    /// n x 192: the frame taken before each press (its session's untouched frame as
    /// measured then), ADC codes: the pressed frame is `features + before`.
    pub before: DMatrix<f64>,
}

/// How a sensor changes between sessions beyond its electrodes moving (which every stand-in
/// has): each channel's gain (the contacts and the amplifier path of each measured pair) and
/// a per-channel offset (a reference frame that no longer matches the sheet: the fabric
/// relaxed, the contacts settled). Drawn anew for each session; the first session is as
/// measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SessionDrift {
    /// Standard deviation of each channel's relative gain change (0.1 = 10 %).
    pub gain: f64,
    /// Standard deviation of each channel's offset, as a share of that channel's spread over
    /// the presses.
    pub offset: f64,
}

impl SessionDrift {
    /// No drift beyond the electrodes' movement.
    pub const NONE: Self = Self {
        gain: 0.0,
        offset: 0.0,
    };
    /// Drift like separate sessions on a real skin: gains within about 15 % and offsets of
    /// a quarter of a channel's spread.
    pub const SESSIONS: Self = Self {
        gain: 0.15,
        offset: 0.25,
    };
}

/// `presses` rows over `sessions` sessions (at least 1), from `seed`.
///
/// # Errors
/// [`CollectError`] if the simulated sheet cannot be built or scanned.
pub fn make(presses: usize, sessions: usize, seed: u64) -> Result<StandIn, CollectError> {
    make_drifting(presses, sessions, seed, SessionDrift::NONE)
}

/// [`make`] with `drift` between sessions.
///
/// # Errors
/// [`CollectError`] if the simulated sheet cannot be built or scanned.
pub fn make_drifting(
    presses: usize,
    sessions: usize,
    seed: u64,
    drift: SessionDrift,
) -> Result<StandIn, CollectError> {
    let scene = Scene::parse(SCENE, "stand-in").map_err(CollectError::Scene)?;
    let config = training_config(scene.scan_config().map_err(CollectError::SceneField)?);
    let sessions = sessions.max(1);
    let per_session = presses.div_ceil(sessions);
    let plan = plan(sessions, seed);
    let draw = |rng: &mut Rng| -> Vec<Press> {
        (0..per_session)
            .map(|_| {
                // Uniform in the disc: radius by the square root.
                let (r, a) = (
                    PRESS_DISC_RADIUS_M * rng.uniform().sqrt(),
                    std::f64::consts::TAU * rng.uniform(),
                );
                Press {
                    label: 0,
                    touches: vec![Touch {
                        position: [r * a.cos(), r * a.sin()],
                        radius: 0.006 + 0.003 * rng.uniform(),
                        pressure: 5e3 + 55e3 * rng.uniform(),
                        footprint: Default::default(),
                    }],
                }
            })
            .collect()
    };
    let data = collect_presses_with(
        &scene.sheet,
        scene.frontend,
        config,
        &[],
        &plan,
        Halving::None,
        draw,
    )?;
    let n = presses.min(data.x.nrows());
    let features = data.features(true).map_err(CollectError::Data)?;
    let mut features = DMatrix::from_fn(n, features.ncols(), |r, j| {
        features[(r, j)] * CODES_PER_VOLT
    });
    let session: Vec<u16> = data.visit.iter().take(n).copied().collect();
    // The frame taken before each press: its session's untouched frame.
    let mut before = DMatrix::from_fn(n, features.ncols(), |r, j| {
        data.baselines
            .get((usize::from(session[r]), j))
            .copied()
            .unwrap_or(0.0)
            * CODES_PER_VOLT
    });
    drift_sessions(&mut features, &mut before, &session, sessions, seed, drift);
    let targets_m = (0..n)
        .map(|r| {
            let p = data.positions[r];
            let depth = 0.002 * data.pressure[r] / 60e3;
            [
                SHEET_ORIGIN_M[0] + p[0],
                SHEET_ORIGIN_M[1] + p[1],
                SHEET_ORIGIN_M[2] - depth,
            ]
        })
        .collect();
    Ok(StandIn {
        features,
        targets_m,
        session,
        before,
    })
}

/// The stand-in's collection: `sessions` visits of one scan each, their variety in the presses
/// the stand-in draws, electrodes moved a little between visits.
fn plan(sessions: usize, seed: u64) -> Plan {
    Plan {
        visits: sessions,
        scans: 1,
        subsections: 1,
        pressure_pa: (5e3, 60e3),
        radius: 0.0075,
        // The stand-in's own presses (below) carry their variety; the collection adds none.
        radius_spread: 0.0,
        target_radius: 0.0,
        creep: 0.0,
        drift: 0.0,
        electrode_movement: 0.0005,
        poses: 4,
        press_movement: 0.0002,
        press_junction: 0.0,
        unevenness: 0.0,
        wobble: 0.0,
        wobble_s: 0.1,
        elongation: 1.0,
        finger_angle: (0.0, 0.0),
        seed,
    }
}

/// Each session after the first drawn its own channel gains and offsets (`drift`, offsets in
/// units of each channel's spread): `features` (pressed minus before) become gain x change +
/// offset, `before` gain x before - offset. No change for [`SessionDrift::NONE`].
fn drift_sessions(
    features: &mut DMatrix<f64>,
    before: &mut DMatrix<f64>,
    session: &[u16],
    sessions: usize,
    seed: u64,
    drift: SessionDrift,
) {
    let n = session.len();
    if drift != SessionDrift::NONE {
        let mut rng = Rng::new(seed ^ 0x5e55_1011);
        let spread: Vec<f64> = (0..features.ncols())
            .map(|j| {
                let c = features.column(j);
                c.variance().sqrt()
            })
            .collect();
        for s in 1..sessions {
            let (gain, offset): (Vec<f64>, Vec<f64>) = spread
                .iter()
                .map(|sd| {
                    (
                        1.0 + drift.gain * rng.normal(),
                        drift.offset * sd * rng.normal(),
                    )
                })
                .unzip();
            for r in (0..n).filter(|&r| usize::from(session[r]) == s) {
                for j in 0..features.ncols() {
                    // The pressed frame and the frame before it both pass through the
                    // channel's gain; the frame before is stale by the offset (the sheet
                    // settled since): pressed - before = gain x change + offset.
                    features[(r, j)] = features[(r, j)] * gain[j] + offset[j];
                    before[(r, j)] = before[(r, j)] * gain[j] - offset[j];
                }
            }
        }
    }
}

impl StandIn {
    /// Writes the two files as the other lab's tools do: a UTF-8 byte-order mark, no header,
    /// CRLF line ends, numbers like `1.5E-05`.
    ///
    /// # Errors
    /// The I/O error.
    pub fn write(&self, features: &Path, targets: &Path) -> std::io::Result<()> {
        self.write_all(features, targets, None)
    }

    /// The pressed frames (`features + before`) and the frames before them, as a sensor that
    /// records both writes them (same dialect as [`write`](Self::write)): for
    /// `--reference-features`.
    ///
    /// # Errors
    /// The I/O error.
    pub fn write_frames(&self, pressed: &Path, before: &Path) -> std::io::Result<()> {
        write_matrix(pressed, &(&self.features + &self.before))?;
        write_matrix(before, &self.before)
    }

    /// [`write`](Self::write), and each row's session (`session-1`, ...) one per line in
    /// `sessions` when given.
    ///
    /// # Errors
    /// The I/O error.
    pub fn write_all(
        &self,
        features: &Path,
        targets: &Path,
        sessions: Option<&Path>,
    ) -> std::io::Result<()> {
        if let Some(path) = sessions {
            let text: String = self
                .session
                .iter()
                .map(|s| format!("session-{}\n", s + 1))
                .collect();
            std::fs::write(path, text)?;
        }
        write_matrix(features, &self.features)?;
        let mut t = std::io::BufWriter::new(std::fs::File::create(targets)?);
        t.write_all("\u{feff}".as_bytes())?;
        for p in &self.targets_m {
            write!(t, "{:.6E},{:.6E},{:.6E}\r\n", p[0], p[1], p[2])?;
        }
        t.flush()
    }
}

/// A matrix as the other lab's tools write one: byte-order mark, no header, CRLF, `1.5E-05`.
fn write_matrix(path: &Path, m: &DMatrix<f64>) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    f.write_all("\u{feff}".as_bytes())?;
    for row in m.row_iter() {
        let cells: Vec<String> = row.iter().map(|v| format!("{v:.6E}")).collect();
        write!(f, "{}\r\n", cells.join(","))?;
    }
    f.flush()
}
