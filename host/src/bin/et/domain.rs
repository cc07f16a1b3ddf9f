//! The domain of every numeric flag: clap value parsers that refuse what is not a number of the
//! flag's kind before any work, saying what the flag takes.

/// A finite number from `lo` to `hi`, both included.
pub(crate) fn real(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |text| {
        let v = number(text)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(format!(
                "{} is outside {} to {}",
                text.trim(),
                short(lo),
                short(hi)
            ))
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
                "{} is not above {} and at most {}",
                text.trim(),
                short(lo),
                short(hi)
            ))
        }
    }
}

/// A whole number from `lo` to `hi`, both included.
pub(crate) fn count(lo: usize, hi: usize) -> impl Fn(&str) -> Result<usize, String> + Clone {
    whole(lo, hi)
}

/// A frame's index, from 0: `-1` (Python's last) is said as not counted from the end.
pub(crate) fn frame_index() -> impl Fn(&str) -> Result<usize, String> + Clone {
    move |text| {
        count(0, usize::MAX)(text).map_err(|e| {
            if text.trim().starts_with('-') {
                format!(
                    "{e} (frames are counted from 0 at the file's first, not from its end: \
                     without --frame the last is imaged)"
                )
            } else {
                e
            }
        })
    }
}

/// A whole number of the flag's type from `lo` to `hi`, both included.
pub(crate) fn whole<T>(lo: T, hi: T) -> impl Fn(&str) -> Result<T, String> + Clone
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display + Copy,
{
    move |text| {
        let t = text.trim();
        let v: T = t
            .parse()
            .map_err(|_| match (t.parse::<i128>(), t.parse::<f64>()) {
                // A whole number past the flag's type.
                (Ok(n), _) if n < 0 => format!("{n} is below {lo}, the least it takes"),
                (Ok(n), _) => format!("{n} is above {hi}, the most it takes"),
                (_, Ok(x)) if x.is_finite() && x.fract() == 0.0 && x.abs() < 1e30 => {
                    format!("'{t}' is not a whole number as written: write {x:.0}")
                }
                _ => format!("'{t}' is not a whole number"),
            })?;
        if v < lo {
            Err(format!("{v} is below {lo}, the least it takes"))
        } else if v > hi {
            Err(format!("{v} is above {hi}, the most it takes"))
        } else {
            Ok(v)
        }
    }
}

/// One electrode's number of a list (`3,7`; spaces around it allowed, as in "3, 7").
pub(crate) fn electrode(text: &str) -> Result<u16, String> {
    let t = text.trim();
    if t.is_empty() {
        return Err(
            "an empty place in the list: electrode numbers separated by commas, as 3,7".into(),
        );
    }
    t.parse().map_err(|_| {
        format!("'{t}' is not an electrode's number (whole numbers separated by commas, as 3,7)")
    })
}

/// A whole number within `range` (a library's domain, [`et_recon::limits`]).
pub(crate) fn within(
    range: std::ops::RangeInclusive<usize>,
) -> impl Fn(&str) -> Result<usize, String> + Clone {
    count(*range.start(), *range.end())
}

/// `x` as a reader writes it: 1e-9, not 0.000000001.
fn short(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e6).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
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
