//! The serial link to the firmware: packets in, commands out (docs/design.md, "The data, end to
//! end").
//!
//! - [`Decoder`] turns a byte stream into [`Uplink`] messages with the resynchronising
//!   [`Accumulator`]: after garbage, truncation or a flipped bit it drops the damaged packet and
//!   carries on at the next 0x00. [`Counters`] say what was lost: damaged packets, packets of
//!   another wire version, and frames missing from the sequence numbers.
//! - [`Link`] owns a serial port (opened by path with `serialport`; [`list_ports`] names
//!   them). A reader thread decodes everything the device sends; when the port fails (a pulled
//!   cable) it closes it and reopens the same path every [`RECONNECT_EVERY`] until the device
//!   is back, counting [`Counters::reconnects`]. [`Link::request`] sends a command and waits
//!   for its reply with a timeout, keeping the frames that arrive meanwhile;
//!   [`Link::upload_model`] sends a model blob in chunks and commits it.

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::collections::VecDeque;
use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use et_core::ScanConfig;
use et_core::wire::{
    self, Accumulator, Command, CommandTag, Event, HostUplink, MODEL_CHUNK, PACKET_MAX, Refusal,
    Uplink, WireError,
};
use serde::Serialize;

/// How often the reader tries to reopen a port that failed.
pub const RECONNECT_EVERY: Duration = Duration::from_millis(200);
/// How long one read waits before the reader checks whether it should stop.
const READ_TIMEOUT: Duration = Duration::from_millis(20);

/// What the link has seen since it was opened.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counters {
    /// Bytes received.
    pub bytes: u64,
    /// Frames decoded.
    pub frames: u64,
    /// Events decoded.
    pub events: u64,
    /// Packets dropped as damaged (COBS, CRC, body, overflow).
    pub corrupt: u64,
    /// Packets of a wire version this build does not speak.
    pub wrong_version: u64,
    /// Frames missing from the sequence (a gap in `seq`: lost on the wire or dropped by the
    /// device).
    pub lost_frames: u64,
    /// Times the port failed and was opened again.
    pub reconnects: u64,
}

/// Counts `message` in `counters`: frames, the frames lost before it (a gap in `seq` after
/// `next_seq`, the one expected), events.
fn count(counters: &mut Counters, next_seq: &mut Option<u32>, message: &HostUplink) {
    match message {
        Uplink::Frame(f) => {
            counters.frames += 1;
            if let Some(want) = *next_seq
                && f.seq > want
            {
                counters.lost_frames += u64::from(f.seq - want);
            }
            *next_seq = Some(f.seq.wrapping_add(1));
        }
        Uplink::Event(_) => counters.events += 1,
    }
}

/// Byte stream to messages, with resynchronisation and counters (see the module docs).
#[derive(Debug)]
pub struct Decoder {
    packets: Box<Accumulator<PACKET_MAX>>,
    counters: Counters,
    next_seq: Option<u32>,
    /// Whether a packet has ended since the stream began (or was resynchronised): the bytes
    /// before the first end are the tail of a packet sent before the port was opened, not a
    /// damaged one (`et record` said "1 damaged packets dropped" on a clean link).
    joined: bool,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder at the start of a stream.
    #[must_use]
    pub fn new() -> Self {
        Self {
            packets: Box::new(Accumulator::new()),
            counters: Counters::default(),
            next_seq: None,
            joined: false,
        }
    }

    /// Decodes `bytes`, appending every good message to `out`.
    pub fn feed(&mut self, bytes: &[u8], out: &mut Vec<HostUplink>) {
        self.counters.bytes += bytes.len() as u64;
        let Self {
            packets,
            counters,
            next_seq,
            joined,
        } = self;
        packets.feed_slice::<HostUplink>(bytes, |result| {
            let first = !std::mem::replace(joined, true);
            match result {
                Ok(message) if message.fits() => {
                    count(counters, next_seq, &message);
                    out.push(message);
                }
                Err(WireError::Version { .. }) => counters.wrong_version += 1,
                // The end of a packet whose start was sent before the stream was joined.
                _ if first => {}
                // A bad packet, or a frame longer than any board sends.
                _ => counters.corrupt += 1,
            }
        });
    }

