//! Loading a run from the command line with the loader's progress callback: on a terminal, a
//! `loading NAME: NN %` line redrawn in place for files over 8 MB, erased when done. Nothing is
//! drawn when stderr is not a terminal, so error output stays one line.

use std::io::{IsTerminal as _, Write as _};
use std::ops::ControlFlow;
use std::path::Path;

use super::CliError;
use crate::run::{LoadOptions, LoadProgress, Run, load_with_progress};

/// Loads `path`, showing progress on an interactive stderr.
///
/// # Errors
/// [`CliError::Input`] with the loader's one-line message.
pub fn load_run(path: &Path) -> Result<Run, CliError> {
    let interactive = std::io::stderr().is_terminal();
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut last = u64::MAX;
    let mut drawn = false;
    let mut show = |p: LoadProgress| {
        if interactive && p.bytes_total > 8 << 20 {
            let pct = p.bytes_done * 100 / p.bytes_total.max(1);
            if pct != last {
                last = pct;
                drawn = true;
                eprint!("\rloading {name}: {pct:3} %");
                let _ = std::io::stderr().flush();
            }
        }
        ControlFlow::Continue(())
    };
    let result = load_with_progress(path, &LoadOptions::default(), &mut show);
    if drawn {
        eprint!("\r\x1b[2K");
    }
    result.map_err(|e| CliError::Input(e.to_string()))
}
