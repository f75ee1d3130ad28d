//! A render is a pure function of (scene, settings, seed, samples): the same film, bit for
//! bit, for any number of threads, any scheduler and any frame sizes.

use glam::Vec3;
use vcm::{Algorithm, Film, Integrator, MergeRadius, PtSettings, Schedule, Scheduler, VcmSettings};
use vcm_scene::Material;
use vcm_scene::light::{Light, PointLight};

use crate::common;

/// [`render_frames`]: 4 frames of `schedule`.
fn render(threads: usize, algorithm: Option<Algorithm>, schedule: Schedule) -> Film {
    let sizes = [schedule.samples_per_frame; 4];
    render_frames(threads, algorithm, schedule.scheduler, &sizes)
}

/// A diffuse floor, a rough metal wall, a one-sided area light facing down and a point light,
/// rendered by `algorithm` (`None`: the path tracer) on `threads` threads with `scheduler`,
/// in frames of `sizes` samples per pixel.
fn render_frames(
    threads: usize,
    algorithm: Option<Algorithm>,
    scheduler: Scheduler,
    sizes: &[u32],
) -> Film {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    let quads = [
        [
            (-2.0, -2.0, 0.0),
            (2.0, -2.0, 0.0),
            (2.0, 2.0, 0.0),
            (-2.0, 2.0, 0.0),
        ],
        [
            (-2.0, 2.0, 0.0),
            (2.0, 2.0, 0.0),
            (2.0, 2.0, 3.0),
            (-2.0, 2.0, 3.0),
        ],
        [
            (-0.5, -0.5, 2.0),
            (-0.5, 0.5, 2.0),
            (0.5, 0.5, 2.0),
            (0.5, -0.5, 2.0),
        ],
    ];
    for quad in quads {
        let corners = quad.map(|(x, y, z)| Vec3::new(x, y, z));
        common::push_quad(&mut positions, &mut triangles, corners);
    }
    let lamp = Material {
        emission: Vec3::new(5.0, 4.0, 3.0),
        ..Material::diffuse("lamp", Vec3::ZERO)
    };
    let scene = common::scene(
        common::mesh(positions, triangles, vec![0, 0, 1, 1, 2, 2]),
        vec![
            Material::diffuse("floor", Vec3::splat(0.7)),
            Material {
                metallic: 1.0,
                roughness: 0.4,
                ..Material::diffuse("wall", Vec3::new(0.9, 0.6, 0.3))
            },
            lamp,
        ],
        vec![Light::Point(PointLight {
            position: Vec3::new(1.0, -1.0, 1.0),
            intensity: Vec3::splat(2.0),
        })],
        common::camera(Vec3::new(0.0, -1.0, 6.0), 0.9),
    );
    // The default, stratified samples.
    let settings = PtSettings {
        seed: 3,
        ..PtSettings::new(24, 16)
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut integrator: Box<dyn Integrator> = match algorithm {
            None => Box::new(common::path_tracer(scene, settings)),
            Some(algorithm) => {
                let settings = VcmSettings {
                    seed: settings.seed,
                    // Large enough that merges happen on 384 light paths a frame.
                    radius: MergeRadius::SceneFraction(0.05),
                    ..VcmSettings::new(algorithm, settings.width, settings.height)
                };
                Box::new(common::vcm(scene, settings))
            }
        };
        let mut film = Film::new(settings.width, settings.height);
        let mut first_sample = 0;
        for &samples_per_frame in sizes {
            let schedule = Schedule {
                scheduler,
                samples_per_frame,
            };
            integrator.set_schedule(schedule).unwrap();
            integrator.render_frame(&mut film, first_sample);
            first_sample += samples_per_frame;
        }
        film
    })
}

/// Queue schedulers: one queue, a few with small tiles (many tiles, merging), more queues
/// than tiles.
const QUEUES: [Scheduler; 3] = [
    Scheduler::Queue {
        queues: 1,
        size: 5,
        merge_below: 0.5,
    },
    Scheduler::Queue {
        queues: 3,
        size: 3,
        merge_below: 0.9,
    },
    Scheduler::Queue {
        queues: 8,
        size: 16,
        merge_below: 0.0,
    },
];

#[test]
fn films_are_bit_identical_for_one_and_two_threads() {
    let algorithms = common::EVERY_ALGORITHM;
    for algorithm in algorithms {
        let schedule = match algorithm {
            None => Schedule::default(),
            Some(_) => Schedule::ONE_BATCH,
        };
        let (one, two) = (
            render(1, algorithm, schedule),
            render(2, algorithm, schedule),
        );
        assert!(one.mean().iter().any(|rgb| rgb.max_element() > 0.0));
        // Film equality compares the f64 sums exactly.
        assert!(one == two, "{algorithm:?} differs between 1 and 2 threads");
    }
}

