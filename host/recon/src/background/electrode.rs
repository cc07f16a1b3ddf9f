//! One electrode whose values the model cannot explain: a detached or broken electrode (a
//! clip off the sheet, a wire off its channel) reads noise or a rail where the sheet's
//! potential should be, or drives no current, and the values it drives or measures (on 16
//! electrodes about a fifth of a frame) carry most of what the homogeneous model leaves of
//! V_0 unexplained.

use et_core::schedule::Row;

/// The electrode whose values the model explains worst beside the rest of a reference.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ElectrodeMisfit {
    /// The electrode (0-based).
    pub electrode: u16,
    /// How many values of the frame it drives or measures.
    pub values: usize,
    /// |V_0 - s m| / |s m| over those values but the one furthest off, s the model's best
    /// scale for the rest: how far off the model they are (1: as far as they are large). The
    /// furthest is left out because one reading off (a rail, a glitch) is not an electrode
    /// off: it is in the values of four electrodes, and named one of them at random.
    pub own: f64,
    /// The same over the rest: what the model leaves of them unexplained.
    pub rest: f64,
}

/// How far off the model an electrode's values must be to name it, as a share of their size
/// ([`ElectrodeMisfit::own`]): a detached electrode's are 71 to 143 % off on the real tanks of
/// docs/measurements.md (reading noise, reading 0 V, or driving no current); the worst sound
/// electrode is 26 % off on those tanks' references, 32 % in their frames with targets, 31 %
/// on 18 simulated tanks with a real tank's departures from the model (electrodes moved,
/// contacts spread), 2 % on et's simulated sheets. Half sits between, about as far from
/// either.
pub const ELECTRODE_OWN: f64 = 0.5;

/// How many times further off than the rest an electrode's values must be to name it: a
/// detached electrode 9 to 90 times on the real tanks; sound ones up to 4.0 times on the
/// real tanks and 3.4 on the simulated tanks with a real tank's departures (each under 32 %
/// off: [`ELECTRODE_OWN`] holds them), 2.0 on et's simulated sheets.
pub const ELECTRODE_FACTOR: f64 = 3.0;

/// At most one electrode in this many is named detached at once ([`detached_electrodes`]; at
/// least one).
pub const DETACHED_PER: u16 = 8;

impl ElectrodeMisfit {
    /// Whether its values stand out as a detached or broken electrode's: off the model by
    /// [`ELECTRODE_OWN`] of their size and [`ELECTRODE_FACTOR`] times the rest.
    #[must_use]
    pub fn stands_out(&self) -> bool {
        self.own >= ELECTRODE_OWN && self.own >= ELECTRODE_FACTOR * self.rest
    }

    /// What is said of it when it [stands out](Self::stands_out), its number counted from
    /// `base` (0, et's, or 1 as a protocol file with `base = 1` counts); None otherwise.
    #[must_use]
    pub fn said(&self, base: u16) -> Option<String> {
        self.stands_out().then(|| {
            format!(
                "electrode {}'s {} values (those it drives or measures) are {:.0} % off the \
                 model, the rest {:.1} %: a detached or broken electrode (a clip off the \
                 sheet, a wire off its channel)?",
                u32::from(self.electrode) + u32::from(base),
                self.values,
                100.0 * self.own,
                100.0 * self.rest
            )
        })
    }
}

/// What is said of the electrodes `detached` ([`detached_electrodes`]), their numbers counted
/// from `base`, and those numbers as `--skip-electrodes` takes them ("7,12"); None when there
/// are none.
#[must_use]
pub fn detached_said(detached: &[ElectrodeMisfit], base: u16) -> Option<(String, String)> {
    let number = |m: &ElectrodeMisfit| u32::from(m.electrode) + u32::from(base);
    let numbers: Vec<String> = detached.iter().map(|m| number(m).to_string()).collect();
    let said = match detached {
        [] => return None,
        [one] => one.said(base)?,
        several => {
            let rest = several.iter().fold(0.0f64, |r, m| r.max(m.rest));
            let off: Vec<String> = several
                .iter()
                .map(|m| format!("{:.0}", 100.0 * m.own))
                .collect();
            format!(
                "electrodes {}: the values each drives or measures are {} % off the model, the \
                 rest at most {:.1} %: detached or broken electrodes (clips off the sheet, \
                 wires off their channels)?",
                numbers.join(", "),
                off.join(", "),
                100.0 * rest
            )
        }
    };
    Some((said, numbers.join(",")))
}

