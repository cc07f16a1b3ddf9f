//! Injection / measurement protocols (docs/method.md §4) as tables computed on the fly.
//!
//! Every protocol here is a case of one general form, the [`Pattern`]: inject current between
//! electrode `i` and electrode `i + drive_skip + 1`, for every `i` in `0..L` (so each electrode
//! takes its turn), and measure the differential voltage between `j` and `j + s + 1` for every
//! measurement skip `s` in the pattern and every `j`. A measurement that touches a
//! current-carrying electrode is dropped (the selection mask, docs/method.md §2-3); what remains, in
//! injection-major order, is the frame vector V_m of length K.
//!
//! | protocol | drive skip | measure skips | K at L = 16 |
//! | --- | --- | --- | --- |
//! | [`ProtocolKind::Adjacent`] | 0 | {0} | L (L - 3) = 208 |
//! | [`ProtocolKind::PseudoPolar`] | L/2 - 2 | {0} | L (L - 4) = 192 |
//! | [`ProtocolKind::PpPp`] | L/2 - 2 | {0, L/2 - 2} | L (2L - 7) = 400 |
//! | [`ProtocolKind::Opposite`] | L/2 - 1 | {0} | L (L - 4) = 192 |
//!
//! Two measurements carry the same information (up to sign) when they involve the same two
//! electrode pairs: reversing the injection negates every voltage, and reciprocity (docs/method.md §4)
//! says V(C,D) under current on (A,B) equals V(A,B) under current on (C,D).
//! [`Protocol::features`] keeps one measurement of each such group when [`Halving::Reciprocity`]
//! is asked for: for the opposite protocol that is p = L (L - 4) / 2 (96 at L = 16), the
//! classifier's features (docs/method.md §9). Whether the halving was applied is always the caller's
//! explicit choice.

use serde::{Deserialize, Serialize};

/// Fewest electrodes supported.
pub const L_MIN: u8 = 4;
/// Most electrodes supported (a pair of 16:1 muxes addresses 16; the tables go to 32).
pub const L_MAX: u8 = 32;
/// Most measurement skips in one [`Pattern`] (PP-PP uses two).
pub const MAX_MEASURE_SKIPS: usize = 2;
/// Longest frame vector V_m any valid protocol produces: L_MAX * L_MAX * MAX_MEASURE_SKIPS.
pub const K_MAX: usize = L_MAX as usize * L_MAX as usize * MAX_MEASURE_SKIPS;
/// Most candidate measurements for one injection (L_MAX per measurement skip).
pub const CANDIDATES_MAX: usize = L_MAX as usize * MAX_MEASURE_SKIPS;
/// Electrodes one 16:1 multiplexer can address (docs/method.md §2).
pub const MUX_CHANNELS: u8 = 16;

/// An electrode on the sheet boundary, numbered `0..L` around the boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ElectrodeId(pub u8);

/// One current injection: the current enters the sheet at `source` and leaves at `sink`
/// (the sink is the electrode the ground mux connects).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Injection {
    /// Electrode connected to the current source.
    pub source: ElectrodeId,
    /// Electrode connected to ground.
    pub sink: ElectrodeId,
}

impl Injection {
    /// The same electrodes with the current flowing the other way (every voltage negates).
    #[must_use]
    pub const fn reversed(self) -> Self {
        Self {
            source: self.sink,
            sink: self.source,
        }
    }

    /// Whether `e` carries current in this injection.
    #[must_use]
    pub fn carries(self, e: ElectrodeId) -> bool {
        self.source == e || self.sink == e
    }
}

/// One differential measurement: V = phi(`positive`) - phi(`negative`), in volts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Measurement {
    /// Electrode on the amplifier's + input.
    pub positive: ElectrodeId,
    /// Electrode on the amplifier's - input.
    pub negative: ElectrodeId,
}

