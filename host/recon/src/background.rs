//! The background from the data: the homogeneous sheet resistance R_s and one contact
//! resistance z_c (every electrode alike) with which the finite elements reproduce the
//! reference frame V_0 best, by least squares (docs/method.md §6.8).
//!
//! Scaling makes the fit one-dimensional: with sigma = 1 / R_s and the complete model's
//! contact z_c, the frame is V(R_s, z_c) = R_s F(z_c / R_s), F(rho) the frame of a unit sheet
//! with contacts of rho ohm. For each rho the best R_s is closed-form (R_s = <F, V_0> / |F|^2);
//! rho is searched on a logarithmic grid, then by golden section. The contact shows in a frame
//! only through measurements on drive electrodes (their contact's drop), so it is fitted only
//! when the protocol has them and the sheet's model is the complete one; otherwise R_s alone is
//! fitted at the scene's contact-to-sheet ratio.
//!
//! A system whose values are not volts (an unknown gain) fits R_s times that gain: images in
//! Delta sigma / sigma_0 do not change with it.

use et_core::schedule::Schedule;
use et_core::sheet::{ElectrodeModel, Sheet};

use crate::fem::{Electrodes, FemError, Forward, MIN_CONTACT_RATIO};
use crate::mesh::Mesh;

mod electrode;
pub use electrode::{
    CameOff, ELECTRODE_FACTOR, ELECTRODE_OWN, ElectrodeMisfit, detached_electrodes, detached_said,
    electrode_misfit, misfit_of,
};

/// The background fitted to a reference frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BackgroundFit {
    /// Sheet resistance R_s, ohm per square.
    pub sheet_resistance: f64,
    /// Each electrode's contact resistance, ohm (the scene's times the ratio kept when not
    /// fitted).
    pub contact_ohm: f64,
    /// Whether the contact was fitted (the complete model and measurements on drive
    /// electrodes), or kept at the scene's ratio to R_s.
    pub contact_fitted: bool,
    /// |V_0 - V(fit)| / |V_0|: what the homogeneous model leaves unexplained.
    pub residual: f64,
    /// The same at the scene's R_s and contact.
    pub scene_residual: f64,
    /// Forward solves the fit took.
    pub solves: usize,
    /// |V_0 - V(fit)| / |V_0| over the values measured on drive electrodes alone (None when
    /// there are none, or before the reconstructor has made the fitted model's frame).
    pub misfit_on_drive: Option<f64>,
    /// The same over the values off the drive electrodes.
    pub misfit_off_drive: Option<f64>,
    /// The electrode whose values the fitted model explains worst beside the rest (None
    /// before the reconstructor has made the fitted model's frame); a detached or broken
    /// electrode [stands out](ElectrodeMisfit::stands_out).
    pub worst_electrode: Option<ElectrodeMisfit>,
}

