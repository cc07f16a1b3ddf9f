//! Electrodes that come off and come back while frames stream. The pipeline names an
//! electrode whose values stand out from the model ([`Output::electrode_off`]); a clip put
//! back, or a contact that opens now and then, fits the model again, and the images are right
//! again (unless V_0 was taken while it was off). [`Contacts`] follows each electrode named, so
//! et stream and the viewer say both: off, back, off again, and stop saying a contact that
//! comes and goes past [`SAID_TIMES`].

use super::{ElectrodeMisfit, LiveFrame, Output, Processor};

/// How many imaged frames in a row an electrode that came off must fit the model again to be
/// said back: a contact that opens now and then leaves few sound frames in a row, a clip put
/// back all of them; 10 frames is a fifth of a second at 50 frames/s.
pub const BACK_AFTER: u32 = 10;

/// How many times an electrode's coming off is said: the last says it comes and goes, and
/// nothing more is said of it (nor its coming back) until V_0 is taken again.
pub const SAID_TIMES: u32 = 3;

/// What changed of an electrode's contact in a frame ([`Contacts::watch`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Contact {
    /// Its values stand out as a detached electrode's: the `times`-th time (1 the first).
    Off {
        /// How far off its values are.
        misfit: ElectrodeMisfit,
        /// Which time it came off since V_0 was taken (1 the first, up to [`SAID_TIMES`]).
        times: u32,
        /// The frame it was last said back at (None the first time).
        back_at: Option<u32>,
    },
    /// Its values fit the model again, [`BACK_AFTER`] frames in a row from frame `since`.
    Back {
        /// The electrode (0-based).
        electrode: u16,
        /// The frame it was said off from (or V_0's, [`Contact::Back::in_v0`]).
        off_since: Option<u32>,
        /// The first of the frames in a row that fit again.
        since: u32,
        /// Whether V_0 was taken while it was off: the images stay wrong until it is taken
        /// again (its changes from V_0 are the contact's, not the sheet's).
        in_v0: bool,
    },
}

impl Contact {
    /// The electrode it is of (0-based).
    #[must_use]
    pub fn electrode(&self) -> u16 {
        match self {
            Self::Off { misfit, .. } => misfit.electrode,
            Self::Back { electrode, .. } => *electrode,
        }
    }

    /// What is said of it beside a frame, numbered from `base` (0 as the board counts, 1 as
    /// a protocol file counting from 1 does): `retake` says how V_0 is taken again (et
    /// stream: start it again; the viewer: Tare), `leave` how an electrode is left out. None
    /// for the first coming off (the caller says it with its misfit,
    /// [`ElectrodeMisfit::said`]).
    #[must_use]
    pub fn said(&self, base: u16, retake: &str, leave: &str) -> Option<String> {
        let electrode = u32::from(self.electrode()) + u32::from(base);
        match self {
            Self::Off { times: 1, .. } => None,
            Self::Off {
                misfit,
                times,
                back_at,
            } => {
                let back = back_at.map_or(String::new(), |f| format!(", back at frame {f}"));
                let more = if *times >= SAID_TIMES {
                    "; it comes and goes: said no more of it"
                } else {
                    ""
                };
                let time = match times {
                    2 => "2nd".to_string(),
                    3 => "3rd".to_string(),
                    n => format!("{n}th"),
                };
                Some(format!(
                    "electrode {electrode} is off again (the {time} time{back}; its values {:.0} \
                     % off the model): a contact that opens now and then? Fix its clip, or \
                     {leave}{more}",
                    100.0 * misfit.own
                ))
            }
            Self::Back {
                off_since,
                since,
                in_v0: false,
                ..
            } => Some(format!(
                "electrode {electrode}'s values fit the model again from frame {since}{}: it \
                 is back, and the images with it",
                off_since.map_or(String::new(), |f| format!(" (off since frame {f})"))
            )),
            Self::Back {
                since, in_v0: true, ..
            } => Some(format!(
                "electrode {electrode}'s values fit the model again from frame {since}, but \
                 V_0 was taken while it was off: its changes from V_0 are the contact's, not \
                 the sheet's, and place touches wrongly; {retake}"
            )),
        }
    }
}

