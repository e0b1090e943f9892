//! Progress on stderr: indicatif bars for the library's stages, and its notes as lines.

use std::sync::{Arc, Mutex};

use indicatif::{ProgressBar, ProgressStyle};
use radiosity::progress::{Progress, ProgressSink};

/// A bar per stage of `len` steps, on stderr; a spinner with the time spent for a stage of
/// uncounted steps (`len` 0).
fn bar(stage: &str, len: usize) -> ProgressBar {
    if len == 0 {
        let spinner = ProgressBar::new_spinner();
        spinner.set_style(
            ProgressStyle::with_template("{msg:>10} {spinner} ({elapsed})")
                .expect("valid template"),
        );
        spinner.set_message(stage.to_string());
        spinner.enable_steady_tick(std::time::Duration::from_millis(250));
        return spinner;
    }
    let bar = ProgressBar::new(len as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(stage.to_string());
    bar
}

/// Draws the library's progress on stderr.
#[derive(Default)]
struct Bars(Mutex<Option<ProgressBar>>);

impl Progress for Bars {
    fn start(&self, stage: &str, len: usize) {
        *self.0.lock().expect("progress lock") = Some(bar(stage, len));
    }
    fn advance(&self, steps: usize) {
        if let Some(b) = self.0.lock().expect("progress lock").as_ref() {
            b.inc(steps as u64);
        }
    }
    fn finish(&self) {
        if let Some(b) = self.0.lock().expect("progress lock").take() {
            b.finish_and_clear();
        }
    }
    fn note(&self, text: &str) {
        eprintln!("{text}");
    }
}

/// Progress bars and notes on stderr.
pub(crate) fn on_stderr() -> ProgressSink {
    ProgressSink(Arc::new(Bars::default()))
}
