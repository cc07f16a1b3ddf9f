//! One line on standard error that says what long work is under way, with the time so far.

use indicatif::{ProgressBar, ProgressStyle};

/// A spinner, its message and the time so far, updating in place on standard error (only on
/// a terminal: scripts and `--json` see nothing of it), cleared when dropped, so every way
/// out of the work (an error's `?` too) leaves no half-drawn line.
pub(crate) struct Spinner(ProgressBar);

impl Spinner {
    /// Starts one saying `message`.
    pub(crate) fn new(message: impl Into<String>) -> Self {
        let bar = ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.set_message(message.into());
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        Self(bar)
    }

    /// Says what is under way now.
    pub(crate) fn say(&self, message: impl Into<String>) {
        self.0.set_message(message.into());
    }

    /// Runs `f` (which prints lines of its own) with the spinner hidden.
    pub(crate) fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.0.suspend(f)
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}
