//! Reading et's input files whole, within a limit: the data-file limit and the memory free,
//! endless devices refused, text in UTF-8 or UTF-16, and files of another kind (a workbook,
//! an array, a picture, the board's blob) or a folder said as what they are.

/// The largest data file et reads whole by default (a dataset, a table, frames, a model): 1 GiB,
/// far above any real one (2 500 presses x 192 channels is 5 MB of text) and below what would
/// exhaust memory; an endless stream (`/dev/zero`, a pipe that never closes) stops here.
/// [`max_file_bytes`] is the limit in force.
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// The data-file limit in force in this process (0: not set, [`MAX_FILE_BYTES`]).
static MAX_FILE_BYTES_SET: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// The largest data file et's readers take whole in this process, in bytes: [`MAX_FILE_BYTES`]
/// unless [`set_max_file_bytes`] changed it.
#[must_use]
pub fn max_file_bytes() -> u64 {
    match MAX_FILE_BYTES_SET.load(std::sync::atomic::Ordering::Relaxed) {
        0 => MAX_FILE_BYTES,
        set => set,
    }
}

/// Sets the data-file limit of every et reader in this process (datasets, tables, frames,
/// models, meshes, protocols, recordings and a `.mat` variable's inflated size) to `limit`
/// bytes: larger for a program that reads recordings past 1 GiB on a machine with the memory
/// for them, smaller for one that must bound what a file can make it allocate. 0 restores
/// [`MAX_FILE_BYTES`]. Scenes (1 MiB) and model blobs (16 MiB) keep their own limits.
pub fn set_max_file_bytes(limit: u64) {
    MAX_FILE_BYTES_SET.store(limit, std::sync::atomic::Ordering::Relaxed);
}

/// Memory the system can give now, bytes (Linux's `MemAvailable`); None where it is not said
/// (another system, or no `/proc`): a check against it then passes.
#[must_use]
pub fn available_memory_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The bytes of `path`, stopping at `limit`: more is an error of kind
/// [`std::io::ErrorKind::FileTooLarge`] saying so, found before reading for a regular file
/// and while reading for a stream (an endless stream is never read to its end). The buffer
/// never grows past `limit` bytes: reading an endless stream allocates at most 1.5 x `limit`
/// (the last growth), a regular file its size.
///
/// # Errors
/// The file's I/O error, or the size error.
pub fn read_at_most(path: &std::path::Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
    let too_large = || {
        std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("more than {limit} bytes: not a file et reads (is it the right one?)"),
        )
    };
    let mut file = std::fs::File::open(path).map_err(|e| said_plainly(e, path))?;
    let meta = file.metadata()?;
    if meta.is_dir() {
        // Read, a folder failed as "Is a directory (os error 21)".
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "a folder, not a file: give a file in it",
        ));
    }
    if meta.is_file() && meta.len() > limit {
        return Err(too_large());
    }
    if endless_device(&file, &meta) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "a character device, which never ends (as /dev/zero or /dev/urandom): not a file \
             et reads",
        ));
    }
    let limit = usize::try_from(limit).unwrap_or(usize::MAX);
    let mut bytes = Vec::new();
    if meta.is_file() {
        // Its size (a file that grows while it is read grows the buffer as a stream would).
        bytes.reserve_exact(usize::try_from(meta.len()).unwrap_or(0));
    }
    let mut chunk = vec![0u8; 1 << 16];
    loop {
        let n = match file.read(&mut chunk) {
            Ok(0) => return Ok(bytes),
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if n > limit - bytes.len() {
            return Err(too_large());
        }
        if bytes.capacity() - bytes.len() < n {
            let grown = bytes.capacity().saturating_mul(2).clamp(1 << 16, limit);
            bytes.reserve_exact(grown.max(bytes.len() + n) - bytes.len());
        }
        bytes.extend_from_slice(chunk.get(..n).unwrap_or_default());
    }
}

/// Text in UTF-16 with its byte-order mark (a spreadsheet's "Unicode text" export), decoded;
/// None for any other bytes.
fn utf16(bytes: &[u8]) -> Option<std::io::Result<String>> {
    let little = match bytes {
        [0xFF, 0xFE, ..] => true,
        [0xFE, 0xFF, ..] => false,
        _ => return None,
    };
    let units: Vec<u16> = bytes[2..]
        .chunks(2)
        .map(|c| match (c, little) {
            ([a, b], true) => u16::from_le_bytes([*a, *b]),
            ([a, b], false) => u16::from_be_bytes([*a, *b]),
            // An odd byte at the end: not a UTF-16 character, refused below.
            _ => 0xDC00,
        })
        .collect();
    Some(String::from_utf16(&units).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "UTF-16 text (its byte-order mark says so) that does not decode: a copy cut short?",
        )
    }))
}

