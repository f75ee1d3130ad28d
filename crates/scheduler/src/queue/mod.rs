//! The `queue` scheduler: a pool of queues in states, one thread collecting every traversal
//! job and the others shading, so that shading overlaps traversal on an asynchronous
//! backend.
//!
//! Threads: the traversal thread and the shading threads are plain threads, never rayon
//! workers, because they block waiting for queues. Their work (starting, shading and
//! resolving paths, and submitting traversal jobs to a backend that traverses as it is
//! submitted, as the CPU backend does, which the traversal thread takes from the pool) runs
//! as jobs on the caller's rayon pool ([`Jobs`]), whose workers therefore never block on
//! anything but rayon's own joins. An asynchronous backend's jobs (a GPU's) are submitted by
//! the shading thread that filled the rays, on that thread, and sent to the traversal thread,
//! which waits for them: the CPU side of a submission (packing and uploading the rays) runs on
//! all shading threads at once rather than on one.

mod jobs;
mod pool;

use std::collections::VecDeque;
use std::sync::mpsc;
use std::time::Instant;

use vcm_traversal::{PendingTraversal, Traversal, TraversalJob};

use crate::stats::{SchedulerStats, time};
use crate::tiles::TileCounter;
use crate::wavefront::{Wavefront, note_queue_memory, top_up};
use jobs::Jobs;
use pool::{AbortOnPanic, Pool, Queue, Role, State, Taken};

/// Traces every tile of `tiles` with a pool of `queues` (at least 1) wavefronts from
/// `new_wavefront`, each merging in the next tile below `merge_below` of a tile, with one
/// traversal thread and one shading thread per thread of the caller's rayon pool.
pub(crate) fn run<W: Wavefront>(
    queues: usize,
    tiles: &TileCounter,
    merge_below: f32,
    traversal: &dyn Traversal,
    new_wavefront: impl Fn() -> W + Sync,
) -> (Vec<W::Output>, SchedulerStats) {
    let start = Instant::now();
    let queues = queues.max(1);
    let pool = Pool::new((0..queues).map(|_| Queue::new(new_wavefront())));
    let merge_at = tiles.merge_at(merge_below);
    let shaders = rayon::current_num_threads().max(1);
    let (traversed, shaded) = Jobs::scope(|jobs| {
        std::thread::scope(|threads| {
            let (pool, jobs) = (&pool, jobs);
            let (sender, flights) = mpsc::channel();
            let submitter = traversal.submits_asynchronously().then_some(sender);
            let traverser = match &submitter {
                // The shading threads submit, the traversal thread collects.
                Some(_) => {
                    threads.spawn(move || traverse(pool, |block| next_submitted(&flights, block)))
                }
                // The traversal thread submits what the pool has ready, on a pool worker.
                None => threads.spawn(move || {
                    traverse(pool, |block| {
                        let taken = if block {
                            pool.take(Role::Traversal, tiles)
                        } else {
                            pool.try_take(Role::Traversal, tiles)
                        };
                        taken.map(|taken| Flight::submit(taken, traversal, Some(jobs)))
                    })
                }),
            };
            let shading: Vec<_> = (0..shaders)
                .map(|_| {
                    let submitter = submitter.clone().map(|flights| (flights, traversal));
                    threads.spawn(move || shade(pool, tiles, merge_at, jobs, submitter))
                })
                .collect();
            // The traversal thread's channel closes when the last shading thread ends.
            drop(submitter);
            jobs.help_until(|| traverser.is_finished() && shading.iter().all(|t| t.is_finished()));
            let join = |thread: std::thread::ScopedJoinHandle<'_, SchedulerStats>| {
                thread
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            };
            (
                join(traverser),
                shading.into_iter().map(join).collect::<Vec<_>>(),
            )
        })
    });
    let mut stats = SchedulerStats {
        workers: shaders,
        queues,
        ..SchedulerStats::default()
    };
    for thread in shaded.iter().chain([&traversed]) {
        stats.accumulate(thread);
    }
    let outputs = pool
        .into_queues()
        .map(|queue| queue.wave.finish())
        .collect();
    stats.close(start, stats.shading);
    (outputs, stats)
}

/// The traversal thread: takes every job submitted so far from `next_flight` (which blocks,
/// when asked to, until there is one; `None` when there will be none), then collects the
/// oldest job in flight and hands its queue back for shading. Returns the rays it traced and
/// the time it had jobs in flight, from the moment the first of them began to be submitted.
fn traverse<'t, W: Wavefront + 't>(
    pool: &Pool<W>,
    mut next_flight: impl FnMut(bool) -> Option<Flight<'t, W>>,
) -> SchedulerStats {
    let _abort = AbortOnPanic(pool);
    let mut stats = SchedulerStats::default();
    let mut in_flight = VecDeque::new();
    // Busy periods: from the first submission after the previous period ended to the
    // landing that leaves nothing in flight. A job that another thread submitted while the
    // previous period ran starts the next one at that period's end, so none overlap.
    let (mut busy_since, mut last_end) = (None, None);
    loop {
        if let Some(flight) = next_flight(in_flight.is_empty()) {
            let started = last_end.map_or(flight.started, |end: Instant| end.max(flight.started));
            busy_since.get_or_insert(started);
            in_flight.push_back(flight);
            continue;
        }
        let Some(flight) = in_flight.pop_front() else {
            return stats;
        };
        let (index, queue, state) = flight.land(&mut stats);
        pool.put(index, queue, state);
        if in_flight.is_empty()
            && let Some(since) = busy_since.take()
        {
            let end = Instant::now();
            stats.traversal += end - since;
            last_end = Some(end);
        }
    }
}

