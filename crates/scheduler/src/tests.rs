//! Every scheduler against a fake wavefront and fake backends: each tile is started once,
//! each path runs to its end with the right hits and occlusion, the rays are counted, and
//! the run ends.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use glam::Vec3;
use vcm_traversal::{HitBatch, PendingTraversal, RayBatch, Traversal, TraversalJob};

use crate::{Scheduler, StopFlag, Tile, TileGrid, Wavefront, run};

/// Segments of pixel `p`'s path: 0 (no path at all) to 6.
fn length(pixel: u32) -> u32 {
    (pixel * 5 + 3) % 7
}

/// Whether segment `remaining` of a path queues a shadow ray.
fn casts_shadow(remaining: u32) -> bool {
    remaining.is_multiple_of(2)
}

/// Whether the fake backends report a shadow ray from pixel `p` occluded.
fn blocked(pixel: u32) -> bool {
    pixel.is_multiple_of(3)
}

/// A path: its pixel, the segments left, and what it has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Path {
    pixel: u32,
    remaining: u32,
    segments: u32,
    lit: u32,
    shadowed: bool,
}

/// What a fake wavefront hands back: the tiles it started and its ended paths.
type Output = (Vec<Tile>, Vec<Path>);

/// Paths that trace `length(pixel)` segments; ray origins carry the pixel so that the fake
/// backends can answer for it and shading can check its hit belongs to its path.
struct FakeWave {
    width: u32,
    /// Panic when shading this pixel.
    panic_at: Option<u32>,
    paths: Vec<Path>,
    started: Vec<Tile>,
    ended: Vec<Path>,
}

impl FakeWave {
    /// A wavefront over an image `width` pixels wide, panicking when it shades `panic_at`.
    fn new(width: u32, panic_at: Option<u32>) -> Self {
        Self {
            width,
            panic_at,
            paths: Vec::new(),
            started: Vec::new(),
            ended: Vec::new(),
        }
    }
}

impl Wavefront for FakeWave {
    type Output = Output;

    fn start(&mut self, tile: Tile) {
        self.started.push(tile);
        let paths = tile.pixels(self.width).map(|pixel| Path {
            pixel,
            remaining: length(pixel),
            ..Path::default()
        });
        self.paths.extend(paths.filter(|path| path.remaining > 0));
    }

    fn active(&self) -> usize {
        self.paths.len()
    }

    fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.paths.as_slice())
    }

    fn extension_rays(&self, rays: &mut RayBatch) {
        rays.clear();
        for path in &self.paths {
            rays.push(Vec3::new(path.pixel as f32, 0.0, 0.0), Vec3::X, 0.0, 1.0);
        }
    }

    fn shade(&mut self, hits: &HitBatch, shadow_rays: &mut RayBatch) {
        assert_eq!(hits.len(), self.paths.len());
        shadow_rays.clear();
        for (i, path) in self.paths.iter_mut().enumerate() {
            assert_eq!(hits.t[i], path.pixel as f32, "a hit of another path");
            assert!(Some(path.pixel) != self.panic_at, "shading panics");
            path.segments += 1;
            path.remaining -= 1;
            path.shadowed = casts_shadow(path.remaining);
            if path.shadowed {
                shadow_rays.push(Vec3::new(path.pixel as f32, 1.0, 0.0), Vec3::Y, 0.0, 1.0);
            }
        }
    }

    fn resolve(&mut self, occluded: &[bool]) {
        let shadowed = self.paths.iter_mut().filter(|path| path.shadowed);
        let mut count = 0;
        for (path, &occluded) in shadowed.zip(occluded) {
            assert_eq!(occluded, blocked(path.pixel));
            path.lit += u32::from(!occluded);
            count += 1;
        }
        assert_eq!(count, occluded.len(), "one flag per shadow ray");
        let ended = &mut self.ended;
        self.paths.retain(|path| {
            if path.remaining == 0 {
                ended.push(*path);
            }
            path.remaining > 0
        });
    }

    fn finish(self) -> Output {
        (self.started, self.ended)
    }
}

