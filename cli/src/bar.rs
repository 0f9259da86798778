//! Progress bars on standard error for the slow paths (the interpreters answer a few thousand
//! queries a second; a large scene takes hours): a thread draws the count of
//! `scion_host::progress` against the total, with the time left, until the bar is dropped.
//! indicatif hides the bar when standard error is not a terminal (logs and tests see nothing).

use indicatif::{ProgressBar, ProgressStyle};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// Whether a [`Bar`] over queries is being drawn.
static QUERIES_BAR: AtomicBool = AtomicBool::new(false);

/// True while a [`Bar`] over queries is up (a [`RunsBar`] then stays away).
pub fn queries_bar_up() -> bool {
    QUERIES_BAR.load(Ordering::Relaxed)
}

/// A bar counting `scion_host::progress` from zero to a total.
pub struct Bar {
    stop: Arc<AtomicBool>,
    drawer: Option<JoinHandle<()>>,
}

impl Bar {
    /// Starts a bar for `total` queries (`what`: "rays", "points").
    pub fn new(what: &str, total: u64) -> Bar {
        scion_host::progress::reset();
        QUERIES_BAR.store(true, Ordering::Relaxed);
        let bar = ProgressBar::new(total);
        if let Ok(style) = ProgressStyle::with_template(&format!(
            "scion: {{bar:40}} {{pos}}/{{len}} {what} ({{elapsed}} elapsed, about {{eta}} left)"
        )) {
            bar.set_style(style);
        }
        let stop = Arc::new(AtomicBool::new(false));
        let stopped = stop.clone();
        let drawer = std::thread::Builder::new()
            .name("scion-progress".into())
            .spawn(move || {
                while !stopped.load(Ordering::Relaxed) {
                    bar.set_position(scion_host::progress::done().min(total));
                    std::thread::sleep(Duration::from_millis(200));
                }
                bar.finish_and_clear();
            })
            .ok();
        Bar { stop, drawer }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        QUERIES_BAR.store(false, Ordering::Relaxed);
        self.stop.store(true, Ordering::Relaxed);
        if let Some(d) = self.drawer.take() {
            let _ = d.join();
        }
    }
}

/// A bar over the runs of a timed trace ("run 3 of 10"), hidden when standard error is not a
/// terminal; cleared when dropped.
pub struct RunsBar(ProgressBar);

impl RunsBar {
    /// A bar for `total` runs (the checked one and the timed ones).
    pub fn new(total: u64) -> RunsBar {
        let bar = ProgressBar::new(total);
        if let Ok(style) = ProgressStyle::with_template(
            "scion: run {pos} of {len} ({elapsed} elapsed, about {eta} left)",
        ) {
            bar.set_style(style);
        }
        RunsBar(bar)
    }

    /// One more run done.
    pub fn tick(&self) {
        self.0.inc(1);
    }
}

impl Drop for RunsBar {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}
