//! Peak resident memory of this process, from Linux's `/proc/self/status` (`VmHWM`).
//!
//! Units: bytes. Elsewhere than Linux (no `/proc`) the peak is `None` and resetting it does
//! nothing.

/// The process's peak resident set size so far (`VmHWM`), bytes; `None` where unreadable.
#[must_use]
pub fn peak_rss_bytes() -> Option<u64> {
    crate::procfs::kib_field_bytes("/proc/self/status", "VmHWM")
}

/// Resets the peak resident set size to the current one (Linux 4.0 and later: writing `5` to
/// `/proc/self/clear_refs`), so that a later [`peak_rss_bytes`] measures what follows. Returns
/// whether the kernel accepted it.
#[must_use = "a false return means the peak still includes earlier work"]
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_grows_with_a_touched_allocation() {
        let Some(before) = peak_rss_bytes() else {
            return; // not Linux
        };
        let big = vec![1_u8; 64 << 20];
        let after = peak_rss_bytes().unwrap_or(0);
        assert!(after >= before.max(64 << 20), "{before} -> {after}");
        drop(std::hint::black_box(big));
    }
}
