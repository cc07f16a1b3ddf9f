//! The multiplexer word: the 10 control lines of the two 16:1 multiplexers that connect the
//! current source and ground for one injection.

use super::*;

/// The 10 mux control lines for one injection (docs/method.md §2): two 16:1 multiplexers, one
/// connecting the current source, one connecting ground, each with 4 address bits and an
/// active-high enable.
///
/// Bit layout: bits 0-3 source address, bit 4 source enable, bits 5-8 sink address, bit 9
/// sink enable. Line `n` of [`MuxWord::line`] is bit `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MuxWord(pub u16);

impl MuxWord {
    /// Number of control lines.
    pub const LINES: usize = 10;
    /// Both multiplexers disabled: no current flows.
    pub const OFF: MuxWord = MuxWord(0);
    const SOURCE_ENABLE: u16 = 1 << 4;
    const SINK_ENABLE: u16 = 1 << 9;

    /// The control word that routes `injection`.
    ///
    /// # Errors
    /// [`ProtocolError::MuxRange`] for an electrode the 16:1 muxes cannot address.
    pub fn for_injection(injection: Injection) -> Result<Self, ProtocolError> {
        for e in [injection.source, injection.sink] {
            if e.0 >= MUX_CHANNELS {
                return Err(ProtocolError::MuxRange { electrode: e });
            }
        }
        Ok(MuxWord(
            u16::from(injection.source.0)
                | Self::SOURCE_ENABLE
                | (u16::from(injection.sink.0) << 5)
                | Self::SINK_ENABLE,
        ))
    }

    /// The same addresses with both enables low (break before make).
    #[must_use]
    pub fn disabled(self) -> Self {
        MuxWord(self.0 & !(Self::SOURCE_ENABLE | Self::SINK_ENABLE))
    }

    /// The level of control line `n` (`0..10`).
    #[must_use]
    pub fn line(self, n: usize) -> bool {
        n < Self::LINES && self.0 & (1 << n) != 0
    }

    /// The injection this word routes, if both muxes are enabled.
    #[must_use]
    pub fn injection(self) -> Option<Injection> {
        let enabled = self.0 & Self::SOURCE_ENABLE != 0 && self.0 & Self::SINK_ENABLE != 0;
        enabled.then_some(Injection {
            source: ElectrodeId((self.0 & 0xF) as u8),
            sink: ElectrodeId(((self.0 >> 5) & 0xF) as u8),
        })
    }
}