    /// Forgets a packet in progress (after a reconnect: its first half came from before, and
    /// its end is not counted as damaged).
    pub fn resync(&mut self) {
        self.packets.clear();
        self.joined = false;
    }

    /// The counters so far.
    #[must_use]
    pub fn counters(&self) -> Counters {
        self.counters
    }
}

/// The serial ports this machine has (paths), for `et ports` and the viewer's list.
///
/// # Errors
/// When the system cannot be asked.
pub fn list_ports() -> Result<Vec<String>, serialport::Error> {
    Ok(serialport::available_ports()?
        .into_iter()
        .map(|p| p.port_name)
        .collect())
}

mod error;
pub use error::{LinkError, silent_board_hint};

type Port = Box<dyn serialport::SerialPort>;

/// Opens the port at `path`, the bytes already waiting in it dropped: what a board sent
/// while no one read (a board that streamed to nobody) is not this link's, and its frames
/// were taken as the first, then the gap to the board's frames now as frames lost.
fn open(path: &str, baud: u32) -> Result<Port, serialport::Error> {
    let port = serialport::new(path, baud).timeout(READ_TIMEOUT).open()?;
    port.clear(serialport::ClearBuffer::Input)?;
    Ok(port)
}

/// A device on a serial port (see the module docs).
#[derive(Debug)]
pub struct Link {
    path: String,
    writer: Arc<Mutex<Option<Port>>>,
    counters: Arc<Mutex<Counters>>,
    incoming: Receiver<HostUplink>,
    pending: VecDeque<HostUplink>,
    stop: Arc<AtomicBool>,
    reader: Option<JoinHandle<()>>,
}

