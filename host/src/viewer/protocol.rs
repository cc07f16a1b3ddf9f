//! The protocol the viewer scans: a fixed one, switched by the buttons, the wizard or the
//! board's own state; or automatic selection (docs/method.md §8), which first takes V_0 of every
//! protocol it may switch to, in turn, while the sheet is untouched, so that a switch scans the
//! new protocol against its own V_0. (Each switch took V_0 anew, from frames of the press that
//! made the switch: the press vanished from the image, and three frames later the selection
//! went back to AD, taking V_0 with the press again.)

use super::*;

/// The protocols automatic selection switches among, in the order their V_0 is taken after
/// AD's; the last is AD again, where selection starts.
const ROUND: [ProtocolKind; 3] = [
    ProtocolKind::PseudoPolar,
    ProtocolKind::PpPp,
    ProtocolKind::Adjacent,
];

impl Viewer {
    /// Scans with `config` from now on (the source is told; V_0 is taken anew); whether the
    /// source took it (else the status says why).
    pub fn switch_config(&mut self, config: ScanConfig) -> bool {
        let taken = self.configure(config);
        if taken {
            self.processor.tare();
            self.status = format!(
                "scanning {}: keep the sheet untouched while V_0 is taken",
                config.protocol.name()
            );
        }
        taken
    }

    /// Tells the source to scan with `config`, keeping every V_0 taken (a configuration
    /// scanned before images against its own); whether it took it (else the status says why).
    pub(super) fn configure(&mut self, config: ScanConfig) -> bool {
        let Some(source) = self.source.as_mut() else {
            return false;
        };
        match source.configure(config) {
            Ok(()) => {
                self.asked = Some(config);
                if self.protocol != ProtocolChoice::Automatic {
                    self.protocol = ProtocolChoice::Fixed(config.protocol);
                }
                true
            }
            Err(e) => {
                self.status = e.to_string();
                false
            }
        }
    }

    /// Chooses a protocol (automatic starts on adjacent and follows docs/method.md §8).
    pub fn choose_protocol(&mut self, choice: ProtocolChoice) {
        self.protocol = choice;
        self.round.clear();
        let kind = match choice {
            ProtocolChoice::Fixed(k) => k,
            ProtocolChoice::Automatic => return self.start_automatic(),
        };
        if let Some(config) = self.source.as_ref().and_then(Source::config)
            && config.protocol != kind
        {
            let _ = self.switch_config(ScanConfig {
                protocol: kind,
                ..config
            });
        }
    }

    /// A fixed protocol shown as the one the frames are scanned with: a board keeps its scan
    /// between connections (another program's, or automatic selection's last), and the
    /// viewer showed AD chosen over frames of PP. Frames of a scan before the last one asked
    /// for (a board's, still on the way) are not followed.
    pub(super) fn follow_the_scan(&mut self, out: &Output) {
        let scanned = out.frame.config;
        if self.asked.is_some_and(|asked| asked != scanned) {
            return;
        }
        self.asked = None;
        if let ProtocolChoice::Fixed(kind) = self.protocol
            && kind != scanned.protocol
        {
            self.protocol = ProtocolChoice::Fixed(scanned.protocol);
        }
    }

    /// Starts automatic selection: V_0 forgotten, then taken on AD, PP and PP-PP in turn. A
    /// recording cannot switch its scan: refused there, its V_0 kept (it was taken again
    /// from the frames playing, a press among them, before the switch to PP failed).
    pub(super) fn start_automatic(&mut self) {
        if let Some(source) = self.source.as_ref().filter(|s| !s.switches_scan())
            && let Some(config) = source.config()
        {
            let recorded = config.protocol;
            self.protocol = ProtocolChoice::Fixed(recorded);
            self.status = format!(
                "automatic selection switches the scan between protocols, which a recording \
                 cannot: it plays the {} protocol it was recorded with (the simulated sheet \
                 and a board switch)",
                recorded.name()
            );
            return;
        }
        self.selector = Selector::new(*self.selector.settings());
        self.processor.tare();
        self.round = ROUND.to_vec();
        if let Some(config) = self.source.as_ref().and_then(Source::config)
            && !self.configure(ScanConfig {
                protocol: ProtocolKind::Adjacent,
                ..config
            })
        {
            self.round.clear();
            return;
        }
        self.status =
            "automatic: taking V_0 of AD, PP and PP-PP in turn: keep the sheet untouched".into();
    }

    /// After each processed frame: the round of references goes on once the scan's V_0 is
    /// complete; after it, the selector sees the frame's touches and may switch the scan
    /// (to a protocol whose V_0 it has).
    pub(super) fn select_automatically(&mut self, out: &Output) {
        if self.protocol != ProtocolChoice::Automatic || out.referencing.is_some() {
            return;
        }
        let Some(config) = self.source.as_ref().and_then(Source::config) else {
            return;
        };
        // A frame of the scan before the last switch (a board's, still on the way) says
        // nothing of the scan now.
        if out.frame.config != config {
            return;
        }
        if !self.round.is_empty() {
            let next = self.round.remove(0);
            if self.configure(ScanConfig {
                protocol: next,
                ..config
            }) {
                self.status = if self.round.is_empty() {
                    "automatic: V_0 of AD, PP and PP-PP taken: touches show on the sheet".into()
                } else {
                    format!(
                        "automatic: taking V_0 of {}: keep the sheet untouched",
                        next.name()
                    )
                };
            } else {
                self.round.clear();
            }
            return;
        }
        let regions = if out.event.is_some() {
            out.regions.clone()
        } else {
            Vec::new()
        };
        if let Some(kind) = self.selector.step(&regions) {
            self.configure(ScanConfig {
                protocol: kind,
                ..config
            });
        }
    }
}
