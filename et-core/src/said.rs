//! A file reader's message in the words of the file's author: serde names the Rust type a
//! field is read into ("invalid type: string "30e3", expected f64", "expected struct
//! ElectrodeSpec", "expected internally tagged enum Shape"); a user wrote a number, a list or a
//! table. [`serde_said`] says what was found and what belongs there in those words, for every
//! reader of TOML and JSON (scenes, Python's sheet specs, model files, recordings' headers).
//!
//! Behind the `std` feature.

/// `message` (one line or several, as a parser's snippet) with serde's type words said as
/// what a file holds: each line's `invalid type: X, expected Y` becomes `X', where Y'
/// belongs`; `unknown variant` and the lists of fields and choices are said as choices; any
/// other text is kept as it is.
#[must_use]
pub fn serde_said(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    for (i, line) in message.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        out.push_str(&line_said(line));
    }
    out
}

/// One line of [`serde_said`], serde_json's place (` at line 1 column 9`) kept at its end.
fn line_said(line: &str) -> String {
    match line.rfind(" at line ") {
        Some(at) if line[at..].contains(" column ") => {
            format!("{}{}", words_said(&line[..at]), &line[at..])
        }
        _ => words_said(line),
    }
}

/// [`line_said`] of a line without serde_json's place.
fn words_said(line: &str) -> String {
    const INVALID_TYPE: &str = "invalid type: ";
    const INVALID_VALUE: &str = "invalid value: ";
    const INVALID_LENGTH: &str = "invalid length ";
    const VARIANT: &str = "unknown variant ";
    const FIELD: &str = "unknown field ";
    if let Some(at) = line.find(INVALID_TYPE) {
        let rest = &line[at + INVALID_TYPE.len()..];
        if let Some((found, expected)) = rest.rsplit_once(", expected ") {
            let hint = quoted_number_hint(found, expected);
            let expected = expected_said(expected);
            return format!(
                "{}{}, where {expected} belongs{hint}",
                &line[..at],
                found_said(found)
            );
        }
    }
    if let Some(at) = line.find(INVALID_VALUE) {
        let rest = &line[at + INVALID_VALUE.len()..];
        if let Some((found, expected)) = rest.rsplit_once(", expected ") {
            return format!(
                "{}{} is not {}",
                &line[..at],
                value_of(found),
                range_said(expected).unwrap_or_else(|| expected_said(expected))
            );
        }
    }
    if let Some(at) = line.find(INVALID_LENGTH) {
        let rest = &line[at + INVALID_LENGTH.len()..];
        if let Some((count, expected)) = rest.split_once(", expected ") {
            // A fixed-size list with more values than it holds ("fewer elements in array").
            if expected.starts_with("fewer elements") {
                return format!("{}{count} values, more than it holds", &line[..at]);
            }
            return format!(
                "{}{count} {}, where {} belongs",
                &line[..at],
                if count == "1" { "value" } else { "values" },
                expected_said(expected)
            );
        }
    }
    if let Some(at) = line.find(VARIANT) {
        let rest = &line[at + VARIANT.len()..];
        if let Some((value, choices)) = rest.split_once(", expected ") {
            return format!("{}unknown value {value}: give {choices}", &line[..at]);
        }
    }
    if let Some(at) = line.find(FIELD) {
        let rest = &line[at + FIELD.len()..];
        if let Some((field, fields)) = rest.split_once(", expected ") {
            let fields = fields.strip_prefix("one of ").unwrap_or(fields);
            return format!(
                "{}unknown field {field}: the fields here are {fields}",
                &line[..at]
            );
        }
        if let Some(field) = rest.strip_suffix(", there are no fields") {
            return format!("{}unknown field {field}: this holds no fields", &line[..at]);
        }
    }
    line.to_string()
}

