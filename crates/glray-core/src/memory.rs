//! This process's memory as the kernel counts it: its resident and peak resident bytes
//! (/proc/self/status), and the limit of its cgroup. What the statistics report, and what a
//! rank weighs a scene against before it takes it in.

/// This process's peak resident memory (VmHWM), bytes; 0 where unknown.
pub fn peak() -> u64 {
    status_bytes("VmHWM:")
}

/// This process's resident memory now (VmRSS), bytes; 0 where unknown.
pub fn resident() -> u64 {
    status_bytes("VmRSS:")
}

/// A field of /proc/self/status given in kB (`VmSize:`, `VmHWM:`, ...), in bytes; 0 where unknown.
pub fn status_bytes(field: &str) -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix(field))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

/// The memory limit of this process's cgroup (v2 `memory.max`, v1 `memory.limit_in_bytes`),
/// if it has one.
pub fn cgroup_limit() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let read = |path: String| std::fs::read_to_string(path).ok()?.trim().parse::<u64>().ok();
    let limit = groups.lines().find_map(|l| {
        let mut parts = l.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        match controllers {
            "" => read(format!("/sys/fs/cgroup{path}/memory.max")),
            c if c.split(',').any(|c| c == "memory") => {
                read(format!("/sys/fs/cgroup/memory{path}/memory.limit_in_bytes"))
            }
            _ => None,
        }
    })?;
    // (No limit is the largest page-aligned number there is.)
    (limit < 1 << 60).then_some(limit)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_process_holds_memory_and_its_peak_is_at_least_what_it_holds() {
        let (now, peak) = (super::resident(), super::peak());
        assert!(now > 0 && peak >= now, "{now} {peak}");
        assert_eq!(super::status_bytes("NoSuchField:"), 0);
    }
}
