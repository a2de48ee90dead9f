//! Benchmark support: how fast the host's cores run at the moment, printed beside every
//! speed figure the benches (and `geltip.host_speed()` in Python) report.

/// How fast the host's cores run at the moment: the time a fixed scalar loop (a 64 KiB array
/// updated 100 times, each element through a call to libm's fused multiply-add; about 5 ms
/// on this project's machine at full speed) takes on one core, and on every core at once
/// (until the slowest is done), the best of three tries each. Why: shared virtual machines
/// slow down by phases, with no steal time to show for it, and the renderer with them; on
/// this project's 2-core machine the loop on both cores takes under 5.3 ms at full speed and
/// 6-8 ms in slow phases (`cargo bench --bench render -- --host-phases 100` prints fps by it),
/// so a speed figure means little without this one beside it. (The loop is scalar and
/// latency-bound on purpose: a vectorised one, bound by cache bandwidth, does not follow those
/// phases.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostSpeed {
    /// Milliseconds for the loop on one core.
    pub one_core_ms: f64,
    /// Milliseconds until every core has run the loop once, all at the same time.
    pub all_cores_ms: f64,
}

impl HostSpeed {
    /// Times the loop now (some 35 ms on that machine).
    pub fn measure() -> HostSpeed {
        fn workload(seed: f32) -> f32 {
            let mut a: Vec<f32> = (0..16384)
                .map(|i| (i as f32 * 1e-3 + seed).fract())
                .collect();
            let mut sum = 0.0;
            for _ in 0..100 {
                for x in a.iter_mut() {
                    *x = (*x * 1.0001 + 0.37).mul_add(0.999, -0.1).abs().min(3.0);
                }
                sum += a[17];
            }
            sum
        }
        let best_ms = |threads: usize| -> f64 {
            (0..3)
                .map(|_| {
                    let start = std::time::Instant::now();
                    std::thread::scope(|scope| {
                        for k in 0..threads {
                            scope.spawn(move || std::hint::black_box(workload(k as f32)));
                        }
                    });
                    start.elapsed().as_secs_f64() * 1e3
                })
                .fold(f64::INFINITY, f64::min)
        };
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        HostSpeed {
            one_core_ms: best_ms(1),
            all_cores_ms: best_ms(cores),
        }
    }
}

impl std::fmt::Display for HostSpeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "host speed: a fixed loop {:.1} ms on one core, {:.1} ms on all at once",
            self.one_core_ms, self.all_cores_ms
        )
    }
}

#[cfg(test)]
mod tests {
    use super::HostSpeed;

    #[test]
    fn host_speed_times_the_loop_on_one_core_and_on_all() {
        let speed = HostSpeed::measure();
        for ms in [speed.one_core_ms, speed.all_cores_ms] {
            assert!(ms.is_finite() && ms > 0.0, "{speed:?}");
        }
        let line = speed.to_string();
        assert!(line.starts_with("host speed: a fixed loop "), "{line}");
        assert!(line.contains(" ms on one core, ") && line.ends_with(" ms on all at once"));
    }
}
