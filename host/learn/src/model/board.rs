//! A board model in use: QDA or LDA from an et dataset (its [`ModelFile`] and the fitted
//! tables made from it once), classifying frames as the live pipeline does, predicting and
//! testing on datasets as `et eval` does, and checked against the blob the chip evaluates.

use nalgebra::DMatrix;

use crate::analysis::{self, Band, Outcome};
use crate::cv::{self, Confusion};
use crate::dataset::{DataError, Dataset};
use crate::fit::{FitError, Fitted};
use crate::model_file::ModelFile;
use crate::regress::posterior_centre;
use et_core::ScanConfig;
use et_core::board::MODEL_SLOT_BYTES;
use et_core::model::Precision;

mod error;
pub use error::{SlotError, UseError};

/// A board model ready to classify: its file, checked, and the fitted tables made from it.
#[derive(Clone, Debug)]
pub struct Board {
    file: ModelFile,
    fitted: Fitted,
}

/// Two board models are equal when their files are (the fitted tables are made from the file).
impl PartialEq for Board {
    fn eq(&self, other: &Self) -> bool {
        self.file == other.file
    }
}

/// What a board model says of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Classification {
    /// The most probable class (argmax of the discriminants).
    pub class: u16,
    /// Its posterior probability (0 to 1), the discriminants' softmax.
    pub posterior: f64,
    /// The class centres weighted by their posteriors, m: a position between the cells.
    pub centre: [f64; 2],
}

impl Board {
    /// The model a file holds, checked as the board checks a blob
    /// ([`ModelFile::validate`]): every reader of a board model accepts and refuses the same.
    ///
    /// # Errors
    /// [`FitError`] when the file's tables are not a usable model.
    pub fn new(file: ModelFile) -> Result<Self, FitError> {
        file.validate()?;
        let fitted = file.fitted()?;
        Ok(Self { file, fitted })
    }

    /// As trained and saved.
    #[must_use]
    pub fn file(&self) -> &ModelFile {
        &self.file
    }

    /// The discriminant tables.
    #[must_use]
    pub fn fitted(&self) -> &Fitted {
        &self.fitted
    }

    /// The class of one frame's features `x` (p values, the model's features), its posterior
    /// and the posterior-weighted centre; None when the discriminants are not finite.
    #[must_use]
    pub fn classify_features(&self, x: &[f64]) -> Option<Classification> {
        if x.len() != self.fitted.features() {
            return None;
        }
        let d = self.fitted.discriminants(x);
        if !d.iter().all(|v| v.is_finite()) {
            return None;
        }
        let class = crate::fit::argmax(&d);
        let top = *d.get(usize::from(class))?;
        let total: f64 = d.iter().map(|v| (v - top).exp()).sum();
        Some(Classification {
            class,
            posterior: 1.0 / total,
            centre: posterior_centre(&self.fitted, x, &self.file.centres, 1.0),
        })
    }

    /// The class of a frame V (K values, V) scanned with `config`, given the untouched frame
    /// V_0 (read only when the model is referenced), as the live pipeline classifies each
    /// touched frame; None when the frame is of another scan than the model's, either frame is
    /// too short, or the discriminants are not finite.
    #[must_use]
    pub fn classify<T: Copy + Into<f64>>(
        &self,
        config: &ScanConfig,
        v: &[T],
        v0: &[f64],
    ) -> Option<Classification> {
        if *config != self.file.config {
            return None;
        }
        self.classify_features(&self.file.features(v, v0)?)
    }

