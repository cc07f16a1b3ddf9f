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
    /// |V_0 - s m| / |s m| over those values, s the model's best scale for the rest: how far
    /// off the model they are (1: as far as they are large).
    pub own: f64,
    /// The same over the rest: what the model leaves of them unexplained.
    pub rest: f64,
}

/// How far off the model an electrode's values must be to name it, as a share of their size
/// ([`ElectrodeMisfit::own`]): a detached electrode's are 73 to 143 % off on the real tanks of
/// docs/measurements.md (reading noise, reading 0 V, or driving no current); the worst sound
/// electrode is 26 % off on those tanks, 31 % on 18 simulated tanks with a real tank's
/// departures from the model (electrodes moved, contacts spread), 2 % on et's simulated
/// sheets. Half sits between, about as far from either.
pub const ELECTRODE_OWN: f64 = 0.5;

/// How many times further off than the rest an electrode's values must be to name it: a
/// detached electrode 9 to 90 times on the real tanks; sound ones up to 4.1 times on the
/// real tanks and 3.4 on the simulated tanks with a real tank's departures (each under 31 %
/// off: [`ELECTRODE_OWN`] holds them), 2.2 on et's simulated sheets.
pub const ELECTRODE_FACTOR: f64 = 3.0;

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

/// Of the `electrodes` electrodes of `rows` (the frame's K rows), the one whose values the
/// model's frame `model` (K values, V) explains worst beside the rest of `v0` (K values, V):
/// the largest [`ElectrodeMisfit::own`] over [`ElectrodeMisfit::rest`]. None when no electrode
/// has values and leaves others.
#[must_use]
pub fn electrode_misfit(
    rows: &[Row],
    electrodes: u16,
    v0: &[f64],
    model: &[f64],
) -> Option<ElectrodeMisfit> {
    let mut worst: Option<ElectrodeMisfit> = None;
    for electrode in 0..electrodes {
        let of =
            |row: &Row| [row.source, row.sink, row.positive, row.negative].contains(&electrode);
        let values = rows.iter().filter(|row| of(row)).count();
        // The model's best scale for the rest: <m, V_0> / |m|^2 over the values without it.
        let (mv, mm) = (rows.iter().zip(model).zip(v0))
            .filter(|((row, _), _)| !of(row))
            .fold((0.0, 0.0), |(mv, mm), ((_, m), v)| (mv + m * v, mm + m * m));
        if values == 0 || values == rows.len() || mm == 0.0 {
            continue;
        }
        let scale = mv / mm;
        // |V_0 - s m| / |s m| over the values for which `own` says.
        let off = |own: bool| {
            let (r2, m2) = (rows.iter().zip(model).zip(v0))
                .filter(|((row, _), _)| of(row) == own)
                .fold((0.0, 0.0), |(r2, m2), ((_, m), v)| {
                    (r2 + (v - scale * m).powi(2), m2 + (scale * m).powi(2))
                });
            (r2 / m2).sqrt()
        };
        let found = ElectrodeMisfit {
            electrode,
            values,
            own: off(true),
            rest: off(false),
        };
        if !(found.own.is_finite() && found.rest.is_finite()) {
            continue;
        }
        if worst.is_none_or(|w| found.own * w.rest > w.own * found.rest) {
            worst = Some(found);
        }
    }
    worst
}
