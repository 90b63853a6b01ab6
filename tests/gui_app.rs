//! The desktop app driven through AccessKit (`egui_kittest`), no GPU: the worker runs in synchronous
//! mode so every frame sees finished results and the tests are deterministic. One pixel snapshot
//! runs only with `--features gui-snapshots`.

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::{App, AppOptions, Command, WorkerMode, sample_run_path};

fn app_on_sample() -> Harness<'static, App> {
    sample_app(Harness::builder())
}

/// The app on the bundled sample run, three frames in.
fn sample_app(builder: egui_kittest::HarnessBuilder<App>) -> Harness<'static, App> {
    let paths = vec![sample_run_path().expect("sample run written")];
    let mut harness = builder
        .with_size(eframe::egui::vec2(1100.0, 720.0))
        .build_eframe(|cc| {
            App::new(
                cc,
                AppOptions {
                    mode: WorkerMode::Synchronous,
                    persist: false,
                    ..AppOptions::new(paths)
                },
            )
        });
    // Repaints keep coming from the worker's waker: step a fixed number of frames.
    harness.run_steps(3);
    harness
}

/// Pixel snapshot, rendered with wgpu on a software adapter (Mesa lavapipe:
/// `mesa-vulkan-drivers libvulkan1`); only with `--features gui-snapshots`. Update the stored
/// image with `UPDATE_SNAPSHOTS=1 cargo test --features gui-snapshots --test integration gui_app::`.
#[cfg(feature = "gui-snapshots")]
#[test]
fn spectra_tab_snapshot() {
    let mut harness = sample_app(Harness::builder().wgpu());
    harness.get_by_label("Spectra").click();
    harness.run_steps(3);
    harness.snapshot("spectra_tab");
}

#[test]
fn opens_on_the_sample_run_and_lists_it() {
    let harness = app_on_sample();
    harness.get_by_label("cruise.csv.gz");
    harness.get_by_label("regime: cruise");
    harness.get_by_label("blocks: gyro, accel");
    let app = harness.state();
    assert_eq!(app.runs().len(), 1);
    let run = &app.runs()[0];
    assert!(run.motion.is_some(), "observer stage done");
    let spectra = run.spectra.as_ref().expect("spectra computed");
    assert_eq!(spectra.blocks.len(), 2);
    assert!(app.errors().is_empty(), "{:?}", app.errors());
}

#[test]
fn a_broken_file_shows_an_error_and_the_app_keeps_working() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("broken.csv");
    std::fs::write(
        &bad,
        "t,roll,yaw,pitch,gx,gy,gz\n0,0,0,0,0,0,0\n0.002,0,abc,0,0,0,0\n",
    )
    .expect("write");
    let mut harness = app_on_sample();
    harness.state_mut().push_command(Command::Open(vec![bad]));
    harness.run_steps(2);
    let app = harness.state();
    assert_eq!(app.errors().len(), 1, "{:?}", app.errors());
    assert!(app.errors()[0].contains("broken.csv"), "{}", app.errors()[0]);
    assert_eq!(app.runs().len(), 1, "the broken run is not listed");
    assert!(app.runs()[0].spectra.is_some(), "the sample run stays");
    harness.get_by_label_contains("broken.csv");
    harness.get_by_label("cruise.csv.gz");
    // Still usable: switch tab and dismiss the error.
    harness.get_by_label("Spectra").click();
    harness.run_steps(2);
    harness.get_by_label("frequency × channel pair: |S_ij|, dB");
    harness.get_by_label("dismiss").click();
    harness.run_steps(2);
    assert!(harness.state().errors().is_empty());
}

#[test]
fn a_new_segment_length_recomputes_the_spectra_only() {
    let mut harness = app_on_sample();
    let (g0, motion0) = {
        let run = &harness.state().runs()[0];
        (run.spectra.generation, run.motion.value.clone().expect("motion"))
    };
    let mut settings = harness.state().settings().clone();
    assert_ne!(settings.welch.segment_len, 1024);
    // A segment picked in the box is the user's (not the program's, which a short record shortens).
    settings.welch.segment_auto = false;
    settings.welch.segment_len = 1024;
    harness
        .state_mut()
        .push_command(Command::SetSettings(Box::new(settings.clone())));
    harness.run_steps(2);
    let run = &harness.state().runs()[0];
    assert!(run.spectra.generation > g0, "generation advances");
    let spectra = run.spectra.as_ref().expect("spectra");
    assert_eq!(spectra.welch.segment_len, 1024);
    assert_eq!(spectra.blocks[0].matrix.n_bins(), 513);
    let motion1 = run.motion.as_ref().expect("motion");
    assert!(
        std::sync::Arc::ptr_eq(&motion0, motion1),
        "the observer stage is not redone"
    );

    // A segment longer than the run: error shown, last good spectra kept.
    settings.welch.segment_len = 1 << 17;
    harness
        .state_mut()
        .push_command(Command::SetSettings(Box::new(settings.clone())));
    harness.run_steps(2);
    let app = harness.state();
    let run = &app.runs()[0];
    assert!(run.spectra.error.is_some() && run.identification.error.is_some());
    assert_eq!(run.spectra.as_ref().expect("kept").welch.segment_len, 1024);
    assert!(
        app.errors().iter().any(|e| e.contains("spectra")),
        "{:?}",
        app.errors()
    );
    let errors_before = app.errors().len();

    // Another bad segment, then the same one again: one line per distinct failure.
    for segment_len in [1 << 18, 1 << 17] {
        settings.welch.segment_len = segment_len;
        harness
            .state_mut()
            .push_command(Command::SetSettings(Box::new(settings.clone())));
        harness.run_steps(2);
    }
    let errors = harness.state().errors();
    assert_eq!(errors.len(), errors_before + 1, "{errors:?}");
    assert!(errors.last().is_some_and(|e| e.ends_with("(x2)")), "{errors:?}");

    // Fixed: the run's analysis errors leave the panel.
    settings.welch.segment_len = 1024;
    harness
        .state_mut()
        .push_command(Command::SetSettings(Box::new(settings)));
    harness.run_steps(3);
    let errors = harness.state().errors();
    assert!(!errors.iter().any(|e| e.contains("spectra")), "{errors:?}");
}

