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