impl Measurement {
    /// The same electrodes with the amplifier inputs swapped (the voltage negates).
    #[must_use]
    pub const fn reversed(self) -> Self {
        Self {
            positive: self.negative,
            negative: self.positive,
        }
    }
}

/// The skips as `et protocol` takes them, separated by spaces ("0 7"); "none" when empty.
impl core::fmt::Display for SkipSet {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.is_empty() {
            return f.write_str("none");
        }
        for (i, s) in self.iter().enumerate() {
            write!(f, "{}{s}", if i == 0 { "" } else { " " })?;
        }
        Ok(())
    }
}

/// A set of measurement skips, as a bit mask (bit `s` set = skip `s`, i.e. pairs `j, j + s + 1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SkipSet(pub u32);

impl SkipSet {
    /// The set holding the single skip `s` (`s < 32`).
    #[must_use]
    pub const fn single(s: u8) -> Self {
        Self(1 << s)
    }

    /// This set with skip `s` added (`s < 32`).
    #[must_use]
    pub const fn with(self, s: u8) -> Self {
        Self(self.0 | (1 << s))
    }

    /// Number of skips in the set.
    #[must_use]
    pub const fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// Whether the set is empty.
    #[must_use]
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The skips in ascending order.
    pub fn iter(self) -> impl Iterator<Item = u8> {
        (0..32u8).filter(move |s| self.0 & (1 << s) != 0)
    }
}

/// The general "drive skip / measure skip" form of a protocol (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pattern {
    /// Inject between `i` and `i + drive_skip + 1`. Valid: `drive_skip + 1 <= L / 2`.
    pub drive_skip: u8,
    /// Measure between `j` and `j + s + 1` for each `s` here. Valid: `1..=MAX_MEASURE_SKIPS`
    /// skips, each with `s + 1 <= L / 2`.
    pub measure_skips: SkipSet,
}

/// A named protocol, or a general [`Pattern`]. Becomes a [`Protocol`] once the electrode count
/// is known ([`Protocol::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ProtocolKind {
    /// AD: inject between neighbours, measure neighbours. Most sensitive near the boundary.
    Adjacent,
    /// PP: inject between `i` and `i + L/2 - 1`, measure neighbours. Most current through the centre.
    PseudoPolar,
    /// PP-PP: inject as PP, measure neighbours and almost-opposite pairs. Best for several touches.
    PpPp,
    /// Opposite (polar): inject between `i` and `i + L/2`, measure neighbours. The classifier's
    /// features come from it (docs/method.md §9).
    Opposite,
    /// Any other drive skip / measure skip combination.
    Custom(Pattern),
}

impl ProtocolKind {
    /// The four named protocols, in the order of docs/method.md §4.
    pub const NAMED: [ProtocolKind; 4] = [
        ProtocolKind::Adjacent,
        ProtocolKind::PseudoPolar,
        ProtocolKind::PpPp,
        ProtocolKind::Opposite,
    ];

    /// The pattern this protocol follows on `l` electrodes (no validation: see [`Protocol::new`]).
    #[must_use]
    pub fn pattern(self, l: u8) -> Pattern {
        let half = l / 2;
        match self {
            ProtocolKind::Adjacent => Pattern {
                drive_skip: 0,
                measure_skips: SkipSet::single(0),
            },
            ProtocolKind::PseudoPolar => Pattern {
                drive_skip: half.saturating_sub(2),
                measure_skips: SkipSet::single(0),
            },
            ProtocolKind::PpPp => Pattern {
                drive_skip: half.saturating_sub(2),
                measure_skips: SkipSet::single(0).with(half.saturating_sub(2)),
            },
            ProtocolKind::Opposite => Pattern {
                drive_skip: half.saturating_sub(1),
                measure_skips: SkipSet::single(0),
            },
            ProtocolKind::Custom(p) => p,
        }
    }