/// The value in serde's `Unexpected` alone (``integer `7` `` is `7`, `string "x"` is `"x"`),
/// or the whole of it where it holds none.
fn value_of(found: &str) -> &str {
    if let Some(text) = found.strip_prefix("string ") {
        return text;
    }
    match (found.find('`'), found.rfind('`')) {
        (Some(a), Some(b)) if b > a => &found[a + 1..b],
        _ => found,
    }
}

/// serde's `Unexpected` (what the file holds) in the file's words: `string "x"` is `"x" is
/// text`, ``integer `16` `` is `16 is a whole number`, `sequence` is `a list`.
fn found_said(found: &str) -> String {
    let ticked = |prefix: &str| {
        found
            .strip_prefix(prefix)
            .and_then(|v| v.strip_prefix('`'))
            .and_then(|v| v.strip_suffix('`'))
    };
    if let Some(text) = found.strip_prefix("string ") {
        return format!("{text} is text");
    }
    if let Some(v) = ticked("integer ") {
        return format!("{v} is a whole number");
    }
    if let Some(v) = ticked("floating point ") {
        return match v.parse::<f64>() {
            Ok(x) if x.fract() == 0.0 => format!("{v} is a decimal number"),
            _ => format!("{v} is a number with a fraction"),
        };
    }
    if let Some(v) = ticked("boolean ") {
        return format!("{v} is a yes-or-no value");
    }
    if let Some(v) = ticked("character ") {
        return format!("'{v}' is text");
    }
    match found {
        "null" | "unit value" | "Option value" => "an empty value (null)".to_string(),
        "sequence" => "a list".to_string(),
        "map" => "a table of fields".to_string(),
        other => other.to_string(),
    }
}

/// serde's `Expected` (the type a field is read into) in the file's words: `f64` is `a
/// number`, `u32` `a whole number`, `struct ElectrodeSpec` or `internally tagged enum Shape`
/// `a table of fields`; the readers' own words ("a whole number") are kept.
fn expected_said(expected: &str) -> String {
    let one_word = !expected.contains(' ');
    match expected {
        "f64" | "f32" => return "a number".to_string(),
        "u8" | "u16" | "u32" | "u64" | "u128" | "usize" | "i8" | "i16" | "i32" | "i64" | "i128"
        | "isize" => return "a whole number".to_string(),
        "a string" | "a borrowed string" | "a character" | "a char" => {
            return "text (in quotes)".to_string();
        }
        "a boolean" => return "true or false".to_string(),
        "path string" => return "a file's path (text in quotes)".to_string(),
        "a sequence" => return "a list".to_string(),
        "a map" => return "a table of fields".to_string(),
        "unit" => return "nothing".to_string(),
        _ => {}
    }
    let type_name = [
        "struct ",
        "internally tagged enum ",
        "untagged enum ",
        "enum ",
    ]
    .iter()
    .find_map(|p| expected.strip_prefix(p));
    if type_name.is_some() || (one_word && expected.starts_with(|c: char| c.is_ascii_uppercase())) {
        return "a table of fields".to_string();
    }
    if let Some(n) = expected
        .strip_prefix("an array of length ")
        .or_else(|| expected.strip_prefix("a tuple of size "))
        .or_else(|| {
            expected
                .strip_prefix("tuple of ")
                .and_then(|r| r.strip_suffix(" elements"))
        })
    {
        return format!("a list of {n} values");
    }
    expected.to_string()
}

/// An integer type's range in words (`u16` is "a whole number from 0 to 65535"), for a value
/// past it.
fn range_said(expected: &str) -> Option<String> {
    let (least, most) = int_range(expected)?;
    Some(format!("a whole number from {least} to {most}"))
}

/// The least and most values of an integer type serde names (`u16`: 0 and 65535).
fn int_range(expected: &str) -> Option<(i128, i128)> {
    Some(match expected {
        "u8" => (0, u8::MAX.into()),
        "u16" => (0, u16::MAX.into()),
        "u32" => (0, u32::MAX.into()),
        "u64" | "usize" => (0, u64::MAX.into()),
        "i8" => (i8::MIN.into(), i8::MAX.into()),
        "i16" => (i16::MIN.into(), i16::MAX.into()),
        "i32" => (i32::MIN.into(), i32::MAX.into()),
        "i64" | "isize" => (i64::MIN.into(), i64::MAX.into()),
        _ => return None,
    })
}