#[test]
fn a_cancelled_load_reports_cancelled_and_loads_nothing() {
    use imu_attest::gui::pipeline::{Event, Job, JobKind, Worker};
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;

    let mut worker = Worker::start(WorkerMode::Synchronous, Arc::new(|| {}));
    let path = sample_run_path().expect("sample run written");
    let cancel = Arc::new(AtomicBool::new(true));
    worker.submit(Job {
        run: 7,
        generation: 1,
        kind: JobKind::Load { path, cancel },
    });
    let events: Vec<Event> = worker.events.try_iter().collect();
    assert!(
        matches!(
            events.last(),
            Some(Event::Failed {
                run: 7,
                kind: imu_attest::gui::pipeline::FailureKind::Cancelled,
                ..
            })
        ),
        "{events:?}"
    );
    // An analysis of a run that never loaded does nothing.
    worker.submit(Job {
        run: 7,
        generation: 2,
        kind: JobKind::Analyse {
            settings: Box::default(),
            accepted: Vec::new(),
        },
    });
    assert_eq!(worker.events.try_iter().count(), 0);
}

#[test]
fn the_worker_thread_delivers_the_newest_analysis() {
    use imu_attest::gui::pipeline::{Event, Job, JobKind, Worker};
    use imu_attest::ident::settings::Settings;
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;
    use std::time::Duration;

    let mut worker = Worker::start(WorkerMode::Thread, Arc::new(|| {}));
    let path = sample_run_path().expect("sample run written");
    let cancel = Arc::new(AtomicBool::new(false));
    worker.submit(Job {
        run: 1,
        generation: 1,
        kind: JobKind::Load { path, cancel },
    });
    let mut short = Settings::default();
    short.welch.segment_len = 512;
    worker.submit(Job {
        run: 1,
        generation: 2,
        kind: JobKind::Analyse {
            settings: Box::new(short),
            accepted: Vec::new(),
        },
    });
    worker.submit(Job {
        run: 1,
        generation: 3,
        kind: JobKind::Analyse {
            settings: Box::default(),
            accepted: Vec::new(),
        },
    });
    loop {
        match worker
            .events
            .recv_timeout(Duration::from_mins(2))
            .expect("worker answers")
        {
            Event::Spectra {
                generation: 3,
                spectra,
                ..
            } => {
                assert_eq!(spectra.welch.segment_len, Settings::default().welch.segment_len);
                break;
            }
            Event::Failed { message, .. } => panic!("{message}"),
            _ => {}
        }
    }
}

/// The single-frequency CSD matrix is coloured on its own cells' range (the whole spectrum's put
/// one frequency's cells in a few shades), and both heatmaps are titled by what they show.
#[test]
fn the_csd_matrix_has_its_own_colour_scale_and_titles_say_the_mode() {
    use imu_attest::gui::app::HeatmapMode;
    use imu_attest::gui::view::colormap::value_range;
    use imu_attest::gui::view::heatmap::matrix_range;
    let mut harness = app_on_sample();
    harness.get_by_label("Spectra").click();
    harness.run_steps(2);
    harness.get_by_label_contains("|S_ij|, dB, at ");
    let app = harness.state();
    let spectra = app.runs()[0].spectra.as_ref().expect("spectra");
    let block = &spectra.blocks[0];
    let df = block.matrix.df_hz();
    let bin = ((app.view().heatmap_frequency_hz / df).round() as usize).clamp(1, block.matrix.n_bins() - 1);
    let own = matrix_range(block, bin, HeatmapMode::Magnitude);
    let whole = value_range(block, HeatmapMode::Magnitude);
    assert!(own.1 - own.0 < 0.8 * (whole.1 - whole.0), "{own:?} vs {whole:?}");
    assert!(own.0 < own.1);
    let top = format!("{:.1} dB", own.1);
    assert!(
        harness.get_all_by_label(&top).count() >= 1,
        "the matrix's legend ends at {top}"
    );
    harness.get_by_label("coherence").click();
    harness.run_steps(2);
    harness.get_by_label_contains("coherence |S_ij|² / (S_ii S_jj) at ");
    harness.get_by_label("frequency × channel pair: coherence");
}