    /// The short name used on the command line and in files (`adjacent`, `pseudo-polar`,
    /// `pp-pp`, `opposite`, `custom`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ProtocolKind::Adjacent => "adjacent",
            ProtocolKind::PseudoPolar => "pseudo-polar",
            ProtocolKind::PpPp => "pp-pp",
            ProtocolKind::Opposite => "opposite",
            ProtocolKind::Custom(_) => "custom",
        }
    }

    /// Parses a named protocol: the names of [`ProtocolKind::name`] plus the method's
    /// abbreviations `ad`, `pp`, `pppp`, `polar`. Case-insensitive.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        let eq = |s: &str| name.eq_ignore_ascii_case(s);
        if eq("adjacent") || eq("ad") {
            Some(ProtocolKind::Adjacent)
        } else if eq("pseudo-polar") || eq("pseudopolar") || eq("pp") {
            Some(ProtocolKind::PseudoPolar)
        } else if eq("pp-pp") || eq("pppp") {
            Some(ProtocolKind::PpPp)
        } else if eq("opposite") || eq("polar") || eq("op") {
            Some(ProtocolKind::Opposite)
        } else {
            None
        }
    }
}

/// The name people read: [`ProtocolKind::name`] for the named protocols, the drive skip and
/// measure skips for a general pattern (`drive skip 3, measure skips 0 7`).
impl core::fmt::Display for ProtocolKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ProtocolKind::Custom(p) => write!(
                f,
                "drive skip {}, measure skips {}",
                p.drive_skip, p.measure_skips
            ),
            named => f.write_str(named.name()),
        }
    }
}

/// Whether to drop measurements that repeat another one up to sign (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Halving {
    /// Keep every measurement of the frame (p = K).
    None,
    /// Keep the first measurement of each reciprocity / reversal group (p = L (L-4) / 2 for
    /// the opposite protocol).
    Reciprocity,
}

/// Sign relating two measurements that carry the same information.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sign {
    /// Same voltage.
    Plus,
    /// Negated voltage.
    Minus,
}

impl Sign {
    fn flip(self, by: bool) -> Self {
        match (self, by) {
            (s, false) => s,
            (Sign::Plus, true) => Sign::Minus,
            (Sign::Minus, true) => Sign::Plus,
        }
    }

    /// +1.0 or -1.0.
    #[must_use]
    pub fn value(self) -> f32 {
        match self {
            Sign::Plus => 1.0,
            Sign::Minus => -1.0,
        }
    }
}

/// One step of a scan: measurement number `k` of the frame vector V_m.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Step {
    /// Index into V_m, `0..K`.
    pub k: u16,
    /// Which injection of the protocol (`0..L`).
    pub injection_index: u8,
    /// The injection.
    pub injection: Injection,
    /// The measurement.
    pub measurement: Measurement,
}

/// A validated protocol for a known electrode count: the tables of docs/method.md §4.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Protocol {
    kind: ProtocolKind,
    electrodes: u8,
    pattern: Pattern,
    /// Selected measurements per injection (the same for every injection, by rotation).
    per_injection: u16,
}

impl Protocol {
    /// Builds the tables of `kind` on `electrodes` electrodes.
    ///
    /// # Errors
    /// [`ProtocolError`] when the electrode count is odd or out of range, or the pattern's
    /// skips do not fit it.
    pub fn new(kind: ProtocolKind, electrodes: u8) -> Result<Self, ProtocolError> {
        if !(L_MIN..=L_MAX).contains(&electrodes) || !electrodes.is_multiple_of(2) {
            return Err(ProtocolError::ElectrodeCount { electrodes });
        }
        let half = electrodes / 2;
        let pattern = kind.pattern(electrodes);
        if pattern.drive_skip + 1 > half {
            return Err(ProtocolError::DriveSkip {
                drive_skip: pattern.drive_skip,
                electrodes,
            });
        }
        let skips = pattern.measure_skips;
        if skips.is_empty() || skips.len() > MAX_MEASURE_SKIPS || skips.iter().any(|s| s + 1 > half)
        {
            return Err(ProtocolError::MeasureSkips {
                measure_skips: skips,
                electrodes,
            });
        }
        let mut protocol = Self {
            kind,
            electrodes,
            pattern,
            per_injection: 0,
        };
        // The pattern is invariant under rotation, so every injection selects as many.
        let per_injection = protocol.measurements(0).count();
        if per_injection == 0 {
            return Err(ProtocolError::Empty);
        }
        protocol.per_injection = per_injection as u16;
        Ok(protocol)
    }

