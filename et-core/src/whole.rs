//! Whole numbers read from files people write (JSON, TOML): any integer is read, and one the
//! field's type cannot hold is refused by that type's range ("70000 is out of range: 0 to
//! 65535"), not by the parser's name for the type ("invalid value: integer `70000`, expected
//! u16"). Binary formats (the wire's postcard) read the field as they always have.

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
whole!(u8, u16, u32, u64);

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
    let v = i128::deserialize(d)?;
    T::try_from(v)
        .map_err(|_| serde::de::Error::custom(format_args!("{v} is out of range: 0 to {}", T::MAX)))
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
