//! LabVIEW's measurement files (`.lvm`, as its Write To Measurement File writes them): a
//! file header and a header per segment, each ending `***End_of_Header***` (special headers
//! run from `***Start_Special***` to `***End_Special***`), then the channels' names
//! (`X_Value` columns of the time, a `Comment` last) and one row per sample. Read as a CSV of
//! its channels, line for line (a header's lines as comments, so that every message names
//! the file's own line), each channel's `Y_Unit_Label` as its unit.

use super::csv_frames::in_name;

/// Whether `text` is a LabVIEW measurement file (by its first line).
pub(super) fn is_lvm(text: &str) -> bool {
    text.trim_start_matches('\u{feff}')
        .starts_with("LabVIEW Measurement")
}

/// Where a line of the file stands.
#[derive(Clone, Copy, PartialEq)]
enum At {
    /// In a header (the file's or a segment's).
    Header,
    /// After a header: the names, a segment's header or the samples come next.
    After,
    /// Among the samples.
    Samples,
}

/// A LabVIEW measurement file read as the CSV of its channels.
pub(super) struct AsCsv {
    /// The CSV (tab-separated), line for line.
    pub csv: String,
    /// The first `Y_Unit_Label` that is no unit of voltage (`Ohm`).
    pub not_volts: Option<String>,
    /// The file's column (from 0) of each of the CSV's.
    columns: Vec<usize>,
}

impl AsCsv {
    /// `error`, a cell's, with its column the file's (from 1), not the CSV's (which leaves
    /// the time out).
    pub fn in_file_columns(&self, mut error: super::FramesError) -> super::FramesError {
        use super::FramesFault::{NotNumber, NotVolts};
        if let super::FramesError::Content {
            fault: NotNumber { column, .. } | NotVolts { column, .. },
            ..
        } = &mut error
            && let Some(c) = column.checked_sub(1).and_then(|c| self.columns.get(c))
        {
            *column = c + 1;
        }
        error
    }
}

/// `text`, a LabVIEW measurement file, as the CSV (tab-separated) of its channels, line for
/// line: its headers as comments, its time and comment columns left out, its units of
/// voltage in its channels' names (`Untitled (mV)`), decimal commas as points; and the first
/// `Y_Unit_Label` that is no unit of voltage (`Ohm`), whose values are taken as volts.
pub(super) fn as_csv(text: &str) -> AsCsv {
    let mut out = String::with_capacity(text.len());
    let (mut separator, mut decimal_comma) = ('\t', false);
    let (mut at, mut units, mut kept) = (At::Header, Vec::<String>::new(), None::<Vec<usize>>);
    for line in text.trim_start_matches('\u{feff}').lines() {
        let (key, rest) = line.split_once(['\t', ',']).unwrap_or((line, ""));
        let key = key.trim();
        let number = key.replace(',', ".").parse::<f64>().is_ok();
        let said = match at {
            // (A special header, `***Start_Special***` to `***End_Special***`, likewise.)
            _ if key.starts_with("***End") => {
                at = At::After;
                None
            }
            _ if key.starts_with("***Start") => {
                at = At::Header;
                None
            }
            At::After | At::Samples if key == "Channels" => {
                at = At::Header;
                None
            }
            At::Header => {
                match key {
                    "Separator" if rest.trim() == "Comma" => separator = ',',
                    "Decimal_Separator" => decimal_comma = rest.trim_matches('\t') == ",",
                    "Y_Unit_Label" if units.is_empty() => {
                        units = rest
                            .split(separator)
                            .map(|u| u.trim().to_string())
                            .collect();
                    }
                    _ => {}
                }
                None
            }
            _ if key.is_empty() && rest.trim().is_empty() => None,
            At::After if !number => {
                at = At::Samples;
                // The first segment's names; a later one's are its own again.
                kept.is_none()
                    .then(|| names(line, separator, &units, &mut kept))
            }
            At::After | At::Samples => {
                at = At::Samples;
                let cells: Vec<&str> = line.split(separator).collect();
                let columns = kept.get_or_insert_with(|| (0..cells.len()).collect());
                let row: Vec<String> = (columns.iter())
                    .map(|&c| {
                        let cell = cells.get(c).copied().unwrap_or("").trim();
                        match decimal_comma {
                            true => cell.replace(',', "."),
                            false => cell.to_string(),
                        }
                    })
                    .collect();
                Some(row.join("\t"))
            }
        };
        match said {
            Some(l) => out.push_str(&l),
            None => out.push('#'),
        }
        out.push('\n');
    }
    let not_volts = (units.iter())
        .find(|u| !u.is_empty() && in_name(&format!("({u})")).is_none())
        .cloned();
    AsCsv {
        csv: out,
        not_volts,
        columns: kept.unwrap_or_default(),
    }
}

/// The names row `line`: its channels' names with their units where a voltage's, tab-
/// separated; `kept` set to the columns of the channels (not `X_Value`, not `Comment`).
fn names(line: &str, separator: char, units: &[String], kept: &mut Option<Vec<usize>>) -> String {
    let cells: Vec<&str> = line.split(separator).map(str::trim).collect();
    let last = cells.len().saturating_sub(1);
    let columns: Vec<usize> = (0..cells.len())
        .filter(|&c| cells[c] != "X_Value" && !(c == last && cells[c] == "Comment"))
        .collect();
    let named: Vec<String> = (columns.iter().enumerate())
        .map(|(j, &c)| {
            let unit = units.get(j).map(String::as_str).unwrap_or("");
            match in_name(&format!("({unit})")) {
                Some((word, _)) if in_name(cells[c]).is_none() => format!("{} ({word})", cells[c]),
                _ => cells[c].to_string(),
            }
        })
        .collect();
    *kept = Some(columns);
    named.join("\t")
}