    /// The class of each frame, a row of `frames` (n x K, V), minus `v0` (K values) when the
    /// model is referenced.
    ///
    /// # Errors
    /// [`UseError::FrameLength`] when the frames or `v0` are not of the model's K values
    /// (frames of 100 values were classified when the features the model reads fell inside
    /// them, though they are another protocol's frames); [`UseError::NotFinite`] for a value
    /// the model reads that is NaN or infinite; [`UseError::Fit`] when a frame's discriminants are not finite.
    pub fn predict_frames(&self, frames: &DMatrix<f64>, v0: &[f64]) -> Result<Vec<u16>, UseError> {
        self.frame_lengths(frames.ncols(), v0.len())?;
        let wrong = UseError::FrameLength {
            frame: frames.ncols(),
            v0: v0.len(),
            k: frames.ncols(),
            features: self.file.feature_index.len(),
            scan: self.file.config,
        };
        // A value the model reads that is NaN was class 8 of 9 (the argmax of NaN
        // discriminants); the values it does not read are left alone.
        let read = &self.file.feature_index;
        let not_finite = |v: &[f64], frame| {
            let index = read
                .iter()
                .map(|&i| usize::from(i))
                .find(|&i| v.get(i).is_some_and(|v| !v.is_finite()))?;
            Some(UseError::NotFinite {
                frame,
                index,
                value: v[index],
            })
        };
        if let Some(e) = not_finite(v0, None) {
            return Err(e);
        }
        let mut frame = vec![0.0; frames.ncols()];
        (0..frames.nrows())
            .map(|r| {
                for (j, v) in frame.iter_mut().enumerate() {
                    *v = frames[(r, j)];
                }
                if let Some(e) = not_finite(&frame, Some(r)) {
                    return Err(e);
                }
                let x = self
                    .file
                    .features(&frame, v0)
                    .ok_or_else(|| wrong.clone())?;
                (self.fitted.predict_finite(&x))
                    .ok_or(UseError::Fit(FitError::Discriminants { row: r }))
            })
            .collect()
    }

    /// Whether frames of `frame` values and an untouched frame of `v0` (0: none) are of the
    /// model's scan, K values each.
    ///
    /// # Errors
    /// [`UseError::FrameLength`] when they are not.
    pub fn frame_lengths(&self, frame: usize, v0: usize) -> Result<(), UseError> {
        let k = self.file.config.validate().map(|p| p.frame_len()).ok();
        if k.is_some_and(|k| frame != k || !(v0 == 0 || v0 == k)) {
            return Err(UseError::FrameLength {
                frame,
                v0,
                k: k.unwrap_or(0),
                features: self.file.feature_index.len(),
                scan: self.file.config,
            });
        }
        Ok(())
    }

    /// What to say when the features of `frames` (n x K, V; minus `v0` when the model is
    /// referenced) are past [`FEATURE_SCALE_SAID`](crate::tabular::FEATURE_SCALE_SAID) times
    /// the training's either way (frames in mV where V was trained, which are classified
    /// without an error, and wrongly), only larger for a referenced model; None when they are
    /// alike or do not fit the model.
    #[must_use]
    pub fn frames_scale_note(&self, frames: &DMatrix<f64>, v0: &[f64]) -> Option<String> {
        let file = &self.file;
        let rows: Vec<Vec<f64>> = (frames.row_iter())
            .filter_map(|r| file.features(&r.iter().copied().collect::<Vec<f64>>(), v0))
            .collect();
        let x = DMatrix::from_row_iterator(
            rows.len(),
            file.feature_mean.len(),
            rows.iter().flatten().copied(),
        );
        let s = crate::tabular::features_scale(&file.feature_mean, &file.feature_scale, &x)?;
        // A referenced model's features are changes: a light touch's, or an untouched
        // frame's, are rightly smaller than the training's (one pressed frame was said to be
        // "1/13 of" them); only larger is a unit's.
        if file.referenced && s < 1.0 {
            return None;
        }
        crate::tabular::features_scale_note(s)
    }

    /// The class of each observation of `data` (raw frames as collected: the model's own
    /// features are taken from it, minus each visit's untouched frame if the model is
    /// referenced).
    ///
    /// # Errors
    /// [`UseError::Config`] when they were scanned differently, [`UseError::Data`] when the
    /// dataset lacks the model's features or untouched frames.
    pub fn predict(&self, data: &Dataset) -> Result<Vec<u16>, UseError> {
        Ok(cv::predict_rows(&self.fitted, &self.features_of(data)?)?)
    }

