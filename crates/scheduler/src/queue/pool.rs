//! The pool of queues and their states, shared by the traversal thread and the shading
//! threads.

use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};

use vcm_traversal::{HitBatch, RayBatch};

use crate::tiles::TileCounter;

/// A wavefront and the buffers of its current pass; what the pool's size counts.
pub(super) struct Queue<W> {
    /// The paths.
    pub wave: W,
    /// The active paths' next segments, in path order.
    pub rays: RayBatch,
    /// Their closest hits.
    pub hits: HitBatch,
    /// The shadow rays shading queued.
    pub shadow_rays: RayBatch,
    /// Their occlusion.
    pub occluded: Vec<bool>,
}

impl<W> Queue<W> {
    /// An empty queue of `wave`'s paths.
    pub fn new(wave: W) -> Self {
        Self {
            wave,
            rays: RayBatch::default(),
            hits: HitBatch::default(),
            shadow_rays: RayBatch::default(),
            occluded: Vec::new(),
        }
    }
}

/// Where a queue is in its pass. A pass goes empty (or ready for resolve) → in use →
/// ready for traversal → in use → ready for shading → in use → ready for shadow traversal
/// → in use → ready for resolve; shading that queues no shadow ray resolves at once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum State {
    /// No path runs: waits for a tile, or stays empty once the tiles are exhausted.
    Empty,
    /// Taken by a thread: being started, shaded or resolved, or being traversed.
    InUse,
    /// Extension rays filled: waits for the closest-hit query.
    ReadyForTraversal,
    /// Hits filled: waits to be shaded.
    ReadyForShading,
    /// Shadow rays filled: waits for the occlusion query.
    ReadyForShadowTraversal,
    /// Occlusion filled: waits to be resolved and given its next rays.
    ReadyForResolve,
}

/// Who takes queues from the pool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Role {
    /// The thread that submits every traversal job.
    Traversal,
    /// The threads that start, shade and resolve paths.
    Shading,
}

impl Role {
    /// Whether a queue in `state` is work for this role; an empty queue is, for shading,
    /// while `tiles_left`.
    fn wants(self, state: State, tiles_left: bool) -> bool {
        match self {
            Role::Traversal => matches!(
                state,
                State::ReadyForTraversal | State::ReadyForShadowTraversal
            ),
            Role::Shading => {
                matches!(state, State::ReadyForShading | State::ReadyForResolve)
                    || (state == State::Empty && tiles_left)
            }
        }
    }
}

/// A queue taken from the pool.
pub(super) struct Taken<W> {
    /// Its place in the pool, to [`put`](Pool::put) it back.
    pub index: usize,
    /// The state it was taken in.
    pub state: State,
    /// The queue.
    pub queue: Queue<W>,
}

/// A queue's place in the pool.
struct Slot<W> {
    state: State,
    /// When the queue entered its state (a counter): the longest waiting is taken first.
    since: u64,
    /// The queue, unless a thread has taken it.
    queue: Option<Queue<W>>,
}

/// The slots and what every thread checks before waiting.
struct Slots<W> {
    slots: Vec<Slot<W>>,
    clock: u64,
    /// Set when a thread panicked: the queues it held will not come back.
    aborted: bool,
}

impl<W> Slots<W> {
    /// Whether the run is over: every queue is empty and back, and no tile is left.
    fn finished(&self, tiles: &TileCounter) -> bool {
        tiles.exhausted() && self.slots.iter().all(|slot| slot.state == State::Empty)
    }

    /// The queue that has waited longest for `role`, marked in use.
    fn take(&mut self, role: Role, tiles: &TileCounter) -> Option<Taken<W>> {
        let tiles_left = !tiles.exhausted();
        let (index, slot) = self
            .slots
            .iter_mut()
            .enumerate()
            .filter(|(_, slot)| role.wants(slot.state, tiles_left))
            .min_by_key(|(_, slot)| slot.since)?;
        let state = std::mem::replace(&mut slot.state, State::InUse);
        let queue = slot
            .queue
            .take()
            .expect("a queue not in use is in its slot");
        Some(Taken {
            index,
            state,
            queue,
        })
    }
}

/// Queues in states, handed between the threads under one lock; nobody holds the lock
/// while working on a queue.
pub(super) struct Pool<W> {
    slots: Mutex<Slots<W>>,
    changed: Condvar,
}

impl<W> Pool<W> {
    /// A pool of `queues`, all empty.
    pub fn new(queues: impl IntoIterator<Item = Queue<W>>) -> Self {
        let slots = queues
            .into_iter()
            .map(|queue| Slot {
                state: State::Empty,
                since: 0,
                queue: Some(queue),
            })
            .collect();
        Self {
            slots: Mutex::new(Slots {
                slots,
                clock: 0,
                aborted: false,
            }),
            changed: Condvar::new(),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Slots<W>> {
        // Nothing panics under the lock; a poisoned one still holds consistent slots.
        self.slots.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Takes the queue that has waited longest for `role`, blocking until there is one;
    /// `None` once there will be none: the run is over, or another thread panicked.
    pub fn take(&self, role: Role, tiles: &TileCounter) -> Option<Taken<W>> {
        let mut slots = self.lock();
        loop {
            if slots.aborted || slots.finished(tiles) {
                return None;
            }
            if let Some(taken) = slots.take(role, tiles) {
                return Some(taken);
            }
            slots = self
                .changed
                .wait(slots)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }

    /// Like [`take`](Self::take), but `None` at once when no queue is ready for `role`.
    pub fn try_take(&self, role: Role, tiles: &TileCounter) -> Option<Taken<W>> {
        let mut slots = self.lock();
        if slots.aborted {
            return None;
        }
        slots.take(role, tiles)
    }

    /// Puts back the queue taken from slot `index`, now in `state`, and wakes the threads
    /// waiting for one.
    pub fn put(&self, index: usize, queue: Queue<W>, state: State) {
        let mut slots = self.lock();
        slots.clock += 1;
        let since = slots.clock;
        slots.slots[index] = Slot {
            state,
            since,
            queue: Some(queue),
        };
        drop(slots);
        self.changed.notify_all();
    }

    /// Stops every thread waiting in [`take`](Self::take), and every later call.
    pub fn abort(&self) {
        self.lock().aborted = true;
        self.changed.notify_all();
    }

    /// The queues, once every one is back.
    pub fn into_queues(self) -> impl Iterator<Item = Queue<W>> {
        let slots = self
            .slots
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner);
        slots
            .slots
            .into_iter()
            .map(|slot| slot.queue.expect("every queue is back in the pool"))
    }
}

/// Aborts the pool when the thread holding it panics, so the other threads stop waiting
/// for the queues it held.
pub(super) struct AbortOnPanic<'a, W>(pub &'a Pool<W>);

impl<W> Drop for AbortOnPanic<'_, W> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.abort();
        }
    }
}
