//! coopnav's Python extension module `coopnav._coopnav`: thin wrappers over the libraries
//! (scenarios, planner, navigation filters, channel, simulator). It computes nothing itself: each
//! function converts its arguments, calls one library entry point and converts the result to
//! numpy arrays or plain Python containers. The Python package `coopnav` re-exports it.
//!
//! Conventions shared by every wrapper: bad input raises `ValueError` with the library's own
//! message (the one the CLI prints after "Error: "); long calls release the GIL, and the ones that
//! can take minutes (simulation, Monte Carlo) stop on Ctrl-C ([`interruptible`]).

mod channel;
mod convert;
mod nav;
mod planner;
mod scenario;
mod simulate;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

/// The error and its causes joined by ": ", each text once — as the CLI prints them.
pub(crate) fn cause_chain(error: &dyn std::error::Error) -> String {
    let mut line = error.to_string();
    let mut cause = error.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !line.ends_with(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
        cause = c.source();
    }
    line
}

/// A library error about the caller's input, as a Python `ValueError`.
pub(crate) fn value_error(error: impl std::error::Error) -> PyErr {
    PyValueError::new_err(cause_chain(&error))
}

/// How often a waiting call looks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` on a worker thread with the GIL released; the calling thread waits and checks for
/// signals (Ctrl-C raises `KeyboardInterrupt` here). On a signal the flag handed to `work` is
/// set, the worker (which must watch it) ends, and the signal's exception is raised.
pub(crate) fn interruptible<T: Send>(py: Python<'_>, work: impl FnOnce(&AtomicBool) -> T + Send) -> PyResult<T> {
    let stop = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let stop = &stop;
        scope.spawn(move || {
            // The receiver is gone only when the caller was interrupted: nothing to report then.
            let _ = tx.send(work(stop));
        });
        py.detach(move || loop {
            match rx.recv_timeout(SIGNAL_POLL) {
                Ok(value) => return Ok(value),
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(signal) = Python::attach(|py| py.check_signals()) {
                        stop.store(true, Ordering::Relaxed);
                        return Err(signal);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err("the coopnav worker thread failed"));
                }
            }
        })
    })
}

#[pymodule]
fn _coopnav(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    scenario::register(m)?;
    planner::register(m)?;
    nav::register(m)?;
    channel::register(m)?;
    simulate::register(m)?;
    Ok(())
}
