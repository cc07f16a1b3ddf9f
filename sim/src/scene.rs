//! Scenes: a TOML file that says everything the simulator needs (docs/design.md, "Scenes"): the
//! sheet and its electrodes, the scan settings, the front end, touches over time, and a seed.
//! Every table refuses unknown keys, so a typo is an error naming the key, not a silent
//! default. See `sim/scenes/*.toml` for examples of every geometry of docs/method.md §1 and the
//! reference scenarios of docs/method.md §7.
//!
//! A scene costs what it asks for: the grid follows the sheet's size and electrodes (see
//! [`SheetSpec::default_resolution`]), and nothing is simulated that the scene does not name.

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::Path;
use std::sync::Arc;

use et_core::protocol::ProtocolKind;
use et_core::scan::ScanError;
pub use et_core::sheet::FieldFault;
use et_core::wire::{Frame, WireError};
use et_core::{Micros, ScanConfig, Scanner};
use serde::{Deserialize, Serialize};

use crate::frontend::{FrontendSpec, SimError, SimFrontend};
use crate::sheet::{SheetError, SheetSpec, SimulatedSheet};
use crate::touch::{Footprint, Touch};
use et_core::rng::Rng;

/// A scene's protocol: a built-in one by name, or any system's from a file.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ProtocolSpec {
    /// adjacent, pseudo-polar, pp-pp or opposite (`protocol = "adjacent"`).
    Named(String),
    /// Any system's protocol (`protocol = { file = "protocol.csv" }`): a CSV with one row per
    /// frame value, `source,sink,positive,negative` and optionally `current_a`
    /// ([`et_core::schedule::Schedule::parse_csv`]). Imaged, not scanned by the simulated
    /// board.
    File(ProtocolFile),
}

/// A protocol file and how it counts electrodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProtocolFile {
    /// The CSV, relative to the scene file.
    pub file: std::path::PathBuf,
    /// The number of the first electrode in the file: 0 (et's), or 1.
    #[serde(default, deserialize_with = "et_core::whole::whole")]
    pub base: u16,
}

/// A name or a table, each read as itself: a damaged `{ ... }` is told by the field that is
/// wrong (an untagged enum said only that no variant matched).
impl<'de> Deserialize<'de> for ProtocolSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Spec;
        impl<'de> serde::de::Visitor<'de> for Spec {
            type Value = ProtocolSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(
                    "a built-in protocol's name (\"adjacent\", \"pseudo-polar\", \"pp-pp\", \
                     \"opposite\") or a file, { file = \"protocol.csv\", base = 0 or 1 }",
                )
            }
            fn visit_str<E: serde::de::Error>(self, name: &str) -> Result<ProtocolSpec, E> {
                Ok(ProtocolSpec::Named(name.into()))
            }
            fn visit_map<M: serde::de::MapAccess<'de>>(
                self,
                m: M,
            ) -> Result<ProtocolSpec, M::Error> {
                ProtocolFile::deserialize(serde::de::value::MapAccessDeserializer::new(m))
                    .map(ProtocolSpec::File)
            }
        }
        d.deserialize_any(Spec)
    }
}

impl Default for ProtocolSpec {
    fn default() -> Self {
        Self::Named("adjacent".into())
    }
}

/// How a scene's frames are scanned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScanSpec {
    /// The protocol: a built-in one's name, or a file of any system's measurements.
    pub protocol: ProtocolSpec,
    /// Samples per injection step (S / L).
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub samples_per_step: u16,
    /// t_s, samples dropped per step.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub settle_samples: u16,
    /// Injected current, uA (the simulated board drives up to 1 000; imaging recorded frames
    /// takes up to 50 000, a tank's milliamperes; a protocol file may give a current per row).
    pub current_ua: f64,
    /// Sample rate per channel, Hz.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub sample_rate_hz: u32,
    /// PGIA gain.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub gain: u8,
    /// Whether the file gave `current_ua` (a protocol file's rows may give their own; one
    /// beside them that differs is refused, not ignored).
    #[serde(skip)]
    pub current_given: bool,
}