/// Of the `electrodes` electrodes of `rows` (the frame's K rows), the one whose values the
/// model's frame `model` (K values, V) explains worst beside the rest of `v0` (K values, V):
/// the largest [`ElectrodeMisfit::own`] over [`ElectrodeMisfit::rest`]. None when no electrode
/// has values and leaves others. One pass over the frame (the sums of v0^2, v0 m and m^2 each
/// electrode's values and all of them give every electrode's scale and misfits), so it may
/// weigh every frame of a recording.
#[must_use]
pub fn electrode_misfit(
    rows: &[Row],
    electrodes: u16,
    v0: &[f64],
    model: &[f64],
) -> Option<ElectrodeMisfit> {
    worst(&each_misfit(rows, electrodes, (v0, model), &[]))
}

/// An electrode whose values stand out as a detached or broken electrode's in frames to
/// image, not in their reference ([`crate::Reconstructor::came_off`]): a clip that came off
/// during the recording.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameOff {
    /// Its misfit in the first frame it stands out in.
    pub misfit: ElectrodeMisfit,
    /// How many of the frames it stands out in.
    pub count: usize,
    /// The first of them, as the frames are numbered.
    pub first: usize,
    /// The frames weighed.
    pub frames: usize,
}

impl CameOff {
    /// What is said of it, its number counted from `base` (0, or 1 as a protocol file with
    /// `base = 1` counts); `leave_out` says how its values are left out, given the number
    /// ("--skip-electrodes 3 leaves them out").
    #[must_use]
    pub fn said(&self, base: u16, leave_out: impl Fn(u32) -> String) -> String {
        let number = u32::from(self.misfit.electrode) + u32::from(base);
        format!(
            "electrode {number}'s values stand out in {} of the {} frames to image, from frame \
             {} ({:.0} % off the model there, the rest {:.1} %), not in the reference: a clip \
             or wire that came off during the recording? Those frames are imaged with its wrong \
             values: {}",
            self.count,
            self.frames,
            self.first,
            100.0 * self.misfit.own,
            100.0 * self.misfit.rest,
            leave_out(number)
        )
    }
}

/// Electrode `electrode`'s misfit ([`ElectrodeMisfit`]) in `v` (K values of `rows`, V)
/// beside the model's frame `model`, over the values none of `without` drives or measures (other
/// electrodes off, which would raise the rest it is weighed against): whether an electrode
/// that came off is back. None when it has fewer than two such values (one left out, say).
#[must_use]
pub fn misfit_of(
    rows: &[Row],
    electrodes: u16,
    (v, model): (&[f64], &[f64]),
    electrode: u16,
    without: &[u16],
) -> Option<ElectrodeMisfit> {
    let without: Vec<u16> = without
        .iter()
        .copied()
        .filter(|e| *e != electrode)
        .collect();
    *each_misfit(rows, electrodes, (v, model), &without).get(usize::from(electrode))?
}

/// Every electrode of `rows` that [stands out](ElectrodeMisfit::stands_out) as detached or
/// broken, each weighed without the others' values (two detached electrodes each raise the
/// misfit of the rest against which the other is weighed, and neither stood out alone): the
/// worst electrode is taken while its values are [`ELECTRODE_OWN`] off the model, the next
/// weighed without it, at most one in [`DETACHED_PER`] (more, and the misfit is the whole
/// frame's: frames of another protocol of the same K left 8 of 16 electrodes far off, and two
/// of them stood out once the other six were left out); then each is kept if it stands out
/// beside the values of none of them.
#[must_use]
pub fn detached_electrodes(
    rows: &[Row],
    electrodes: u16,
    v0: &[f64],
    model: &[f64],
) -> Vec<ElectrodeMisfit> {
    let mut candidates: Vec<u16> = Vec::new();
    loop {
        match worst(&each_misfit(rows, electrodes, (v0, model), &candidates)) {
            Some(w) if w.own >= ELECTRODE_OWN => candidates.push(w.electrode),
            _ => break,
        }
        // More electrodes far off than a few: the misfit is the whole frame's (another
        // protocol, numbering or sheet), which the poor fit says; none is named.
        if candidates.len() > usize::from(electrodes / DETACHED_PER).max(1) {
            return Vec::new();
        }
    }
    let mut found: Vec<ElectrodeMisfit> = (candidates.iter())
        .filter_map(|&e| {
            let others: Vec<u16> = candidates.iter().copied().filter(|o| *o != e).collect();
            each_misfit(rows, electrodes, (v0, model), &others)[usize::from(e)]
        })
        .filter(ElectrodeMisfit::stands_out)
        .collect();
    found.sort_by_key(|m| m.electrode);
    found
}