/// The two ways opening a file fails most often, said without the system's error number
/// ("No such file or directory (os error 2)"); any other as it is. `-`, standard input to
/// many Unix tools, is a file's name to et.
fn said_plainly(e: std::io::Error, path: &std::path::Path) -> std::io::Error {
    let said = match e.kind() {
        std::io::ErrorKind::NotFound if path.as_os_str() == "-" => {
            "no such file: et reads files, not standard input ('-'); write what you pipe to a \
             file and give its path"
        }
        std::io::ErrorKind::NotFound if has_tilde(path) => {
            return std::io::Error::new(e.kind(), format!("no such file: {TILDE_SAID}"));
        }
        std::io::ErrorKind::NotFound if spaced_twin(path) => {
            "no such file, but there is one of the name without the spaces around it (a \
             space copied with the path?)"
        }
        std::io::ErrorKind::NotFound => "no such file (is the path right?)",
        std::io::ErrorKind::PermissionDenied => "not allowed to read it (its permissions)",
        _ => return e,
    };
    std::io::Error::new(e.kind(), said)
}

/// What is said of a path with `~` in it that is not there (given in quotes, or in a file
/// et reads): the shell's word, which et does not expand.
pub const TILDE_SAID: &str = "'~' is the shell's word for the home folder, which the shell \
                              expands only outside quotes and never in a file et reads; write \
                              the folder's path ($HOME/...)";

/// Whether `path` has a component `~` (the home folder, as the shell writes it).
#[must_use]
pub fn has_tilde(path: &std::path::Path) -> bool {
    path.components().any(|c| c.as_os_str() == "~")
}

/// Whether `path`'s file name has spaces around it and a file of the name without them is
/// there.
fn spaced_twin(path: &std::path::Path) -> bool {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return false;
    };
    let trimmed = name.trim();
    trimmed != name && !trimmed.is_empty() && path.with_file_name(trimmed).is_file()
}

/// Whether `file` is a character device other than the null device (read as empty) and a
/// terminal (typed input ends with Ctrl-D): /dev/zero and /dev/urandom were read to the
/// data limit, a gigabyte, before they were refused.
#[cfg(unix)]
fn endless_device(file: &std::fs::File, meta: &std::fs::Metadata) -> bool {
    use std::io::IsTerminal as _;
    use std::os::unix::fs::{FileTypeExt as _, MetadataExt as _};
    let null = std::fs::metadata("/dev/null").map(|m| m.rdev()).ok();
    meta.file_type().is_char_device() && !file.is_terminal() && null != Some(meta.rdev())
}

#[cfg(not(unix))]
fn endless_device(_: &std::fs::File, _: &std::fs::Metadata) -> bool {
    false
}

/// What is said of a file of a kind et does not read where it reads text.
const ANOTHER_KIND: &str = "a file of another kind given?";