/// The next job the shading threads submitted: waits for one if `block`, else takes one only
/// if it is there.
fn next_submitted<F>(flights: &mpsc::Receiver<F>, block: bool) -> Option<F> {
    if block {
        flights.recv().ok()
    } else {
        flights.try_recv().ok()
    }
}

/// A queue whose rays are being traversed.
struct Flight<'t, W> {
    index: usize,
    /// The queue, without the buffers the job holds.
    queue: Queue<W>,
    pending: Box<dyn PendingTraversal + 't>,
    /// When the job's submission began (not counting the wait for a pool worker).
    started: Instant,
}

impl<'t, W: Wavefront + 't> Flight<'t, W> {
    /// Moves the rays and the output buffer of a queue ready for (shadow) traversal into a
    /// job and submits it: on a worker of the pool with `on_pool` (a backend that traverses
    /// as it is submitted), else on this thread (one that only hands the rays over).
    fn submit(
        Taken {
            index,
            state,
            mut queue,
        }: Taken<W>,
        traversal: &'t dyn Traversal,
        on_pool: Option<&Jobs<'_, 't>>,
    ) -> Self {
        let job = match state {
            State::ReadyForTraversal => TraversalJob::Intersect {
                rays: std::mem::take(&mut queue.rays),
                hits: std::mem::take(&mut queue.hits),
            },
            State::ReadyForShadowTraversal => TraversalJob::Occluded {
                rays: std::mem::take(&mut queue.shadow_rays),
                occluded: std::mem::take(&mut queue.occluded),
            },
            _ => unreachable!("only queues ready for traversal are submitted"),
        };
        let submit = move || (Instant::now(), traversal.submit(job));
        let (started, pending) = match on_pool {
            Some(jobs) => jobs.run(submit),
            None => submit(),
        };
        Self {
            index,
            queue,
            pending,
            started,
        }
    }

    /// Waits for the job, counts its rays and gives the queue its buffers back: ready for
    /// shading after a closest-hit query, for resolving after an occlusion query.
    fn land(self, stats: &mut SchedulerStats) -> (usize, Queue<W>, State) {
        let mut queue = self.queue;
        let state = match self.pending.wait() {
            TraversalJob::Intersect { rays, hits } => {
                stats.closest_rays += rays.len() as u64;
                (queue.rays, queue.hits) = (rays, hits);
                State::ReadyForShading
            }
            TraversalJob::Occluded { rays, occluded } => {
                stats.shadow_rays += rays.len() as u64;
                (queue.shadow_rays, queue.occluded) = (rays, occluded);
                State::ReadyForResolve
            }
        };
        (self.index, queue, state)
    }
}

/// A shading thread: takes the queue that has waited longest for shading, resolving or a
/// tile, and advances it on the rayon pool to its next traversal (or to empty). With a
/// `submitter` (an asynchronous backend) it submits the queue's traversal job itself and
/// sends it to the traversal thread; otherwise the queue goes back to the pool, where the
/// traversal thread finds it. Returns what its steps measured.
fn shade<'s, W: Wavefront + 's>(
    pool: &Pool<W>,
    tiles: &'s TileCounter<'s>,
    merge_at: usize,
    jobs: &Jobs<'_, 's>,
    submitter: Option<(mpsc::Sender<Flight<'s, W>>, &'s dyn Traversal)>,
) -> SchedulerStats {
    let _abort = AbortOnPanic(pool);
    let mut stats = SchedulerStats::default();
    while let Some(Taken {
        index,
        state,
        queue,
    }) = pool.take(Role::Shading, tiles)
    {
        let (queue, state, step) = jobs.run(move || {
            let (mut queue, mut step) = (queue, SchedulerStats::default());
            let state = advance(&mut queue, state, tiles, merge_at, &mut step);
            (queue, state, step)
        });
        stats.accumulate(&step);
        let traversal_next = matches!(
            state,
            State::ReadyForTraversal | State::ReadyForShadowTraversal
        );
        match &submitter {
            Some((flights, traversal)) if traversal_next => {
                let taken = Taken {
                    index,
                    state,
                    queue,
                };
                // The queue stays out of the pool, in use, until the traversal thread lands
                // it. The channel closes only if that thread panicked, which aborts the pool.
                let _ = flights.send(Flight::submit(taken, *traversal, None));
            }
            _ => pool.put(index, queue, state),
        }
    }
    stats
}

/// The shading part of a queue's pass, from `state` to the next state that waits for
/// traversal, or to empty when its paths have ended and no tile is left: shade the hits;
/// resolve the shadow rays (at once when shading queued none); start a tile when few paths
/// are left, as the tile scheduler does; fill the next extension rays. Once a stop is
/// requested the queue is empty at once: its paths are dropped with the pass (shading
/// stops advancing them).
fn advance<W: Wavefront>(
    queue: &mut Queue<W>,
    state: State,
    tiles: &TileCounter,
    merge_at: usize,
    stats: &mut SchedulerStats,
) -> State {
    if tiles.stopped() {
        return State::Empty;
    }
    let Queue {
        wave,
        rays,
        hits,
        shadow_rays,
        occluded,
    } = queue;
    if state == State::ReadyForShading {
        time(&mut stats.shading, || wave.shade(hits, shadow_rays));
        note_queue_memory(stats, wave, (rays, hits, shadow_rays), occluded);
        if !shadow_rays.is_empty() {
            return State::ReadyForShadowTraversal;
        }
        occluded.clear();
    }
    if state != State::Empty {
        time(&mut stats.shading, || wave.resolve(occluded));
    }
    if !top_up(wave, tiles, merge_at, stats) {
        return State::Empty;
    }
    time(&mut stats.shading, || wave.extension_rays(rays));
    State::ReadyForTraversal
}