/// A backend that answers from the ray origins: hit distance = origin x, occluded =
/// [`blocked`]. With `delay`, [`submit`](Traversal::submit) answers on another thread after
/// that delay, as a GPU would (and says it submits asynchronously), and counts the jobs in
/// flight.
struct FakeTraversal {
    delay: Option<Duration>,
    in_flight: AtomicUsize,
    most_in_flight: AtomicUsize,
}

impl FakeTraversal {
    fn new(delay: Option<Duration>) -> Self {
        Self {
            delay,
            in_flight: AtomicUsize::new(0),
            most_in_flight: AtomicUsize::new(0),
        }
    }
}

impl Traversal for FakeTraversal {
    fn intersect(&self, rays: &RayBatch, hits: &mut HitBatch) {
        hits.resize(rays.len());
        for i in 0..rays.len() {
            (hits.t[i], hits.prim[i]) = (rays.origin_x[i], 0);
        }
    }

    fn occluded(&self, rays: &RayBatch, occluded: &mut Vec<bool>) {
        occluded.clear();
        occluded.extend(rays.origin_x.iter().map(|&x| blocked(x as u32)));
    }

    fn submit(&self, mut job: TraversalJob) -> Box<dyn PendingTraversal + '_> {
        let Some(delay) = self.delay else {
            job.run(self);
            return Box::new(vcm_traversal::CompletedTraversal(job));
        };
        let now = self.in_flight.fetch_add(1, Ordering::SeqCst) + 1;
        self.most_in_flight.fetch_max(now, Ordering::SeqCst);
        let eager = FakeTraversal::new(None);
        let answer = std::thread::spawn(move || {
            std::thread::sleep(delay);
            job.run(&eager);
            job
        });
        Box::new(Later {
            answer,
            in_flight: &self.in_flight,
        })
    }

    fn submits_asynchronously(&self) -> bool {
        self.delay.is_some()
    }
}

/// A job answered on its own thread.
struct Later<'a> {
    answer: std::thread::JoinHandle<TraversalJob>,
    in_flight: &'a AtomicUsize,
}

impl PendingTraversal for Later<'_> {
    fn wait(self: Box<Self>) -> TraversalJob {
        let job = self.answer.join().expect("the fake traversal thread");
        self.in_flight.fetch_sub(1, Ordering::SeqCst);
        job
    }
}

