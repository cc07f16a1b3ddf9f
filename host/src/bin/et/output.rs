//! The output policy of `et_host::output` with anyhow errors, for every command that writes.

use std::path::Path;

pub(crate) use et_host::output::{check, check_all, check_format};

/// Writes `out` by `save` aside and renames it when complete (`et_host::output::write`).
pub(crate) fn write<T, E: Into<anyhow::Error>>(
    out: &Path,
    save: impl FnOnce(&Path) -> Result<T, E>,
) -> anyhow::Result<T> {
    use anyhow::Context as _;
    if et_host::output::is_stdout(out) {
        crate::note_stdout_closed();
    }
    // The error names the user's path first (the temporary file's name only after it).
    et_host::output::write(out, |partial| save(partial).map_err(Into::into))
        .with_context(|| format!("writing {}", out.display()))
}