/// Why a background could not be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BackgroundError {
    /// The forward model failed.
    #[error("background fit: {0}")]
    Fem(#[from] FemError),
    /// The reference frame is not of K values.
    #[error(
        "background fit: the reference has {got} values for K = {k}{}",
        et_core::schedule::other_frame_len(*got, *k)
            .map_or_else(String::new, |may| format!(" (of another protocol? {may})"))
    )]
    FrameLength {
        /// Its length.
        got: usize,
        /// The protocol's.
        k: usize,
    },
    /// The reference frame holds a NaN or infinite value.
    #[error("background fit: the reference holds a NaN or infinite value")]
    FrameValues,
    /// The reference frame is one value throughout: not measured voltages.
    #[error("background fit: the reference {}", not_measured_said(*.0))]
    NotMeasured(f64),
    /// The reference frame is not the signed voltages the model gives ([`not_signed`]:
    /// magnitudes, or the model's frame plus a common level).
    #[error("background fit: the reference {0}")]
    NotSigned(NotSigned),
    /// The reference frame runs against the model (the best R_s is negative).
    #[error(
        "background fit: the reference frame runs against the model (R_s would be {rs:.3e} \
         ohm/sq < 0): are the protocol's positive and negative electrodes, or source and sink, \
         swapped, or the electrodes numbered the other way (electrodes.direction in a scene, \
         direction= in Python)?{}",
        if *one_sign { ONE_SIGN } else { "" }
    )]
    Sign {
        /// The best sheet resistance, ohm/sq (negative).
        rs: f64,
        /// Whether every value of the reference is of one sign (the model's of the other).
        one_sign: bool,
    },
    /// The fitted sheet resistance is outside the sheets et models
    /// ([`et_core::sheet::SHEET_OHM_RANGE`]): frames in other units or at another current.
    #[error(
        "background fit: the reference makes the sheet {rs:.3e} ohm/sq, where sheets are {:e} \
         to {:e}: are the frames in volts, at the protocol's current ({current_a:e} A)?",
        et_core::sheet::SHEET_OHM_RANGE.0,
        et_core::sheet::SHEET_OHM_RANGE.1
    )]
    Scale {
        /// The fitted sheet resistance, ohm per square.
        rs: f64,
        /// The protocol's (first row's) current, A.
        current_a: f64,
    },
}

/// How a reference is not the signed voltages the model of the untouched sheet gives.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum NotSigned {
    /// Magnitudes without their sign ([`not_signed`]): every value of `sign` (+1 or -1) or
    /// zero, where `other` of the model's `k` values are clearly of the other sign.
    Magnitudes {
        /// The sign every value holds.
        sign: i8,
        /// The model's values clearly of the other sign.
        other: usize,
        /// The frame's length, K.
        k: usize,
    },
    /// The model's frame at some scale plus a common `level` (V, or the frames' unit): ADC
    /// counts about a mid-scale, or an offset added. `with` and `without`: the share of V_0
    /// the model leaves unexplained with the level and without it.
    Offset {
        /// The common level.
        level: f64,
        /// The share left with the level.
        with: f64,
        /// The share left without it.
        without: f64,
    },
}

impl std::fmt::Display for NotSigned {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            NotSigned::Magnitudes { sign, other, k } => {
                let (has, lacks) = if sign > 0 {
                    ("positive", "negative")
                } else {
                    ("negative", "positive")
                };
                write!(
                    f,
                    "has every value {has} or zero, where the model's frame of the untouched \
                     sheet has {other} of its {k} {lacks} (the protocol's values change sign \
                     around the sheet): magnitudes without their sign? et images signed \
                     voltages: give the real part, or each magnitude with the sign of its \
                     phase's cosine"
                )
            }
            NotSigned::Offset {
                level,
                with,
                without,
            } => write!(
                f,
                "is the model's frame of the untouched sheet plus a common level of {} \
                 (with it the model leaves {:.1} % of V_0 unexplained, without it {:.0} %): ADC \
                 counts about a mid-scale, or an offset added? et images signed voltages: \
                 subtract the level (and scale counts to volts)",
                et_core::said::Plain(level),
                100.0 * with,
                100.0 * without
            ),
        }
    }
}

/// Whether `v0` (K values) is not the signed voltages the model gives, `model` being the
/// model's frame of the untouched sheet:
/// - [`NotSigned::Offset`] when a common level added to the model's frame at its best scale
///   explains `v0` (at most [`POOR_FIT`] left, and at most half what the scale alone leaves,
///   which is past [`POOR_FIT`]): ADC counts about a mid-scale read as magnitudes or as a
///   polarity swapped, the wrong causes;
/// - [`NotSigned::Magnitudes`] when every value is of one sign (or zero) where the model has
///   at least a tenth of its values clearly (beyond 5 % of its largest) of each sign. Some
///   systems write magnitudes; a protocol's values change sign around the sheet, and a
///   difference of magnitudes images every change where V_0 is negative with the wrong sign.
#[must_use]
pub fn not_signed(v0: &[f64], model: &[f64]) -> Option<NotSigned> {
    offset(v0, model).or_else(|| magnitudes(v0, model))
}