impl Link {
    /// Opens the port at `path` at `baud` and starts reading.
    ///
    /// # Errors
    /// [`LinkError::Open`] if the port cannot be opened.
    pub fn open(path: &str, baud: u32) -> Result<Self, LinkError> {
        let port = open(path, baud).map_err(|error| LinkError::Open {
            path: path.to_string(),
            error,
        })?;
        let writer = port.try_clone().map_err(|error| LinkError::Open {
            path: path.to_string(),
            error,
        })?;
        let writer = Arc::new(Mutex::new(Some(writer)));
        let counters = Arc::new(Mutex::new(Counters::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, incoming) = mpsc::channel();
        let reader = Reader {
            path: path.to_string(),
            baud,
            writer: Arc::clone(&writer),
            counters: Arc::clone(&counters),
            stop: Arc::clone(&stop),
            out: tx,
        };
        let reader = std::thread::Builder::new()
            .name(format!("et-link {path}"))
            .spawn(move || reader.run(port))
            .map_err(|e| LinkError::Open {
                path: path.to_string(),
                error: e.into(),
            })?;
        Ok(Self {
            path: path.to_string(),
            writer,
            counters,
            incoming,
            pending: VecDeque::new(),
            stop,
            reader: Some(reader),
        })
    }

    /// The port's path.
    #[must_use]
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Whether the port is open right now (false between a pulled cable and its return).
    #[must_use]
    pub fn connected(&self) -> bool {
        self.writer
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .is_some()
    }

    /// What the link has seen so far.
    #[must_use]
    pub fn counters(&self) -> Counters {
        *self.counters.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Sends raw bytes (tests use it to send damaged packets).
    ///
    /// # Errors
    /// [`LinkError::Disconnected`] while the port is closed, [`LinkError::Write`] when writing
    /// fails.
    pub fn send_bytes(&self, bytes: &[u8]) -> Result<(), LinkError> {
        let mut writer = self.writer.lock().unwrap_or_else(|e| e.into_inner());
        let port = writer.as_mut().ok_or(LinkError::Disconnected)?;
        port.write_all(bytes).map_err(LinkError::Write)?;
        port.flush().map_err(LinkError::Write)
    }

    /// Sends `command` without waiting for its reply.
    ///
    /// # Errors
    /// As [`send_bytes`](Self::send_bytes).
    pub fn send(&self, command: &Command) -> Result<(), LinkError> {
        let mut buf = [0u8; wire::COMMAND_PACKET_MAX];
        let n = wire::encode(command, &mut buf).map_err(LinkError::Encode)?;
        self.send_bytes(buf.get(..n).unwrap_or_default())
    }

    /// The next message from the device (kept ones first), waiting at most `timeout`.
    ///
    /// # Errors
    /// [`LinkError::Timeout`] when nothing came.
    pub fn next(&mut self, timeout: Duration) -> Result<HostUplink, LinkError> {
        if let Some(m) = self.pending.pop_front() {
            return Ok(m);
        }
        self.incoming
            .recv_timeout(timeout)
            .map_err(|_| LinkError::Timeout { waiting_for: None })
    }

    /// How many messages [`request`](Self::request) kept (they came before its reply, so
    /// were sent before the device acted on it): [`next`](Self::next) returns them first.
    #[must_use]
    pub fn kept(&self) -> usize {
        self.pending.len()
    }

    /// Sends `command` and waits up to `timeout` for its reply: `Pong` for a ping, the
    /// acknowledgement otherwise. Messages that arrive meanwhile are kept for [`next`](Self::next).
    ///
    /// # Errors
    /// [`LinkError::Refused`] with the device's reason, [`LinkError::Timeout`], or a send error.
    pub fn request(&mut self, command: &Command, timeout: Duration) -> Result<Event, LinkError> {
        let tag = command.tag();
        self.send(command)?;
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let message = match self.incoming.recv_timeout(left) {
                Ok(m) => m,
                Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => {
                    return Err(LinkError::Timeout {
                        waiting_for: Some(tag),
                    });
                }
            };
            match (&message, command) {
                (Uplink::Event(Event::Pong { nonce }), Command::Ping { nonce: sent })
                    if nonce == sent =>
                {
                    return Ok(Event::Pong { nonce: *nonce });
                }
                (Uplink::Event(e @ Event::Ack { command }), _) if *command == tag => {
                    return Ok(e.clone());
                }
                (Uplink::Event(Event::Refused { command, reason }), _)
                    if *command == tag || *command == CommandTag::Unknown =>
                {
                    return Err(LinkError::Refused {
                        command: *command,
                        reason: *reason,
                    });
                }
                _ => self.pending.push_back(message),
            }
        }
    }

    /// Uploads a model blob: begin (the device erases a slot: allow for `erase_timeout`),
    /// chunks of [`MODEL_CHUNK`] bytes, commit. The device verifies it (CRC, model checks, scan
    /// configuration) before it replaces the old model.
    ///
    /// # Errors
    /// The first refusal or timeout; the device keeps its old model.
    pub fn upload_model(
        &mut self,
        blob: &[u8],
        timeout: Duration,
        erase_timeout: Duration,
    ) -> Result<(), LinkError> {
        let too_large = || LinkError::TooLarge { bytes: blob.len() };
        let len = u32::try_from(blob.len()).map_err(|_| too_large())?;
        let crc = wire::crc32(blob);
        (self.request(&Command::ModelBegin { len, crc }, erase_timeout)).map_err(|e| match e {
            LinkError::Refused {
                reason: Refusal::TooLarge,
                ..
            } => too_large(),
            e => e,
        })?;
        for (i, chunk) in blob.chunks(MODEL_CHUNK).enumerate() {
            let data = heapless::Vec::from_slice(chunk)
                .map_err(|_| LinkError::Encode(WireError::BufferFull))?;
            let offset = (i * MODEL_CHUNK) as u32;
            self.request(&Command::ModelChunk { offset, data }, timeout)?;
        }
        self.request(&Command::ModelCommit, timeout)?;
        Ok(())
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(reader) = self.reader.take() {
            let _ = reader.join();
        }
    }
}

/// The reader thread's state.
struct Reader {
    path: String,
    baud: u32,
    writer: Arc<Mutex<Option<Port>>>,
    counters: Arc<Mutex<Counters>>,
    stop: Arc<AtomicBool>,
    out: Sender<HostUplink>,
}

impl Reader {
    fn run(self, port: Port) {
        let mut decoder = Decoder::new();
        let mut port = Some(port);
        let mut buf = vec![0u8; 4096];
        let mut messages = Vec::new();
        let mut reconnects = 0;
        while !self.stop.load(Ordering::Relaxed) {
            let Some(p) = port.as_mut() else {
                std::thread::sleep(RECONNECT_EVERY);
                port = self.reopen();
                if port.is_some() {
                    reconnects += 1;
                    decoder.resync();
                }
                continue;
            };
            match p.read(&mut buf) {
                Ok(0) => {}
                Ok(n) => decoder.feed(buf.get(..n).unwrap_or_default(), &mut messages),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(_) => {
                    // The cable is out (or the device reset): close and try again later.
                    port = None;
                    *self.writer.lock().unwrap_or_else(|e| e.into_inner()) = None;
                }
            }
            {
                let mut c = self.counters.lock().unwrap_or_else(|e| e.into_inner());
                *c = Counters {
                    reconnects,
                    ..decoder.counters()
                };
            }
            for m in messages.drain(..) {
                if self.out.send(m).is_err() {
                    return;
                }
            }
        }
    }

