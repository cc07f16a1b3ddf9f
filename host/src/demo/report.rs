//! The report's pieces: sections with their summary keys, the at-a-glance table, the machine and
//! the date.

use super::*;

/// One section of the report.
pub(super) struct Section<T> {
    pub(super) markdown: String,
    pub(super) json: serde_json::Value,
    pub(super) key: T,
}

pub(super) fn summary_table(
    learning: &Section<LearningKey>,
    imaging: &Section<ImagingKey>,
    sweep: &Section<SweepKey>,
) -> String {
    let mut s = String::from(
        "## At a glance\n\n| what | result | reference (docs/method.md §10) |\n| --- | --- | --- |\n",
    );
    let l = &learning.key;
    let _ = writeln!(
        s,
        "| next-day accuracy, 49 classes, QDA on referenced frames | **{:.1} %** | 91.6 % |",
        100.0 * l.next_day
    );
    let _ = writeln!(
        s,
        "| the same with docs/method.md §9's QDA on raw frames | {} | 91.6 % |",
        l.raw
            .map_or("cannot be fitted".into(), |a| format!("{:.1} %", 100.0 * a))
    );
    let _ = writeln!(
        s,
        "| 10-fold cross-validation (training set) | {:.1} % | |",
        100.0 * l.cv
    );
    if let Some(c) = l.chip {
        let _ = writeln!(
            s,
            "| on the chip: {} features, f16, {} bytes, through et-core | {:.1} % | |",
            c.features,
            c.bytes,
            100.0 * c.accuracy()
        );
    }
    let i = &imaging.key;
    let _ = writeln!(
        s,
        "| single touch: ROI centroid within the touch radius (docs/method.md §7) | {} of {} images | |",
        i.single.0, i.single.1
    );
    let _ = writeln!(
        s,
        "| single touch: found as one touch, within its radius | {} of {} images | |",
        i.one_touch.0, i.one_touch.1
    );
    let _ = writeln!(
        s,
        "| ... with the protocol docs/method.md §8 chooses from the AD image | {} of {} touches | |",
        i.chosen.0, i.chosen.1
    );
    let _ = writeln!(
        s,
        "| two touches found as two touches | {} | |",
        if i.two.is_empty() {
            "no protocol".to_string()
        } else {
            i.two.join(", ")
        }
    );
    if let Some((t, setup, live)) = sweep.key.at_8k {
        let _ = writeln!(
            s,
            "| set-up at {t} triangles (mesh, forward, Jacobian, one-step matrix) | {setup:.3} s | |"
        );
        let _ = writeln!(
            s,
            "| live frame onto the mesh at {t} triangles | {live:.0} us ({:.0} frames/s) | about 30 Hz |",
            1e6 / live
        );
    }
    s.push('\n');
    s
}

/// "CPU model, N cores, M GiB" from /proc where it exists.
#[must_use]
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    let mem = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemTotal"))?;
            let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(format!(", {:.0} GiB", kb / 1024.0 / 1024.0))
        })
        .unwrap_or_default();
    format!("{cpu}, {cores} cores{mem}")
}

/// Today's date, UTC, as YYYY-MM-DD.
#[must_use]
pub fn today_utc() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    civil_date(secs / 86_400)
}

/// Days since 1970-01-01 as YYYY-MM-DD (proleptic Gregorian; H. Hinnant's algorithm).
pub fn civil_date(days: u64) -> String {
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

/// The report's last section: every abbreviation and symbol it uses, with the section of
/// docs/method.md that defines it.
pub(super) const GLOSSARY: &str = "## Glossary\n\n\
The method's sections are in `docs/method.md` of the et repository.\n\n\
| term | meaning | method |\n\
| --- | --- | --- |\n\
| AD, PP, PP-PP, opposite | the protocols: current between adjacent electrodes (i, i+1); pseudo-polar, between electrodes one short of opposite (i, i + L/2 - 1); PP drive read on adjacent and on pseudo-polar pairs; between opposite electrodes (i, i + L/2) | §4 |\n\
| K | measurements per frame (the length of V_m) | §3, §4 |\n\
| V_m, V_0 | a frame of boundary voltages, V; the untouched sheet's frame (the mean of the reference frames) | §3 |\n\
| BVC | boundary voltage change, the length of V_m - V_0, V: how much a touch changes the boundary | §7 |\n\
| CEM | the complete electrode model: electrodes with width and contact resistance | §5 |\n\
| NOSER | the prior that weighs each element by its own sensitivity, to the power s | §6.2 |\n\
| s (`--s`) | NOSER's exponent: 0 weighs every element alike, 1 fully by its sensitivity; 0.5 here | §6.2 |\n\
| alpha | the regularisation weight: larger gives smoother, quieter, blurrier images | §6.2, §6.3 |\n\
| GCV | generalised cross-validation, the rule that picks alpha from the frame itself | §6.3 |\n\
| ROI | region of interest: the pixels at or above f times the image's maximum | §6.5 |\n\
| f | the ROI threshold, a share of the image's maximum (0.10 AD and opposite, 0.08 PP, 0.05 PP-PP) | §6.5 |\n\
| z | a pixel's value over its noise (its standard deviation on the untouched sheet); a touch reaches z = 5 | §6.5 |\n\
| PE | position error: from the true centre to the ROI's centroid, over the sheet's largest extent | §7 |\n\
| SE | size error: the ROI's area less the touch's, over the sheet's area | §7 |\n\
| RNG | ringing: the area of opposite-sign change over the area outside the ROI | §7 |\n\
| xi | how near the centre a single touch must be for §8 to switch to PP (a share of d_c, the centre's distance to the outline) | §8 |\n\
| QDA, LDA | quadratic and linear discriminant analysis: a Gaussian per class, with its own or one shared covariance | §9.2 |\n\
| p | features: the measurements the classifier uses (reciprocity halves K) | §9.1 |\n\
| shrinkage | lambda, the weight pulling each class's covariance toward a target, the pooled covariance or a multiple of the identity (0: none); chosen by cross-validation | §9.2 |\n\
| S_num, S_sub, T | scans per visit, sub-section medians per scan, visits: S_num x S_sub x T observations per class | §9.4 |\n\
| AEE | aggregated estimation error: the distances of the wrong decisions, summed and divided by the number of classes | §9.5 |\n\
| Fisher ratio | a feature's spread of class means over its spread within the classes (`et train --keep` keeps the largest) | - |\n";
