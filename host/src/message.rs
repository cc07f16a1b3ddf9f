//! An error and its causes as the one line a person reads.

/// The error and the causes under it, "outer: inner: ...", each said once: an error type that
/// already prints its cause in its own message (`#[error("mesh: {0}")]` over a `#[from]`
/// field) does not have it printed again, nor one whose message ends in a line break it
/// trimmed (a TOML parser's message, its snippet of the file included, was said twice).
#[must_use]
pub fn one_line(e: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        let text = text.trim_end();
        if message.contains(text) {
            continue;
        }
        if !message.is_empty() {
            message += ": ";
        }
        message += text;
    }
    message
}

/// Whether the error is, at its root, a write to a pipe whose reader went away (`et sim --out
/// /dev/stdout | head`): a command ends quietly then, as Unix tools do, instead of calling the
/// reader's choice to stop an error. Looks through the chain, and into JSON's error, which
/// keeps the I/O error it wraps out of the chain.
#[must_use]
pub fn reader_went_away(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            || cause
                .downcast_ref::<serde_json::Error>()
                .and_then(serde_json::Error::io_error_kind)
                == Some(std::io::ErrorKind::BrokenPipe)
    })
}