    /// The protocol's kind as given to [`Protocol::new`].
    #[must_use]
    pub fn kind(&self) -> ProtocolKind {
        self.kind
    }

    /// Number of electrodes L.
    #[must_use]
    pub fn electrodes(&self) -> u8 {
        self.electrodes
    }

    /// The general pattern this protocol follows.
    #[must_use]
    pub fn pattern(&self) -> Pattern {
        self.pattern
    }

    /// Frame length K: the number of selected measurements over all injections.
    #[must_use]
    pub fn frame_len(&self) -> usize {
        usize::from(self.electrodes) * self.measurements_per_injection()
    }

    /// Selected measurements per injection (K / L).
    #[must_use]
    pub fn measurements_per_injection(&self) -> usize {
        usize::from(self.per_injection)
    }

    /// Number of injections per scan (always L: every electrode takes its turn).
    #[must_use]
    pub fn injection_count(&self) -> usize {
        usize::from(self.electrodes)
    }

    fn electrode(&self, i: u32) -> ElectrodeId {
        ElectrodeId((i % u32::from(self.electrodes)) as u8)
    }

    /// Injection number `i` (`0..L`): from `i` to `i + drive_skip + 1`.
    ///
    /// # Panics
    /// If `i >= L`.
    #[must_use]
    pub fn injection(&self, i: u8) -> Injection {
        assert!(i < self.electrodes, "injection index {i} out of range");
        Injection {
            source: self.electrode(u32::from(i)),
            sink: self.electrode(u32::from(i) + u32::from(self.pattern.drive_skip) + 1),
        }
    }