/// Runs `scheduler` over a `width × height` image on a rayon pool of `threads` (`None`:
/// from outside any pool) and checks everything the module promises. Returns the most
/// traversal jobs that were in flight at once (0 without `delay`).
fn check(
    scheduler: Scheduler,
    (width, height): (u32, u32),
    threads: Option<usize>,
    delay: bool,
) -> usize {
    let traversal = FakeTraversal::new(delay.then(|| Duration::from_micros(200)));
    let new_wave = || FakeWave::new(width, None);
    let go = || {
        run(
            scheduler,
            (width, height),
            &traversal,
            &StopFlag::new(),
            new_wave,
        )
    };
    let (outputs, stats) = match threads {
        Some(threads) => pool(threads).install(go),
        None => go(),
    };
    let context = format!("{scheduler:?}, {threads:?} threads, delay {delay}");

    let size = match scheduler {
        Scheduler::None => width.max(height),
        Scheduler::Tile { size, .. } | Scheduler::Queue { size, .. } => size,
    };
    let grid = TileGrid::new(width, height, size);
    let mut started: Vec<_> = outputs
        .iter()
        .flat_map(|(tiles, _)| tiles)
        .copied()
        .collect();
    started.sort_by_key(|tile| (tile.y0, tile.x0));
    let every_tile: Vec<_> = (0..grid.len()).map(|t| grid.tile(t)).collect();
    assert_eq!(started, every_tile, "{context}: every tile started once");
    assert_eq!(stats.tiles, grid.len() as u64, "{context}");

    let mut ended: Vec<_> = outputs.into_iter().flat_map(|(_, paths)| paths).collect();
    ended.sort_by_key(|path| path.pixel);
    let expected: Vec<_> = (0..width * height)
        .filter(|&pixel| length(pixel) > 0)
        .map(|pixel| {
            let shadows = (0..length(pixel)).filter(|&r| casts_shadow(r)).count() as u32;
            Path {
                pixel,
                remaining: 0,
                segments: length(pixel),
                lit: if blocked(pixel) { 0 } else { shadows },
                shadowed: casts_shadow(0),
            }
        })
        .collect();
    assert_eq!(ended, expected, "{context}: every path ran to its end");
    let segments: u32 = expected.iter().map(|path| path.segments).sum();
    let shadows: u32 = (0..width * height)
        .map(|pixel| (0..length(pixel)).filter(|&r| casts_shadow(r)).count() as u32)
        .sum();
    assert_eq!(stats.closest_rays, u64::from(segments), "{context}");
    assert_eq!(stats.shadow_rays, u64::from(shadows), "{context}");
    assert!(
        stats.workers >= 1 && stats.utilization() <= 1.0,
        "{context}"
    );
    if let Scheduler::Queue { .. } = scheduler {
        // The traversal thread's busy periods never overlap.
        assert!(stats.traversal <= stats.wall, "{context}: {stats:?}");
    }
    traversal.most_in_flight.into_inner()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

#[test]
fn none_and_tile_trace_every_path_once() {
    for threads in [Some(1), Some(2), None] {
        check(Scheduler::None, (13, 7), threads, false);
        for (size, merge_below) in [(1, 0.0), (3, 0.5), (4, 0.9), (64, 0.5)] {
            check(
                Scheduler::Tile { size, merge_below },
                (13, 7),
                threads,
                false,
            );
        }
    }
}

#[test]
fn queue_traces_every_path_once() {
    let shapes = [
        // One queue: every step of the run goes through it in turn.
        (1, 3, 0.5),
        (2, 1, 0.0),
        (3, 4, 0.9),
        // More queues than tiles: most stay empty.
        (8, 64, 0.5),
        (40, 5, 0.5),
    ];
    let mut most_in_flight = 0;
    for threads in [Some(1), Some(2), Some(3), None] {
        for delay in [false, true] {
            for (queues, size, merge_below) in shapes {
                let scheduler = Scheduler::Queue {
                    queues,
                    size,
                    merge_below,
                };
                let most = check(scheduler, (13, 7), threads, delay);
                assert!(queues > 1 || most <= 1, "one queue, one job at a time");
                most_in_flight = most_in_flight.max(most);
            }
        }
    }
    // With jobs answered later, the traversal thread keeps several queues' jobs in flight.
    assert!(most_in_flight > 1);
}

#[test]
fn queue_counts_its_threads_and_queues() {
    let traversal = FakeTraversal::new(None);
    let scheduler = Scheduler::Queue {
        queues: 3,
        size: 4,
        merge_below: 0.5,
    };
    let new_wave = || FakeWave::new(16, None);
    let (_, stats) =
        pool(2).install(|| run(scheduler, (16, 16), &traversal, &StopFlag::new(), new_wave));
    assert_eq!((stats.workers, stats.queues), (2, 3));
    assert!(stats.traversal <= stats.wall && stats.traversal_share() == stats.traversal);
    assert!(stats.peak_paths > 0 && stats.peak_paths <= 2 * 16);
}

#[test]
fn a_panicking_wavefront_stops_the_queue_scheduler() {
    for threads in [1, 2] {
        let traversal = FakeTraversal::new(None);
        let scheduler = Scheduler::Queue {
            queues: 3,
            size: 2,
            merge_below: 0.0,
        };
        let new_wave = || FakeWave::new(8, Some(37));
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool(threads).install(|| run(scheduler, (8, 8), &traversal, &StopFlag::new(), new_wave))
        }));
        let panic = result.expect_err("the panic comes out of run");
        let message = panic
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| panic.downcast_ref::<&str>().copied())
            .unwrap_or_default();
        assert!(message.contains("shading panics"), "{message}");
    }
}

