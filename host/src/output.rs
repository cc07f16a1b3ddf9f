//! Where et writes: never onto a command's own input, never over an existing file unless the
//! user said so (`--force`), and a file appears only when it is complete: it is written under a
//! temporary name beside its target and renamed over it at the end, so a crash or Ctrl-C leaves
//! the old file or none, never half of one.

use std::path::{Path, PathBuf};

mod error;
pub use error::*;

/// Outputs that are streams, written straight through (no temporary name, no rename): the
/// null device and the process's own standard output and error.
const STREAMS: [&str; 7] = [
    "/dev/null",
    "/dev/stdout",
    "/dev/stderr",
    "/dev/fd/1",
    "/dev/fd/2",
    "/proc/self/fd/1",
    "/proc/self/fd/2",
];

/// Whether standard output was closed when et started ([`note_standard_streams`]).
static STDOUT_CLOSED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Notes whether the caller may have closed standard output (`et eval --json >&-`): then a
/// result printed there ([`stdout_closed`]) or written to `/dev/stdout` is said to be dropped.
/// Rust opens the null device in place of a closed standard stream before `main`, so writes
/// vanished without a word; that null device is told from one a shell gave (`> /dev/null`,
/// which asks for the result to be dropped) by its being open for reading and writing (Linux,
/// from `/proc`; elsewhere nothing is noted). Python's `subprocess.DEVNULL` opens it so too,
/// which is why this is a note and not a failure. Call once, first in `main`.
pub fn note_standard_streams() {
    let null = std::fs::read_link("/proc/self/fd/1").is_ok_and(|p| p == Path::new("/dev/null"));
    let read_write = || {
        let info = std::fs::read_to_string("/proc/self/fdinfo/1").unwrap_or_default();
        info.lines()
            .find_map(|l| l.strip_prefix("flags:"))
            .and_then(|f| u32::from_str_radix(f.trim(), 8).ok())
            .is_some_and(|flags| flags & 0o3 == 0o2)
    };
    if null && read_write() {
        STDOUT_CLOSED.store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

/// Whether standard output was closed when et started (or is the null device opened for
/// reading and writing): a command's result has nowhere to go.
#[must_use]
pub fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(std::sync::atomic::Ordering::Relaxed)
}

/// Whether `out` names the process's standard output.
#[must_use]
pub fn is_stdout(out: &Path) -> bool {
    ["/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"]
        .iter()
        .any(|s| out == Path::new(s))
}

/// Whether `out` is one of [`STREAMS`].
#[must_use]
pub fn is_stream(out: &Path) -> bool {
    STREAMS.iter().any(|s| out == Path::new(s))
}

/// `p` spelled canonically, whether or not it exists yet: its longest existing ancestor
/// resolved (`.`, `..`, symlinks), then the rest of its components with `.` dropped and `..`
/// taken lexically.
fn canonical(p: &Path) -> Option<PathBuf> {
    use std::path::Component;
    let absolute = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().ok()?.join(p)
    };
    let mut base = absolute.as_path();
    let mut rest: Vec<Component<'_>> = Vec::new();
    let mut resolved = loop {
        if let Ok(c) = base.canonicalize() {
            break c;
        }
        let (Some(parent), Some(last)) = (base.parent(), base.components().next_back()) else {
            return None;
        };
        rest.push(last);
        base = parent;
    };
    for c in rest.into_iter().rev() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                resolved.pop();
            }
            other => resolved.push(other),
        }
    }
    Some(resolved)
}

/// Whether `a` and `b` name the same file, however spelled (`./a`, a symlink, ...), existing
/// or not.
fn same_file(a: &Path, b: &Path) -> bool {
    match (canonical(a), canonical(b)) {
        // Writing to the null device harms no input, the null device read as one too
        // (`--frames /dev/null --out /dev/null` was refused as overwriting its input).
        (Some(a), Some(b)) => a == b && a != Path::new("/dev/null"),
        _ => false,
    }
}

