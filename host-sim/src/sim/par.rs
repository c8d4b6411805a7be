//! Ordered parallel map: items mapped on every core (rayon's pool), results handed back in
//! input order, so a run gives the same result whatever the number of threads.
//!
//! The items are taken in batches of [`batch_len`] items; a batch is mapped in parallel, then
//! its results are passed one by one, in order, to the caller's `take` on the calling thread
//! (which may fold them, report progress, or stop at the first error). Nothing a mapped item
//! computes may depend on another item or on the thread that runs it; the caller's fold sees
//! the same sequence as a serial loop would. The number of threads is rayon's: all cores, or
//! `RAYON_NUM_THREADS`, or the pool a caller installs.

use rayon::prelude::*;

/// Items per batch: 8 per thread of the current pool (enough to keep every core busy while
/// the items of one batch differ in cost; few enough that progress is reported often).
pub fn batch_len() -> usize {
    8 * rayon::current_num_threads().max(1)
}

/// Maps `f` over `items` in parallel and calls `take(index, result)` in input order. Stops at
/// the first error `take` returns (the rest of that batch is mapped but not taken).
pub fn map_ordered<T: Sync, R: Send, E>(
    items: &[T],
    f: impl Fn(usize, &T) -> R + Sync,
    mut take: impl FnMut(usize, R) -> Result<(), E>,
) -> Result<(), E> {
    let batch = batch_len();
    for (b, chunk) in items.chunks(batch).enumerate() {
        let first = b * batch;
        let results: Vec<R> = chunk
            .par_iter()
            .enumerate()
            .map(|(i, item)| f(first + i, item))
            .collect();
        for (i, r) in results.into_iter().enumerate() {
            take(first + i, r)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The results come back in input order on a pool of 1 and of 3 threads.
    #[test]
    fn results_in_input_order_on_any_pool() {
        let items: Vec<u64> = (0..1000).collect();
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            let mut seen = Vec::new();
            pool.install(|| {
                map_ordered(
                    &items,
                    |i, &x| (i as u64, x * x),
                    |i, r| {
                        seen.push((i, r));
                        Ok::<(), ()>(())
                    },
                )
            })
            .expect("no error");
            assert_eq!(seen.len(), items.len());
            for (k, (i, (j, sq))) in seen.iter().enumerate() {
                assert_eq!((*i, *j, *sq), (k, k as u64, (k * k) as u64));
            }
        }
    }

    /// The first error stops the taking.
    #[test]
    fn stops_at_the_first_error() {
        let items: Vec<u32> = (0..100).collect();
        let mut taken = 0;
        let r = map_ordered(
            &items,
            |_, &x| x,
            |_, x| {
                taken += 1;
                if x == 41 { Err(x) } else { Ok(()) }
            },
        );
        assert_eq!(r, Err(41));
        assert_eq!(taken, 42);
    }
}
