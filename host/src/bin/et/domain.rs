//! The domain of every numeric flag: clap value parsers that refuse what is not a number of the
//! flag's kind before any work, saying what the flag takes.

/// A finite number from `lo` to `hi`, both included.
pub(crate) fn real(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |text| {
        let v = number(text)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(format!("{} is outside {lo} to {hi}", text.trim()))
        }
    }
}

/// A finite number above `lo` (excluded) and at most `hi`.
pub(crate) fn above(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |text| {
        let v = number(text)?;
        if v > lo && v <= hi {
            Ok(v)
        } else {
            Err(format!(
                "{} is not above {lo} and at most {hi}",
                text.trim()
            ))
        }
    }
}

/// A whole number from `lo` to `hi`, both included.
pub(crate) fn count(lo: usize, hi: usize) -> impl Fn(&str) -> Result<usize, String> + Clone {
    move |text| {
        let v: usize = text
            .trim()
            .parse()
            .map_err(|_| format!("'{text}' is not a whole number"))?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(format!("{v} is outside {lo} to {hi}"))
        }
    }
}

/// A whole number within `range` (a library's domain, [`et_recon::limits`]).
pub(crate) fn within(
    range: std::ops::RangeInclusive<usize>,
) -> impl Fn(&str) -> Result<usize, String> + Clone {
    count(*range.start(), *range.end())
}

fn number(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{} is not a finite number", text.trim()))
    }
}
