//! Long work said while it runs: its whole time once, a few seconds in, at the pace so far,
//! and where standard error is not a terminal (a log, CI), where no bar is drawn, its
//! progress at each tenth from then on (`et collect` of 2.5 million observations, `et sim` of
//! 200 000 frames ran for minutes without a word there).

use std::time::Instant;

use indicatif::ProgressBar;

/// Seconds into the work after which its whole time is said: shorter work says nothing more.
const SAY_AFTER_S: f64 = 3.0;

/// The pace of `total` units of work begun now.
#[derive(Debug)]
pub struct Pace {
    /// What is done, as a verb: "collect".
    what: &'static str,
    /// The unit counted: "presses".
    unit: &'static str,
    total: u64,
    started: Instant,
    said: bool,
    /// Tenths said.
    tenths: u64,
    interactive: bool,
}

impl Pace {
    /// Starts the clock on `total` `unit`s of work that `what`s.
    #[must_use]
    pub fn new(what: &'static str, unit: &'static str, total: u64) -> Self {
        Self {
            what,
            unit,
            total,
            started: Instant::now(),
            said: false,
            tenths: 0,
            interactive: std::io::IsTerminal::is_terminal(&std::io::stderr()),
        }
    }

    /// A progress bar of the work, drawn on a terminal only.
    #[must_use]
    pub fn bar(&self, style: indicatif::ProgressStyle) -> ProgressBar {
        let bar = ProgressBar::new(self.total).with_style(style);
        if !self.interactive {
            bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
        }
        bar
    }

    /// Whether standard error is a terminal, where a bar shows the tenths (`new` asks it).
    #[must_use]
    pub fn on_terminal(mut self, on_terminal: bool) -> Self {
        self.interactive = on_terminal;
        self
    }

    /// `done` units are done: says what is due on standard error, the bar hidden while it
    /// does (a line that cannot be written is dropped).
    pub fn at(&mut self, done: u64, bar: &ProgressBar) {
        use std::io::Write as _;
        let seconds = self.started.elapsed().as_secs_f64();
        for line in self.due(done, seconds) {
            bar.suspend(|| {
                let _ = writeln!(std::io::stderr(), "{line}");
            });
        }
    }

    /// What is due to be said when `done` units are done after `seconds`: the whole's time
    /// once, past [`SAY_AFTER_S`]; off a terminal, each tenth newly reached from then on.
    pub fn due(&mut self, done: u64, seconds: f64) -> Vec<String> {
        let mut said = Vec::new();
        if done == 0 || seconds < SAY_AFTER_S {
            return said;
        }
        if !self.said {
            self.said = true;
            #[allow(clippy::cast_precision_loss)]
            let whole = seconds * self.total as f64 / done as f64;
            said.push(format!(
                "{} to {} in all, at the pace of its first {done} {}",
                et_learn::pipeline::cost::about(whole),
                self.what,
                self.unit
            ));
        }
        let tenths = done.saturating_mul(10) / self.total.max(1);
        if !self.interactive && tenths > self.tenths {
            self.tenths = tenths;
            said.push(format!(
                "{}: {} % ({done} of {} {}, {})",
                self.what,
                tenths * 10,
                self.total,
                self.unit,
                et_learn::pipeline::cost::time_said(seconds)
            ));
        }
        said
    }
}