#[test]
fn queue_memory_follows_the_paths_in_flight() {
    let traversal = FakeTraversal::new(None);
    let new_wave = || FakeWave::new(32, None);
    let memory = |scheduler| {
        let (_, stats) =
            pool(2).install(|| run(scheduler, (32, 32), &traversal, &StopFlag::new(), new_wave));
        assert!(stats.peak_queue_bytes > 0, "{scheduler:?}");
        assert!(stats.queue_memory() >= stats.peak_queue_bytes);
        stats.queue_memory()
    };
    // One batch holds all 1024 paths at once; 4-pixel tiles hold at most a tile and a half
    // per worker, a queue pool of 3 at most that per queue.
    let one_batch = memory(Scheduler::None);
    let tiles = memory(Scheduler::Tile {
        size: 4,
        merge_below: 0.5,
    });
    let queues = memory(Scheduler::Queue {
        queues: 3,
        size: 4,
        merge_below: 0.5,
    });
    assert!(
        tiles * 8 < one_batch,
        "tiles {tiles} vs one batch {one_batch}"
    );
    assert!(
        queues * 8 < one_batch,
        "queues {queues} vs one batch {one_batch}"
    );
    // A pool far larger than the image's 4 tiles: only the queues that started a tile count,
    // each holding at most a tile and a half.
    let many_queues = memory(Scheduler::Queue {
        queues: 100_000,
        size: 16,
        merge_below: 0.5,
    });
    assert!(
        many_queues < 2 * one_batch,
        "100,000 queues {many_queues} vs one batch {one_batch}"
    );
}

/// Counts the traversal calls made from a thread outside every rayon pool.
struct OffPoolCalls(FakeTraversal, AtomicUsize);

impl OffPoolCalls {
    fn note(&self) {
        if rayon::current_thread_index().is_none() {
            self.1.fetch_add(1, Ordering::SeqCst);
        }
    }
}

impl Traversal for OffPoolCalls {
    fn intersect(&self, rays: &RayBatch, hits: &mut HitBatch) {
        self.note();
        self.0.intersect(rays, hits);
    }

    fn occluded(&self, rays: &RayBatch, occluded: &mut Vec<bool>) {
        self.note();
        self.0.occluded(rays, occluded);
    }
}

#[test]
fn none_and_tile_workers_run_on_the_pool_when_called_from_outside_it() {
    // A worker on the calling thread would hand every parallel loop of the backend and
    // the shading to the pool and sleep until it came back, once per batch.
    let tile = Scheduler::Tile {
        size: 64,
        merge_below: 0.5,
    };
    for scheduler in [Scheduler::None, tile] {
        let traversal = OffPoolCalls(FakeTraversal::new(None), AtomicUsize::new(0));
        let (outputs, _) = run(scheduler, (13, 7), &traversal, &StopFlag::new(), || {
            FakeWave::new(13, None)
        });
        assert_eq!(outputs.len(), 1, "{scheduler:?}: one worker for one tile");
        assert_eq!(traversal.1.into_inner(), 0, "{scheduler:?}");
    }
}