impl Default for ScanSpec {
    /// The reference operating point of docs/method.md §3.
    fn default() -> Self {
        let r = ScanConfig::REFERENCE;
        Self {
            protocol: ProtocolSpec::default(),
            samples_per_step: r.samples_per_step,
            settle_samples: r.settle_samples,
            current_ua: f64::from(r.current_na) / 1e3,
            sample_rate_hz: r.sample_rate_hz,
            gain: r.gain,
            current_given: false,
        }
    }
}

/// Electrode movement of a frameless sheet: every electrode sits off its nominal place along
/// the outline by a random amount (normal, this rms), drawn once per scene from the seed.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Movement {
    /// Rms offset along the outline, m.
    pub rms: f64,
}

/// The largest touch pressure a scene takes, Pa: 1 GPa, past which no fabric is pressed
/// (steel yields near 0.25 GPa); the fabric's law saturates near a finger's tens of kPa.
pub const MAX_PRESSURE_PA: f64 = 1e9;

/// The longest load or unload time constant a scene takes, s: a day.
pub const MAX_TIME_CONSTANT_S: f64 = 86_400.0;

/// How the fabric follows pressure: loading is quick, unloading slow (elastic return), and a
/// pressed fabric stays a little more conductive than on the way in (hysteresis).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Dynamics {
    /// Time constant while the pressure rises, s.
    pub load_s: f64,
    /// Time constant while it falls (slow elastic return), s.
    pub unload_s: f64,
    /// Fraction of the peak pressure the fabric keeps "remembering" while unloading.
    pub hysteresis: f64,
}

impl Default for Dynamics {
    fn default() -> Self {
        Self {
            load_s: 0.02,
            unload_s: 0.3,
            hysteresis: 0.1,
        }
    }
}

/// One touch over time. Before `start` and after `end` it is off (its effect then fades
/// with the unloading dynamics); in between it moves linearly from `position` to `to`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TouchEvent {
    /// Centre at `start`, m.
    #[serde(deserialize_with = "et_core::sheet::xy::one")]
    pub position: [f64; 2],
    /// Centre at `end` (default: not moving), m.
    #[serde(default, deserialize_with = "et_core::sheet::xy::option")]
    pub to: Option<[f64; 2]>,
    /// Contact radius, m.
    pub radius: f64,
    /// Pressure while on, Pa.
    pub pressure: f64,
    /// The contact's shape (default a disc; `footprint = { elongation = 1.5, angle = 1.57 }`
    /// for a finger pressed at a slant, its long axis along `angle` rad from +x).
    #[serde(default)]
    pub footprint: Footprint,
    /// When it lands, s (default 0).
    #[serde(default)]
    pub start: f64,
    /// When it lifts, s (default: never).
    #[serde(default)]
    pub end: Option<f64>,
}

impl TouchEvent {
    /// The touch at its start position and full pressure (its timing ignored): a still
    /// picture of the scene.
    #[must_use]
    pub fn touch(&self) -> Touch {
        Touch {
            position: self.position,
            radius: self.radius,
            pressure: self.pressure,
            footprint: self.footprint,
        }
    }
}

/// What is wrong with an electrode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FaultKind {
    /// The contact is open for good.
    Disconnected,
    /// The contact opens now and then (`probability` per step).
    Intermittent,
    /// Shorted to electrode `with`.
    Shorted,
}

/// An electrode fault.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fault {
    /// The faulty electrode.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub electrode: u8,
    /// What is wrong.
    pub kind: FaultKind,
    /// For `shorted`: the other electrode.
    #[serde(default)]
    pub with: Option<u8>,
    /// For `intermittent`: chance per step that the contact is open, (0, 1).
    #[serde(default)]
    pub probability: Option<f64>,
}

/// Temperature drift: the sheet's conductance changes by `per_kelvin` per kelvin while the
/// temperature ramps at `kelvin_per_minute`. Simulated only when a scene asks for it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drift {
    /// Relative conductance change per kelvin (PPy fabric: about +0.01).
    pub per_kelvin: f64,
    /// Temperature ramp, K per minute.
    pub kelvin_per_minute: f64,
}

