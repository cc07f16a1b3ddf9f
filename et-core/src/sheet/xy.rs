//! Points `[x, y]` read from files: exactly two numbers. (Serde's fixed-size arrays take the
//! first two of a longer list and drop the rest: `position = [0, 0, 0]` was read as `[0, 0]`.)

use serde::{Deserialize, Deserializer};

fn exactly_two<E: serde::de::Error>(v: &[f64]) -> Result<[f64; 2], E> {
    <[f64; 2]>::try_from(v).map_err(|_| E::invalid_length(v.len(), &"two numbers, [x, y]"))
}

/// One point.
///
/// # Errors
/// Not a list of exactly two numbers.
pub fn one<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    exactly_two(&Vec::<f64>::deserialize(d)?)
}

/// A point that may be absent (use with `#[serde(default)]`).
///
/// # Errors
/// As [`one`].
pub fn option<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    Option::<Vec<f64>>::deserialize(d)?
        .map(|v| exactly_two(&v))
        .transpose()
}

/// A list of points.
///
/// # Errors
/// As [`one`], for any of them.
pub fn many<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    Vec::<Vec<f64>>::deserialize(d)?
        .iter()
        .map(|v| exactly_two(v))
        .collect()
}

#[cfg(test)]
mod tests {
    #[derive(serde::Deserialize, Debug)]
    struct P {
        #[serde(deserialize_with = "super::one")]
        at: [f64; 2],
        #[serde(default, deserialize_with = "super::option")]
        to: Option<[f64; 2]>,
        #[serde(default, deserialize_with = "super::many")]
        path: Vec<[f64; 2]>,
    }

    #[test]
    fn a_point_is_exactly_two_numbers() {
        let p: P = serde_json::from_str(r#"{"at": [1, 2], "path": [[0, 0], [1, 1]]}"#).unwrap();
        assert_eq!((p.at, p.to, p.path.len()), ([1.0, 2.0], None, 2));
        for bad in [
            r#"{"at": [0, 0, 0]}"#,
            r#"{"at": [0]}"#,
            r#"{"at": [0, 0], "to": [1, 2, 3]}"#,
            r#"{"at": [0, 0], "path": [[0, 0], [1, 1, 1]]}"#,
        ] {
            let e = serde_json::from_str::<P>(bad).unwrap_err().to_string();
            assert!(e.contains("two numbers"), "{bad}: {e}");
        }
    }
}
