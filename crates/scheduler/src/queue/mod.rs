//! The `queue` scheduler: a pool of queues in states, one thread submitting every traversal
//! job and the others shading, so that shading overlaps traversal on an asynchronous
//! backend.
//!
//! Threads: the traversal thread and the shading threads are plain threads, never rayon
//! workers, because they block waiting for queues. Their work (starting, shading and
//! resolving paths, and submitting traversal jobs to a backend that traverses as it is
//! submitted, as the CPU backend does) runs as jobs on the caller's rayon pool ([`Jobs`]),
//! whose workers therefore never block on anything but rayon's own joins. An asynchronous
//! backend's jobs (a GPU's) are submitted on the traversal thread itself, without waiting
//! for a pool worker, and waiting for them happens there too.

mod jobs;
mod pool;

use std::collections::VecDeque;
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
            let traverser = threads.spawn(|| traverse(&pool, tiles, traversal, jobs));
            let shading: Vec<_> = (0..shaders)
                .map(|_| threads.spawn(|| shade(&pool, tiles, merge_at, jobs)))
                .collect();
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

/// The traversal thread: submits the job of every queue ready for traversal, oldest first,
/// then collects the oldest job in flight and hands its queue back for shading; blocks for
/// a ready queue only when no job is in flight. Returns the rays it traced and the time it
/// had jobs in flight, from the moment the first of them began to be submitted.
fn traverse<'s, W: Wavefront + 's>(
    pool: &Pool<W>,
    tiles: &TileCounter,
    traversal: &'s dyn Traversal,
    jobs: &Jobs<'_, 's>,
) -> SchedulerStats {
    let _abort = AbortOnPanic(pool);
    let mut stats = SchedulerStats::default();
    let mut in_flight = VecDeque::new();
    let mut busy_since = None;
    loop {
        let ready = if in_flight.is_empty() {
            pool.take(Role::Traversal, tiles)
        } else {
            pool.try_take(Role::Traversal, tiles)
        };
        if let Some(taken) = ready {
            let flight = Flight::submit(taken, traversal, jobs, &mut stats);
            busy_since.get_or_insert(flight.started);
            in_flight.push_back(flight);
            continue;
        }
        let Some(flight) = in_flight.pop_front() else {
            return stats;
        };
        let (index, queue, state) = flight.land();
        pool.put(index, queue, state);
        if in_flight.is_empty() {
            stats.traversal += busy_since
                .take()
                .map_or_else(Default::default, |t| t.elapsed());
        }
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
    /// job and submits it, counting its rays.
    fn submit(
        Taken {
            index,
            state,
            mut queue,
        }: Taken<W>,
        traversal: &'t dyn Traversal,
        jobs: &Jobs<'_, 't>,
        stats: &mut SchedulerStats,
    ) -> Self {
        let job = match state {
            State::ReadyForTraversal => {
                stats.closest_rays += queue.rays.len() as u64;
                TraversalJob::Intersect {
                    rays: std::mem::take(&mut queue.rays),
                    hits: std::mem::take(&mut queue.hits),
                }
            }
            State::ReadyForShadowTraversal => {
                stats.shadow_rays += queue.shadow_rays.len() as u64;
                TraversalJob::Occluded {
                    rays: std::mem::take(&mut queue.shadow_rays),
                    occluded: std::mem::take(&mut queue.occluded),
                }
            }
            _ => unreachable!("the traversal thread takes queues ready for traversal only"),
        };
        let submit = move || (Instant::now(), traversal.submit(job));
        // An asynchronous backend only hands the rays over: do that here rather than wait
        // for a pool worker, which may be busy shading for a while.
        let (started, pending) = if traversal.submits_asynchronously() {
            submit()
        } else {
            jobs.run(submit)
        };
        Self {
            index,
            queue,
            pending,
            started,
        }
    }

    /// Waits for the job and gives the queue its buffers back: ready for shading after a
    /// closest-hit query, for resolving after an occlusion query.
    fn land(self) -> (usize, Queue<W>, State) {
        let mut queue = self.queue;
        let state = match self.pending.wait() {
            TraversalJob::Intersect { rays, hits } => {
                (queue.rays, queue.hits) = (rays, hits);
                State::ReadyForShading
            }
            TraversalJob::Occluded { rays, occluded } => {
                (queue.shadow_rays, queue.occluded) = (rays, occluded);
                State::ReadyForResolve
            }
        };
        (self.index, queue, state)
    }
}

/// A shading thread: takes the queue that has waited longest for shading, resolving or a
/// tile, and advances it on the rayon pool to its next traversal (or to empty). Returns
/// what its steps measured.
fn shade<'s, W: Wavefront + 's>(
    pool: &Pool<W>,
    tiles: &'s TileCounter,
    merge_at: usize,
    jobs: &Jobs<'_, 's>,
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
        pool.put(index, queue, state);
        stats.accumulate(&step);
    }
    stats
}

/// The shading part of a queue's pass, from `state` to the next state that waits for
/// traversal, or to empty when its paths have ended and no tile is left: shade the hits;
/// resolve the shadow rays (at once when shading queued none); start a tile when few paths
/// are left, as the tile scheduler does; fill the next extension rays.
fn advance<W: Wavefront>(
    queue: &mut Queue<W>,
    state: State,
    tiles: &TileCounter,
    merge_at: usize,
    stats: &mut SchedulerStats,
) -> State {
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