/// A whole scene file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// What the scene shows, for people.
    #[serde(default)]
    pub description: String,
    /// Seed of every random draw (noise, electrode movement).
    #[serde(default = "default_seed", deserialize_with = "et_core::whole::whole")]
    pub seed: u64,
    /// The sheet.
    pub sheet: SheetSpec,
    /// Electrode movement (frameless sheets).
    #[serde(default)]
    pub movement: Movement,
    /// Scan settings.
    #[serde(default)]
    pub scan: ScanSpec,
    /// Front end and noise.
    #[serde(default)]
    pub frontend: FrontendSpec,
    /// Pressure dynamics.
    #[serde(default)]
    pub dynamics: Dynamics,
    /// Touches over time.
    #[serde(default, rename = "touch")]
    pub touches: Vec<TouchEvent>,
    /// Electrode faults.
    #[serde(default, rename = "fault")]
    pub faults: Vec<Fault>,
    /// Temperature drift.
    #[serde(default)]
    pub drift: Option<Drift>,
    /// The folder of the scene file (what a protocol file's path is relative to); the
    /// working folder for a scene parsed from text.
    #[serde(skip)]
    pub dir: std::path::PathBuf,
    /// The scene's file as the user named it (the name [`Scene::parse`] was given), for
    /// messages about it after loading.
    #[serde(skip)]
    pub name: String,
    /// The protocol file's text, read once by [`Scene::schedule`] and kept (a FIFO, or a file
    /// rewritten meanwhile, gives every use the same rows).
    #[serde(skip)]
    pub read: ReadOnce,
}

fn default_seed() -> u64 {
    1
}

/// The deepest nesting of `[` and `{` a scene may have (a scene needs 3).
pub const MAX_NESTING: usize = 32;

/// The smallest touch radius, as a fraction of the sheet's size (its shorter side). A touch
/// changes a frame by about its share of the sheet's area, whatever its pressure: at 1e-4 of
/// the size by 1e-8 of the frame (a 10 um touch on a 20 cm disc: 1.3e-8 by the finite
/// elements), under what single precision resolves; and a radius of 1e-20 m hung the mesher,
/// which refines to a quarter of it.
pub const MIN_TOUCH_FRACTION: f64 = 1e-4;

/// The largest scene text read, bytes (the shipped scenes are under 1 kB; parsing TOML takes
/// up to about 100 times its size in memory).
pub const MAX_SCENE_BYTES: usize = 1 << 20;

/// Checks that brackets and braces never nest deeper than `max`, counted on the tokens of the
/// TOML parser's own lexer (so strings and comments are what the parser thinks they are). The
/// parser recovers from an unclosed inline table by recursing, one stack frame per `{`, so a
/// damaged file of a few tens of kilobytes (`b = {` repeated) overflowed the stack and aborted;
/// this bounds the recursion before the parser runs. A closer only closes its own kind (`{ ]`
/// stays open, as the parser keeps it), so the count is never below the parser's depth; in a
/// valid file it is exactly the nesting.
///
/// # Errors
/// The 1-based line where the nesting goes too deep.
fn nesting_within(text: &str, max: usize) -> Result<(), usize> {
    use toml_parser::lexer::TokenKind;
    let mut open: Vec<TokenKind> = Vec::new();
    for token in toml_parser::Source::new(text).lex() {
        match token.kind() {
            kind @ (TokenKind::LeftSquareBracket | TokenKind::LeftCurlyBracket) => {
                open.push(kind);
                if open.len() > max {
                    let at = token.span().start();
                    let line = 1 + text
                        .as_bytes()
                        .iter()
                        .take(at)
                        .filter(|&&b| b == b'\n')
                        .count();
                    return Err(line);
                }
            }
            TokenKind::RightSquareBracket if open.last() == Some(&TokenKind::LeftSquareBracket) => {
                open.pop();
            }
            TokenKind::RightCurlyBracket if open.last() == Some(&TokenKind::LeftCurlyBracket) => {
                open.pop();
            }
            _ => {}
        }
    }
    Ok(())
}

