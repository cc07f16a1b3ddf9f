//! Another lab's instrument, as the simulator stands in for it: any schedule (a protocol file
//! of any system: its numbering, its families of injections, measurements on drive
//! electrodes, milliampere currents) measured on the resistor network, with the noise and
//! drift a real instrument adds. Frames come out in volts, one `Vec` per frame, the empty
//! sheet's first, as other systems write them (`et reconstruct --frames` reads them from CSV,
//! .npy, .npz or .mat).
//!
//! The noise of real systems is not et's front end: each value carries white noise of
//! `noise` times the frame's rms (the amplifier and ADC floor) and `proportional` times its own
//! magnitude (the current source's and gain's jitter, largest on the drive electrodes'
//! values); the instrument's gain drifts by `gain_drift` per frame (temperature, a slowly
//! discharging reference), so a frame taken long after its reference is off by a common
//! factor.

use et_core::rng::Rng;
use et_core::schedule::Schedule;

use crate::sheet::{SheetError, SheetSpec, SimulatedSheet, Unevenness};
use crate::touch::Inclusion;

/// A foreign instrument's imperfections (all dimensionless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instrument {
    /// White noise per value, as a share of the empty sheet's rms value.
    pub noise: f64,
    /// Noise proportional to each value, as a share of it.
    pub proportional: f64,
    /// The gain's change per frame (frame i is scaled by 1 + i gain_drift).
    pub gain_drift: f64,
    /// The noise's seed.
    pub seed: u64,
}

impl Instrument {
    /// An instrument with no noise and no drift.
    #[must_use]
    pub fn ideal() -> Self {
        Self {
            noise: 0.0,
            proportional: 0.0,
            gain_drift: 0.0,
            seed: 0,
        }
    }

    /// A good laboratory system: 0.05 % of the rms white, 0.05 % proportional, 0.01 % gain
    /// drift per frame (signal-to-noise about 66 dB on an average channel).
    #[must_use]
    pub fn laboratory(seed: u64) -> Self {
        Self {
            noise: 5e-4,
            proportional: 5e-4,
            gain_drift: 1e-4,
            seed,
        }
    }
}

/// How a real tank departs from the model that images it: what no fit of one sheet
/// resistance and one contact removes (the misfit a real 32-electrode tank leaves is 5 to 15
/// % of V_0; the resistor network against et's finite elements alone leaves about 1 %).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mismatch {
    /// Each electrode's place along the outline off by a normal draw of this standard
    /// deviation, as a share of the electrodes' spacing.
    pub position: f64,
    /// The electrodes' true width over the width the model is told (one factor for all).
    pub width: f64,
    /// Each electrode's contact impedance the model's times exp(this x a normal draw).
    pub contact_spread: f64,
    /// Each contact's change from the reference frame to the later frames, likewise (the
    /// electrodes settle, the saline's level and temperature change).
    pub contact_drift: f64,
    /// The medium's conductance uneven by a smooth field of this rms (natural-log units,
    /// [`Unevenness::draw`]): a temperature gradient, a meniscus, the third dimension.
    pub unevenness: f64,
    /// The draws' seed.
    pub seed: u64,
}

impl Mismatch {
    /// A saline tank as labs build them: electrodes 3 % of a spacing off their drawn places
    /// and 10 % wider than drawn, contacts spread by a factor of about 1.35 and drifting by
    /// 2 % after the reference, the medium 5 % uneven.
    #[must_use]
    pub fn tank(seed: u64) -> Self {
        Self {
            position: 0.03,
            width: 1.1,
            contact_spread: 0.3,
            contact_drift: 0.02,
            unevenness: 0.05,
            seed,
        }
    }

