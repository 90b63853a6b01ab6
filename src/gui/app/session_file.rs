//! Sessions: a day's work saved and reopened (File > Save session / Open session). A session
//! file (`imu-attest/session/1`, JSON) holds the runs by path with the SHA-256 they had, each
//! run's accepted and rejected effects, the identifier settings, the view, the selected run and
//! the compared ones. Reopening loads the runs again (they are not copied into the session) and
//! says so in the error panel when a file is missing or its bytes changed since the session was
//! saved; a run already open is not opened twice.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{App, Command, ErrorTopic, ViewState};
use crate::block::Block;
use crate::effect::Effect;
use crate::ident::settings::{Settings, json_problem};

/// The session file's schema.
pub const SESSION_SCHEMA: &str = "imu-attest/session/1";

/// How many recently opened runs File > Open recent lists.
pub const RECENT_RUNS: usize = 8;

/// One run of a session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SessionRun {
    /// The run file, as opened.
    pub path: PathBuf,
    /// Its SHA-256 when the session was saved.
    pub sha256: String,
    /// Effects accepted into its model (block, effect).
    #[serde(default)]
    pub accepted: Vec<(Block, Effect)>,
    /// Effects rejected (never offered again).
    #[serde(default)]
    pub rejected: Vec<(Block, Effect)>,
}

/// A session file.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SessionFile {
    /// [`SESSION_SCHEMA`].
    pub schema: String,
    /// The identifier settings.
    pub settings: Settings,
    /// The view (tab, blocks shown, plot choices).
    pub view: ViewState,
    /// The loaded runs, in the run list's order.
    pub runs: Vec<SessionRun>,
    /// Index of the selected run.
    pub selected: Option<usize>,
    /// Indices of the compared runs.
    #[serde(default)]
    pub compared: Vec<usize>,
}

/// Why a session file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// Reading the file failed.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// Not JSON of the session schema.
    #[error("{path}: line {line}, column {column}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// Another schema.
    #[error("{path}: schema \"{found}\" is not {SESSION_SCHEMA}")]
    Schema {
        /// The file.
        path: String,
        /// The schema found.
        found: String,
    },
}

/// Reads a session file.
///
/// # Errors
/// [`SessionError`] with the file, and the line and column of a parse error.
pub fn read_session(path: &Path) -> Result<SessionFile, SessionError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| SessionError::Io {
        path: name.clone(),
        source,
    })?;
    // As the settings and effects files: the JSON path of the problem in the message.
    let parse_error = |path: String, inner: &serde_json::Error| {
        let (line, column, message) = json_problem(&path, inner);
        SessionError::Parse {
            path: name.clone(),
            line,
            column,
            message,
        }
    };
    let mut de = serde_json::Deserializer::from_str(&text);
    let file: SessionFile = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| parse_error(e.path().to_string(), e.inner()))?;
    de.end().map_err(|e| parse_error(".".into(), &e))?;
    if file.schema != SESSION_SCHEMA {
        return Err(SessionError::Schema {
            path: name,
            found: file.schema,
        });
    }
    Ok(file)
}

impl App {
    /// The session file of the app as it is: loaded runs only.
    #[must_use]
    pub fn session_file(&self) -> SessionFile {
        let loaded: Vec<_> = self.runs.iter().filter(|r| r.loaded()).collect();
        let index = |id| loaded.iter().position(|r| r.id == id);
        SessionFile {
            schema: SESSION_SCHEMA.to_owned(),
            settings: self.prefs.settings.clone(),
            view: self.prefs.view.clone(),
            runs: loaded
                .iter()
                .filter_map(|r| {
                    let s = r.summary()?;
                    Some(SessionRun {
                        path: s.path.clone(),
                        sha256: s.sha256.clone(),
                        accepted: r.accepted.clone(),
                        rejected: r.rejected.clone(),
                    })
                })
                .collect(),
            selected: self.selected.and_then(index),
            compared: self.compared.iter().filter_map(|&id| index(id)).collect(),
        }
    }

    /// Writes the session to `path` (atomically; never over one of the runs).
    pub(super) fn save_session(&mut self, path: &Path) {
        let inputs: Vec<PathBuf> = self.runs.iter().map(|r| r.path.clone()).collect();
        let file = self.session_file();
        let written = crate::output::ensure_not_input(path, &inputs).and_then(|()| {
            crate::output::write_atomic(path, |w| {
                serde_json::to_writer_pretty(&mut *w, &file).map_err(std::io::Error::other)
            })
        });
        match written {
            Ok(()) => self.status = Some(format!("session written to {}", path.display())),
            Err(e) => self.errors.push(ErrorTopic::Export, format!("save session: {e}")),
        }
    }

    /// Reopens the session at `path`: its settings and view, its runs (those not already open
    /// are loaded) with their accepted and rejected effects, the selection and the comparison.
    pub(super) fn open_session(&mut self, path: &Path) {
        let file = match read_session(path) {
            Ok(f) => f,
            Err(e) => {
                self.errors.push(ErrorTopic::Load, format!("open session: {e}"));
                return;
            }
        };
        self.prefs.view = file.view;
        let mut ids = Vec::with_capacity(file.runs.len());
        for run in &file.runs {
            let id = match self.runs.iter().find(|r| r.path == run.path) {
                Some(open) => open.id,
                None => self.open(run.path.clone()),
            };
            if let Some(entry) = self.run_mut(id) {
                entry.accepted.clone_from(&run.accepted);
                entry.rejected.clone_from(&run.rejected);
                entry.expected_sha256 = Some(run.sha256.clone());
            }
            ids.push(id);
        }
        if let Some(&id) = file.selected.and_then(|i| ids.get(i)) {
            self.selected = Some(id);
        }
        self.compared = file
            .compared
            .iter()
            .filter_map(|&i| ids.get(i).copied())
            .collect();
        self.apply(Command::SetSettings(Box::new(file.settings)));
    }

    /// Puts `path` first in the recently opened runs.
    pub(super) fn remember_recent(&mut self, path: &Path) {
        let recent = &mut self.prefs.recent;
        recent.retain(|p| p != path);
        recent.insert(0, path.to_path_buf());
        recent.truncate(RECENT_RUNS);
    }
}