/// [`NotSigned::Offset`] of [`not_signed`].
fn offset(v0: &[f64], model: &[f64]) -> Option<NotSigned> {
    let k = v0.len().max(1) as f64;
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let vv = dot(v0, v0);
    let left = |proj: f64, of: f64| ((of - proj).max(0.0) / vv).sqrt();
    let (_, without) = best_scale(model, v0);
    let (mean_v, mean_m) = (v0.iter().sum::<f64>() / k, model.iter().sum::<f64>() / k);
    let vc: Vec<f64> = v0.iter().map(|v| v - mean_v).collect();
    let mc: Vec<f64> = model.iter().map(|m| m - mean_m).collect();
    let mcmc = dot(&mc, &mc).max(f64::MIN_POSITIVE);
    let slope = dot(&vc, &mc) / mcmc;
    let with = left(dot(&vc, &mc).powi(2) / mcmc, dot(&vc, &vc));
    let level = mean_v - slope * mean_m;
    (without > POOR_FIT && with <= POOR_FIT && with <= 0.5 * without).then_some(NotSigned::Offset {
        level,
        with,
        without,
    })
}

/// [`NotSigned::Magnitudes`] of [`not_signed`].
fn magnitudes(v0: &[f64], model: &[f64]) -> Option<NotSigned> {
    let sign: i8 = if v0.iter().all(|v| *v >= 0.0) {
        1
    } else if v0.iter().all(|v| *v <= 0.0) {
        -1
    } else {
        return None;
    };
    let clear = 0.05 * model.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let of = |s: f64| model.iter().filter(|m| **m * s > clear).count();
    let (same, other) = (of(f64::from(sign)), of(-f64::from(sign)));
    (same * 10 >= model.len() && other * 10 >= model.len()).then_some(NotSigned::Magnitudes {
        sign,
        other,
        k: v0.len(),
    })
}

/// What is added where a reference that runs against the model is of one sign throughout (a
/// protocol whose values the model gives all of one sign, adjacent's, read as magnitudes is
/// the model's frame negated: a system that writes magnitudes, not a swap).
pub const ONE_SIGN: &str = " Or magnitudes without their sign: every value of the reference is \
     of one sign, the model's all of the other; et images signed voltages (the real part)";

/// Whether every value of `v` is of one sign (zeros aside).
#[must_use]
pub fn one_sign(v: &[f64]) -> bool {
    v.iter().all(|x| *x >= 0.0) || v.iter().all(|x| *x <= 0.0)
}

/// The share of V_0 the homogeneous model may leave unexplained before it is said: the real
/// tanks' fitted models leave 1.5 and 7.7 %, a simulated tank with a real tank's departures
/// from the model 16.3 % (docs/measurements.md), frames of another built-in protocol of the
/// same K 71 %.
pub const POOR_FIT: f64 = 0.2;

/// What is said when the model leaves `residual` (a share, |V_0 - V(model)| / |V_0|) of V_0
/// unexplained past [`POOR_FIT`]; None within it.
#[must_use]
pub fn poor_fit_said(residual: f64) -> Option<String> {
    (residual > POOR_FIT).then(|| {
        format!(
            "the homogeneous model leaves {:.0} % of V_0 unexplained (past {:.0} %): check the \
             protocol's order and electrode numbering (electrodes.first_deg, direction), \
             that the sheet is the one measured (its outline, size and electrodes), and that \
             no reading is clipped",
            100.0 * residual,
            100.0 * POOR_FIT
        )
    })
}

/// The largest |value| (V) a reference frame from an EIT instrument reaches: tank systems
/// drive 0.1 to 5 mA and read a few volts (the real tanks of docs/measurements.md 3.5 V at
/// most), et's board reads 3.3 V at most. Frames past it are in another unit.
pub const VOLTS_MOST: f64 = 100.0;