/// What is at an output's path now.
enum Occupant {
    Nothing,
    File,
    EmptyFolder,
    Folder,
    Stream,
    Other(&'static str),
}

fn occupant(out: &Path) -> Occupant {
    if is_stream(out) {
        return Occupant::Stream;
    }
    let Ok(m) = std::fs::symlink_metadata(out) else {
        return Occupant::Nothing;
    };
    let t = m.file_type();
    if t.is_symlink() {
        Occupant::Other("a symbolic link")
    } else if t.is_file() {
        Occupant::File
    } else if t.is_dir() {
        if std::fs::read_dir(out).map_or(true, |mut d| d.next().is_some()) {
            Occupant::Folder
        } else {
            Occupant::EmptyFolder
        }
    } else {
        use std::os::unix::fs::FileTypeExt as _;
        Occupant::Other(if t.is_fifo() {
            "a FIFO"
        } else if t.is_socket() {
            "a socket"
        } else if t.is_block_device() || t.is_char_device() {
            "a device"
        } else {
            "not a file"
        })
    }
}

/// Whether the command checked a file (or folder) to write, not a stream ([`check`]).
static FILES_TO_WRITE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether the command has checked a file or folder to write ([`check`], [`check_folder`],
/// [`check_all`]), not only streams: standard output's reader going away (`| head`) does not
/// end such a command before its files are written.
#[must_use]
pub fn files_to_write() -> bool {
    FILES_TO_WRITE.load(std::sync::atomic::Ordering::Relaxed)
}

/// Checks the file `out` before a command writes it: not one of `inputs` (even with
/// `force`); a regular file only with `force`; never a folder, symbolic link, FIFO, socket or
/// device (except the null device and standard output or error, written through); and its
/// folder must exist.
///
/// # Errors
/// [`OutputError::Input`], [`OutputError::Exists`], [`OutputError::NotAFile`] or
/// [`OutputError::NoFolder`].
pub fn check(out: &Path, inputs: &[&Path], force: bool) -> Result<(), OutputError> {
    check_at(out, inputs, force, false)
}

/// Checks that `out`'s extension names a format `what` is written in (one of `extensions`,
/// any case): a PNG named `r.jpg`, a model named `m.png` or a recording named `x.png` was
/// written without a word, a file whose name says what it is not. A name without an
/// extension, and a stream, are taken.
///
/// # Errors
/// [`OutputError::Format`] naming the extensions.
pub fn check_format(
    out: &Path,
    what: &'static str,
    extensions: &'static [&'static str],
) -> Result<(), OutputError> {
    match out.extension().and_then(|e| e.to_str()) {
        Some(e) if !is_stream(out) && !extensions.iter().any(|x| e.eq_ignore_ascii_case(x)) => {
            Err(OutputError::Format {
                out: out.into(),
                what,
                extensions,
            })
        }
        _ => Ok(()),
    }
}

/// [`check`] for a report folder `out` (`et demo --out`): an empty folder is taken, one
/// with files only with `force`, a file never.
///
/// # Errors
/// As [`check`], and [`OutputError::NotAFolder`].
pub fn check_folder(out: &Path, force: bool) -> Result<(), OutputError> {
    check_at(out, &[], force, true)
}

fn check_at(
    out: &Path,
    inputs: &[&Path],
    force: bool,
    folder_out: bool,
) -> Result<(), OutputError> {
    if out == Path::new("-") {
        return Err(OutputError::Dash);
    }
    // `m.json/` is written aside as `m.json`'s partial file, and the rename to a folder's
    // name failed after the work (et sim said the file "appeared while et was writing it").
    let text = out.as_os_str().as_encoded_bytes();
    if !folder_out && text.len() > 1 && text.last() == Some(&b'/') {
        let file = PathBuf::from(out.to_string_lossy().trim_end_matches('/'));
        return Err(OutputError::FolderSpelling {
            out: out.into(),
            file,
        });
    }
    let bytes = out.file_name().map_or(0, |n| n.as_encoded_bytes().len());
    if bytes > NAME_MAX {
        return Err(OutputError::NameTooLong {
            out: out.into(),
            bytes,
        });
    }
    if let Some(input) = inputs.iter().find(|i| same_file(out, i)) {
        return Err(OutputError::Input {
            out: out.into(),
            input: input.to_path_buf(),
        });
    }
    match occupant(out) {
        Occupant::Nothing => new_at_check(out),
        Occupant::Stream if !folder_out => return Ok(()),
        Occupant::Stream => {
            let what = "a device";
            return Err(OutputError::NotAFile {
                out: out.into(),
                what,
            });
        }
        Occupant::File if folder_out => return Err(OutputError::NotAFolder { out: out.into() }),
        Occupant::EmptyFolder | Occupant::Folder if !folder_out => {
            // A file's output is never a folder, even with --force (its files are not et's).
            let what = "a folder";
            return Err(OutputError::NotAFile {
                out: out.into(),
                what,
            });
        }
        Occupant::EmptyFolder => {}
        Occupant::Other(what) => {
            return Err(OutputError::NotAFile {
                out: out.into(),
                what,
            });
        }
        Occupant::File | Occupant::Folder if !force => {
            return Err(OutputError::Exists { out: out.into() });
        }
        Occupant::File | Occupant::Folder => {}
    }
    let folder = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(OutputError::NoFolder {
            out: out.into(),
            folder: folder.into(),
        });
    }
    // The file it will be written as (or the report folder) made and removed now: a folder
    // that takes no new file is said before the work (a training of minutes), not when its
    // result is lost.
    let (made, kind, folder) = if folder_out && out.is_dir() {
        // A report folder that is there (empty, or replaced with --force): its files are
        // written inside it.
        let probe = out.join(format!(".et-probe-{}", std::process::id()));
        let made = std::fs::File::create_new(&probe).and_then(|_| std::fs::remove_file(&probe));
        (made, "file", out)
    } else if folder_out {
        let made = std::fs::create_dir(out).and_then(|()| std::fs::remove_dir(out));
        (made, "folder", folder)
    } else {
        let partial = partial_path(out);
        let made = std::fs::File::create_new(&partial).and_then(|_| std::fs::remove_file(&partial));
        (made, "file", folder)
    };
    made.map_err(|source| OutputError::Unwritable {
        out: out.into(),
        kind,
        folder: folder.into(),
        source,
    })?;
    FILES_TO_WRITE.store(true, std::sync::atomic::Ordering::Relaxed);
    Ok(())
}

