//! CPU time of this process (all threads, user + system), from Linux's `/proc/self/stat`.
//!
//! On a machine shared with other work, wall times vary with the load; the CPU time a stage used
//! varies much less. Units: s, with the kernel's resolution of 1/100 s (`USER_HZ`, fixed at 100
//! in the `/proc` interface). `None` where `/proc` cannot be read (not Linux).

/// Clock ticks per second of the `/proc` interface.
const USER_HZ: f64 = 100.0;

/// User plus system CPU time used so far by every thread of this process, s.
#[must_use]
pub fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) may hold spaces; the fields after its closing parenthesis are
    // plain: state is field 3, utime field 14, stime field 15.
    let rest = &stat[stat.rfind(')')? + 1..];
    let mut fields = rest.split_whitespace().skip(11);
    let utime: u64 = fields.next()?.parse().ok()?;
    let stime: u64 = fields.next()?.parse().ok()?;
    Some((utime + stime) as f64 / USER_HZ)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_grows_with_work() {
        let Some(before) = process_cpu_s() else {
            return; // not Linux
        };
        let mut x = 0.0_f64;
        let start = std::time::Instant::now();
        while start.elapsed().as_secs_f64() < 0.3 {
            x = std::hint::black_box(x + 1.0).sqrt();
        }
        let after = process_cpu_s().unwrap_or(0.0);
        assert!(after > before, "{before} -> {after}");
    }
}