/// What is said of a reference `v0` (K values) whose largest |value| passes [`VOLTS_MOST`]:
/// frames in millivolts, microvolts or ADC counts, which image the same places and signs
/// (the background fit takes the unit into the sheet resistance) but background, noise and
/// image values in the wrong unit; None within it.
#[must_use]
pub fn not_volts_said(v0: &[f64]) -> Option<String> {
    let most = v0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    (most > VOLTS_MOST).then(|| {
        format!(
            "the reference V_0 reaches {most:.0} V, past the {VOLTS_MOST:.0} V an EIT instrument \
             reads: frames in millivolts, microvolts or ADC counts? et reads volts (mV / \
             1000); where each object lies and its sign do not depend on the unit, but the \
             background (ohm/sq), the noise and the images' values do"
        )
    })
}

/// How far a reference frame may differ from the others as a change of the sheet does
/// ([`crate::Reconstructor::reference_changes`]: its mean square over that of its part no
/// conductivity change can make) before it is said: untouched references of et's scenes
/// under the four protocols reach 3.6, with a laboratory instrument's drift 4.3; a touch
/// during the reference 15 to 150.
pub const REFERENCE_CHANGE_SAID: f64 = 10.0;

/// What is said of untouched reference frames of which one differs from their mean as a
/// change of the sheet does past [`REFERENCE_CHANGE_SAID`]
/// ([`crate::Reconstructor::reference_changes`]); None within. Where one frame is the first
/// to differ from those before it, it is named (the words, not when they are said), and
/// `fewer` (given the count of frames before it) says how to take those alone, where the
/// caller can (`--reference N`).
#[must_use]
pub fn reference_changes_said(
    changes: crate::ReferenceChanges,
    fewer: Option<fn(usize) -> String>,
) -> Option<String> {
    let tail = "was the sheet touched, or drifting, while the reference was taken? every frame \
                is imaged against it";
    let noise = format!(
        "times the noise the protocol's redundancy shows (noise alone gives about 1; past \
         {REFERENCE_CHANGE_SAID:.0} is said)"
    );
    if changes.ratio <= REFERENCE_CHANGE_SAID {
        return None;
    }
    if let Some((n, ratio)) = changes.first_unlike {
        let fix = match fewer {
            Some(fewer) => {
                let before = if n == 1 {
                    "frame 0 before it is untouched, take it".to_string()
                } else {
                    format!("the {n} frames before it are untouched, take them")
                };
                format!(
                    "if only {before} alone ({}); else take it again untouched",
                    fewer(n)
                )
            }
            None => "take it again untouched".into(),
        };
        return Some(format!(
            "the untouched reference's frame {n} (from 0) is the first to differ from those \
             before it as a change of the sheet does, {ratio:.0} {noise}: {tail}: {fix}"
        ));
    }
    let (frame, ratio) = (changes.frame, changes.ratio);
    Some(format!(
        "the untouched reference's frame {frame} (from 0) differs from their mean as a change \
         of the sheet does, {ratio:.0} {noise}: {tail}: take it again untouched"
    ))
}

/// The value of a frame that holds one value throughout (all zero, or a constant): no
/// sheet's measurements do, whatever the protocol, its numbering or its polarity.
#[must_use]
pub fn one_value(v: &[f64]) -> Option<f64> {
    let first = *v.first()?;
    v.iter().all(|x| *x == first).then_some(first)
}

/// What is said of a frame of one value (`value` in every entry).
#[must_use]
pub fn not_measured_said(value: f64) -> String {
    // Frames are read in single precision: say such a value as it was written (0.01, not
    // 0.009999999776482582).
    // (-0 is said as 0.)
    let value = value + 0.0;
    #[allow(clippy::cast_possible_truncation)]
    let single = value as f32;
    let value = if f64::from(single) == value {
        single.to_string()
    } else {
        value.to_string()
    };
    format!(
        "is {value} in every entry: not measured voltages (a column of another quantity, \
         frames from a DAQ that was not running, or an empty recording?)"
    )
}

