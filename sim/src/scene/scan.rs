//! The scan section: the built-in protocol or the protocol file, the current, the schedule imaged
//! and the configuration the simulated board scans.

use super::*;

/// The most current the board drives, uA ([`et_core::config::CURRENT_NA_MAX`]).
const BOARD_MAX_UA: f64 = et_core::config::CURRENT_NA_MAX as f64 / 1e3;

impl Scene {
    /// The built-in protocol named, if it is one.
    pub(super) fn named_protocol(&self) -> Result<Option<ProtocolKind>, FieldError> {
        match &self.scan.protocol {
            ProtocolSpec::File(_) => Ok(None),
            ProtocolSpec::Named(name) => ProtocolKind::from_name(name).map(Some).ok_or_else(|| {
                FieldError::new("scan.protocol", SceneFault::UnknownProtocol(name.clone()))
            }),
        }
    }

    /// The scan section as far as it can be checked without reading files: the board's
    /// configuration where the simulated board can scan it (a named protocol at up to
    /// 1 mA), else a known protocol and a current up to 50 mA for imaging recorded frames.
    pub(super) fn check_scan(&self) -> Result<(), FieldError> {
        let ua = self.scan.current_ua;
        let (min_ua, max_ua) = (
            et_core::schedule::MIN_CURRENT_A * 1e6,
            et_core::schedule::MAX_CURRENT_A * 1e6,
        );
        if !(ua.is_finite() && ua >= min_ua && ua <= max_ua) {
            // (Said in uA, as written: 0.0004 uA was said as the board's "current_na = 0".)
            let fault = FieldFault::Span {
                value: ua,
                low: min_ua,
                high: max_ua,
                unit: "uA",
                why: "from 1 nA, the smallest a board drives, to 50 mA (systems drive \
                      microamperes to milliamperes)",
            };
            return Err(FieldError::new("scan.current_ua", fault));
        }
        if self.named_protocol()?.is_some() && ua <= BOARD_MAX_UA {
            self.scan_config()?;
        }
        Ok(())
    }

    /// The files the scene names and a command reads through it (its protocol file), as
    /// paths from the working directory: outputs must not replace them.
    #[must_use]
    pub fn files(&self) -> Vec<std::path::PathBuf> {
        match &self.scan.protocol {
            ProtocolSpec::File(f) => vec![self.dir.join(&f.file)],
            ProtocolSpec::Named(_) => Vec::new(),
        }
    }

    /// The number the scene's user gives its first electrode: its protocol file's `base` (0,
    /// or 1 for a system that counts from 1), else et's 0.
    #[must_use]
    pub fn electrode_base(&self) -> u16 {
        match &self.scan.protocol {
            ProtocolSpec::File(f) => f.base,
            ProtocolSpec::Named(_) => 0,
        }
    }

    /// What each frame value measures: the built-in protocol's rows at the scene's current,
    /// or the protocol file's (relative to [`Scene::dir`]), its rows without a current at
    /// the scene's.
    ///
    /// # Errors
    /// [`FieldError`] naming `scan.protocol` (with the file, line and cell) or
    /// `scan.current_ua`.
    pub fn schedule(&self) -> Result<et_core::schedule::Schedule, FieldError> {
        self.check_scan()?;
        let amps = self.scan.current_ua * 1e-6;
        let electrodes = self.sheet.physical.electrodes.count;
        let field = |fault: SceneFault| FieldError::new("scan.protocol", fault);
        match (&self.scan.protocol, self.named_protocol()?) {
            (ProtocolSpec::File(f), _) => {
                let path = self.dir.join(&f.file);
                let text = self.read.text(&path).map_err(|e| field(e.into()))?;
                let schedule = et_core::schedule::Schedule::parse_csv(
                    &path,
                    &text,
                    u16::from(electrodes),
                    f.base,
                    amps,
                )
                .map_err(|e| field(e.into()))?;
                self.current_beside_rows(&schedule, &f.file)?;
                Ok(schedule)
            }
            (_, Some(kind)) => et_core::protocol::Protocol::new(kind, electrodes)
                .map_err(|e| field(e.into()))?
                .schedule(amps)
                .map_err(|e| field(e.into())),
            (ProtocolSpec::Named(name), None) => {
                Err(field(SceneFault::UnknownProtocol(name.clone())))
            }
        }
    }

    /// Refuses a `current_ua` the scene gives beside a protocol `file` whose rows drive
    /// other currents: the rows' are imaged, and the scene's was ignored without a word (a
    /// current_ua of 1.4142, meant as mA, beside rows of 1.4142e-3 A).
    fn current_beside_rows(
        &self,
        schedule: &et_core::schedule::Schedule,
        file: &std::path::Path,
    ) -> Result<(), FieldError> {
        let ua = self.scan.current_ua;
        let rows_ua = schedule.rows().iter().map(|r| r.current_a * 1e6);
        let (low, high) = rows_ua.fold((f64::INFINITY, 0.0_f64), |(l, h), x| (l.min(x), h.max(x)));
        let alike = |x: f64| (x - ua).abs() <= 1e-6 * ua;
        if !self.scan.current_given || (alike(low) && alike(high)) {
            return Ok(());
        }
        let fault = SceneFault::CurrentBesideRows {
            ua,
            file: file.display().to_string(),
            rows_ua: (low, high),
        };
        Err(FieldError::new("scan.current_ua", fault))
    }