    fn reopen(&self) -> Option<Port> {
        let port = open(&self.path, self.baud).ok()?;
        let writer = port.try_clone().ok()?;
        *self.writer.lock().unwrap_or_else(|e| e.into_inner()) = Some(writer);
        Some(port)
    }
}

/// A change on the link that people should hear about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkChange {
    /// The port went away (cable pulled, board reset): waiting for it to come back.
    Vanished,
    /// The port is back (the scan asked for and Start sent again when the [`Keepalive`]
    /// sends them).
    Back,
    /// No frame for [`Keepalive::SILENCE`] while connected: the scan asked for and Start sent
    /// again (a board that came back idle).
    Restarted,
}

impl std::fmt::Display for LinkChange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LinkChange::Vanished => "the port went away; waiting for it to come back",
            LinkChange::Back => "the port is back",
            LinkChange::Restarted => "no frames for a second: asked the board to scan again",
        })
    }
}

/// Keeps a board scanning across pulled cables and resets: notices when the port vanishes
/// and comes back, and (when it may send commands) sends Start again to a board that is
/// silent, after the scan it was asked for ([`keep_scan`](Self::keep_scan)): a board that
/// restarted scans its stored model's configuration, or adjacent. Call
/// [`frame`](Self::frame) for every frame and [`check`](Self::check) often.
#[derive(Debug)]
pub struct Keepalive {
    send_start: bool,
    /// The configuration last asked for, sent again before Start.
    scan: Option<ScanConfig>,
    connected: bool,
    reconnects: u64,
    quiet_since: Instant,
}

impl Keepalive {
    /// How long a connected board may send nothing before Start is sent again.
    pub const SILENCE: Duration = Duration::from_secs(1);

    /// Watches `link`; `send_start` = false only listens (the board is started by someone
    /// else).
    #[must_use]
    pub fn new(link: &Link, send_start: bool) -> Self {
        Self {
            send_start,
            scan: None,
            connected: link.connected(),
            reconnects: link.counters().reconnects,
            quiet_since: Instant::now(),
        }
    }

    /// The board was asked to scan `config` (and acknowledged it): a board that comes back is
    /// asked for it again before Start.
    pub fn keep_scan(&mut self, config: ScanConfig) {
        self.scan = Some(config);
    }

    /// A frame arrived.
    pub fn frame(&mut self) {
        self.quiet_since = Instant::now();
    }

    /// Looks at the link; sends the scan asked for and Start where needed. Returns what
    /// changed, if anything.
    pub fn check(&mut self, link: &Link) -> Option<LinkChange> {
        let now = Instant::now();
        let (connected, reconnects) = (link.connected(), link.counters().reconnects);
        let change = if reconnects != self.reconnects {
            self.reconnects = reconnects;
            self.connected = connected;
            Some(LinkChange::Back)
        } else if self.connected && !connected {
            self.connected = false;
            return Some(LinkChange::Vanished);
        } else if self.send_start
            && connected
            && now.duration_since(self.quiet_since) >= Self::SILENCE
        {
            Some(LinkChange::Restarted)
        } else {
            None
        }?;
        if self.send_start {
            // Both are idempotent on the board (Configure clears V_0 only for another scan);
            // a failed send is retried after SILENCE.
            if let Some(config) = self.scan {
                let _ = link.send(&Command::Configure(config));
            }
            let _ = link.send(&Command::Start);
        }
        self.quiet_since = now;
        Some(change)
    }
}