    /// The true tank of the model `spec`, as measured for the reference frame and for the
    /// later frames (its contacts drifted): two sheets of the resistor network.
    ///
    /// # Errors
    /// [`ForeignError::Sheet`] when a network cannot be built or solved.
    pub fn sheets(
        &self,
        spec: &SheetSpec,
    ) -> Result<(SimulatedSheet, SimulatedSheet), ForeignError> {
        let mut rng = Rng::new(self.seed);
        let mut truth = spec.clone();
        truth.physical.electrodes.width *= self.width;
        let n = usize::from(spec.physical.electrodes.count);
        let spacing = spec.physical.shape.perimeter() / n.max(1) as f64;
        let offsets: Vec<f64> = (0..n)
            .map(|_| self.position * spacing * rng.normal())
            .collect();
        let z0 = spec.physical.electrodes.contact_ohm;
        let contacts: Vec<f64> = (0..n)
            .map(|_| z0 * (self.contact_spread * rng.normal()).exp())
            .collect();
        let later: Vec<f64> = contacts
            .iter()
            .map(|z| z * (self.contact_drift * rng.normal()).exp())
            .collect();
        let field = Unevenness::draw(self.unevenness, &mut rng);
        Ok((
            SimulatedSheet::with_contacts(&truth, &offsets, &contacts, Some(&field))?,
            SimulatedSheet::with_contacts(&truth, &offsets, &later, Some(&field))?,
        ))
    }
}

/// Why frames could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ForeignError {
    /// The sheet's network could not be solved with the inclusions.
    #[error("simulated sheet: {0}")]
    Sheet(#[from] SheetError),
    /// The schedule is for another number of electrodes than the sheet's.
    #[error("the protocol is for {protocol} electrodes, the sheet has {sheet}")]
    Electrodes {
        /// The schedule's electrodes.
        protocol: usize,
        /// The sheet's.
        sheet: usize,
    },
}

/// The frames `instrument` measures on `sheet` under `schedule`: the empty sheet's first, then
/// one per entry of `scenes` (the inclusions present in that frame), V (K values each).
///
/// # Errors
/// [`ForeignError`] when the network cannot be solved or the schedule has another electrode
/// count.
pub fn frames(
    sheet: &SimulatedSheet,
    schedule: &Schedule,
    scenes: &[Vec<Inclusion>],
    instrument: &Instrument,
) -> Result<Vec<Vec<f64>>, ForeignError> {
    frames_between(sheet, sheet, schedule, scenes, instrument)
}

/// As [`frames`], the empty tank's frame measured on `reference` and the later frames on
/// `later` (the same tank with its contacts drifted: [`Mismatch::sheets`]).
///
/// # Errors
/// As [`frames`].
pub fn frames_between(
    reference: &SimulatedSheet,
    later: &SimulatedSheet,
    schedule: &Schedule,
    scenes: &[Vec<Inclusion>],
    instrument: &Instrument,
) -> Result<Vec<Vec<f64>>, ForeignError> {
    let mut out = Vec::with_capacity(scenes.len() + 1);
    let scenes = scenes.iter().map(Vec::as_slice);
    each_frame_between(reference, later, schedule, scenes, instrument, |v| {
        out.push(v);
        Ok::<(), ForeignError>(())
    })?;
    Ok(out)
}

