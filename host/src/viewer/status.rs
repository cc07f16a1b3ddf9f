//! What the status line says of the frames: what is wrong with V_0 once it is taken, an
//! electrode that comes off after it, and what the board flags in them; and what it said
//! before, to read after the next message replaced it.

use super::*;

/// What the status line said, each message once with how many times, the most recent last
/// (at most [`StatusLog::KEPT`]): a warning that the next message replaced within a frame
/// (V_0's, an electrode come off, the board's flags) stays to read under "Earlier messages".
#[derive(Debug, Default)]
pub struct StatusLog {
    said: std::collections::VecDeque<(String, u32)>,
}

impl StatusLog {
    /// The most messages kept: the oldest go first.
    pub const KEPT: usize = 30;

    /// Notes the status line `now`: a message other than the last noted joins the log at its
    /// end (one said before moves there, counted again).
    pub fn note(&mut self, now: &str) {
        if now.is_empty() || self.said.back().is_some_and(|(last, _)| last == now) {
            return;
        }
        let times = match self.said.iter().position(|(said, _)| said == now) {
            Some(i) => self.said.remove(i).map_or(1, |(_, times)| times + 1),
            None => 1,
        };
        self.said.push_back((now.to_string(), times));
        while self.said.len() > Self::KEPT {
            self.said.pop_front();
        }
    }

    /// The messages before the last noted (the status line now), the most recent first, with
    /// how many times each was said.
    pub fn earlier(&self) -> impl Iterator<Item = (&str, u32)> {
        (self.said.iter().rev().skip(1)).map(|(said, times)| (said.as_str(), *times))
    }
}

impl Viewer {
    /// The bottom panel: the status line, and what it said before (folded).
    pub(super) fn show_status(&mut self, ui: &mut egui::Ui) {
        self.said.note(&self.status);
        let earlier: Vec<(&str, u32)> = self.said.earlier().collect();
        if !earlier.is_empty() {
            ui.collapsing(format!("Earlier messages ({})", earlier.len()), |ui| {
                egui::ScrollArea::vertical()
                    .max_height(160.0)
                    .show(ui, |ui| {
                        for (said, times) in earlier {
                            match times {
                                1 => ui.label(said),
                                _ => ui.label(format!("{said} (said {times} times)")),
                            };
                        }
                    });
            });
        }
        ui.label(&self.status);
    }

    /// The status once V_0 is taken: what to do next, or what is wrong with it (frames of
    /// another protocol, numbering or sheet than the scene's, or a reference taken while
    /// the sheet was touched, show touches in the wrong places; frames in mV, values in the
    /// wrong unit).
    pub(super) fn reference_taken(&mut self) -> String {
        let sim = matches!(self.source.as_ref(), Some(Source::Sim(_)));
        let poor_fit = (!sim)
            .then(|| self.processor.v0_unexplained())
            .flatten()
            .and_then(et_recon::background::poor_fit_said);
        let changes = (self.processor.reference_changes())
            .and_then(|c| et_recon::background::reference_changes_said(c, None));
        let not_volts =
            (self.processor.v0()).and_then(|v0| et_recon::background::not_volts_said(&v0));
        let (electrode, detached) = self.processor.v0_electrode_said().unzip();
        let electrode = electrode.map(|said| format!("{said}, or leave it out (the side panel)"));
        self.detached = detached.unwrap_or_default();
        self.contacts.reference(&self.detached);
        // Said here, or the cause said above: not again for the frames after V_0.
        let v0_flags = std::mem::take(&mut self.v0_flags);
        self.flags_said.mark(v0_flags);
        let flagged = crate::live::flagged_readings(v0_flags)
            .map(|words| format!("{words} in frames of V_0: take it again once that is fixed"));
        let said = (electrode.or(flagged).or(poor_fit))
            .or(changes)
            .or(not_volts);
        match (said, sim) {
            (Some(said), _) => format!("V_0 taken; warning: {said}"),
            (None, true) => "V_0 taken: press and hold the mouse on the sheet".into(),
            (None, false) => "V_0 taken: touches show on the sheet".into(),
        }
    }

    /// What is said when the wizard starts while electrodes are left out of the images or named
    /// detached: its model trains on whole frames, their values among them. None otherwise.
    pub(super) fn trains_on_detached(&self) -> Option<String> {
        let mut off = [self.processor.left_out(), &self.detached].concat();
        off.sort_unstable();
        off.dedup();
        let numbers: Vec<String> = off.iter().map(u16::to_string).collect();
        let (noun, them) = match off.len() {
            0 => return None,
            1 => ("electrode", "it"),
            _ => ("electrodes", "them"),
        };
        Some(format!(
            "warning: the wizard's model trains on whole frames, and {noun} {} is left out of \
             the images or named detached: its classes would learn a detached electrode's \
             values; fix {them} before collecting",
            numbers.join(", ")
        ))
    }

    /// Says what the board flagged in `out`'s frame (readings on an ADC rail, its current
    /// source in compliance), the first time it flags each after V_0 (V_0's are said with
    /// it); the link health counts them.
    pub(super) fn board_flagged(&mut self, out: &Output) {
        if out.referencing.is_some() {
            self.v0_flags |= out.frame.flags;
            return;
        }
        if let Some(words) = self.flags_said.first(out.frame.flags) {
            self.status = format!(
                "frame {}: {words}: such frames' values may not be the sheet's (the link's \
                 health counts them)",
                out.frame.seq
            );
        }
    }

    /// Says of an electrode whose values stand out in the frame `out` as a detached one's,
    /// not said before (come off since V_0 was taken), and offers to leave it out; says it
    /// back when it fits the model again, or off again ([`crate::live::Contacts`]).
    pub(super) fn electrode_contact(&mut self, out: &Output) {
        use crate::live::Contact;
        let Some(contact) = self.contacts.watch(out, &self.processor) else {
            return;
        };
        let electrode = contact.electrode();
        // Offered to leave out while off, and while V_0 holds it off.
        match contact {
            Contact::Back { in_v0: false, .. } => self.detached.retain(|e| *e != electrode),
            _ if !self.detached.contains(&electrode) => self.detached.push(electrode),
            _ => {}
        }
        let said = match &contact {
            Contact::Off {
                misfit, times: 1, ..
            } => misfit.said(self.processor.electrode_base()).map(|said| {
                format!(
                    "{said} Not in V_0: a clip or wire come off, or a contact that opens now \
                     and then? Check it, or leave it out (the side panel)"
                )
            }),
            other => other.said(
                self.processor.electrode_base(),
                "take V_0 again untouched (Tare)",
                "leave it out (the side panel)",
            ),
        };
        if let Some(said) = said {
            self.status = format!("frame {}: {said}", out.frame.seq);
        }
    }
}
