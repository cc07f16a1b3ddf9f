//! The processor's electrodes: those left out of the images, those V_0 names detached (and
//! whether one is back), a classifier that reads them, and how the source's user counts them.

use super::*;

impl Processor {
    /// What is said of the electrodes whose values in V_0 stand out from the model as a
    /// detached or broken electrode's ([`Reconstructor::detached_electrodes`]; of the values
    /// imaged, so not those left out), numbered as the source's user counts them (from
    /// [`Processor::electrode_base`]), and those electrodes (0-based); None until the
    /// reference is complete, or when none stands out.
    #[must_use]
    pub fn v0_electrode_said(&self) -> Option<(String, Vec<u16>)> {
        let detached = self.recon.detached_electrodes(&self.at.keep(&self.v0()?));
        let (said, _) = et_recon::background::detached_said(&detached, self.electrode_base)?;
        let check = if detached.len() == 1 {
            "its clip and wire"
        } else {
            "their clips and wires"
        };
        let electrodes = detached.iter().map(|m| m.electrode).collect();
        Some((format!("{said} Check {check}"), electrodes))
    }

    /// Electrode `electrode`'s misfit in `frame` beside the model of the untouched sheet,
    /// weighed without the values `without` drive or measure ([`Reconstructor::misfit_of`]):
    /// whether one that came off is back. None for a frame of another scan than the one set up
    /// last, or an electrode left out.
    #[must_use]
    pub fn misfit_of(
        &self,
        frame: &LiveFrame,
        electrode: u16,
        without: &[u16],
    ) -> Option<ElectrodeMisfit> {
        let volts: Vec<f64> = frame.voltages.iter().map(|v| f64::from(*v)).collect();
        (frame.config == self.at.config).then(|| {
            self.recon
                .misfit_of(&self.at.keep(&volts), electrode, without)
        })?
    }

    /// Leaves every value that `electrodes` (0-based, as the board counts) drive or measure
    /// out of the images from the next frame on (none: every value imaged again): a detached
    /// or broken electrode ([`Processor::v0_electrode_said`] names one). V_0 is kept; the
    /// classifier still sees whole frames. The reconstruction is set up for `scan` without
    /// them now (its matrix made at the next frame).
    ///
    /// Returns how many values of a frame of `scan` (None: the latest frame's scan) are left
    /// out, and its K.
    ///
    /// # Errors
    /// [`LiveError::LeftOut`] for an electrode past the sheet's, more than half of them, or
    /// electrodes every value of the scan involves; the images then stay as they were.
    pub fn set_left_out(
        &mut self,
        electrodes: &[u16],
        scan: Option<ScanConfig>,
    ) -> Result<(usize, usize), LiveError> {
        let mut left_out = electrodes.to_vec();
        left_out.sort_unstable();
        left_out.dedup();
        let config = scan.or(self.current).unwrap_or(self.at.config);
        let (at, schedule) = At::new(config, &left_out)?;
        let k = config.validate()?.frame_len();
        let kept = at.kept.as_ref().map_or(k, Vec::len);
        // Set up now: what is said of V_0 from here on is of the values imaged.
        self.recon.set_schedule(schedule)?;
        self.at = at;
        self.left_out = left_out;
        Ok((k - kept, k))
    }

    /// Numbers electrodes from `base` in what it says of them (the source's,
    /// [`crate::live::Source::electrode_base`]: a protocol file counting from 1).
    pub fn set_electrode_base(&mut self, base: u16) {
        self.electrode_base = base;
    }

    /// The number of the first electrode in what is said of electrodes.
    #[must_use]
    pub fn electrode_base(&self) -> u16 {
        self.electrode_base
    }

    /// `electrodes` as the source's user counts them (from [`Self::electrode_base`]: 1 for
    /// a protocol file counting from 1) as the board does, from 0 ([`Self::set_left_out`]).
    ///
    /// # Errors
    /// [`LiveError::Counted`] for one outside the sheet's, said as the user counts.
    pub fn counted_from_zero(&self, electrodes: &[u16]) -> Result<Vec<u16>, LiveError> {
        let (base, count) = (self.electrode_base, u16::from(self.at.config.electrodes));
        (electrodes.iter())
            .map(|&e| {
                (e.checked_sub(base).filter(|z| *z < count)).ok_or(LiveError::Counted {
                    electrode: e,
                    base,
                    count,
                })
            })
            .collect()
    }

    /// The electrodes whose values are left out of the images (0-based, ascending).
    #[must_use]
    pub fn left_out(&self) -> &[u16] {
        &self.left_out
    }

    /// What is said when the classifier reads values that `electrodes` (0-based) drive or
    /// measure (a detached electrode's, which leaving them out of the images does not take out
    /// of its features); None without a classifier, or when it reads none of them.
    #[must_use]
    pub fn classifier_reads_said(&self, electrodes: &[u16]) -> Option<String> {
        let file = self.classifier.as_ref()?.file();
        let schedule = file.config.schedule().ok()?;
        let rows = schedule.rows();
        let involves = |j: &&u16| {
            rows.get(usize::from(**j)).is_some_and(|r| {
                [r.source, r.sink, r.positive, r.negative]
                    .iter()
                    .any(|e| electrodes.contains(e))
            })
        };
        let read = file.feature_index.iter().filter(involves).count();
        (read > 0).then(|| {
            format!(
                "the model classifies with {read} of its {} features from their values, which \
                 it was trained on sound: its classes stay wrong while they are off (fix the \
                 electrode)",
                file.feature_index.len()
            )
        })
    }
}
