//! A stop request ends the frame in progress whatever the scheduler, dropping it whole.

use std::sync::mpsc;
use std::time::Duration;

use vcm::{Algorithm, Film, Schedule, Scheduler, StopFlag};

use crate::common;

/// Side of the image: with 16 samples per frame, 10⁶ paths, a frame of seconds on 2 cores.
const SIZE: u32 = 256;
const SAMPLES_PER_FRAME: u32 = 16;

#[test]
fn a_stop_during_a_frame_drops_it_with_every_scheduler() {
    let scene = common::scene_file("cornell-box.gltf");
    let schedulers = [
        Scheduler::None,
        Scheduler::default(),
        Scheduler::Queue {
            queues: 3,
            size: 32,
            merge_below: 0.5,
        },
    ];
    for algorithm in [None, Some(Algorithm::Bpt), Some(Algorithm::Vcm)] {
        for scheduler in schedulers {
            let mut integrator = common::integrator(&scene, algorithm, SIZE, 1, 0.01);
            let schedule = Schedule {
                scheduler,
                samples_per_frame: SAMPLES_PER_FRAME,
            };
            integrator.set_schedule(schedule).unwrap();
            let stop = StopFlag::new();
            integrator.set_stop(stop.clone());
            // The frame runs on its own thread, so that one that never ends fails the test
            // instead of hanging it.
            let (sender, receiver) = mpsc::channel();
            std::thread::spawn(move || {
                let mut film = Film::new(SIZE, SIZE);
                let stats = integrator.render_frame(&mut film, 0);
                let untouched = (0..(SIZE * SIZE) as usize).all(|pixel| film.samples(pixel) == 0);
                sender.send((stats.interrupted, untouched))
            });
            std::thread::sleep(Duration::from_millis(20));
            stop.raise();
            let ended = receiver.recv_timeout(Duration::from_secs(60));
            let case = format!("{algorithm:?}, {scheduler:?}");
            let (interrupted, untouched) = ended.unwrap_or_else(|_| {
                panic!("{case}: the frame did not end within 60 s of the stop request")
            });
            assert!(
                interrupted,
                "{case}: the frame ended before the stop request"
            );
            assert!(untouched, "{case}: the dropped frame added to the film");
        }
    }
}
