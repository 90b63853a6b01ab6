//! The application: persisted preferences, the runs shown, the worker, and the command queue.
//!
//! `logic` (in `logic.rs`) applies the commands the widgets pushed during the previous `ui`
//! pass and drains the worker's events; `ui` (in `ui.rs`) only draws. Presentation-only state
//! (tab, overlay toggle, heatmap mode) lives in [`ViewState`] and is edited by the widgets
//! directly; everything that reaches the pipeline goes through a [`Command`].

mod ask;
mod commands;
pub mod dialog;
mod entry;
mod errors;
mod export;
mod logic;
pub mod prompt;
mod record;
pub mod session_file;
mod ui;

use std::path::PathBuf;
use std::sync::Arc;

use eframe::egui;
use serde::{Deserialize, Serialize};

pub use commands::Command;
pub use dialog::{DialogRequest, FilePicker};
pub use prompt::PathPurpose;

use crate::block::Block;
use crate::compare::Comparison;
use crate::gui::pipeline::{RunId, Worker, WorkerMode};
use crate::ident::settings::Settings;
use crate::run::LoadOptions;
use crate::spectral::DEFAULT_SEGMENT_LEN;
pub use entry::{LoadedRun, Reading, RunEntry};
pub use errors::{ErrorEntry, ErrorLog, ErrorTopic};
pub use record::StageRecord;

/// Storage key of [`Prefs`] (JSON, in eframe's storage: `~/.local/share/imu-attest/app.ron` on
/// Linux).
const PREFS_KEY: &str = "imu-attest/prefs";

/// How to start the app.
#[derive(Clone, Debug)]
pub struct AppOptions {
    /// Runs to open.
    pub paths: Vec<PathBuf>,
    /// Threaded worker, or synchronous for tests.
    pub mode: WorkerMode,
    /// Read and write preferences in eframe's storage.
    pub persist: bool,
    /// How runs are loaded (memory limit, chunk size).
    pub load: LoadOptions,
    /// How files are picked: the system's dialog, on its own thread.
    pub file_picker: FilePicker,
}

impl AppOptions {
    /// The app's options: threaded worker, persisted preferences, default loading.
    #[must_use]
    pub fn new(paths: Vec<PathBuf>) -> Self {
        Self {
            paths,
            mode: WorkerMode::Thread,
            persist: true,
            load: LoadOptions::default(),
            file_picker: FilePicker::system(),
        }
    }
}

/// The central panel's tab.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Tab {
    /// Measured angles, block inputs and outputs over time.
    #[default]
    TimeSeries,
    /// PSDs and cross-spectral heatmaps.
    Spectra,
    /// `W_u` Bode grid, coherence, disturbance PSD.
    Bode,
    /// The missing-effect workflow.
    Diagnosis,
    /// Several runs side by side.
    Compare,
    /// A model's predicted outputs over the measured ones.
    Validation,
}

/// What the heatmaps show.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum HeatmapMode {
    /// `10 log10 |S_ij|`.
    #[default]
    Magnitude,
    /// `|S_ij|^2 / (S_ii S_jj)`.
    Coherence,
}

/// Presentation state, persisted.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default)]
pub struct ViewState {
    /// Central tab.
    pub tab: Tab,
    /// Overlay the plain-differentiation inputs on the observer's.
    pub show_differentiated: bool,
    /// Block whose spectra are shown.
    pub spectra_block: Block,
    /// Heatmap quantity.
    pub heatmap_mode: HeatmapMode,
    /// Frequency of the CSD-matrix heatmap, Hz.
    pub heatmap_frequency_hz: f64,
    /// Block shown on the Bode and Compare tabs.
    pub bode_block: Block,
    /// A stretch being selected by shift+drag in the Time series: `[start, now]`, s (not
    /// persisted).
    #[serde(skip)]
    pub span_drag: Option<[f64; 2]>,
    /// The Validation tab's model: this run's (`None`) or another loaded run's (not persisted).
    #[serde(skip)]
    pub validation_model: Option<RunId>,
    /// Bode grids show the deviation from K (ppm, mrad) instead of the magnitude in dB.
    pub bode_deviation: bool,
    /// The Bode read-out of the element and frequency under the pointer (last frame's).
    #[serde(skip)]
    pub bode_readout: Option<String>,
    /// The Time series' reference cursor A, s (right-click; the read-out gives differences to it).
    #[serde(skip)]
    pub reference_t: Option<f64>,
    /// What the Time series' first plot shows, `[t_min, t_max, y_min, y_max]` (last frame's).
    #[serde(skip)]
    pub time_series_bounds: Option<[f64; 4]>,
}