/// The largest [`ElectrodeMisfit::own`] over [`ElectrodeMisfit::rest`] of `misfits`.
fn worst(misfits: &[Option<ElectrodeMisfit>]) -> Option<ElectrodeMisfit> {
    misfits
        .iter()
        .flatten()
        .fold(None, |worst: Option<ElectrodeMisfit>, &m| match worst {
            Some(w) if m.own * w.rest <= w.own * m.rest => Some(w),
            _ => Some(m),
        })
}

/// Each electrode's misfit ([`ElectrodeMisfit`]) over the values of `rows` that none of
/// `without` drives or measures; None for an electrode with fewer than two such values, or
/// none left beside them. `(v0, model)`: the frame and the model's, K values each, V. Two
/// passes: the sums give each electrode's scale, then its value furthest off is found.
fn each_misfit(
    rows: &[Row],
    electrodes: u16,
    (v0, model): (&[f64], &[f64]),
    without: &[u16],
) -> Vec<Option<ElectrodeMisfit>> {
    // Per electrode, over the values it drives or measures: (sum v0^2, sum v0 m, sum m^2, n).
    let mut of = vec![Sums::default(); usize::from(electrodes)];
    let mut all = Sums::default();
    for ((row, m), v) in rows.iter().zip(model).zip(v0) {
        let four = [row.source, row.sink, row.positive, row.negative];
        if four.iter().any(|e| without.contains(e)) {
            continue;
        }
        all.add(*v, *m);
        for (i, e) in four.iter().enumerate() {
            if !four[..i].contains(e)
                && let Some(sums) = of.get_mut(usize::from(*e))
            {
                sums.add(*v, *m);
            }
        }
    }
    // The model's best scale for the rest of each electrode's values.
    let scales: Vec<Option<f64>> = (of.iter())
        .map(|own| {
            let rest = all.less(own);
            (own.n > 1 && rest.n > 0 && rest.mm > 0.0).then(|| rest.vm / rest.mm)
        })
        .collect();
    // Each electrode's value furthest off at its scale: (its departure squared, v0, m).
    let mut furthest = vec![(f64::NEG_INFINITY, 0.0, 0.0); usize::from(electrodes)];
    for ((row, m), v) in rows.iter().zip(model).zip(v0) {
        let four = [row.source, row.sink, row.positive, row.negative];
        if four.iter().any(|e| without.contains(e)) {
            continue;
        }
        for e in four {
            let e = usize::from(e);
            if let (Some(Some(s)), Some(f)) = (scales.get(e), furthest.get_mut(e)) {
                let departure = (v - s * m).powi(2);
                if departure > f.0 {
                    *f = (departure, *v, *m);
                }
            }
        }
    }
    (0..electrodes)
        .zip(of.iter().zip(&scales).zip(&furthest))
        .map(|(electrode, ((own, scale), &(_, v, m)))| {
            let scale = (*scale)?;
            let rest = all.less(own);
            let mut one = Sums::default();
            one.add(v, m);
            let found = ElectrodeMisfit {
                electrode,
                values: own.n,
                own: own.less(&one).off(scale),
                rest: rest.off(scale),
            };
            (found.own.is_finite() && found.rest.is_finite()).then_some(found)
        })
        .collect()
}

/// Sums over some values of a frame `v0` and the model's `m`.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    vv: f64,
    vm: f64,
    mm: f64,
    n: usize,
}

impl Sums {
    fn add(&mut self, v: f64, m: f64) {
        self.vv += v * v;
        self.vm += v * m;
        self.mm += m * m;
        self.n += 1;
    }

    /// These sums without `part`'s (a subset of the values).
    fn less(&self, part: &Sums) -> Sums {
        Sums {
            vv: self.vv - part.vv,
            vm: self.vm - part.vm,
            mm: self.mm - part.mm,
            n: self.n - part.n,
        }
    }

    /// |v0 - s m| / |s m| over these values, at scale `s`.
    fn off(&self, s: f64) -> f64 {
        let r2 = (self.vv - 2.0 * s * self.vm + s * s * self.mm).max(0.0);
        (r2 / (s * s * self.mm)).sqrt()
    }
}