/// `" (write it without quotes)"` where text that reads as a number was given for a number;
/// `" (write it as digits alone: 10000)"` where a whole number was written as a decimal, or
/// the field's range where that number is past it (`expected` is serde's type name).
fn quoted_number_hint(found: &str, expected_type: &str) -> String {
    let expected = expected_said(expected_type);
    if let Some(v) = found
        .strip_prefix("floating point `")
        .and_then(|v| v.strip_suffix('`'))
    {
        let whole = |x: f64| expected == "a whole number" && x.fract() == 0.0;
        return match (v.parse::<f64>(), int_range(expected_type)) {
            (Ok(x), Some((least, most))) if whole(x) && (x < least as f64 || x > most as f64) => {
                format!(" (this field takes {least} to {most})")
            }
            (Ok(x), _) if whole(x) && x.abs() < 1e19 => {
                format!(" (write it as digits alone: {x:.0})")
            }
            _ => String::new(),
        };
    }
    let text = found
        .strip_prefix("string \"")
        .and_then(|t| t.strip_suffix('"'));
    let numeric = expected == "a number" || expected == "a whole number";
    match text {
        Some(t) if numeric && t.trim().parse::<f64>().is_ok() => {
            " (write it without quotes)".to_string()
        }
        _ => String::new(),
    }
}

/// A number said in powers of ten to six significant digits, trailing zeros dropped
/// (1.3000000000000001e-5 as 1.3e-5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sig(pub f64);

impl core::fmt::Display for Sig {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let said = format!("{:.5e}", self.0);
        match said.split_once('e') {
            Some((mantissa, exponent)) if mantissa.contains('.') => {
                let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
                if exponent == "0" {
                    // 0, -1, 2.5: no power of ten to say.
                    f.write_str(mantissa)
                } else {
                    write!(f, "{mantissa}e{exponent}")
                }
            }
            _ => f.write_str(&said),
        }
    }
}

/// A value as people write it: up to four decimals, trailing zeros trimmed, for magnitudes
/// from 1e-3 to 1e6 (0.8796, 1414.2, 2023.5254, 25); in powers of ten ([`Sig`]) past them.
#[derive(Clone, Copy, Debug)]
pub struct Plain(pub f64);

