//! Whole numbers read from files people write (JSON, TOML): any integer is read, and one the
//! field's type cannot hold is refused by that type's range ("70000 is out of range: 0 to
//! 65535"), not by the parser's name for the type ("invalid value: integer `70000`, expected
//! u16"). Binary formats (the wire's postcard) read the field as they always have.

use core::fmt;

use serde::de::{Error, Visitor};
use serde::{Deserialize, Deserializer};

/// An unsigned integer type a file's field is read into, with its range.
pub trait Whole: Sized + TryFrom<i128> {
    /// The largest value, as i128.
    const MAX: i128;
}

macro_rules! whole {
    ($($t:ty),*) => {$(
        impl Whole for $t {
            const MAX: i128 = <$t>::MAX as i128;
        }
    )*};
}
whole!(u8, u16, u32, u64, usize);

/// `#[serde(deserialize_with = "crate::whole::whole")]`: the field read as any integer in a
/// human-readable format and refused by its type's range when it is past it; as the type
/// itself in a binary one.
///
/// # Errors
/// The format's error, or one saying the value and the range.
pub fn whole<'de, D, T>(d: D) -> Result<T, D::Error>
where
    D: Deserializer<'de>,
    T: Whole + Deserialize<'de>,
{
    if !d.is_human_readable() {
        return T::deserialize(d);
    }
    let v = any_whole(d)?;
    T::try_from(v).map_err(|_| Error::custom(format_args!("{v} is out of range: 0 to {}", T::MAX)))
}

/// Any integer a human-readable file holds, as i128, for a field that says its own range; any
/// other value is "invalid type: ..., expected a whole number" (a string, a fraction, a list).
///
/// # Errors
/// The format's error for a value that is not an integer.
pub fn any_whole<'de, D: Deserializer<'de>>(d: D) -> Result<i128, D::Error> {
    d.deserialize_any(AnyWhole)
}

/// [`any_whole`]'s visitor.
struct AnyWhole;

impl Visitor<'_> for AnyWhole {
    type Value = i128;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a whole number")
    }

    fn visit_i64<E: Error>(self, v: i64) -> Result<i128, E> {
        Ok(v.into())
    }

    fn visit_u64<E: Error>(self, v: u64) -> Result<i128, E> {
        Ok(v.into())
    }

    fn visit_i128<E: Error>(self, v: i128) -> Result<i128, E> {
        Ok(v)
    }

    fn visit_u128<E: Error>(self, v: u128) -> Result<i128, E> {
        i128::try_from(v).map_err(|_| E::custom(format_args!("{v} is out of range")))
    }
}

#[cfg(test)]
mod tests {
    use crate::config::ScanConfig;

    /// A file's value past its field's type is said with the type's range; the wire (postcard)
    /// reads the same fields as before, bit for bit.
    #[test]
    fn a_value_past_its_type_is_said_by_the_range_and_the_wire_is_unchanged() {
        let json = serde_json::to_value(ScanConfig::REFERENCE).unwrap();
        for (field, value, said) in [
            ("gain", "1000", "1000 is out of range: 0 to 255"),
            (
                "samples_per_step",
                "70000",
                "70000 is out of range: 0 to 65535",
            ),
            ("settle_samples", "-1", "-1 is out of range: 0 to 65535"),
            (
                "current_na",
                "5000000000",
                "5000000000 is out of range: 0 to 4294967295",
            ),
        ] {
            let mut j = json.clone();
            j[field] = serde_json::from_str(value).unwrap();
            let e = serde_json::from_value::<ScanConfig>(j)
                .unwrap_err()
                .to_string();
            assert!(e.contains(said), "{field}: {e}");
        }
        let back: ScanConfig = serde_json::from_value(json).unwrap();
        assert_eq!(back, ScanConfig::REFERENCE);
        let config = ScanConfig {
            gain: 200,
            sample_rate_hz: 4_000_000_000,
            ..ScanConfig::REFERENCE
        };
        let mut buf = [0u8; 64];
        let bytes = postcard::to_slice(&config, &mut buf).unwrap();
        assert_eq!(postcard::from_bytes::<ScanConfig>(bytes).unwrap(), config);
    }
}