    /// `data`'s observations as the model reads them (n x p: its features, minus each
    /// visit's untouched frame when referenced).
    ///
    /// # Errors
    /// As [`predict`](Self::predict).
    fn features_of(&self, data: &Dataset) -> Result<DMatrix<f64>, UseError> {
        let file = &self.file;
        let (m, d) = (file.config, data.config);
        if (m.electrodes, m.protocol, m.current_na, m.gain)
            != (d.electrodes, d.protocol, d.current_na, d.gain)
        {
            return Err(UseError::Config { model: m, data: d });
        }
        let columns = model_columns(file, data)?;
        Ok(analysis::select_columns(
            &data.features(file.referenced)?,
            &columns,
        ))
    }

    /// Tests the model on `data` ([`predict`](Self::predict)): the confusion, the errors by
    /// distance from the electrodes, and from the true press positions when known.
    ///
    /// # Errors
    /// As [`predict`](Self::predict); [`UseError::Fit`] when the dataset does not match its
    /// classes.
    pub fn test(&self, data: &Dataset) -> Result<Tested, UseError> {
        let file = &self.file;
        // One prediction per observation serves the confusion, the bands and the errors; the
        // features it reads are those the training kept fingerprints of. (Another scan is
        // said first: its sheet differs too.)
        let observations = self.features_of(data)?;
        self.same_places(data)?;
        let predicted = cv::predict_rows(&self.fitted, &observations)?;
        let trained_note = crate::fingerprint::seen_share(&file.seen, &observations)
            .filter(|&share| share > crate::fingerprint::SEEN_SAID)
            .map(|share| {
                format!(
                    "these observations hold about {:.0} % of those the model was trained on: \
                     their accuracy is the training's, higher than on a session it has not \
                     seen; test on another visit's dataset (et collect --seed ...)",
                    100.0 * share
                )
            });
        // A dataset in mV where V was trained is classified without an error, and wrongly.
        let scale_note =
            crate::tabular::features_scale(&file.feature_mean, &file.feature_scale, &observations)
                .and_then(crate::tabular::features_scale_note);
        let confusion = cv::confusion_of(file.classes.len(), &data.y, &predicted)?;
        // The report is in mm, as people read it.
        let centres_mm = file.board_positions();
        let electrodes_mm: Vec<[f64; 2]> = data
            .electrodes
            .iter()
            .map(|e| [e[0] * 1e3, e[1] * 1e3])
            .collect();
        let outcomes = if electrodes_mm.is_empty() {
            Vec::new()
        } else {
            analysis::outcomes(&predicted, &data.y, &centres_mm, &electrodes_mm)?
        };
        let bands = analysis::by_distance(&outcomes, 10.0);
        let errors_from_truth_mm = if data.positions.len() == predicted.len() {
            predicted
                .iter()
                .zip(&data.positions)
                .map(|(&c, truth)| {
                    let c = centres_mm.get(usize::from(c))?;
                    Some((c[0] - truth[0] * 1e3).hypot(c[1] - truth[1] * 1e3))
                })
                .collect::<Option<Vec<f64>>>()
                .unwrap_or_default()
        } else {
            Vec::new()
        };
        Ok(Tested {
            trained_note,
            scale_note,
            centres_mm,
            confusion,
            outcomes,
            bands,
            errors_from_truth_mm,
        })
    }