/// What a file that is not text is, by the bytes it starts with, and what to do to write it
/// as a table of text, for the files users give in place of a text file most often (a
/// spreadsheet, another format's array, a picture); None for any other.
#[must_use]
pub fn binary_kind(bytes: &[u8]) -> Option<(&'static str, &'static str)> {
    const UNPACK: &str = "decompress it first (gunzip -k, unxz -k, bunzip2 -k or unzstd \
                          FILE): et reads files as written, not packed";
    const KINDS: [(&[u8], usize, &str, &str); 12] = [
        (b"\x1f\x8b", 0, "a gzip-compressed file (.gz)", UNPACK),
        (b"\xFD7zXZ\x00", 0, "an xz-compressed file (.xz)", UNPACK),
        (b"BZh", 0, "a bzip2-compressed file (.bz2)", UNPACK),
        (
            b"\x28\xB5\x2F\xFD",
            0,
            "a zstd-compressed file (.zst)",
            UNPACK,
        ),
        (
            b"PK\x03\x04",
            0,
            "a zip archive (an Excel .xlsx workbook, or a NumPy .npz)",
            "save a sheet as CSV (\"CSV UTF-8\"), an array with numpy.savetxt(f, X, \
             delimiter=',')",
        ),
        (
            b"\xD0\xCF\x11\xE0\xA1\xB1\x1A\xE1",
            0,
            "an Excel 97-2003 workbook (.xls)",
            "save its sheet as CSV (\"CSV UTF-8\")",
        ),
        (
            b"\x89HDF\r\n\x1a\n",
            0,
            "an HDF5 file (h5py, MATLAB's -v7.3)",
            "et reads no HDF5; save the arrays as CSV (frames also as .npy, or a MATLAB -v7 .mat)",
        ),
        (
            b"\x89HDF\r\n\x1a\n",
            512,
            "a MATLAB 7.3 .mat file (HDF5)",
            "write a table with writematrix(X, 'f.csv'); frames are also read from a .mat saved \
             with save(..., '-v7')",
        ),
        (
            b"\x93NUMPY",
            0,
            "a NumPy .npy array",
            "write a table with numpy.savetxt(f, X, delimiter=','); frames are also read from \
             .npy files named .npy",
        ),
        (
            b"MATLAB 5.0 MAT-file",
            0,
            "a MATLAB .mat file",
            "write a table with writematrix(X, 'f.csv'); frames are also read from .mat files \
             named .mat (FILE.mat:VARIABLE)",
        ),
        (b"\x89PNG\r\n\x1a\n", 0, "a PNG picture", ANOTHER_KIND),
        (
            &crate::model::MODEL_MAGIC,
            0,
            "a model blob for the board (et export writes them; et upload takes them)",
            ANOTHER_KIND,
        ),
    ];
    // Python's pickle (protocols 2 to 5: `pickle.dump`, pandas' `to_pickle`): its first
    // opcode PROTO, its last STOP.
    if let [0x80, 2..=5, .., b'.'] = bytes {
        return Some((
            "a Python pickle (pickle.dump, pandas' to_pickle)",
            "et reads no pickles (loading one runs its code): save an array with \
             numpy.save(path, X) (frames), a table with numpy.savetxt(f, X, delimiter=',')",
        ));
    }
    KINDS
        .iter()
        .find(|(magic, at, ..)| bytes.get(*at..).is_some_and(|b| b.starts_with(magic)))
        .map(|(_, _, what, fix)| (*what, *fix))
}

/// What a text file holds, for what is said when another kind of file comes in its place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Holds {
    /// A table (frames, a protocol, a dataset, a mesh's CSV): a spreadsheet's or an array's
    /// file is said with how to write it as text.
    Table,
    /// One of et's documents (a scene, a model): another kind of file is said as what it is
    /// (a scene given as a .npy was told to be written with numpy.savetxt).
    Document,
}

/// [`read_at_most`] as the text of a table (or of frames: a recording), without a leading byte-order mark: UTF-8, or
/// UTF-16 with its byte-order mark (what a spreadsheet's "Unicode text" export writes,
/// tab-separated).
///
/// # Errors
/// As [`read_at_most`], and [`std::io::ErrorKind::InvalidData`] for text that is neither,
/// naming the line and byte (Latin-1's accented letters, most often).
pub fn read_text_at_most(path: &std::path::Path, limit: u64) -> std::io::Result<String> {
    read_holding(path, limit, Holds::Table)
}

/// [`read_text_at_most`] for a document of et's own (a scene, a model).
///
/// # Errors
/// As [`read_text_at_most`].
pub fn read_document_at_most(path: &std::path::Path, limit: u64) -> std::io::Result<String> {
    read_holding(path, limit, Holds::Document)
}

fn read_holding(path: &std::path::Path, limit: u64, holds: Holds) -> std::io::Result<String> {
    text_of(read_at_most(path, limit)?, holds)
}

/// The text of a table's `bytes` already read (a file named for an array format that holds
/// text: read once, as a FIFO can be), as [`read_text_at_most`] reads a file's.
///
/// # Errors
/// As [`read_text_at_most`], but for reading.
pub fn table_text_of(bytes: Vec<u8>) -> std::io::Result<String> {
    text_of(bytes, Holds::Table)
}

