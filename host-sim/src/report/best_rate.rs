//! Throughput of a repeated run on a shared machine: the best of batches, so that the least
//! disturbed batch is what is reported.

use std::time::Instant;

use anyhow::Result;

/// Runs per second of `run`: the best of batches of 100 over at least `seconds` (s).
pub fn best_rate(seconds: f64, mut run: impl FnMut() -> Result<()>) -> Result<f64> {
    const BATCH: usize = 100;
    let start = Instant::now();
    let mut best = f64::INFINITY;
    while best.is_infinite() || start.elapsed().as_secs_f64() < seconds {
        let t = Instant::now();
        for _ in 0..BATCH {
            run()?;
        }
        best = best.min(t.elapsed().as_secs_f64() / BATCH as f64);
    }
    Ok(1.0 / best)
}