/// The unit sheet's frames: one forward model whose contacts change between solves (its
/// pattern and symbolic factorisation made once).
#[derive(Debug)]
pub struct UnitSheet<'a> {
    forward: Forward,
    width: f64,
    count: usize,
    schedule: &'a Schedule,
}

impl<'a> UnitSheet<'a> {
    /// `sheet`'s electrode model on `mesh` (the complete model at contacts of 1 ohm until
    /// [`UnitSheet::frame`] asks for others).
    ///
    /// # Errors
    /// [`FemError`] when the sheet's electrodes or the mesh cannot make a forward model.
    pub fn new(sheet: &Sheet, mesh: &Mesh, schedule: &'a Schedule) -> Result<Self, FemError> {
        let count = usize::from(sheet.electrodes.count);
        let width = sheet.electrodes.width;
        let electrodes = match sheet.electrodes.model {
            ElectrodeModel::Complete => Electrodes::Complete(vec![width; count]),
            _ => Electrodes::of_sheet(sheet)?,
        };
        Ok(Self {
            forward: Forward::new(mesh.clone(), electrodes)?,
            width,
            count,
            schedule,
        })
    }

    /// The unit sheet's frame with contacts of `rho` ohm (None: the sheet's point or shunt
    /// model).
    ///
    /// # Errors
    /// [`FemError`] when the contacts or the solve fail.
    pub fn frame(&mut self, rho: Option<f64>) -> Result<Vec<f64>, FemError> {
        if let Some(rho) = rho {
            self.forward
                .set_contacts(vec![rho * self.width; self.count])?;
        }
        let n = self.forward.mesh().triangles.len();
        self.forward.frame(&vec![1.0; n], self.schedule)
    }
}

/// (R_s, |V_0 - R_s F| / |V_0|) for the unit frame `f`: the best scale of `f` for `v0` and
/// the share of `v0` it leaves unexplained.
pub(crate) fn best_scale(f: &[f64], v0: &[f64]) -> (f64, f64) {
    let (fv, ff) = f
        .iter()
        .zip(v0)
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x * y, b + x * x));
    let rs = if ff > 0.0 { fv / ff } else { 0.0 };
    let misfit: f64 = f.iter().zip(v0).map(|(x, y)| (y - rs * x).powi(2)).sum();
    let norm: f64 = v0.iter().map(|v| v * v).sum();
    (rs, (misfit / norm).sqrt())
}

