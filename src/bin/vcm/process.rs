//! What the operating system reports about this process: peak memory and CPU time (Linux
//! `/proc`; `None` elsewhere).

/// Peak resident memory of this process in MiB, if known.
pub fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// Clock ticks per second of `/proc`'s CPU times (USER_HZ, fixed at 100 by the kernel ABI).
const USER_HZ: f64 = 100.0;

/// CPU seconds this process has used so far, in user and kernel mode over all threads, if
/// known (10 ms resolution).
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) may contain spaces: count fields after its closing ')'.
    let after_name = &stat[stat.rfind(')')? + 1..];
    let mut fields = after_name.split_whitespace();
    // Fields 14 (utime) and 15 (stime) of proc(5); `after_name` starts at field 3.
    let utime: f64 = fields.nth(11)?.parse().ok()?;
    let stime: f64 = fields.next()?.parse().ok()?;
    Some((utime + stime) / USER_HZ)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_follows_the_work_of_a_busy_thread_on_linux() {
        if !cfg!(target_os = "linux") {
            return;
        }
        let before = cpu_seconds().expect("/proc/self/stat is readable on Linux");
        // Spin until 0.3 CPU seconds are counted (other processes may slow the clock down,
        // never speed it up): one busy thread cannot use more CPU time than wall time.
        let start = std::time::Instant::now();
        let mut x = 0u64;
        let used = loop {
            for _ in 0..100_000 {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
            let used = cpu_seconds().unwrap() - before;
            if used >= 0.3 {
                break used;
            }
            assert!(start.elapsed().as_secs() < 30, "CPU time stuck at {used} s");
        };
        // One 10 ms tick of slack for the rounding of both readings.
        assert!(used <= start.elapsed().as_secs_f64() + 0.02, "{used} s");
        assert!(peak_memory_mib().unwrap() > 0.0);
    }
}