impl core::fmt::Display for Plain {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if (1e-3..1e6).contains(&self.0.abs()) {
            let said = format!("{:.4}", self.0);
            f.write_str(said.trim_end_matches('0').trim_end_matches('.'))
        } else {
            Sig(self.0).fmt(f)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values as people write them: four decimals at most, trimmed; powers of ten past them
    /// (an outline of 0.8796459430051422 m was said so).
    #[test]
    fn plain_values_are_said_as_written() {
        let said = |v: f64| Plain(v).to_string();
        assert_eq!(said(0.879_645_943_005_142_2), "0.8796");
        assert_eq!(said(1_414.200_000_000_000_3), "1414.2");
        assert_eq!(said(25.0), "25");
        assert_eq!(said(-2_023.525_4), "-2023.5254");
        assert_eq!(said(1e-9), "1e-9");
        assert_eq!(said(2.5e7), "2.5e7");
    }

    /// Each form serde writes, read from the real parsers' errors, is said in the file's
    /// words; the path in front of it and the lines around it are kept.
    #[test]
    fn serde_type_words_are_said_as_what_a_file_holds() {
        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Inner {
            n: u32,
        }
        #[derive(Debug, serde::Deserialize)]
        #[serde(tag = "kind", rename_all = "lowercase")]
        #[allow(dead_code)]
        enum Shape {
            Disc { radius: f64 },
            Square { side: f64 },
        }
        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Outer {
            x: Option<f64>,
            inner: Option<Inner>,
            shape: Option<Shape>,
            flag: Option<bool>,
            list: Option<Vec<f64>>,
            pair: Option<[f64; 2]>,
            name: Option<String>,
        }
        let said = |json: &str| {
            let e = serde_json::from_str::<Outer>(json).unwrap_err().to_string();
            serde_said(&e)
        };
        for (json, words) in [
            (
                r#"{"x": "30e3"}"#,
                "\"30e3\" is text, where a number belongs (write it without quotes)",
            ),
            (
                r#"{"x": "thirty"}"#,
                "\"thirty\" is text, where a number belongs at",
            ),
            (
                r#"{"x": true}"#,
                "true is a yes-or-no value, where a number belongs",
            ),
            (r#"{"x": [1]}"#, "a list, where a number belongs"),
            (
                r#"{"inner": 16}"#,
                "16 is a whole number, where a table of fields belongs",
            ),
            (
                r#"{"inner": {"n": 1.5}}"#,
                "1.5 is a number with a fraction, where a whole number belongs",
            ),
            (
                r#"{"inner": {"n": "16"}}"#,
                "\"16\" is text, where a whole number belongs (write it without quotes)",
            ),
            (
                r#"{"shape": "disc"}"#,
                "\"disc\" is text, where a table of fields belongs",
            ),
            (
                r#"{"shape": {"kind": "blob"}}"#,
                "unknown value `blob`: give `disc` or `square`",
            ),
            (
                r#"{"flag": 1}"#,
                "1 is a whole number, where true or false belongs",
            ),
            (
                r#"{"list": 3}"#,
                "3 is a whole number, where a list belongs",
            ),
            (
                r#"{"inner": {"n": 1e4}}"#,
                "10000.0 is a decimal number, where a whole number belongs (write it as digits alone: 10000)",
            ),
            (
                r#"{"inner": {"n": 1e12}}"#,
                "1000000000000.0 is a decimal number, where a whole number belongs (this field takes 0 to 4294967295)",
            ),
            (
                r#"{"inner": {"n": -2.0}}"#,
                "where a whole number belongs (this field takes 0 to 4294967295)",
            ),
            (
                r#"{"pair": [1]}"#,
                "1 value, where a list of 2 values belongs",
            ),
            (
                r#"{"name": 3}"#,
                "3 is a whole number, where text (in quotes) belongs",
            ),
            (
                r#"{"inner": {"n": -1}}"#,
                "-1 is not a whole number from 0 to 4294967295",
            ),
            (
                r#"{"bogus": 3}"#,
                "unknown field `bogus`: the fields here are `x`, `inner`",
            ),
        ] {
            let got = said(json);
            assert!(got.contains(words), "{json}: {got}");
            for internal in ["f64", "u32", "struct", "enum", "Inner", "Shape", "expected"] {
                assert!(!got.contains(internal), "{json}: {got}");
            }
        }
        // A fixed-size list with a value too many, as a file read into a JSON value first
        // gives it (serde's "expected fewer elements in array").
        let value: serde_json::Value = serde_json::from_str(r#"{"pair": [1, 2, 3]}"#).unwrap();
        let e = serde_json::from_value::<Outer>(value)
            .unwrap_err()
            .to_string();
        let got = serde_said(&e);
        assert!(got.contains("3 values, more than it holds"), "{got}");
        // A TOML parser's snippet: the lines around the message kept as they are.
        let snippet = "TOML parse error at line 4, column 20\n  |\n4 | x = \"3\"\n  |     ^^^\ninvalid type: string \"3\", expected f64\n";
        let got = serde_said(snippet);
        assert!(got.starts_with("TOML parse error at line 4, column 20\n  |\n4 | x = \"3\"\n"));
        assert!(got.contains("\"3\" is text, where a number belongs (write it without quotes)\n"));
        // Anything else is left as it is.
        for kept in [
            "missing field `radius`",
            "radius = -0.1: must be a positive length",
            "",
        ] {
            assert_eq!(serde_said(kept), kept);
        }
    }
}
