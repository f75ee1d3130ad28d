//! Running work on the caller's rayon pool from plain threads that block.

use std::sync::mpsc;
use std::thread::Thread;
use std::time::Duration;

/// Hands closures from plain threads to the rayon pool of the thread that made it (the
/// global pool, unless it was called inside [`rayon::ThreadPool::install`]).
pub(super) struct Jobs<'a, 'scope> {
    scope: &'a rayon::Scope<'scope>,
    /// The thread that waits for the plain threads, woken when there is a job to help with.
    caller: Thread,
}

impl<'scope> Jobs<'_, 'scope> {
    /// Calls `f` with a [`Jobs`] for the current rayon pool and returns its result once every
    /// job it ran is done.
    pub fn scope<R>(f: impl for<'a> FnOnce(&Jobs<'a, 'scope>) -> R) -> R {
        rayon::in_place_scope(|scope| {
            f(&Jobs {
                scope,
                caller: std::thread::current(),
            })
        })
    }

    /// Runs `job` on a worker of the pool and blocks the calling thread, which must not be
    /// one of its workers, until it is done. Panics if `job` does (the panic itself comes
    /// out of [`scope`](Self::scope)).
    pub fn run<R: Send + 'scope>(&self, job: impl FnOnce() -> R + Send + 'scope) -> R {
        let (sender, receiver) = mpsc::sync_channel(1);
        self.scope.spawn(move |_| {
            // The receiver only goes away if its thread panicked; nothing to report then.
            let _ = sender.send(job());
        });
        self.caller.unpark();
        receiver
            .recv()
            .expect("a job of the queue scheduler panicked")
    }

    /// Until `done`, keeps the calling thread, if it is a worker of the pool, running the
    /// pool's jobs: blocked, it would take itself away from the jobs the plain threads wait
    /// for (all of them, in a pool of one thread). Returns at once on other threads, which
    /// may block.
    pub fn help_until(&self, done: impl Fn() -> bool) {
        while !done() {
            match rayon::yield_now() {
                Some(rayon::Yield::Executed) => {}
                Some(rayon::Yield::Idle) => std::thread::park_timeout(Duration::from_millis(1)),
                None => return,
            }
        }
    }
}
