//! The checks an et dataset passes after it is read, whatever its format.

use std::path::Path;

use super::{Dataset, DatasetError, DatasetFault, content};

/// The checks both formats share, after reading: every number finite (features, positions,
/// pressures, untouched frames, class and electrode centres), one centre per electrode, and the visits numbered 0 to T - 1 with none missing (a
/// visit number is a fold of leave-one-visit-out: 65 535 of them for three visits would run
/// 65 535 folds).
pub(super) fn consistent(path: &Path, data: &Dataset) -> Result<(), DatasetError> {
    let fault = |field: &str, fault| content(path, 0, Some(field.to_string()), fault);
    let finite = |field: &str, mut values: std::slice::Iter<'_, f64>| match values
        .position(|v| !v.is_finite())
    {
        Some(i) => Err(fault(field, DatasetFault::ValueNotFinite(i + 1))),
        None => Ok(()),
    };
    data.config
        .validate()
        .map_err(|e| content(path, 0, None, DatasetFault::ConfigInvalid(e)))?;
    if let Some(&class) = data
        .y
        .iter()
        .find(|&&c| usize::from(c) >= data.centres.len())
    {
        let centres = data.centres.len();
        return Err(fault("label", DatasetFault::NoCentre { class, centres }));
    }
    finite("features", data.x.as_slice().iter())?;
    finite("untouched", data.baselines.as_slice().iter())?;
    finite("pressure", data.pressure.iter())?;
    if let Some(i) = data.pressure.iter().position(|&p| p < 0.0) {
        return Err(fault("pressure", DatasetFault::NegativePressure(i + 1)));
    }
    finite("position", data.positions.as_flattened().iter())?;
    finite("centres_m", data.centres.as_flattened().iter())?;
    finite("electrodes_m", data.electrodes.as_flattened().iter())?;
    let (given, scan) = (data.electrodes.len(), usize::from(data.config.electrodes));
    if given != 0 && given != scan {
        return Err(fault(
            "electrodes_m",
            DatasetFault::ElectrodeCount { given, scan },
        ));
    }
    let frame_len = et_core::protocol::Protocol::new(data.config.protocol, data.config.electrodes)
        .map_or(usize::MAX, |p| p.frame_len());
    for (j, pair) in data.feature_index.windows(2).enumerate() {
        if let [before, index] = pair
            && index <= before
        {
            let (feature, index, before) = (j + 2, *index, *before);
            let order = DatasetFault::FeatureOrder {
                feature,
                index,
                before,
            };
            return Err(fault("feature_index", order));
        }
    }
    if let Some(&last) = data.feature_index.last()
        && usize::from(last) >= frame_len
    {
        let past = DatasetFault::PastFrame {
            index: last,
            frame_len,
        };
        return Err(fault("feature_index", past));
    }
    let mut seen = vec![false; data.x.nrows().min(usize::from(u16::MAX)) + 1];
    for &v in &data.visit {
        match seen.get_mut(usize::from(v)) {
            Some(s) => *s = true,
            None => {
                let rows = data.x.nrows();
                return Err(fault("visit", DatasetFault::VisitPast { visit: v, rows }));
            }
        }
    }
    let t = data.visits();
    if let Some(missing) = seen.iter().take(t).position(|s| !s) {
        let last = t - 1;
        return Err(fault("visit", DatasetFault::VisitMissing { last, missing }));
    }
    Ok(())
}
