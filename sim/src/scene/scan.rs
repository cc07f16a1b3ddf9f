//! The scan section: the built-in protocol or the protocol file, the current, the schedule imaged
//! and the configuration the simulated board scans.

use super::*;

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
        if self.named_protocol()?.is_some() && ua <= 1000.0 {
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
                et_core::schedule::Schedule::parse_csv(
                    &path,
                    &text,
                    u16::from(electrodes),
                    f.base,
                    amps,
                )
                .map_err(|e| field(e.into()))
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

    /// The scan configuration the scene asks of the (simulated) board.
    ///
    /// # Errors
    /// [`FieldError`] naming the `scan.` field at fault: a protocol file (imaged from
    /// recorded frames, not scanned by the board), or a current above the board's 1 mA.
    pub fn scan_config(&self) -> Result<ScanConfig, FieldError> {
        let s = &self.scan;
        let protocol = self
            .named_protocol()?
            .ok_or_else(|| FieldError::new("scan.protocol", SceneFault::NotScanned))?;
        if !(s.current_ua.is_finite() && s.current_ua > 0.0 && s.current_ua <= 1000.0) {
            let fault = SceneFault::BoardCurrent(s.current_ua);
            return Err(FieldError::new("scan.current_ua", fault));
        }
        let config = ScanConfig {
            electrodes: self.sheet.physical.electrodes.count,
            protocol,
            samples_per_step: s.samples_per_step,
            settle_samples: s.settle_samples,
            current_na: (s.current_ua * 1e3).round() as u32,
            sample_rate_hz: s.sample_rate_hz,
            gain: s.gain,
        };
        config.validate().map_err(|e| FieldError::new("scan", e))?;
        Ok(config)
    }
}
