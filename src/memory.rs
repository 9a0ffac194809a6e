//! The process's peak resident memory (Linux: `VmHWM` of `/proc/self/status`), for the
//! summaries of runs and studies.

/// Resets the process's peak resident memory to its current resident memory, where Linux
/// allows it (`/proc/self/clear_refs`, value 5); elsewhere the next reading is the process's
/// peak since it started.
pub fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The process's peak resident memory since it started or the last [`reset_peak`], in MB;
/// `None` where the system does not say.
pub fn peak_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

#[cfg(test)]
mod tests {
    /// The peak covers memory the process touched: a 64 MB buffer written through raises it
    /// by about that much.
    #[test]
    fn the_peak_follows_what_the_process_touched() {
        let Some(before) = super::peak_mb() else {
            return; // not Linux
        };
        let buffer = vec![1u8; 64 << 20];
        let after = super::peak_mb().unwrap();
        assert!(buffer.iter().all(|&b| b == 1));
        assert!(after >= before + 60.0, "{before} MB -> {after} MB");
    }
}