fn text_of(bytes: Vec<u8>, holds: Holds) -> std::io::Result<String> {
    let mut text = match utf16(&bytes) {
        Some(text) => text?,
        None => String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            let bytes = e.as_bytes();
            // A file of another kind is said as what it is, not as text in another encoding.
            if let Some((what, fix)) = binary_kind(bytes) {
                let fix = if holds == Holds::Table {
                    fix
                } else {
                    ANOTHER_KIND
                };
                return std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("{what}, not text: {fix}"),
                );
            }
            // Text in another encoding has no control bytes but tab, line ends and form feed:
            // a file with them is binary (a raw dump of numbers), not Latin-1's letters.
            let head = &bytes[..bytes.len().min(1024)];
            if head
                .iter()
                .any(|&b| (b < 0x20 && !b"\t\n\r\x0c".contains(&b)) || b == 0x7f)
            {
                let fix = if holds == Holds::Table {
                    "a table is text (CSV); raw numbers as a program dumps them are read as a \
                     .npy array (numpy.fromfile(path, dtype) then numpy.save)"
                } else {
                    ANOTHER_KIND
                };
                return std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("binary, not text: {fix}"),
                );
            }
            let line = 1 + bytes[..at].iter().filter(|b| **b == b'\n').count();
            let column = at
                - bytes[..at]
                    .iter()
                    .rposition(|b| *b == b'\n')
                    .map_or(0, |i| i + 1);
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "not UTF-8 text (line {line}, byte {} of the line: 0x{:02x}, as Latin-1 or \
                     Windows-1252 write an accented letter): save it as UTF-8 (a \
                     spreadsheet's \"CSV UTF-8\")",
                    column + 1,
                    bytes.get(at).copied().unwrap_or(0)
                ),
            )
        })?,
    };
    // A byte-order mark (Windows editors write one) is not part of the text: every reader
    // of every format accepts it alike.
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_reader_stops_at_its_limit_on_an_endless_stream() {
        // A pipe that never closes is read to the limit, and no further.
        let fifo = std::env::temp_dir().join(format!("et-text-fifo-{}", std::process::id()));
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.is_ok_and(|s| s.success()), "mkfifo");
        let writer = {
            let fifo = fifo.clone();
            std::thread::spawn(move || {
                use std::io::Write as _;
                let mut pipe = std::fs::OpenOptions::new().write(true).open(&fifo).unwrap();
                // Until the reader goes away (a broken pipe).
                while pipe.write_all(&[b'1'; 4096]).is_ok() {}
            })
        };
        let e = super::read_at_most(&fifo, 1 << 16).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::FileTooLarge);
        assert!(e.to_string().contains("more than 65536 bytes"), "{e}");
        writer.join().unwrap();
        std::fs::remove_file(&fifo).unwrap();
        // A character device that never ends is refused by its kind, before a byte is read;
        // the null device reads as empty.
        for endless in ["/dev/zero", "/dev/urandom"] {
            let e = super::read_at_most(std::path::Path::new(endless), 1 << 16).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{endless}: {e}");
            assert!(
                e.to_string()
                    .contains("a character device, which never ends"),
                "{e}"
            );
        }
        let text = super::read_text_at_most(std::path::Path::new("/dev/null"), 10).unwrap();
        assert!(text.is_empty());
        // A regular file is measured before it is read; one at the limit is read whole.
        let path = std::env::temp_dir().join(format!("et-text-{}", std::process::id()));
        std::fs::write(&path, vec![b'a'; 100_000]).unwrap();
        assert_eq!(super::read_at_most(&path, 100_000).unwrap().len(), 100_000);
        let e = super::read_at_most(&path, 99_999).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::FileTooLarge);
        // UTF-16 with its mark (a spreadsheet's "Unicode text") is read as its text, both
        // byte orders; Latin-1 is refused by line and byte, with the fix.
        let text = "a\tb\n1\t2\n";
        for (mark, bytes) in [
            (
                [0xFF, 0xFE],
                text.encode_utf16()
                    .flat_map(u16::to_le_bytes)
                    .collect::<Vec<u8>>(),
            ),
            (
                [0xFE, 0xFF],
                text.encode_utf16().flat_map(u16::to_be_bytes).collect(),
            ),
        ] {
            std::fs::write(&path, [&mark[..], &bytes].concat()).unwrap();
            assert_eq!(super::read_text_at_most(&path, 100).unwrap(), text);
        }
        std::fs::write(&path, b"x,y\ngr\xf6\xdfe,1\n").unwrap();
        let e = super::read_text_at_most(&path, 100)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 2, byte 3 of the line: 0xf6") && e.contains("CSV UTF-8"),
            "{e}"
        );
        // Files of another kind given for text (a spreadsheet, another format's array, a
        // picture) are named as what they are, with the fix (they were said as Latin-1 text).
        let mut hdf5 = b"MATLAB 7.3 MAT-file, Platform: GLNXA64".to_vec();
        hdf5.resize(512, b' ');
        hdf5.extend(b"\x89HDF\r\n\x1a\n\xff");
        for (bytes, said) in [
            (
                &b"PK\x03\x04\x14\x00\x06\x00\x08\x00\xb8"[..],
                "an Excel .xlsx workbook, or a NumPy .npz",
            ),
            (b"\xD0\xCF\x11\xE0\xA1\xB1\x1A\xE1\x00", "Excel 97-2003"),
            (b"\x89HDF\r\n\x1a\n\x00", "an HDF5 file"),
            (&hdf5, "MATLAB 7.3 .mat file"),
            (b"\x93NUMPY\x01\x00v\x00", "numpy.savetxt"),
            (b"MATLAB 5.0 MAT-file \xff\x00", "writematrix"),
            (b"\x89PNG\r\n\x1a\n", "a PNG picture"),
            (b"\x1f\x8b\x08\x00\xff", "a gzip-compressed file"),
            (b"\xFD7zXZ\x00\x00\xff", "an xz-compressed file"),
            // `pickle.dump(np.zeros(2), f)`'s first and last bytes.
            (b"\x80\x04\x95\x9b\x00\xff.", "a Python pickle"),
            (
                b"ETDA\x01\x00\x00\x00\x09\x00\x60\x00\xc0",
                "a model blob for the board",
            ),
        ] {
            std::fs::write(&path, bytes).unwrap();
            let e = super::read_text_at_most(&path, 1000)
                .unwrap_err()
                .to_string();
            assert!(e.contains(said) && !e.contains("Latin-1"), "{e}");
            // A scene or a model is told what the file is, not how to write a
            // table (a scene given as a .npy was told to use numpy.savetxt).
            let e = super::read_document_at_most(&path, 1000)
                .unwrap_err()
                .to_string();
            assert!(
                e.ends_with("not text: a file of another kind given?")
                    && !e.contains("savetxt")
                    && !e.contains("writematrix"),
                "{e}"
            );
        }
        // Raw numbers as a program dumps them (float32, little-endian): binary, not Latin-1.
        let raw: Vec<u8> = [-0.056_f32, 1.5, -2e-3, 0.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        std::fs::write(&path, &raw).unwrap();
        let e = super::read_text_at_most(&path, 1000)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("binary, not text") && e.contains("numpy.save"),
            "{e}"
        );
        let e = super::read_document_at_most(&path, 1000)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "binary, not text: a file of another kind given?");
        // A folder, and a path with nothing at it, said without the system's numbers ("Is a
        // directory (os error 21)").
        let folder = path.parent().unwrap();
        let e = super::read_text_at_most(folder, 100).unwrap_err();
        assert_eq!(e.to_string(), "a folder, not a file: give a file in it");
        let e = super::read_text_at_most(&folder.join("none.csv"), 100).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::NotFound);
        assert_eq!(e.to_string(), "no such file (is the path right?)");
        // `-`, standard input to many tools, is said not to be read as that; `~`, the shell's
        // word, said as the shell's; a name with a space copied after it, said beside the file.
        let e = super::read_text_at_most(std::path::Path::new("-"), 100).unwrap_err();
        assert!(e.to_string().contains("not standard input ('-')"), "{e}");
        let e = super::read_text_at_most(&folder.join("~/none.csv"), 100).unwrap_err();
        assert!(e.to_string().contains("'~' is the shell's word"), "{e}");
        let spaced = folder.join(format!("{} ", path.file_name().unwrap().to_str().unwrap()));
        let e = super::read_text_at_most(&spaced, 100).unwrap_err();
        assert!(
            e.to_string().contains("without the spaces around it"),
            "{e}"
        );
        // Text that starts like one is text.
        std::fs::write(&path, "PK\x03\x04 is text here\n").unwrap();
        assert!(super::read_text_at_most(&path, 100).is_ok());
        // A byte-order mark is dropped, for every format alike.
        std::fs::write(&path, "\u{feff}{\"a\": 1}").unwrap();
        assert_eq!(super::read_text_at_most(&path, 100).unwrap(), "{\"a\": 1}");
        std::fs::remove_file(&path).unwrap();
    }
}