impl Default for ViewState {
    fn default() -> Self {
        Self {
            tab: Tab::TimeSeries,
            show_differentiated: false,
            spectra_block: Block::Gyro,
            heatmap_mode: HeatmapMode::Magnitude,
            heatmap_frequency_hz: 5.0,
            bode_block: Block::Gyro,
            span_drag: None,
            validation_model: None,
            bode_deviation: false,
            bode_readout: None,
            reference_t: None,
            time_series_bounds: None,
        }
    }
}

/// Everything kept between launches.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default)]
pub struct Prefs {
    /// Identifier settings.
    pub settings: Settings,
    /// Presentation.
    pub view: ViewState,
    /// Recently opened runs, newest first (File > Open recent).
    pub recent: Vec<PathBuf>,
    /// The preferences' version: 0 (absent) before the segment could be left to the program
    /// (26 Nov), when every file carried the segment as a number; [`PREFS_VERSION`] since.
    /// Absent from a file, 0 (not the default's current version).
    #[serde(default)]
    pub version: u32,
}

/// The preferences' version written now ([`Prefs::version`]).
pub const PREFS_VERSION: u32 = 1;

impl Default for Prefs {
    fn default() -> Self {
        Self {
            settings: Settings::default(),
            view: ViewState::default(),
            recent: Vec::new(),
            version: PREFS_VERSION,
        }
    }
}

impl Prefs {
    /// The preferences a launch starts from, read back from `json`: the stretch to analyse
    /// (`span_s`) is left out, since it belongs to the run it was chosen on, not to the next
    /// launch's runs (a 50 s stretch of one run silently applied to another misleads).
    #[must_use]
    pub fn restored(json: &str) -> Option<Self> {
        let mut prefs: Self = serde_json::from_str(json).ok()?;
        prefs.settings.span_s = None;
        // Before version 1 the segment was always written: the default's 4096 was the program's.
        if prefs.version < 1 && prefs.settings.welch.segment_len == DEFAULT_SEGMENT_LEN {
            prefs.settings.welch.segment_auto = true;
        }
        prefs.version = PREFS_VERSION;
        Some(prefs)
    }
}

/// The imu-attest desktop app.
pub struct App {
    prefs: Prefs,
    persist: bool,
    worker: Worker,
    runs: Vec<RunEntry>,
    selected: Option<RunId>,
    errors: ErrorLog,
    commands: Vec<Command>,
    next_run: RunId,
    generation: u64,
    pair_texture: Option<(logic::TextureKey, egui::TextureHandle)>,
    compared: Vec<RunId>,
    comparison: Option<(logic::ComparisonKey, Arc<Comparison>)>,
    status: Option<String>,
    screenshots: export::Screenshots,
    /// The typed-path window, when open (File > Type a path, or no file dialog available).
    prompt: Option<prompt::PathPrompt>,
    /// The system's file dialog, when one is open (on its own thread).
    dialog: Option<dialog::PendingDialog>,
    /// What shows it.
    picker: FilePicker,
    /// The context, to wake the app from other threads.
    ctx: egui::Context,
    /// CPU time of the previous frame (the app's `ui` and rendering), s.
    frame_cpu_s: Option<f32>,
    /// Print every frame's CPU time to stderr (environment variable [`FRAME_LOG_VAR`] set).
    frame_log: bool,
    /// Worker events taken in the current frame (printed with its time, to tell a slow frame
    /// that took a result from one that only drew).
    frame_events: usize,
}