/// The background of `sheet` (its outline and electrodes; its R_s and contact the starting
/// guess) on `mesh` that best reproduces `v0` (K values of `schedule`, V). See the module docs.
///
/// # Errors
/// [`BackgroundError`] for a frame of the wrong length, non-finite or all zero, a reference
/// that runs against the model, or a failed solve.
pub fn fit(
    sheet: &Sheet,
    mesh: &Mesh,
    schedule: &Schedule,
    v0: &[f64],
) -> Result<BackgroundFit, BackgroundError> {
    let k = schedule.frame_len();
    if v0.len() != k {
        return Err(BackgroundError::FrameLength { got: v0.len(), k });
    }
    if v0.iter().any(|v| !v.is_finite()) {
        return Err(BackgroundError::FrameValues);
    }
    if let Some(value) = one_value(v0) {
        return Err(BackgroundError::NotMeasured(value));
    }
    let complete = matches!(sheet.electrodes.model, ElectrodeModel::Complete);
    let ratio = sheet.electrodes.contact_ohm / sheet.sheet_resistance;
    let unit = std::cell::RefCell::new(UnitSheet::new(sheet, mesh, schedule)?);
    let solves = std::cell::Cell::new(1);
    let eval = |rho: Option<f64>| -> Result<(f64, f64), BackgroundError> {
        solves.set(solves.get() + 1);
        Ok(best_scale(&unit.borrow_mut().frame(rho)?, v0))
    };
    let scene_rho = complete.then_some(ratio);
    let scene_frame = unit.borrow_mut().frame(scene_rho)?;
    if let Some(not) = not_signed(v0, &scene_frame) {
        return Err(BackgroundError::NotSigned(not));
    }
    let scene_fit = best_scale(&scene_frame, v0);
    // The scene's own residual, at its R_s (not the fitted scale).
    let scene_residual = {
        let misfit: f64 = scene_frame
            .iter()
            .zip(v0)
            .map(|(x, y)| (y - sheet.sheet_resistance * x).powi(2))
            .sum();
        (misfit / v0.iter().map(|v| v * v).sum::<f64>()).sqrt()
    };
    let fit_contact = complete && schedule.first_on_drive().is_some();
    let (rho, (rs, residual)) = if fit_contact {
        // log10 rho from 1e-4 sheet squares (where the contact's drop is under a thousandth
        // of the sheet's) to 100, half decades.
        let lo = -4.0f64.max(MIN_CONTACT_RATIO.log10());
        let grid: Vec<f64> = (0..)
            .map(|i| lo + 0.5 * f64::from(i))
            .take_while(|x| *x <= 2.0)
            .collect();
        let mut scores = Vec::with_capacity(grid.len());
        for &x in &grid {
            scores.push(eval(Some(10f64.powf(x)))?);
        }
        let best = (0..grid.len())
            .filter(|&i| scores[i].0 > 0.0)
            .min_by(|&a, &b| scores[a].1.total_cmp(&scores[b].1))
            .ok_or(BackgroundError::Sign {
                rs: scores[0].0,
                one_sign: one_sign(v0),
            })?;
        // Golden section on [grid[best - 1], grid[best + 1]].
        let (mut a, mut b) = (
            grid[best.saturating_sub(1)],
            grid[(best + 1).min(grid.len() - 1)],
        );
        let g = (5f64.sqrt() - 1.0) / 2.0;
        let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
        let (mut fc, mut fd) = (eval(Some(10f64.powf(c)))?, eval(Some(10f64.powf(d)))?);
        for _ in 0..8 {
            if fc.1 < fd.1 {
                (b, d, fd) = (d, c, fc);
                c = b - g * (b - a);
                fc = eval(Some(10f64.powf(c)))?;
            } else {
                (a, c, fc) = (c, d, fd);
                d = a + g * (b - a);
                fd = eval(Some(10f64.powf(d)))?;
            }
        }
        let (x, s) = if fc.1 < fd.1 { (c, fc) } else { (d, fd) };
        let (x, s) = if scores[best].1 < s.1 {
            (grid[best], scores[best])
        } else {
            (x, s)
        };
        (Some(10f64.powf(x)), s)
    } else {
        (scene_rho, scene_fit)
    };
    if rs <= 0.0 {
        let one_sign = one_sign(v0);
        return Err(BackgroundError::Sign { rs, one_sign });
    }
    let (low, high) = et_core::sheet::SHEET_OHM_RANGE;
    if !(low..=high).contains(&rs) {
        let current_a = schedule.rows().first().map_or(0.0, |r| r.current_a);
        return Err(BackgroundError::Scale { rs, current_a });
    }
    Ok(BackgroundFit {
        sheet_resistance: rs,
        contact_ohm: rho.map_or(sheet.electrodes.contact_ohm, |r| r * rs),
        contact_fitted: fit_contact,
        residual,
        scene_residual,
        solves: solves.get(),
        misfit_on_drive: None,
        misfit_off_drive: None,
        worst_electrode: None,
    })
}

impl BackgroundFit {
    /// `sheet` with the fitted sheet resistance and contact.
    #[must_use]
    pub fn apply(&self, sheet: &Sheet) -> Sheet {
        let mut out = sheet.clone();
        out.sheet_resistance = self.sheet_resistance;
        out.electrodes.contact_ohm = self.contact_ohm;
        out
    }
}
