//! Progress indication for anything that may take longer than a second.

use indicatif::{ProgressBar, ProgressStyle};
use std::time::{Duration, Instant};

/// Runs `f` behind a spinner labelled `what` (on stderr, hidden when not a terminal) and
/// returns its result and the elapsed wall time.
pub fn spin<T>(what: &str, f: impl FnOnce() -> T) -> (T, Duration) {
    let bar = ProgressBar::new_spinner();
    bar.set_style(ProgressStyle::with_template("{spinner} {msg} [{elapsed}]").expect("valid template"));
    bar.set_message(what.to_string());
    bar.enable_steady_tick(Duration::from_millis(100));
    let start = Instant::now();
    let out = f();
    let elapsed = start.elapsed();
    bar.finish_and_clear();
    (out, elapsed)
}