/// [`check`] for every output of one command at once, before any work: each against every
/// input, and no two outputs at the same file. `folders` are folders the command creates
/// (a folder of plots): an output inside one needs no existing folder.
///
/// # Errors
/// As [`check`], and [`OutputError::Collision`].
pub fn check_all(
    outputs: &[&Path],
    folders: &[&Path],
    inputs: &[&Path],
    force: bool,
) -> Result<(), OutputError> {
    for folder in folders {
        if let Some(input) = inputs.iter().find(|i| same_file(folder, i)) {
            return Err(OutputError::Input {
                out: folder.to_path_buf(),
                input: input.to_path_buf(),
            });
        }
        // A file where the folder goes failed only after the work ("File exists (os error 17)").
        if std::fs::metadata(folder).is_ok_and(|m| !m.is_dir()) {
            return Err(OutputError::NotAFolder {
                out: folder.to_path_buf(),
            });
        }
    }
    for (i, out) in outputs.iter().enumerate() {
        let made = out
            .parent()
            .is_some_and(|d| folders.iter().any(|f| f == &d || same_file(f, d)));
        match check(out, inputs, force) {
            Err(OutputError::NoFolder { .. }) if made => {}
            other => other?,
        }
        if let Some(other) = outputs
            .get(..i)
            .unwrap_or_default()
            .iter()
            .find(|o| !is_stream(out) && same_file(out, o))
        {
            return Err(OutputError::Collision {
                out: other.to_path_buf(),
                other: out.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// File names longer than this many bytes are refused by most file systems.
pub const NAME_MAX: usize = 255;

/// The temporary name `out` is written under: hidden, beside it (so the rename stays on one
/// file system), with the same extension (writers that pick a format by it still do), the
/// stem shortened when the whole would pass the file system's 255 bytes.
#[must_use]
pub fn partial_path(out: &Path) -> PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let tail = match out.extension() {
        Some(ext) => format!(".partial-{}.{}", std::process::id(), ext.to_string_lossy()),
        None => format!(".partial-{}", std::process::id()),
    };
    let budget = NAME_MAX.saturating_sub(tail.len() + 1);
    let mut short = String::new();
    for c in stem.chars() {
        if short.len() + c.len_utf8() > budget {
            break;
        }
        short.push(c);
    }
    out.with_file_name(format!(".{short}{tail}"))
}

/// Outputs that did not exist when [`check`] looked: a file that appears there before et
/// writes it is another writer's, never replaced (only an output that existed then was
/// sanctioned by `--force`).
static NEW_AT_CHECK: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn new_at_check(out: &Path) {
    let mut list = NEW_AT_CHECK
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    list.push(out.into());
}

fn was_new_at_check(out: &Path) -> bool {
    NEW_AT_CHECK
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .iter()
        .any(|p| p == out)
}

/// The partial files being written now, removed if et is stopped by Ctrl-C or SIGTERM.
static PARTIALS: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Removes every partial output being written when the process gets a signal whose default
/// ends it (SIGINT from Ctrl-C, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGXCPU,
/// SIGXFSZ, SIGVTALRM, SIGPROF), then exits with 128 + the signal. SIGKILL cannot be caught;
/// SIGPIPE is left as Rust sets it (ignored: a closed pipe is a write error, said as one).
/// Call once, early in `main`.
///
/// # Errors
/// When the handler cannot be installed.
pub fn clean_up_on_signals() -> std::io::Result<()> {
    use signal_hook::consts::{
        SIGALRM, SIGHUP, SIGINT, SIGPROF, SIGQUIT, SIGTERM, SIGUSR1, SIGUSR2, SIGVTALRM, SIGXCPU,
        SIGXFSZ,
    };
    let mut signals = signal_hook::iterator::Signals::new([
        SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGXCPU, SIGXFSZ, SIGVTALRM,
        SIGPROF,
    ])?;
    std::thread::Builder::new()
        .name("et-signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                let partials = PARTIALS
                    .lock()
                    .map_or_else(|e| e.into_inner().clone(), |p| p.clone());
                for p in partials {
                    // (A report folder's partial is a folder: `write_folder`.)
                    let _ = std::fs::remove_file(&p).or_else(|_| std::fs::remove_dir_all(&p));
                }
                std::process::exit(128 + signal);
            }
        })?;
    Ok(())
}

fn track(partial: &Path, on: bool) {
    let mut list = PARTIALS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if on {
        list.push(partial.into());
    } else {
        list.retain(|p| p != partial);
    }
}

/// Writes `out` with `save` (which writes the path it is given) under [`partial_path`], then
/// moves it to `out`: over an existing file (which [`check`] allowed: `--force`), or as a new
/// name created exclusively, so that two runs writing the same new file cannot both succeed.
/// The partial file is removed when `save` fails (and on Ctrl-C, see
/// [`clean_up_on_signals`]). A stream ([`is_stream`]) is written straight through.
///
/// # Errors
/// `save`'s error, or an [`OutputError`] converted into it.
pub fn write<T, E: From<OutputError>>(
    out: &Path,
    save: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    if is_stream(out) {
        return save(out);
    }
    // Whether the output is new (when the command checked it, or now): then it is created
    // exclusively at the end, and one that appeared meanwhile is left as it is.
    let new = was_new_at_check(out) || std::fs::symlink_metadata(out).is_err();
    let partial = partial_path(out);
    track(&partial, true);
    let result = save(&partial).and_then(|value| {
        settle(&partial, out, new)?;
        Ok(value)
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    track(&partial, false);
    result
}

/// Makes the folder `out` (`et demo`'s report, a `--plots` folder) with `make`, which writes
/// into the folder it is given: a new folder, or an empty one, is made under
/// [`partial_path`] and renamed to `out` at the end, so a run stopped part way (a stage's
/// error, Ctrl-C) leaves no half of one, which the next run refused without `--force`; a
/// folder with files (replaced with `--force`, as [`check_folder`] allowed) is written in
/// place, its other files left alone.
///
/// # Errors
/// `make`'s error, or an [`OutputError`] converted into it: [`OutputError::Raced`] when a
/// folder with files appeared at `out` meanwhile.
pub fn write_folder<T, E: From<OutputError>>(
    out: &Path,
    make: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    if std::fs::read_dir(out).is_ok_and(|mut entries| entries.next().is_some()) {
        return make(out);
    }
    let partial = partial_path(out);
    track(&partial, true);
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OutputError::Io { path, source }
    };
    let result = (std::fs::create_dir(&partial).map_err(io(&partial)))
        .map_err(E::from)
        .and_then(|()| make(&partial))
        .and_then(|value| {
            // (Over an empty folder, or none; one that got files meanwhile is another's.)
            std::fs::rename(&partial, out).map_err(|e| {
                if std::fs::read_dir(out).is_ok_and(|mut entries| entries.next().is_some()) {
                    OutputError::Raced { out: out.into() }
                } else {
                    io(out)(e)
                }
            })?;
            Ok(value)
        });
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&partial);
    }
    track(&partial, false);
    result
}

/// Moves the finished `partial` to `out`: over it, or as a `new` file created exclusively.
fn settle(partial: &Path, out: &Path, new: bool) -> Result<(), OutputError> {
    let io = |source| OutputError::Io {
        path: out.into(),
        source,
    };
    if !new {
        return std::fs::rename(partial, out).map_err(io);
    }
    match std::fs::hard_link(partial, out) {
        Ok(()) => {
            let _ = std::fs::remove_file(partial);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            Err(OutputError::Raced { out: out.into() })
        }
        // A file system without hard links: the plain rename.
        Err(_) => std::fs::rename(partial, out).map_err(io),
    }
}
