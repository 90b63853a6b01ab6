//! Progress bars on the command line (indicatif), drawn only when stderr is a terminal, so that
//! error output stays one line when it is not. Bars are cleared when their work ends.
//!
//! Shown for work that may take over half a second: loading a run over 8 MB, simulating and
//! writing a run, identify's stages, the bench's stages.

use std::io::IsTerminal as _;
use std::ops::ControlFlow;
use std::path::Path;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

use super::CliError;
use crate::run::{LoadOptions, LoadProgress, Run, load_with_progress};

/// Files at least this large get a loading bar, bytes.
const LOAD_BAR_MIN_BYTES: u64 = 8 << 20;

/// A bar of `len` steps with `template` (indicatif's syntax), hidden unless stderr is a terminal.
pub fn bar(len: u64, template: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar());
    ProgressBar::new(len).with_style(style)
}

/// A spinner showing `message` until cleared, hidden unless stderr is a terminal.
pub fn spinner(message: &str) -> ProgressBar {
    let spinner = bar(0, "{spinner} {msg} {elapsed}");
    spinner.set_message(message.to_owned());
    spinner.enable_steady_tick(Duration::from_millis(100));
    spinner
}

/// The name of `path` as shown on a bar.
pub fn display_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// Loads `path`, with a bar of bytes read on an interactive stderr for files over 8 MB.
///
/// # Errors
/// [`CliError::Input`] with the loader's one-line message.
pub fn load_run(path: &Path) -> Result<Run, CliError> {
    let size = std::fs::metadata(path).map_or(0, |m| m.len());
    let progress = if size >= LOAD_BAR_MIN_BYTES {
        bar(size, "loading {msg} {wide_bar} {bytes}/{total_bytes} {eta}")
    } else {
        ProgressBar::hidden()
    };
    progress.set_message(display_name(path));
    let mut show = |p: LoadProgress| {
        progress.set_position(p.bytes_done);
        ControlFlow::Continue(())
    };
    let result = load_with_progress(path, &LoadOptions::default(), &mut show);
    progress.finish_and_clear();
    result.map_err(|e| CliError::Input(e.to_string()))
}

/// The loader's notices for `path` as stderr lines (`imu-attest: note: run.csv: no sidecar
/// run.json: ...`): contract section 2 has the program say when it assumed a missing sidecar's
/// defaults or ignores a column. Printed when the command succeeds, after its output is written;
/// on a refusal they join its one line instead ([`with_notes`]).
#[must_use]
pub fn note_lines(path: &Path, notices: &[String]) -> Vec<String> {
    notices
        .iter()
        .map(|notice| format!("imu-attest: note: {}: {notice}", display_name(path)))
        .collect()
}

/// A refusal's one line with the run's notices after it, so that a refusal a notice explains
/// (no sidecar: the lever arms taken as zero, the accelerometer's vertical input then flat)
/// says so on the same line.
#[must_use]
pub fn with_notes(message: String, notices: &[String]) -> String {
    if notices.is_empty() {
        message
    } else {
        format!("{message} (note: {})", notices.join("; "))
    }
}
