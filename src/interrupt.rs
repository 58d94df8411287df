//! A request to stop, set by the binary on SIGINT or SIGTERM and polled by the long loops (the
//! explicit time loop, the speed sweep, the relief study's FE cross-check, the stages of
//! `geardyn run`; the optimizer's own loop, seconds long, finishes first). A
//! loop that sees it stops at a consistent state, between two steps or points, and hands back
//! what it has; the caller writes that, says where it stopped and exits non-zero.
//!
//! One flag for the process: a stop request ends every loop in it.

use std::sync::atomic::{AtomicBool, Ordering};

static STOP: AtomicBool = AtomicBool::new(false);

/// Asks every long loop of the process to stop at its next consistent state.
pub fn request_stop() {
    STOP.store(true, Ordering::SeqCst);
}

/// Whether a stop was requested.
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}
