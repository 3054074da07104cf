//! The host machine as the loaders use it: work spread over its threads (decoding a capture's
//! images), and the most memory the process has held (reported by long runs).

use std::sync::atomic::{AtomicUsize, Ordering};

/// `f` applied to every item on up to `available_parallelism` threads, the results in the
/// items' order, so the outcome never depends on scheduling. On failure the error of the
/// first failing item in item order is returned (items after a failure may not be run).
pub fn parallel_map<T: Sync, R: Send, E: Send>(
    items: &[T],
    f: impl Fn(&T) -> Result<R, E> + Sync,
) -> Result<Vec<R>, E> {
    parallel_map_counted(items, f, &mut |_| {})
}

/// [`parallel_map`], calling `done(items finished so far)` on the calling thread as items
/// finish (a progress display's count; the results do not depend on it).
pub fn parallel_map_counted<T: Sync, R: Send, E: Send>(
    items: &[T],
    f: impl Fn(&T) -> Result<R, E> + Sync,
    done: &mut dyn FnMut(usize),
) -> Result<Vec<R>, E> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(items.len());
    if threads <= 1 {
        let mut finished = 0;
        return items
            .iter()
            .map(|item| {
                let result = f(item);
                finished += 1;
                done(finished);
                result
            })
            .collect();
    }
    // Items are handed out one at a time: decode times differ by file, so fixed chunks would
    // leave threads idle.
    let next = AtomicUsize::new(0);
    let failed_at = AtomicUsize::new(usize::MAX);
    let (finished, finishing) = std::sync::mpsc::channel();
    let mut results: Vec<(usize, Result<R, E>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let finished = finished.clone();
                let (next, failed_at, f) = (&next, &failed_at, &f);
                scope.spawn(move || {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        if i >= items.len() || i > failed_at.load(Ordering::Relaxed) {
                            break mine;
                        }
                        let result = f(&items[i]);
                        if result.is_err() {
                            failed_at.fetch_min(i, Ordering::Relaxed);
                        }
                        mine.push((i, result));
                        // The receiver lives until every worker has ended.
                        let _ = finished.send(());
                    }
                })
            })
            .collect();
        // Each worker holds its own sender: the count ends when the last worker does.
        drop(finished);
        for (count, ()) in finishing.iter().enumerate() {
            done(count + 1);
        }
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    results.sort_unstable_by_key(|(i, _)| *i);
    results.into_iter().map(|(_, r)| r).collect()
}

/// The host's physical memory, bytes (`MemTotal` of `/proc/meminfo`); None where the system
/// does not say (not Linux).
pub fn total_memory_bytes() -> Option<u64> {
    proc_kib("/proc/meminfo", "MemTotal:").map(|kib| kib * 1024)
}

/// The peak resident memory of this process so far, bytes (`VmHWM` of `/proc/self/status`);
/// None where the system does not say (not Linux).
pub fn peak_resident_bytes() -> Option<u64> {
    proc_kib("/proc/self/status", "VmHWM:").map(|kib| kib * 1024)
}

/// The value of line `key` (`Key:   1234 kB`) of a /proc file, in KiB.
fn proc_kib(path: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].trim().trim_end_matches("kB").trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_keep_the_items_order_and_the_first_error_wins() {
        let items: Vec<u32> = (0..1000).collect();
        let squares = parallel_map(&items, |&x| Ok::<_, ()>(x * x)).unwrap();
        assert_eq!(squares, items.iter().map(|x| x * x).collect::<Vec<_>>());
        let failing = parallel_map(&items, |&x| if x % 100 == 37 { Err(x) } else { Ok(x) });
        assert_eq!(failing, Err(37));
        assert_eq!(parallel_map(&[] as &[u32], |&x| Ok::<_, ()>(x)), Ok(vec![]));
    }

    #[test]
    fn the_count_reaches_every_item_once() {
        let items: Vec<u32> = (0..100).collect();
        let mut counts = Vec::new();
        let doubled =
            parallel_map_counted(&items, |&x| Ok::<_, ()>(2 * x), &mut |n| counts.push(n));
        assert_eq!(doubled.unwrap(), items.iter().map(|x| 2 * x).collect::<Vec<_>>());
        assert_eq!(counts, (1..=100).collect::<Vec<_>>());
    }

    #[test]
    fn peak_memory_covers_a_buffer_just_touched() {
        if !cfg!(target_os = "linux") {
            assert_eq!(peak_resident_bytes(), None);
            return;
        }
        let before = peak_resident_bytes().expect("Linux has VmHWM in /proc/self/status");
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let after = peak_resident_bytes().unwrap();
        assert!(after >= before && after >= 64 << 20, "{before} → {after}");
        let total = total_memory_bytes().expect("Linux has MemTotal in /proc/meminfo");
        assert!(total >= after, "{total} bytes of memory, {after} held");
    }
}