    /// The scan configuration the scene asks of the (simulated) board.
    ///
    /// # Errors
    /// [`FieldError`] naming the `scan.` field at fault: a protocol file whose rows are no
    /// built-in protocol's (imaged from recorded frames, not scanned by the board), or a
    /// current above the board's 1 mA (the file's rows', or `current_ua`).
    pub fn scan_config(&self) -> Result<ScanConfig, FieldError> {
        let ((protocol, ua), field) = match self.named_protocol()? {
            Some(kind) => ((kind, self.scan.current_ua), "scan.current_ua"),
            // (A file of a built-in protocol's rows is scanned as that one: `file_said`.)
            None => (
                (self.built_in_of_file()?)
                    .ok_or_else(|| FieldError::new("scan.protocol", SceneFault::NotScanned))?,
                "scan.protocol",
            ),
        };
        if !(ua.is_finite() && ua > 0.0 && ua <= BOARD_MAX_UA) {
            let fault = SceneFault::BoardCurrent(ua);
            return Err(FieldError::new(field, fault));
        }
        self.config_at(protocol, ua)
    }

    /// [`Scene::scan_config`], its error naming the scene's file.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the file and the `scan` field at fault.
    pub fn board_config(&self) -> Result<ScanConfig, SceneError> {
        self.scan_config().map_err(|error| SceneError::Invalid {
            path: self.name.clone(),
            error,
        })
    }

    /// The configuration another system's frames of the scene's built-in protocol play at
    /// as a recording (`et stream --replay`, `et view`), and the factor their voltages are
    /// multiplied by for it: the scene's own, factor 1, when its current is one the board
    /// drives (up to 1 mA); else the board's 1 mA and the ratio of the currents (1 mA over
    /// the scene's), the frames then what the same sheet gives at 1 mA. Images, positions
    /// and noise-relative intensities are unchanged, a difference image being linear in the
    /// current.
    ///
    /// # Errors
    /// [`FieldError`] naming `scan.protocol` for a protocol file whose rows are no built-in
    /// protocol's (its frames are imaged by `et reconstruct --frames`), or the `scan` field
    /// the board's scan refuses.
    pub fn replay_config(&self) -> Result<(ScanConfig, f64), FieldError> {
        let (protocol, ua) = match self.named_protocol()? {
            Some(kind) => (kind, self.scan.current_ua),
            None => self.file_as_built_in()?,
        };
        let played = ua.min(BOARD_MAX_UA);
        Ok((self.config_at(protocol, played)?, played / ua))
    }

    /// The built-in protocol whose rows, in their order, a protocol file's are (`et protocol
    /// --csv` writes them so; another system's file of adjacent in et's order), and the one
    /// current they drive, uA: such a file plays as that protocol.
    ///
    /// # Errors
    /// [`SceneFault::NotPlayed`] for rows of no built-in protocol, or of several currents;
    /// what [`Scene::schedule`] finds wrong with the file.
    fn file_as_built_in(&self) -> Result<(ProtocolKind, f64), FieldError> {
        self.built_in_of_file()?
            .ok_or_else(|| FieldError::new("scan.protocol", SceneFault::NotPlayed))
    }

    /// Where the scene's protocol is a file whose rows are a built-in protocol's (scanned and
    /// played as that one), the words saying so and how its electrodes are numbered in what
    /// is said of them (as the file counts them): " (its protocol file's rows are pp-pp's)".
    #[must_use]
    pub fn file_said(&self) -> Option<String> {
        if !matches!(self.scan.protocol, ProtocolSpec::File(_)) {
            return None;
        }
        let (kind, _) = self.built_in_of_file().ok()??;
        let base = match self.electrode_base() {
            0 => String::new(),
            b => format!("; its electrodes numbered from {b} here, as the file counts them"),
        };
        Some(format!(
            " (its protocol file's rows are {}'s{base})",
            kind.name()
        ))
    }

    /// [`Scene::file_as_built_in`], `None` for rows of no built-in protocol or of several
    /// currents.
    fn built_in_of_file(&self) -> Result<Option<(ProtocolKind, f64)>, FieldError> {
        let schedule = self.schedule()?;
        let rows = schedule.rows();
        let ua = rows.first().map_or(0.0, |r| r.current_a * 1e6);
        let one_current = rows
            .iter()
            .all(|r| (r.current_a * 1e6 - ua).abs() <= 1e-6 * ua);
        let four = |r: &et_core::schedule::Row| (r.source, r.sink, r.positive, r.negative);
        let electrodes = self.sheet.physical.electrodes.count;
        let same = |kind: ProtocolKind| {
            let built_in = et_core::protocol::Protocol::new(kind, electrodes).ok();
            let built_in = built_in.and_then(|p| p.schedule(ua * 1e-6).ok());
            built_in.is_some_and(|b| b.rows().iter().map(four).eq(rows.iter().map(four)))
        };
        Ok((ProtocolKind::NAMED.into_iter())
            .find(|&kind| one_current && same(kind))
            .map(|kind| (kind, ua)))
    }

    /// The board's configuration of the scene's scan at `current_ua` (within the board's).
    fn config_at(&self, protocol: ProtocolKind, current_ua: f64) -> Result<ScanConfig, FieldError> {
        let s = &self.scan;
        let config = ScanConfig {
            electrodes: self.sheet.physical.electrodes.count,
            protocol,
            samples_per_step: s.samples_per_step,
            settle_samples: s.settle_samples,
            current_na: (current_ua * 1e3).round() as u32,
            sample_rate_hz: s.sample_rate_hz,
            gain: s.gain,
        };
        config.validate().map_err(|e| FieldError::new("scan", e))?;
        Ok(config)
    }
}
