//! A small work queue on scoped threads: independent jobs (experiments, diagnosis
//! candidates) on all cores, results in the order of the jobs. Written here rather than with
//! rayon: the jobs are few (tens) and coarse (seconds), so a mutex-guarded queue is enough
//! and adds no dependency.

/// Runs `jobs` on up to `threads` threads, results in order.
pub fn parallel<T: Send, R: Send>(
    jobs: Vec<T>,
    threads: usize,
    work: impl Fn(T) -> R + Sync,
) -> Vec<R> {
    use std::sync::Mutex;
    let n = jobs.len();
    // Reversed, so that `pop` hands out the jobs in the given order.
    let queue = Mutex::new(jobs.into_iter().enumerate().rev().collect::<Vec<_>>());
    let results = Mutex::new((0..n).map(|_| None).collect::<Vec<Option<R>>>());
    let threads = threads.clamp(1, n.max(1));
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let job = queue.lock().map(|mut q| q.pop()).unwrap_or(None);
                let Some((index, job)) = job else { break };
                let result = work(job);
                if let Ok(mut slots) = results.lock() {
                    slots[index] = Some(result);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| r.expect("every job ran"))
        .collect()
}

/// Threads to use: the machine's parallelism.
pub fn threads() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}
