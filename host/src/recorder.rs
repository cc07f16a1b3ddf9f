//! `et record` as a library: frames from a board's [`Link`] into recording files, one part per
//! scan configuration, surviving what real cables and boards do. A frame whose value count
//! disagrees with its configuration is counted and skipped (the recording goes on); a frame
//! with non-finite values is kept and flagged (see [`crate::recording`]); a pulled cable is
//! waited for, and a board that comes back idle is sent Start again ([`Keepalive`]).

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use et_core::ScanConfig;
use et_core::wire::Uplink;

use crate::link::{Counters, Keepalive, Link, LinkChange};
use crate::recording::{self, Header, Record, RecordingError};

/// What to record.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The first part's path; later parts (after a configuration change) are
    /// [`part_path`]s of it.
    pub out: PathBuf,
    /// Stop after this many frames written.
    pub frames: Option<u64>,
    /// Stop after this long.
    pub duration: Option<Duration>,
    /// Send Start (at the beginning, after a replug, to a silent board).
    pub send_start: bool,
    /// Replace existing files instead of refusing them.
    pub force: bool,
}

/// Something a person watching the recording should know.
#[derive(Clone, Debug, PartialEq)]
pub enum Notice {
    /// A new part began (first frame, or the configuration changed).
    Part {
        /// The file.
        path: PathBuf,
        /// Its configuration.
        config: ScanConfig,
    },
    /// A frame was skipped because its value count is not its configuration's K.
    Skipped {
        /// Its sequence number.
        seq: u32,
        /// Values it had.
        got: usize,
        /// K.
        expected: usize,
    },
    /// The link changed.
    Link(LinkChange),
    /// The board reported a fault or refused a command, in words (a front end that cannot
    /// scan its configuration sends no frames: `et record` waited without a word).
    Board(String),
    /// The first frame the board flagged with a kind of fault in its readings (on an ADC
    /// rail, the current source in compliance: [`crate::live::flagged_readings`]), in words.
    Flagged {
        /// Its sequence number.
        seq: u32,
        /// What the board flagged.
        said: String,
    },
    /// Progress (every 25 frames and while waiting).
    Progress(Tally),
}

/// What a recording got.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Frames written.
    pub written: u64,
    /// Frames written with non-finite values (flagged in the file).
    pub flagged: u64,
    /// Frames skipped (wrong value count).
    pub skipped: u64,
    /// Frames written whose readings the board flagged (on an ADC rail, its source in
    /// compliance).
    pub board_flagged: u64,
    /// The link's counters (lost, damaged, reconnects).
    pub link: Counters,
}

impl std::fmt::Display for Tally {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} frames ({} with non-finite values, flagged; {} with readings the board \
             flagged), {} skipped for a wrong value count, {} lost on the way, {} damaged \
             packets dropped, {} reconnects",
            self.written,
            self.flagged,
            self.board_flagged,
            self.skipped,
            self.link.lost_frames,
            self.link.corrupt,
            self.link.reconnects
        )
    }
}

/// `FILE.jsonl` for part 1, `FILE-2.jsonl`, `FILE-3.jsonl`, ... after configuration changes.
#[must_use]
pub fn part_path(out: &Path, part: u32) -> PathBuf {
    if part == 1 {
        return out.to_path_buf();
    }
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let ext = out
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    out.with_file_name(format!("{stem}-{part}{ext}"))
}

/// Records frames from `link` as `plan` says, telling `notice` what happens. Start is sent
/// (when the plan says so) by the caller before, and by the [`Keepalive`] after a replug or a
/// silence.
///
/// # Errors
/// [`RecordingError`] when a part cannot be created (an existing file without
/// [`Plan::force`]) or written.
pub fn record(
    link: &mut Link,
    plan: &Plan,
    mut notice: impl FnMut(Notice),
) -> Result<Tally, RecordingError> {
    crate::output::check(&plan.out, &[], plan.force)?;
    let deadline = plan.duration.map(|d| Instant::now() + d);
    let mut keepalive = Keepalive::new(link, plan.send_start);
    let mut tally = Tally::default();
    let mut part = 0u32;
    let mut writer: Option<(ScanConfig, recording::Writer)> = None;
    let mut said_flags = crate::live::FlagsSaid::default();
    while plan.frames.is_none_or(|n| tally.written < n)
        && deadline.is_none_or(|d| Instant::now() < d)
    {
        if let Some(change) = keepalive.check(link) {
            notice(Notice::Link(change));
        }
        let frame = match link.next(Duration::from_millis(200)) {
            Ok(Uplink::Frame(f)) => f,
            Ok(Uplink::Event(e)) if let Some(report) = crate::live::board_report(&e) => {
                notice(Notice::Board(report));
                continue;
            }
            Ok(Uplink::Event(_)) | Err(_) => {
                tally.link = link.counters();
                notice(Notice::Progress(tally));
                continue;
            }
        };
        keepalive.frame();
        let expected = frame.config.validate().map_or(0, |p| p.frame_len());
        if frame.voltages.len() != expected {
            tally.skipped += 1;
            notice(Notice::Skipped {
                seq: frame.seq,
                got: frame.voltages.len(),
                expected,
            });
            continue;
        }
        let w =
            match &mut writer {
                Some((config, w)) if *config == frame.config => w,
                slot => {
                    part += 1;
                    let path = part_path(&plan.out, part);
                    // A valid config (its K was computed above), so the header cannot fail.
                    let header = Header::new(format!("port:{}", link.path()), &frame.config)
                        .map_err(|e| RecordingError::Line {
                            path: path.clone(),
                            line: 1,
                            fault: recording::LineFault::Config(e),
                        })?;
                    let w = if plan.force {
                        recording::Writer::create(&path, &header)?
                    } else {
                        recording::Writer::create_new(&path, &header)?
                    };
                    notice(Notice::Part {
                        path,
                        config: frame.config,
                    });
                    &mut slot.insert((frame.config, w)).1
                }
            };
        let record = Record::new(&frame, None);
        tally.flagged += u64::from(!record.invalid.is_empty());
        if let Some(said) = said_flags.first(frame.flags) {
            notice(Notice::Flagged {
                seq: frame.seq,
                said,
            });
        }
        tally.board_flagged += u64::from(crate::live::readings_flagged(frame.flags));
        w.append(&record)?;
        tally.written += 1;
        if tally.written % 25 == 0 {
            tally.link = link.counters();
            notice(Notice::Progress(tally));
        }
    }
    tally.link = link.counters();
    Ok(tally)
}