    /// Whether `data`'s classes are the model's: as many, each at the model's place for it
    /// (within a twentieth of the closest two classes' spacing; one scene's grid is the same to
    /// rounding). Data collected on another grid or sheet label other places with the same
    /// numbers: a 2 x 2 grid scored 25 % on a 3 x 3 model, a 17 cm sheet's 3 x 3 grid 88.9 %
    /// on the 13 cm sheet's, without a word. Data that do not say their centres pass; so does
    /// their sheet ([`same_sheet`](Self::same_sheet)).
    fn same_places(&self, data: &Dataset) -> Result<(), UseError> {
        let (model, theirs) = (&self.file.centres, &data.centres);
        if model.is_empty() || theirs.is_empty() {
            return self.same_sheet(&data.electrodes);
        }
        if model.len() != theirs.len() {
            return Err(UseError::Classes {
                model: model.len(),
                data: theirs.len(),
            });
        }
        match first_moved(model, theirs) {
            Some(class) => Err(UseError::Places {
                class,
                model_mm: model[class].map(|c| c * 1e3),
                data_mm: theirs[class].map(|c| c * 1e3),
            }),
            None => self.same_sheet(&data.electrodes),
        }
    }

    /// Whether the model's classes are places on the sheet whose nominal electrode centres
    /// are `electrodes` (m, in the scan's order): its training data's electrodes each within a
    /// twentieth of their closest two's spacing of them. A model trained on a 17 cm sheet
    /// classified touches on the 13 cm sheet with its own class centres, 56.7 mm out for a
    /// touch 25 mm from the middle, at a posterior of 1.0, without a word (the frames of two
    /// squares of one shape differ little). Passes when either side does not say.
    ///
    /// # Errors
    /// [`UseError::Electrodes`] for another count, [`UseError::Sheet`] for another place.
    pub fn same_sheet(&self, electrodes: &[[f64; 2]]) -> Result<(), UseError> {
        let model = &self.file.electrodes;
        if model.is_empty() || electrodes.is_empty() {
            return Ok(());
        }
        if model.len() != electrodes.len() {
            return Err(UseError::Electrodes {
                model: model.len(),
                given: electrodes.len(),
            });
        }
        match first_moved(model, electrodes) {
            Some(electrode) => Err(UseError::Sheet {
                electrode,
                model_mm: model[electrode].map(|c| c * 1e3),
                given_mm: electrodes[electrode].map(|c| c * 1e3),
            }),
            None => Ok(()),
        }
    }

    /// The et-core blob at `precision` (what `et upload` sends).
    ///
    /// # Errors
    /// [`FitError`] when the blob's own validation refuses the tables.
    pub fn blob(&self, precision: Precision) -> Result<Vec<u8>, FitError> {
        self.file.blob(precision)
    }

    /// The blob for one model slot of the board: f32 when it fits, else f16 (about 3
    /// significant digits, half the flash).
    ///
    /// # Errors
    /// [`SlotError::TooLarge`] when not even the f16 blob fits; [`SlotError::Fit`] when the
    /// blob's own validation refuses the tables.
    pub fn slot_blob(&self) -> Result<Vec<u8>, SlotError> {
        let mut bytes = 0;
        for precision in [Precision::F32, Precision::F16] {
            let blob = self.blob(precision)?;
            if blob.len() <= MODEL_SLOT_BYTES {
                return Ok(blob);
            }
            bytes = blob.len();
        }
        Err(SlotError::TooLarge { bytes })
    }