/// As [`frames_between`], the scenes taken one at a time and each frame handed to `each` as it
/// is measured, none kept (a writer streams them to its file: `iter::repeat_n` of one scene
/// holds it once); a scene equal to the one before is not solved again. `each`'s error ends
/// the run.
///
/// # Errors
/// As [`frames`], or `each`'s.
pub fn each_frame_between<'a, E: From<ForeignError>>(
    reference: &SimulatedSheet,
    later: &SimulatedSheet,
    schedule: &Schedule,
    scenes: impl IntoIterator<Item = &'a [Inclusion]>,
    instrument: &Instrument,
    mut each: impl FnMut(Vec<f64>) -> Result<(), E>,
) -> Result<(), E> {
    let ideal =
        |sheet: &SimulatedSheet, inclusions: &[Inclusion]| -> Result<Vec<f64>, ForeignError> {
            sheet
                .transfer_inclusions(inclusions)?
                .frame_of(schedule)
                .ok_or(ForeignError::Electrodes {
                    protocol: schedule.electrodes(),
                    sheet: sheet.electrodes(),
                })
        };
    let empty = ideal(reference, &[])?;
    let rms = (empty.iter().map(|v| v * v).sum::<f64>() / empty.len().max(1) as f64).sqrt();
    let mut rng = Rng::new(instrument.seed);
    let mut measure = |i: usize, v: Vec<f64>| -> Vec<f64> {
        let gain = 1.0 + i as f64 * instrument.gain_drift;
        v.into_iter()
            .map(|x| {
                let sd = (instrument.noise * rms).hypot(instrument.proportional * x);
                gain * x + sd * rng.normal()
            })
            .collect()
    };
    each(measure(0, empty))?;
    let mut last: Option<(&[Inclusion], Vec<f64>)> = None;
    for (i, inclusions) in scenes.into_iter().enumerate() {
        let frame = match &last {
            Some((scene, frame)) if *scene == inclusions => frame.clone(),
            _ => ideal(later, inclusions)?,
        };
        each(measure(i + 1, frame.clone()))?;
        last = Some((inclusions, frame));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use et_core::sheet::Sheet;

    /// A 10 cm disc of 16 electrodes on a 5 mm network, adjacent pairs measured under
    /// adjacent injections.
    fn tank() -> (SheetSpec, Schedule) {
        let spec = SheetSpec {
            resolution: Some(0.005),
            ..SheetSpec::of(Sheet::disc(0.1, 16))
        };
        let pairs: Vec<(u16, u16)> = (0..16).map(|i| (i, (i + 1) % 16)).collect();
        let schedule = Schedule::adjacent_pairs_under(16, &pairs, 1e-3).expect("a schedule");
        (spec, schedule)
    }

    /// No departure from the model at all.
    fn none() -> Mismatch {
        Mismatch {
            position: 0.0,
            width: 1.0,
            contact_spread: 0.0,
            contact_drift: 0.0,
            unevenness: 0.0,
            seed: 1,
        }
    }

    #[test]
    fn no_mismatch_is_the_network_as_drawn() {
        let (spec, schedule) = tank();
        let (reference, later) = none().sheets(&spec).unwrap();
        let plain = SimulatedSheet::new(&spec, &[]).unwrap();
        let ideal = Instrument::ideal();
        let a = frames_between(&reference, &later, &schedule, &[vec![]], &ideal).unwrap();
        let b = frames(&plain, &schedule, &[vec![]], &ideal).unwrap();
        for (x, y) in a.iter().flatten().zip(b.iter().flatten()) {
            assert!((x - y).abs() <= 1e-9 * y.abs().max(1e-6), "{x} against {y}");
        }
    }

    #[test]
    fn contacts_drifting_change_the_drive_electrodes_values_most() {
        // A contact's impedance is in series with its electrode: it adds I z to the values
        // measured on a drive electrode and reaches the others only through the current's
        // spread under the electrode.
        let (spec, schedule) = tank();
        let drift = Mismatch {
            contact_drift: 0.2,
            seed: 3,
            ..none()
        };
        let (reference, later) = drift.sheets(&spec).unwrap();
        let f = frames_between(
            &reference,
            &later,
            &schedule,
            &[vec![]],
            &Instrument::ideal(),
        )
        .unwrap();
        let (mut on, mut off) = (Vec::new(), Vec::new());
        for (k, row) in schedule.rows().iter().enumerate() {
            let change = (f[1][k] - f[0][k]).abs() / f[0][k].abs().max(1e-12);
            let driven = [row.source, row.sink];
            if driven.contains(&row.positive) || driven.contains(&row.negative) {
                on.push(change);
            } else {
                off.push(change);
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        assert!(
            mean(&on) > 5.0 * mean(&off),
            "relative change on drive electrodes {:.2e}, off them {:.2e}",
            mean(&on),
            mean(&off)
        );
    }

    #[test]
    fn a_contact_count_other_than_the_electrodes_is_refused() {
        let (spec, _) = tank();
        let err = SimulatedSheet::with_contacts(&spec, &[], &[20.0; 15], None).unwrap_err();
        assert!(
            matches!(
                err,
                crate::sheet::SheetError::Spec(et_core::sheet::SheetError::Field {
                    field: "contacts",
                    fault: et_core::sheet::FieldFault::Count {
                        found: 15,
                        need: 16,
                        ..
                    },
                })
            ),
            "{err}"
        );
    }
}
