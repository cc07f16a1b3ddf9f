//! Why an output was refused or could not be written.

use std::path::PathBuf;

use super::NAME_MAX;

/// Why an output was refused or could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The output is one of the command's inputs.
    #[error("{}: this is the input {}; refusing to overwrite it (write elsewhere)", .out.display(), .input.display())]
    Input {
        /// The output path as given.
        out: PathBuf,
        /// The input it names.
        input: PathBuf,
    },
    /// Two outputs of one command name the same file.
    #[error("{} and {} are the same file: give each output its own path", .out.display(), .other.display())]
    Collision {
        /// One output.
        out: PathBuf,
        /// The other.
        other: PathBuf,
    },
    /// The output's file name is longer than a file system takes: said before the work, which
    /// was lost at its end ("File name too long" when the finished file was given its name).
    #[error(
        "{}: its file name is {bytes} bytes, past the {NAME_MAX} a file name takes: give a \
         shorter name",
        .out.display()
    )]
    NameTooLong {
        /// The output.
        out: PathBuf,
        /// Its file name's length in bytes.
        bytes: usize,
    },
    /// The output exists and replacing was not asked for.
    #[error("{} already exists; refusing to overwrite it (--force replaces it)", .out.display())]
    Exists {
        /// The output.
        out: PathBuf,
    },
    /// A file's output whose path ends with a separator, a folder's name by its spelling.
    #[error(
        "{}: a path ending in '/' names a folder; give the file's path ({})",
        .out.display(), .file.display()
    )]
    FolderSpelling {
        /// The output as given.
        out: PathBuf,
        /// The path without its trailing separators.
        file: PathBuf,
    },
    /// The output is something et does not replace, even with --force.
    #[error("{} is {what}, not a regular file; et replaces only regular files (write to a file, or remove it first)", .out.display())]
    NotAFile {
        /// The output.
        out: PathBuf,
        /// What it is: "a symbolic link", "a FIFO", "a device", ...
        what: &'static str,
    },
    /// An output whose extension names a format other than the one written in it.
    #[error(
        "{}: {what} is written as {}: name the file so (or with no extension)",
        .out.display(),
        .extensions.iter().map(|e| format!(".{e}")).collect::<Vec<_>>().join(", ")
    )]
    Format {
        /// The output.
        out: PathBuf,
        /// What is written there ("the image (PNG)").
        what: &'static str,
        /// The extensions of the formats it can be written in.
        extensions: &'static [&'static str],
    },
    /// A report folder's path holds a file.
    #[error("{} is a file; the report is a folder of files (give another path, or remove it first)", .out.display())]
    NotAFolder {
        /// The output.
        out: PathBuf,
    },
    /// The folder the output goes into does not exist or is not a folder.
    #[error(
        "{}: the folder {} does not exist ({})",
        .out.display(),
        .folder.display(),
        if et_core::text::has_tilde(folder) {
            et_core::text::TILDE_SAID
        } else {
            "create it first"
        }
    )]
    NoFolder {
        /// The output.
        out: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// `-`, which many tools take as standard output, and et would write as a file named `-`.
    #[error(
        "'-' as an output would be a file named '-', not standard output: give /dev/stdout for \
         standard output, or ./- for a file of that name"
    )]
    Dash,
    /// The output's folder takes no new file (read-only, not permitted, a virtual file system
    /// such as /proc): found before the work, not after it.
    #[error(
        "{}: et cannot create a {kind} in {} ({source}); give another folder",
        .out.display(), .folder.display()
    )]
    Unwritable {
        /// The output.
        out: PathBuf,
        /// "file", or "folder" for a report folder.
        kind: &'static str,
        /// Its folder.
        folder: PathBuf,
        /// Why a file could not be created there.
        source: std::io::Error,
    },
    /// Another writer created the output while et was writing it.
    #[error("{} appeared while et was writing it (another run writing the same file?); left it as it is, and et's result is not saved (run again, or --force to replace it)", .out.display())]
    Raced {
        /// The output.
        out: PathBuf,
    },
    /// Writing or renaming failed.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
}
