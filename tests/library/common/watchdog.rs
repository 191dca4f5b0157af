//! A watchdog for long generated-input runs: a run that stays on one input too long is a hang.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The index a run stores in its `current` counter when it is done.
pub const DONE: u64 = u64::MAX;

/// Watches `current`, the index of the input being run: when it stays on one index for longer than
/// `limit`, `on_hang(index)` runs (to report and save the input) and the process exits with 101, since a
/// hung input cannot be interrupted. Returns when `current` holds [`DONE`].
pub fn watch(
    current: Arc<AtomicU64>,
    limit: Duration,
    on_hang: impl Fn(u64) + Send + 'static,
) -> JoinHandle<()> {
    std::thread::spawn(move || {
        let mut last = (DONE - 1, Instant::now());
        loop {
            std::thread::sleep(Duration::from_millis(200));
            let now = current.load(Ordering::Relaxed);
            if now == DONE {
                return;
            }
            if now != last.0 {
                last = (now, Instant::now());
            } else if last.1.elapsed() > limit {
                on_hang(now);
                std::process::exit(101);
            }
        }
    })
}