/// Set (to anything) to print `frame_cpu_ms <ms>` to stderr after every frame: how the frame
/// budget is measured (README, Speed).
pub const FRAME_LOG_VAR: &str = "IMU_ATTEST_FRAME_LOG";

impl App {
    /// Builds the app and starts loading `options.paths`.
    #[must_use]
    pub fn new(cc: &eframe::CreationContext<'_>, options: AppOptions) -> Self {
        let prefs = cc
            .storage
            .filter(|_| options.persist)
            .and_then(|s| s.get_string(PREFS_KEY))
            .and_then(|json| Prefs::restored(&json))
            .unwrap_or_default();
        let ctx = cc.egui_ctx.clone();
        let worker = Worker::start_with(
            options.mode,
            Arc::new(move || ctx.request_repaint()),
            options.load,
        );
        let mut app = Self {
            prefs,
            persist: options.persist,
            worker,
            runs: Vec::new(),
            selected: None,
            errors: ErrorLog::default(),
            commands: Vec::new(),
            next_run: 1,
            generation: 0,
            pair_texture: None,
            compared: Vec::new(),
            comparison: None,
            status: None,
            screenshots: export::Screenshots::default(),
            prompt: None,
            dialog: None,
            picker: options.file_picker,
            ctx: cc.egui_ctx.clone(),
            frame_cpu_s: None,
            frame_log: std::env::var_os(FRAME_LOG_VAR).is_some(),
            frame_events: 0,
        };
        app.push_command(Command::Open(options.paths));
        app
    }

    /// The runs in the list, loading ones included.
    #[must_use]
    pub fn runs(&self) -> &[RunEntry] {
        &self.runs
    }

    /// The selected run.
    #[must_use]
    pub fn selected(&self) -> Option<&RunEntry> {
        self.selected.and_then(|id| self.run(id))
    }

    /// Error messages shown in the error panel.
    #[must_use]
    pub fn errors(&self) -> Vec<String> {
        self.errors.lines()
    }

    /// What is kept between launches (settings, view, recent runs).
    #[must_use]
    pub fn prefs(&self) -> &Prefs {
        &self.prefs
    }

    /// The runs chosen for comparison, in the order chosen.
    #[must_use]
    pub fn compared(&self) -> &[RunId] {
        &self.compared
    }

    /// The comparison of the chosen runs' identifications, when two or more have one.
    #[must_use]
    pub fn comparison(&self) -> Option<&Arc<Comparison>> {
        self.comparison.as_ref().map(|(_, c)| c)
    }

    /// The last export's outcome, shown in the menu bar.
    #[must_use]
    pub fn status(&self) -> Option<&str> {
        self.status.as_deref()
    }

    /// Runs the jobs queued by a [`WorkerMode::Manual`] worker; returns how many ran.
    pub fn run_worker_jobs(&mut self) -> usize {
        self.worker.run_queued()
    }

    /// The presentation state (tab, view choices).
    #[must_use]
    pub fn view(&self) -> &ViewState {
        &self.prefs.view
    }

    /// The identifier settings in force.
    #[must_use]
    pub fn settings(&self) -> &Settings {
        &self.prefs.settings
    }

    fn run(&self, id: RunId) -> Option<&RunEntry> {
        self.runs.iter().find(|r| r.id == id)
    }

    fn run_mut(&mut self, id: RunId) -> Option<&mut RunEntry> {
        self.runs.iter_mut().find(|r| r.id == id)
    }

    fn next_generation(&mut self) -> u64 {
        self.generation += 1;
        self.generation
    }
}

impl eframe::App for App {
    fn logic(&mut self, ctx: &egui::Context, frame: &mut eframe::Frame) {
        // `cpu_usage` is the previous frame's, and so are the events counted.
        self.frame_cpu_s = frame.info().cpu_usage;
        if self.frame_log
            && let Some(s) = self.frame_cpu_s
        {
            eprintln!("frame_cpu_ms {:.3} events {}", 1e3 * s, self.frame_events);
        }
        self.frame_events = 0;
        self.logic_pass(ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.draw(ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.persist
            && let Ok(json) = serde_json::to_string(&self.prefs)
        {
            storage.set_string(PREFS_KEY, json);
        }
    }
}