impl Scene {
    /// Reads and validates a scene file.
    ///
    /// # Errors
    /// [`SceneError`] naming the file, and the field where one is at fault.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let name = path.display().to_string();
        let text = et_core::text::read_document_at_most(path, MAX_SCENE_BYTES as u64).map_err(
            |source| SceneError::Io {
                path: name.clone(),
                source,
            },
        )?;
        let mut scene = Self::parse(&text, &name)?;
        scene.dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        // A protocol file is read now, so that a scene that loads images.
        scene.schedule().map_err(|error| SceneError::Invalid {
            path: name.clone(),
            error,
        })?;
        Ok(scene)
    }

    /// Parses and validates scene text; `name` is used in messages.
    ///
    /// # Errors
    /// [`SceneError::Parse`] or [`SceneError::Invalid`].
    pub fn parse(text: &str, name: &str) -> Result<Self, SceneError> {
        if text.len() > MAX_SCENE_BYTES {
            return Err(SceneError::TooLarge {
                path: name.into(),
                bytes: text.len(),
            });
        }
        if let Err(line) = nesting_within(text, MAX_NESTING) {
            return Err(SceneError::TooDeep {
                path: name.into(),
                line,
            });
        }
        let blank = |l: &str| l.trim().is_empty() || l.trim_start().starts_with('#');
        let mut scene: Scene = toml::from_str(text).map_err(|error| {
            // Another of et's files is said as what it is (no scene's first line is one's).
            match et_core::text::EtFile::of(text) {
                Some(kind) => SceneError::OtherFile {
                    path: name.into(),
                    kind,
                },
                None if text.trim_start_matches('\u{feff}').lines().all(blank) => {
                    SceneError::Empty { path: name.into() }
                }
                None => SceneError::Parse {
                    path: name.into(),
                    error,
                },
            }
        })?;
        scene.name = name.into();
        scene.scan.current_given = toml::from_str::<toml::Table>(text)
            .ok()
            .and_then(|t| t.get("scan")?.get("current_ua").cloned())
            .is_some();
        scene.validate().map_err(|error| SceneError::Invalid {
            path: name.into(),
            error,
        })?;
        Ok(scene)
    }

    /// Checks every value, naming the field at fault.
    fn validate(&self) -> Result<(), FieldError> {
        self.sheet.validate()?;
        self.frontend.validate()?;
        self.check_scan()?;
        if !(self.movement.rms.is_finite() && self.movement.rms >= 0.0) {
            return Err(FieldError::value(
                "movement.rms",
                self.movement.rms,
                ">= 0 m",
            ));
        }
        let d = &self.dynamics;
        for (field, tau) in [
            ("dynamics.load_s", d.load_s),
            ("dynamics.unload_s", d.unload_s),
        ] {
            if !(0.0..=MAX_TIME_CONSTANT_S).contains(&tau) {
                let fault = FieldFault::Span {
                    value: tau,
                    low: 0.0,
                    high: MAX_TIME_CONSTANT_S,
                    unit: "s",
                    why: "a fabric follows a press in milliseconds to seconds; a time constant \
                          past a day is a press that never arrives or never leaves: is it in s?",
                };
                return Err(FieldError::new(field, fault));
            }
        }
        if !(0.0..1.0).contains(&d.hysteresis) {
            let rule = "in [0, 1) (a fraction of the peak pressure)";
            return Err(FieldError::value("dynamics.hysteresis", d.hysteresis, rule));
        }
        let l = self.sheet.physical.electrodes.count;
        for (i, f) in self.faults.iter().enumerate() {
            let at = |what: &str| format!("fault[{i}].{what}");
            if f.electrode >= l {
                let (electrode, count) = (f.electrode, l);
                return Err(FieldError::new(
                    at("electrode"),
                    SceneFault::Electrode { electrode, count },
                ));
            }
            match f.kind {
                FaultKind::Shorted if f.with.is_none_or(|w| w >= l || w == f.electrode) => {
                    return Err(FieldError::new(at("with"), SceneFault::ShortWith(l)));
                }
                FaultKind::Intermittent if f.probability.is_none_or(|p| !(p > 0.0 && p < 1.0)) => {
                    let rule = "intermittent needs a probability in (0, 1)";
                    return Err(FieldError::rule(at("probability"), rule));
                }
                _ => {}
            }
        }
        if let Some(d) = &self.drift
            && !(d.per_kelvin.is_finite() && d.kelvin_per_minute.is_finite())
        {
            let rule = "per_kelvin and kelvin_per_minute must be finite";
            return Err(FieldError::rule("drift", rule));
        }
        for (i, t) in self.touches.iter().enumerate() {
            let at = |what: &str| format!("touch[{i}].{what}");
            let inside = |p: [f64; 2]| self.sheet.physical.shape.contains(p, 1e-9);
            let size = self.sheet.physical.shape.size();
            // (Divided, so that 1e-4 of 0.2 m is said as 2e-5.)
            let least = size / (1.0 / MIN_TOUCH_FRACTION);
            if !(t.radius.is_finite() && t.radius >= least && t.radius <= size) {
                let fault = FieldFault::Span {
                    value: t.radius,
                    low: least,
                    high: size,
                    unit: "m",
                    why: "from 1e-4 of the sheet's size (a smaller touch changes the frames by \
                          less than single precision resolves) to the sheet's size",
                };
                return Err(FieldError::new(at("radius"), fault));
            }
            if !t.footprint.is_valid() {
                let (elongation, angle) = (t.footprint.elongation, t.footprint.angle);
                return Err(FieldError::new(
                    at("footprint"),
                    SceneFault::Footprint { elongation, angle },
                ));
            }
            if !(t.pressure.is_finite() && t.pressure >= 0.0) {
                return Err(FieldError::value(at("pressure"), t.pressure, ">= 0 Pa"));
            }
            if t.pressure > MAX_PRESSURE_PA {
                let fault = FieldFault::Span {
                    value: t.pressure,
                    low: 0.0,
                    high: MAX_PRESSURE_PA,
                    unit: "Pa",
                    why: "a finger presses tens of kPa and the fabric's law saturates near \
                          them; past 1 GPa (steel yields) no fabric is pressed: is it in Pa?",
                };
                return Err(FieldError::new(at("pressure"), fault));
            }
            if !t.position.iter().all(|v| v.is_finite()) || !inside(t.position) {
                return Err(FieldError::new(
                    at("position"),
                    SceneFault::OffSheet(t.position),
                ));
            }
            if let Some(to) = t.to
                && (!to.iter().all(|v| v.is_finite()) || !inside(to))
            {
                return Err(FieldError::new(at("to"), SceneFault::OffSheet(to)));
            }
            if !t.start.is_finite() || t.end.is_some_and(|e| !(e.is_finite() && e >= t.start)) {
                return Err(FieldError::rule(
                    at("start"),
                    "need finite start <= end (s)",
                ));
            }
        }
        Ok(())
    }

    /// Each touch against the simulator's grid ([`SheetSpec::check_touch`]): checked where
    /// the scene is simulated (imaging measured frames keeps its touches as the truth).
    ///
    /// # Errors
    /// [`SheetError::Unresolved`] for the first touch the grid does not resolve.
    pub fn check_touches_resolved(&self) -> Result<(), crate::sheet::SheetError> {
        self.touches
            .iter()
            .enumerate()
            .try_for_each(|(i, t)| self.sheet.check_touch(i, t.radius))
    }

    /// The touches at time `t` as scheduled (before dynamics): on, positioned, at full pressure.
    #[must_use]
    pub fn scheduled(&self, t: f64) -> Vec<Option<Touch>> {
        self.touches
            .iter()
            .map(|ev| {
                let on = t >= ev.start && ev.end.is_none_or(|e| t < e);
                on.then(|| {
                    let f = match (ev.to, ev.end) {
                        (Some(_), Some(end)) if end > ev.start => {
                            ((t - ev.start) / (end - ev.start)).clamp(0.0, 1.0)
                        }
                        _ => 0.0,
                    };
                    let to = ev.to.unwrap_or(ev.position);
                    Touch {
                        position: [
                            ev.position[0] + f * (to[0] - ev.position[0]),
                            ev.position[1] + f * (to[1] - ev.position[1]),
                        ],
                        radius: ev.radius,
                        pressure: ev.pressure,
                        footprint: ev.footprint,
                    }
                })
            })
            .collect()
    }
}

mod fault;
mod read_once;
mod run;
mod scan;
pub use fault::{FieldError, SceneFault};
pub use read_once::ReadOnce;
pub use run::*;

mod error;
pub use error::*;

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod tests;
