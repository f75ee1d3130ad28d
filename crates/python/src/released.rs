//! Running Rust work with the interpreter released, while Ctrl-C and a progress callback keep
//! working: the work runs on a thread of its own, and the calling thread wakes every
//! [`POLL`] to run Python's signal handlers and the callback.

use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use vcm_rs::vcm::StopFlag;

/// How often the calling thread checks for signals and reports progress.
const POLL: Duration = Duration::from_millis(50);

/// Runs `work` on a new thread and waits for it with the interpreter released, calling
/// Python's signal handlers and then `poll` every [`POLL`] and once more at the end. When
/// either fails (Ctrl-C makes the signal handlers raise `KeyboardInterrupt`), `stop` is
/// raised, so that the work ends within a tile, and the error is returned once it has ended.
pub fn run_released<T: Send>(
    py: Python<'_>,
    stop: &StopFlag,
    mut poll: impl FnMut(Python<'_>) -> PyResult<()>,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let (done, mut finished) = mpsc::channel::<()>();
    std::thread::scope(|scope| {
        let worker = scope.spawn(move || {
            let value = work();
            // The receiver outlives the worker, so the send cannot fail.
            let _ = done.send(());
            value
        });
        let mut failure = None;
        loop {
            let (waited, receiver) = py.detach(move || (finished.recv_timeout(POLL), finished));
            finished = receiver;
            if failure.is_none()
                && let Err(error) = py.check_signals().and_then(|()| poll(py))
            {
                stop.raise();
                failure = Some(error);
            }
            // Disconnected: the worker panicked before it could say it was done.
            if waited != Err(RecvTimeoutError::Timeout) {
                break;
            }
        }
        let value = worker
            .join()
            .map_err(|_| PyRuntimeError::new_err("vcm_rs: the render panicked (a bug)"));
        match failure {
            Some(error) => Err(error),
            None => value,
        }
    })
}
