//! Reading `key: N kB` fields of Linux's `/proc` text files (`/proc/meminfo`,
//! `/proc/self/status`). Elsewhere than Linux, or for a missing field, the value is `None`.

/// The field `key` (without its colon) of the `/proc` file at `path`, converted from kB to
/// bytes; `None` where the file or the field is missing or not a number.
pub(crate) fn kib_field_bytes(path: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines().find_map(|line| {
        let value = line.strip_prefix(key)?.strip_prefix(':')?;
        let kib: u64 = value.trim().trim_end_matches("kB").trim().parse().ok()?;
        Some(kib.saturating_mul(1024))
    })
}

#[cfg(test)]
mod tests {
    use super::kib_field_bytes;

    #[test]
    fn fields_are_read_in_bytes_and_missing_ones_are_none() {
        let path = std::env::temp_dir().join(format!("imu-attest-procfs-{}", std::process::id()));
        std::fs::write(
            &path,
            "MemTotal:       1000 kB\nMemAvailable:    250 kB\nOdd: x kB\n",
        )
        .expect("write");
        let p = path.to_str().expect("utf-8 path");
        assert_eq!(kib_field_bytes(p, "MemAvailable"), Some(250 * 1024));
        assert_eq!(kib_field_bytes(p, "MemTotal"), Some(1000 * 1024));
        assert_eq!(kib_field_bytes(p, "Mem"), None, "a prefix is not a field");
        assert_eq!(kib_field_bytes(p, "Odd"), None);
        assert_eq!(kib_field_bytes(p, "Swap"), None);
        assert_eq!(kib_field_bytes("/nonexistent/meminfo", "MemAvailable"), None);
        let _ = std::fs::remove_file(&path);
    }
}