#[test]
fn a_stop_request_ends_a_pass_between_tiles_and_passes() {
    let tile = Scheduler::Tile {
        size: 4,
        merge_below: 0.5,
    };
    let queue = Scheduler::Queue {
        queues: 3,
        size: 4,
        merge_below: 0.5,
    };
    for scheduler in [Scheduler::None, tile, queue] {
        let traversal = FakeTraversal::new(None);
        let new_wave = || FakeWave::new(64, None);
        // Raised before the pass: no tile starts.
        let stop = StopFlag::new();
        stop.raise();
        let (_, stats) = pool(2).install(|| run(scheduler, (64, 64), &traversal, &stop, new_wave));
        assert_eq!(stats.tiles, 0, "{scheduler:?}");
        // Raised by the first shading call: the pass ends without starting every tile (the
        // `none` scheduler's one tile is the image, so it ends right after that shading,
        // before tracing its shadow rays).
        let stop = StopFlag::new();
        let raising_wave = || StopAfterShading(FakeWave::new(64, None), stop.clone());
        let (_, stats) =
            pool(2).install(|| run(scheduler, (64, 64), &traversal, &stop, raising_wave));
        assert!(stats.tiles < 256, "{scheduler:?}: {} tiles", stats.tiles);
        assert!(stats.closest_rays > 0, "{scheduler:?}");
        if scheduler == Scheduler::None {
            assert!(
                stats.closest_rays <= 64 * 64,
                "at most one segment per path"
            );
            assert_eq!(stats.shadow_rays, 0, "no step after the shading");
        }
    }
}

/// A wavefront that raises a stop flag when it first shades.
struct StopAfterShading(FakeWave, StopFlag);

impl Wavefront for StopAfterShading {
    type Output = Output;

    fn start(&mut self, tile: Tile) {
        self.0.start(tile)
    }

    fn active(&self) -> usize {
        self.0.active()
    }

    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }

    fn extension_rays(&self, rays: &mut RayBatch) {
        self.0.extension_rays(rays)
    }

    fn shade(&mut self, hits: &HitBatch, shadow_rays: &mut RayBatch) {
        self.1.raise();
        self.0.shade(hits, shadow_rays)
    }

    fn resolve(&mut self, occluded: &[bool]) {
        self.0.resolve(occluded)
    }

    fn finish(self) -> Output {
        self.0.finish()
    }
}

#[test]
fn the_paths_in_flight_stay_within_the_bound_for_memory_budgets() {
    let schedulers = [
        Scheduler::None,
        Scheduler::Tile {
            size: 4,
            merge_below: 0.5,
        },
        Scheduler::Tile {
            size: 3,
            merge_below: 0.9,
        },
        Scheduler::Queue {
            queues: 2,
            size: 4,
            merge_below: 0.5,
        },
    ];
    for scheduler in schedulers {
        pool(2).install(|| {
            let bound = scheduler.most_paths_in_flight((13, 7), 1);
            let traversal = FakeTraversal::new(None);
            let new_wave = || FakeWave::new(13, None);
            let (_, stats) = run(scheduler, (13, 7), &traversal, &StopFlag::new(), new_wave);
            assert!(
                stats.peak_paths as u64 <= bound,
                "{scheduler:?}: {} paths in flight, bound {bound}",
                stats.peak_paths
            );
        });
    }
    // Two workers, each with a tile of 16 paths and the 8 below which it merges the next.
    let tiles = Scheduler::Tile {
        size: 4,
        merge_below: 0.5,
    };
    assert_eq!(
        pool(2).install(|| tiles.most_paths_in_flight((100, 100), 1)),
        48
    );
    // Three queues of 2 × 64 paths and 32 more.
    let queues = Scheduler::Queue {
        queues: 3,
        size: 8,
        merge_below: 0.5,
    };
    assert_eq!(queues.most_paths_in_flight((100, 100), 2), 480);
    // Never more than the whole image, however large the tiles.
    assert_eq!(Scheduler::None.most_paths_in_flight((13, 7), 3), 273);
    let huge = Scheduler::Tile {
        size: u32::MAX,
        merge_below: 1e30,
    };
    assert_eq!(huge.most_paths_in_flight((13, 7), 1), 91);
}