    /// All L injections in scan order.
    pub fn injections(&self) -> impl Iterator<Item = Injection> + '_ {
        (0..self.electrodes).map(|i| self.injection(i))
    }

    /// Every candidate measurement of injection `i`, selected or not, with its selection bit
    /// (false = it touches a current-carrying electrode and is dropped). Candidates are ordered
    /// by measurement skip, then by `j`; for a skip of exactly L/2 only `j < L/2` is a
    /// candidate (the rest repeat those reversed).
    ///
    /// # Panics
    /// If `i >= L`.
    pub fn candidates(&self, i: u8) -> impl Iterator<Item = (Measurement, bool)> + '_ {
        let injection = self.injection(i);
        let l = self.electrodes;
        self.pattern.measure_skips.iter().flat_map(move |s| {
            let offset = u32::from(s) + 1;
            let count = if offset == u32::from(l / 2) { l / 2 } else { l };
            (0..count).map(move |j| {
                let m = Measurement {
                    positive: self.electrode(u32::from(j)),
                    negative: self.electrode(u32::from(j) + offset),
                };
                let selected = !injection.carries(m.positive) && !injection.carries(m.negative);
                (m, selected)
            })
        })
    }

    /// The selection mask of injection `i` over its [`candidates`](Self::candidates): bit `c`
    /// set = candidate `c` is measured.
    ///
    /// # Panics
    /// If `i >= L`.
    #[must_use]
    pub fn selection_mask(&self, i: u8) -> u64 {
        self.candidates(i)
            .enumerate()
            .filter(|(_, (_, sel))| *sel)
            .fold(0, |mask, (c, _)| mask | (1 << c))
    }

    /// The selected measurements of injection `i`, in frame order.
    ///
    /// # Panics
    /// If `i >= L`.
    pub fn measurements(&self, i: u8) -> impl Iterator<Item = Measurement> + '_ {
        self.candidates(i).filter_map(|(m, sel)| sel.then_some(m))
    }

    /// Every step of one scan, in frame order (`k = 0..K`).
    pub fn steps(&self) -> impl Iterator<Item = Step> + '_ {
        (0..self.electrodes)
            .flat_map(move |i| self.measurements(i).map(move |m| (i, m)))
            .enumerate()
            .map(move |(k, (i, m))| Step {
                k: k as u16,
                injection_index: i,
                injection: self.injection(i),
                measurement: m,
            })
    }

    /// Step `k` of the scan, `None` past K.
    #[must_use]
    pub fn step(&self, k: usize) -> Option<Step> {
        let per = self.measurements_per_injection();
        let i = u8::try_from(k / per)
            .ok()
            .filter(|&i| i < self.electrodes)?;
        let measurement = self.measurements(i).nth(k % per)?;
        Some(Step {
            k: k as u16,
            injection_index: i,
            injection: self.injection(i),
            measurement,
        })
    }

    /// The frame index of exactly this (injection, measurement) pair, if the protocol
    /// measures it with these orientations.
    #[must_use]
    pub fn index_of(&self, injection: Injection, measurement: Measurement) -> Option<usize> {
        let i = injection.source.0;
        if i >= self.electrodes || self.injection(i) != injection {
            return None;
        }
        self.measurements(i)
            .position(|m| m == measurement)
            .map(|pos| usize::from(i) * self.measurements_per_injection() + pos)
    }

    /// The measurements carrying the same information as step `k` (itself included), with
    /// the sign relating their voltage to step `k`'s: the injection or the measurement
    /// reversed, and injection and measurement swapped (reciprocity, docs/method.md §4).
    pub fn equivalents(&self, k: usize) -> impl Iterator<Item = (usize, Sign)> + '_ {
        let step = self.step(k);
        step.into_iter().flat_map(move |step| {
            let (a, b) = (step.injection, step.measurement);
            // Swap roles: current on the measurement pair, measure on the injection pair.
            let swapped_inj = Injection {
                source: b.positive,
                sink: b.negative,
            };
            let swapped_meas = Measurement {
                positive: a.source,
                negative: a.sink,
            };
            (0..8u8).filter_map(move |bits| {
                let (swap, rev_inj, rev_meas) = (bits & 4 != 0, bits & 2 != 0, bits & 1 != 0);
                let (inj, meas) = if swap {
                    (swapped_inj, swapped_meas)
                } else {
                    (a, b)
                };
                let inj = if rev_inj { inj.reversed() } else { inj };
                let meas = if rev_meas { meas.reversed() } else { meas };
                let sign = Sign::Plus.flip(rev_inj ^ rev_meas);
                self.index_of(inj, meas).map(|j| (j, sign))
            })
        })
    }

    /// The index of the first measurement of step `k`'s equivalence group and the sign that
    /// relates the two: V_m\[k] = sign * V_m\[representative].
    #[must_use]
    pub fn representative(&self, k: usize) -> (usize, Sign) {
        self.equivalents(k)
            .min_by_key(|&(j, _)| j)
            .unwrap_or((k, Sign::Plus))
    }

    /// Frame indices of the feature set, ascending: all of `0..K` for [`Halving::None`], or the
    /// first of each reciprocity / reversal group for [`Halving::Reciprocity`].
    pub fn features(&self, halving: Halving) -> impl Iterator<Item = usize> + '_ {
        (0..self.frame_len()).filter(move |&k| match halving {
            Halving::None => true,
            Halving::Reciprocity => self.representative(k).0 == k,
        })
    }

    /// Feature count p (see [`Protocol::features`]).
    #[must_use]
    pub fn feature_count(&self, halving: Halving) -> usize {
        self.features(halving).count()
    }
}

mod error;
mod mux;
#[cfg(feature = "clap")]
mod value_enum;
pub use error::ProtocolError;
pub use mux::*;

#[cfg(test)]
mod tests;
