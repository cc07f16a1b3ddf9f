//! Which of et's own files a text is, by its first line: said where another of them is given
//! in its place (a recording as a scene or a model, a dataset as a model), instead of the
//! parser's words for text it does not expect.

/// One of et's own files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EtFile {
    /// A recording (`et sim`, `et record`): a JSON header naming "et-recording", then a frame
    /// a line.
    Recording,
    /// A dataset (`et collect`): `# et-dataset N`, then `#` lines and a table.
    Dataset,
    /// A model file (`et train`): JSON naming "et-model" or "et-table-model".
    Model,
    /// A protocol file (`et protocol --csv`): a header of source, sink, positive, negative.
    Protocol,
}

impl EtFile {
    /// Which of et's files `text` is, by its first line that is not blank; None for any
    /// other text.
    #[must_use]
    pub fn of(text: &str) -> Option<Self> {
        let first = first_line(text)?;
        let names = |format: &str| {
            // The format's value, as JSON writes it (spaces after the colon or not).
            first.starts_with('{')
                && first.contains(&format!("\"{format}\""))
                && first.contains("\"format\"")
        };
        if first.starts_with("# et-dataset") {
            Some(Self::Dataset)
        } else if names("et-recording") {
            Some(Self::Recording)
        } else if names("et-model") || names("et-table-model") {
            Some(Self::Model)
        } else {
            Self::columns_beside_protocol(first).map(|_| Self::Protocol)
        }
    }

    /// Of a protocol file's header (`text`'s first line that is not blank), how many columns
    /// stand beside a protocol file's own (source, sink, positive, negative, current_a): a
    /// hardware log's values. None when it has not the four electrodes' columns.
    #[must_use]
    pub fn columns_beside_protocol(text: &str) -> Option<usize> {
        // (Read in place: a file of one long line, a JSON object of every frame, was copied
        // and split into a list of its cells, several times its size.)
        let header = first_line(text)?;
        let cells = || header.split([',', ';', '\t']).map(str::trim);
        let columns = &crate::schedule::COLUMNS;
        let is = |cell: &str, c: &&str| cell.eq_ignore_ascii_case(c);
        let electrodes = columns.get(..4).unwrap_or_default();
        (electrodes.iter().all(|c| cells().any(|cell| is(cell, c)))).then(|| {
            cells()
                .filter(|cell| !columns.iter().any(|c| is(cell, c)))
                .count()
        })
    }

    /// What it is, and what writes it: "an et recording (et sim, et record)".
    #[must_use]
    pub fn said(self) -> &'static str {
        match self {
            Self::Recording => "an et recording (et sim, et record)",
            Self::Dataset => "an et dataset (et collect)",
            Self::Model => "an et model file (et train)",
            Self::Protocol => "a protocol file (et protocol --csv)",
        }
    }
}

/// `text`'s first line that is not blank, trimmed (a byte-order mark and Excel's `sep=;`
/// left out).
fn first_line(text: &str) -> Option<&str> {
    let first = text
        .trim_start_matches('\u{feff}')
        .lines()
        .find(|l| !l.trim().is_empty() && super::excel_sep(l).is_none())?;
    Some(first.trim())
}

#[cfg(test)]
mod tests {
    use super::EtFile;

    #[test]
    fn et_s_files_are_told_by_their_first_line() {
        let cases = [
            (
                "{\"format\":\"et-recording\",\"version\":1}\n{\"seq\":0}",
                Some(EtFile::Recording),
            ),
            (
                "{\"format\": \"et-table-model\", \"version\": 2}",
                Some(EtFile::Model),
            ),
            (
                "{\"centres_m\":[],\"format\":\"et-model\"}",
                Some(EtFile::Model),
            ),
            (
                "\u{feff}# et-dataset 2\n# config: {}\n",
                Some(EtFile::Dataset),
            ),
            (
                "\nSource;Sink;Positive;Negative\n0;1;2;3\n",
                Some(EtFile::Protocol),
            ),
            (
                "source,sink,positive,negative,current_a\n",
                Some(EtFile::Protocol),
            ),
            ("[sheet]\nshape = 1\n", None),
            ("v0,v1\n1,2\n", None),
            ("{\"format\":\"other\"}", None),
            ("", None),
        ];
        for (text, kind) in cases {
            assert_eq!(EtFile::of(text), kind, "{text:?}");
        }
        // A hardware log: the electrodes' columns and its values beside them.
        let beside = EtFile::columns_beside_protocol;
        assert_eq!(
            beside("source,sink,positive,negative,current_a,v0,v1\n"),
            Some(2)
        );
        assert_eq!(beside("source,sink,positive,negative,current_a\n"), Some(0));
        assert_eq!(beside("v0,v1\n"), None);
    }
}