/// One electrode named off since V_0 was taken.
#[derive(Clone, Debug)]
struct Watched {
    electrode: u16,
    /// Said off from this frame (None: V_0 named it).
    off_since: Option<u32>,
    /// Said back at this frame; None while off.
    back_at: Option<u32>,
    /// Imaged frames in a row it fitted the model, and the first of them.
    fits: u32,
    first_fit: u32,
    /// Times said off.
    times: u32,
    /// V_0 was taken while it was off.
    in_v0: bool,
}

/// Each electrode named off since V_0 was taken, followed frame by frame (module docs).
#[derive(Clone, Debug, Default)]
pub struct Contacts {
    watched: Vec<Watched>,
}

impl Contacts {
    /// A new V_0: forgets every electrode and follows `detached` (those V_0 names detached or
    /// broken, said with it) as off.
    pub fn reference(&mut self, detached: &[u16]) {
        self.watched = (detached.iter())
            .map(|&electrode| Watched {
                electrode,
                off_since: None,
                back_at: None,
                fits: 0,
                first_fit: 0,
                times: 1,
                in_v0: true,
            })
            .collect();
    }

    /// Whether `electrode` is followed as off now (named, and not back since).
    #[must_use]
    pub fn is_off(&self, electrode: u16) -> bool {
        (self.watched.iter()).any(|w| w.electrode == electrode && w.back_at.is_none())
    }

    /// What changed in the imaged frame `out` (None for a frame of the reference): an
    /// electrode named off that was not (the first time, again, or a last time past
    /// [`SAID_TIMES`]), else one off that fits the model again [`BACK_AFTER`] frames in a
    /// row, weighed by `processor` without the others off. At most one a frame; another's
    /// turn comes with the next.
    pub fn watch(&mut self, out: &Output, processor: &Processor) -> Option<Contact> {
        if out.referencing.is_some() {
            return None;
        }
        let seq = out.frame.seq;
        let named = out.electrode_off.filter(ElectrodeMisfit::stands_out);
        if let Some(m) = named {
            match self.watched.iter_mut().find(|w| w.electrode == m.electrode) {
                None => {
                    self.watched.push(Watched {
                        electrode: m.electrode,
                        off_since: Some(seq),
                        back_at: None,
                        fits: 0,
                        first_fit: 0,
                        times: 1,
                        in_v0: false,
                    });
                    return Some(Contact::Off {
                        misfit: m,
                        times: 1,
                        back_at: None,
                    });
                }
                Some(w) if w.back_at.is_some() => {
                    let back_at = w.back_at.take();
                    w.off_since = Some(seq);
                    w.fits = 0;
                    w.times += 1;
                    return (w.times <= SAID_TIMES).then_some(Contact::Off {
                        misfit: m,
                        times: w.times,
                        back_at,
                    });
                }
                Some(w) => w.fits = 0,
            }
        }
        self.back(&out.frame, named.map(|m| m.electrode), processor)
    }

    /// Counts the frames each electrode off (but `named`, off in this frame) fits the model;
    /// the first to reach [`BACK_AFTER`] is said back.
    fn back(
        &mut self,
        frame: &LiveFrame,
        named: Option<u16>,
        processor: &Processor,
    ) -> Option<Contact> {
        let off: Vec<u16> = (self.watched.iter())
            .filter(|w| w.back_at.is_none())
            .map(|w| w.electrode)
            .collect();
        let mut said = None;
        for w in &mut self.watched {
            if w.back_at.is_some() || Some(w.electrode) == named {
                continue;
            }
            // An electrode not weighed (left out, another scan) keeps its count.
            let Some(m) = processor.misfit_of(frame, w.electrode, &off) else {
                continue;
            };
            if m.stands_out() {
                w.fits = 0;
                continue;
            }
            if w.fits == 0 {
                w.first_fit = frame.seq;
            }
            w.fits += 1;
            if w.fits >= BACK_AFTER && said.is_none() {
                w.back_at = Some(frame.seq);
                said = (w.times < SAID_TIMES).then_some(Contact::Back {
                    electrode: w.electrode,
                    off_since: w.off_since,
                    since: w.first_fit,
                    in_v0: w.in_v0,
                });
            }
        }
        said
    }
}