    /// Classifies every observation of `data` with `blob` through `et_core::model` (frames as
    /// f32 V_m, and each visit's untouched frame as V_0 for a referenced model), as the
    /// firmware does, and compares with this f64 model.
    ///
    /// # Errors
    /// [`UseError::Blob`] when the blob does not parse, [`UseError::Data`] when the dataset
    /// lacks the model's features, [`UseError::Frame`] when a frame cannot be classified (not
    /// finite).
    pub fn on_chip(&self, blob: &[u8], data: &Dataset) -> Result<OnChip, UseError> {
        let file = &self.file;
        let chip = et_core::model::Model::parse(blob).map_err(UseError::Blob)?;
        let columns = model_columns(file, data)?;
        let xs = analysis::select_columns(&data.features(file.referenced)?, &columns);
        // A whole frame (K values) with the dataset's features in their frame positions.
        let k = chip.frame_len();
        let frame = |m: &DMatrix<f64>, r: usize| {
            let mut v = vec![0.0f32; k];
            for (j, &i) in data.feature_index.iter().enumerate() {
                if let Some(slot) = v.get_mut(usize::from(i)) {
                    *slot = m[(r, j)] as f32;
                }
            }
            v
        };
        let mut scratch = vec![0.0f32; chip.scratch_len()];
        let mut out = OnChip {
            right: 0,
            total: 0,
            disagree: 0,
        };
        let mut row = vec![0.0; xs.ncols()];
        for r in 0..data.x.nrows() {
            let v_m = frame(&data.x, r);
            let v_0 = file
                .referenced
                .then(|| frame(&data.baselines, usize::from(data.visit[r])));
            let d = chip
                .evaluate_referenced(&v_m, v_0.as_deref(), &mut scratch)
                .map_err(|error| UseError::Frame { row: r, error })?;
            for (j, v) in row.iter_mut().enumerate() {
                *v = xs[(r, j)];
            }
            out.disagree += usize::from(d.class != self.fitted.predict(&row));
            out.right += usize::from(d.class == data.y[r]);
            out.total += 1;
        }
        Ok(out)
    }
}

/// A model's results on a test set.
#[derive(Clone, Debug)]
pub struct Tested {
    /// The model's class centres, mm (what the cell errors are measured between).
    pub centres_mm: Vec<[f64; 2]>,
    /// The confusion matrix.
    pub confusion: Confusion,
    /// Per observation: distance from the electrodes and position error (empty when the
    /// dataset does not say where the electrodes are).
    pub outcomes: Vec<Outcome>,
    /// Mean error per 10 mm band of distance from the electrodes.
    pub bands: Vec<Band>,
    /// Per observation: the distance from where the finger really was to the predicted
    /// class's centre, mm (what a regressor's error compares with; not 0 when the class is
    /// right). Empty when the dataset has no positions.
    pub errors_from_truth_mm: Vec<f64>,
    /// What to say when the observations hold many the model was trained on.
    pub trained_note: Option<String>,
    /// What to say when the observations' features are another scale than the training's
    /// (another unit or gain; [`FEATURE_SCALE_SAID`](crate::tabular::FEATURE_SCALE_SAID)).
    pub scale_note: Option<String>,
}

/// How an exported blob did on a test set, evaluated by et-core as the firmware does it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct OnChip {
    /// Observations classified right.
    pub right: usize,
    /// Observations.
    pub total: usize,
    /// Observations where the chip's class differs from the f64 host model's.
    pub disagree: usize,
}

/// The dataset's columns holding `file`'s features, in the model's order (a feature-reduced
/// model uses a subset).
fn model_columns(file: &ModelFile, data: &Dataset) -> Result<Vec<usize>, DataError> {
    file.feature_index
        .iter()
        .map(|i| data.feature_index.iter().position(|d| d == i))
        .collect::<Option<Vec<usize>>>()
        .ok_or(DataError::MissingFeatures {
            dataset: data.feature_index.len(),
            model: file.feature_index.len(),
        })
}

/// The first point of `theirs` farther from `ours`' point of its number than a twentieth of
/// the closest two of `ours` (or not finite); `ours` and `theirs` of one length.
fn first_moved(ours: &[[f64; 2]], theirs: &[[f64; 2]]) -> Option<usize> {
    let apart = |a: &[f64; 2], b: &[f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let spacing = (ours.iter().enumerate())
        .flat_map(|(i, a)| ours.iter().skip(i + 1).map(move |b| apart(a, b)))
        .fold(f64::INFINITY, f64::min);
    (ours.iter().zip(theirs))
        .position(|(m, d)| apart(m, d) > spacing / 20.0 || !apart(m, d).is_finite())
}
