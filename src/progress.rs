//! How long-running library work reports its progress without printing: the caller passes an
//! observer, the library only counts. The binary draws bars on stderr; tests and benches stay
//! silent.

use std::sync::Arc;

/// Receives the progress of long-running work (called from worker threads).
pub trait Progress: Send + Sync {
    /// A stage of `len` steps begins (`assembly`, `emission`); `len` 0 for a stage whose
    /// steps are not counted (`scene`, `occluders`, `blocks`), shown as running.
    fn start(&self, stage: &str, len: usize);
    /// `steps` more steps of the current stage are done.
    fn advance(&self, steps: usize);
    /// The current stage is over.
    fn finish(&self);
    /// A line of news, such as which run of a study starts.
    fn note(&self, text: &str);
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _: &str, _: usize) {}
    fn advance(&self, _: usize) {}
    fn finish(&self) {}
    fn note(&self, _: &str) {}
}

/// Runs `work` as a stage whose steps are not counted, so that a long preprocessing step shows
/// as running instead of as silence.
pub fn in_stage<T>(progress: &dyn Progress, stage: &str, work: impl FnOnce() -> T) -> T {
    progress.start(stage, 0);
    let result = work();
    progress.finish();
    result
}

/// A shared progress observer, as configurations hold it ([`Silent`] by default).
#[derive(Clone)]
pub struct ProgressSink(pub Arc<dyn Progress>);

impl Default for ProgressSink {
    fn default() -> Self {
        Self(Arc::new(Silent))
    }
}

impl std::fmt::Debug for ProgressSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ProgressSink")
    }
}

impl std::ops::Deref for ProgressSink {
    type Target = dyn Progress;
    fn deref(&self) -> &Self::Target {
        self.0.as_ref()
    }
}