#[test]
fn path_tracer_films_are_bit_identical_under_every_scheduler() {
    let schedule = |scheduler| Schedule {
        scheduler,
        samples_per_frame: 3,
    };
    let reference = render(1, None, schedule(Scheduler::None));
    assert!(reference.mean().iter().any(|rgb| rgb.max_element() > 0.0));
    let tiles = [(5, 0.5), (7, 0.0), (64, 0.9), (1, 0.5)];
    let schedulers = tiles
        .map(|(size, merge_below)| Scheduler::Tile { size, merge_below })
        .into_iter()
        .chain(QUEUES);
    for threads in [1, 2] {
        for scheduler in schedulers.clone() {
            let film = render(threads, None, schedule(scheduler));
            assert!(
                film == reference,
                "{scheduler:?} on {threads} threads differs"
            );
        }
    }
}

#[test]
fn vcm_family_films_are_bit_identical_under_every_scheduler() {
    let schedule = |scheduler| Schedule {
        scheduler,
        samples_per_frame: 1,
    };
    // Tiles of 1 and 5 pixels split the light paths of one frame over many wavefronts, so
    // the light vertex cache and the splats are gathered from all of them.
    let tiles = [(5, 0.5), (1, 0.0), (64, 0.9)];
    let schedulers = tiles
        .map(|(size, merge_below)| Scheduler::Tile { size, merge_below })
        .into_iter()
        .chain(QUEUES);
    for algorithm in common::EVERY_ALGORITHM.into_iter().flatten() {
        let reference = render(1, Some(algorithm), Schedule::ONE_BATCH);
        for threads in [1, 2] {
            for scheduler in schedulers.clone() {
                let film = render(threads, Some(algorithm), schedule(scheduler));
                assert!(
                    film == reference,
                    "{algorithm:?}: {scheduler:?} on {threads} threads differs"
                );
            }
        }
    }
}

#[test]
fn films_are_the_same_for_any_frame_sizes() {
    // Sample s is the same path (and, for the VCM family, iteration s with its own cache,
    // grid and radius) whatever frame renders it, and each pixel's samples (and each
    // iteration's splats) are added in sample order: frames of 2 + 2, 4, or 1 + 2 + 1 samples
    // add exactly what four frames of 1 do, as paced frames of changing size need.
    let tiles = |size, merge_below| Scheduler::Tile { size, merge_below };
    let queues = Scheduler::Queue {
        queues: 2,
        size: 5,
        merge_below: 0.5,
    };
    let frames: [(&[u32], Scheduler); 5] = [
        (&[2, 2], Scheduler::None),
        (&[4], tiles(5, 0.5)),
        (&[1, 2, 1], tiles(1, 0.0)),
        (&[3, 1], tiles(64, 0.5)),
        (&[2, 2], queues),
    ];
    for algorithm in common::EVERY_ALGORITHM {
        let reference = render(1, algorithm, Schedule::ONE_BATCH);
        for (sizes, scheduler) in frames {
            for threads in [1, 2] {
                let film = render_frames(threads, algorithm, scheduler, sizes);
                assert!(
                    film == reference,
                    "{algorithm:?}: frames of {sizes:?}, {scheduler:?}, {threads} threads"
                );
            }
        }
    }
}

#[test]
fn invalid_schedules_are_rejected() {
    let bad = [
        Schedule {
            samples_per_frame: 0,
            ..Schedule::default()
        },
        Schedule {
            scheduler: Scheduler::Tile {
                size: 0,
                merge_below: 0.5,
            },
            ..Schedule::default()
        },
        Schedule {
            scheduler: Scheduler::Queue {
                queues: 2,
                size: 0,
                merge_below: 0.5,
            },
            ..Schedule::default()
        },
        Schedule {
            scheduler: Scheduler::Queue {
                queues: 0,
                size: 8,
                merge_below: 0.5,
            },
            ..Schedule::default()
        },
        Schedule {
            scheduler: Scheduler::Tile {
                size: 8,
                merge_below: f32::NAN,
            },
            ..Schedule::default()
        },
        Schedule {
            scheduler: Scheduler::Queue {
                queues: 2,
                size: 8,
                merge_below: 2.0,
            },
            ..Schedule::default()
        },
    ];
    for schedule in bad {
        assert!(schedule.validated().is_err(), "{schedule:?}");
    }
}
