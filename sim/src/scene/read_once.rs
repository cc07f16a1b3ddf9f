//! A scene's protocol file read once and kept (code moved from scene.rs, not changed).

/// A file's text read once, kept with the scene (clones share it; it takes no part in
/// comparing scenes).
#[derive(Clone, Debug, Default)]
pub struct ReadOnce(std::sync::Arc<std::sync::Mutex<Option<FileText>>>);

/// A file's path and its text (or why it could not be read).
type FileText = (
    std::path::PathBuf,
    Result<String, et_core::schedule::ScheduleError>,
);

impl PartialEq for ReadOnce {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl ReadOnce {
    /// `path`'s text, read the first time (up to the data files' limit) and kept.
    ///
    /// # Errors
    /// [`et_core::schedule::ScheduleError::Read`] when it cannot be read (kept too).
    pub fn text(&self, path: &std::path::Path) -> Result<String, et_core::schedule::ScheduleError> {
        let mut kept = self
            .0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some((p, text)) = kept.as_ref()
            && p == path
        {
            return text.clone();
        }
        let text = et_core::schedule::read_text(path);
        *kept = Some((path.to_path_buf(), text.clone()));
        text
    }
}
