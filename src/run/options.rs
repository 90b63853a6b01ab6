//! What a load can be told ([`LoadOptions`]) and what it tells while it runs ([`LoadProgress`]).

/// Fewest data rows a run may have.
pub const MIN_SAMPLES: usize = 16;

/// How to load a run. `LoadOptions::default()` is what the app and the command line use.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Size of the blocks read and parsed at a time, bytes (default 2 MiB; 8 MiB blocks took about
    /// 15 % longer to load the 220 MB benchmark run). Smaller values only
    /// make tests cross chunk boundaries; progress is reported once per block.
    pub chunk_bytes: usize,
    /// Largest relative deviation of a time step from the nominal step (default 0.01).
    pub sampling_tolerance: f64,
    /// Memory the decoded columns may take, bytes; `None`: `MemAvailable` of `/proc/meminfo`
    /// where readable, otherwise no limit.
    pub memory_limit_bytes: Option<u64>,
    /// Largest step of an angle between two samples once whole turns are removed, rad (default
    /// 1: no stand moves a radian in one sample); a larger one is refused (`run::wrap`). `None`:
    /// the angles are kept exactly as read, neither unwrapped nor checked (parser tests).
    pub max_angle_step_rad: Option<f64>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            chunk_bytes: 2 << 20,
            sampling_tolerance: 0.01,
            memory_limit_bytes: None,
            max_angle_step_rad: Some(1.0),
        }
    }
}

/// How far loading has got: bytes of the file read (compressed bytes for a gzip file).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadProgress {
    /// Bytes of the file read so far.
    pub bytes_done: u64,
    /// Size of the file, bytes.
    pub bytes_total: u64,
}

/// `MemAvailable` from `/proc/meminfo`, bytes; `None` where unreadable.
pub(super) fn mem_available_bytes() -> Option<u64> {
    crate::procfs::kib_field_bytes("/proc/meminfo", "MemAvailable")
}
