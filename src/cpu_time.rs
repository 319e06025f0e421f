//! The process's CPU time (user + system, all threads), for throughput per CPU-second: on a
//! machine shared with other work, wall time measures the neighbours as much as the renderer.

/// CPU seconds this process has used so far (Linux: `/proc/self/stat`, in ticks of 1/100 s),
/// or `None` where the platform does not say.
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count from after it.
    let rest = &stat[stat.rfind(')')? + 1..];
    let mut fields = rest.split_whitespace().skip(11); // fields 14 (utime) and 15 (stime)
    let user: u64 = fields.next()?.parse().ok()?;
    let system: u64 = fields.next()?.parse().ok()?;
    // USER_HZ, the unit of these fields, is 100 on every Linux architecture's user ABI.
    Some((user + system) as f64 / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_grows_with_work() {
        let Some(before) = process_cpu_seconds() else {
            return;
        };
        // Spin until the clock moves (its resolution is at most a scheduler tick).
        let mut x = 0u64;
        let mut after = before;
        while after <= before {
            for i in 0..1_000_000u64 {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
            }
            std::hint::black_box(x);
            after = process_cpu_seconds().expect("it answered once");
        }
        assert!(after > before && after - before < 60.0);
    }
}
