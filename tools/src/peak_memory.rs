//! The process's peak resident memory, which `spu paper` reports on standard error so a
//! user sizing `--threads` sees what a run cost (issue #35). Host facts never enter the
//! report itself: its numbers are the simulator's alone.

/// The peak resident set of this process in bytes (Linux's `VmHWM`), or `None` where the
/// host does not say.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    vm_hwm(&status)
}

/// `VmHWM:   123456 kB` of a `/proc/PID/status` text, in bytes.
fn vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find_map(|l| l.strip_prefix("VmHWM:"))?;
    let mut words = line.split_whitespace();
    let kib: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") => kib.checked_mul(1024),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::vm_hwm;

    #[test]
    fn reads_the_high_water_mark_in_bytes() {
        let status = "Name:\tspu\nVmPeak:\t  900 kB\nVmHWM:\t    2048 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(vm_hwm(status), Some(2048 * 1024));
    }

    #[test]
    fn a_missing_or_odd_line_is_none() {
        assert_eq!(vm_hwm("Name:\tspu\n"), None);
        assert_eq!(vm_hwm("VmHWM:\t12 MB\n"), None);
        assert_eq!(vm_hwm("VmHWM:\tlots kB\n"), None);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn this_process_has_a_peak() {
        let bytes = super::peak_resident_bytes().expect("Linux reports VmHWM");
        assert!(bytes >= 1024 * 1024, "{bytes}");
    }
}
