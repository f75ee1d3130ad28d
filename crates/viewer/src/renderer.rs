//! The render worker: a thread that renders the current [`Job`] frame after frame into a film
//! and publishes the running mean, so the UI thread never waits for a frame. A new job
//! replaces the current one between two frames: the accumulation restarts. A job may continue
//! a saved render state's film, and the worker hands out a copy of its film between two
//! frames ([`Renderer::request_film`]), so that a render state holds whole frames only.
//! With `auto`, the worker chooses the algorithm by pilot renders before the first frame
//! (`vcm_rs::integrators::choice`), and keeps the choice while only the camera moves.

use std::sync::mpsc::{Receiver, Sender, TryRecvError};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;
use vcm::image_io::RgbImage;
use vcm::{Film, FrameStats, Integrator, StopFlag};
use vcm_rs::integrators::choice::{self, Choice, Pilots, Unpiloted};
use vcm_rs::integrators::{Algorithm, AlgorithmOption, IntegratorOptions};
use vcm_rs::render_loop::{Frames, Remaining};
use vcm_rs::state::SampleRanges;
use vcm_rs::{Backend, BuiltTraversal, Shading};
use vcm_scene::Scene;

use crate::session::View;

/// A render to run until it is replaced.
pub struct Job {
    /// The session's generation of this render (see [`crate::session::Session`]).
    pub generation: u64,
    /// The scene as loaded; the view's camera replaces its camera.
    pub scene: Arc<Scene>,
    /// Settings, camera and image size.
    pub view: View,
    /// Stop after this many frames; `None`: render until replaced.
    pub frame_limit: Option<u32>,
    /// The film to continue (a render state's), instead of an empty one.
    pub resume: Option<Box<Resume>>,
}

/// A render to continue: its film and the global samples (iterations) it holds. The job
/// renders on from the sample after the last one held, so the film grows exactly as the
/// uninterrupted render's would (see `vcm_rs::state`).
#[derive(Clone, Debug)]
pub struct Resume {
    /// The accumulated samples and splats, of the job's image size.
    pub film: Film,
    /// The global samples the film holds.
    pub samples: SampleRanges,
}

/// A copy of a render's film after its last whole frame, and the global samples it holds.
#[derive(Clone, Debug)]
pub struct FilmCopy {
    /// The job's generation.
    pub generation: u64,
    /// The film.
    pub film: Film,
    /// The global samples in it: those the job continued from and those it rendered since.
    pub samples: SampleRanges,
}

/// What the UI asks of the worker.
enum Request {
    /// Render this job instead of the current one.
    Job(Job),
    /// Send a copy of the current render's film here (between two frames). Dropped
    /// unanswered when there is no render to copy.
    Film(Sender<FilmCopy>),
}

/// The state of a render after some frames.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// The job's generation.
    pub generation: u64,
    /// Image (width, height) in pixels.
    pub size: (u32, u32),
    /// The algorithm rendering (with `auto`, the one chosen).
    pub algorithm: Algorithm,
    /// With `auto`, how the algorithm was chosen (pilots and their time, or why none ran).
    pub chosen: Option<String>,
    /// Mean radiance per pixel (W·sr⁻¹·m⁻², RGB), row by row from the top left.
    pub mean: Vec<Vec3>,
    /// Samples per pixel rendered by this job.
    pub spp: u32,
    /// Samples per pixel the job continued from (a render state's), 0 for a new render.
    pub resumed_spp: u64,
    /// Time spent rendering frames since the job started.
    pub elapsed: Duration,
    /// Rays and times summed over the frames.
    pub totals: FrameStats,
    /// Non-finite samples dropped.
    pub dropped: u64,
    /// relMSE of the mean against the reference, when there is one of this size.
    pub relmse: Option<f64>,
}

/// What the worker reports.
#[derive(Clone, Debug)]
pub enum Update {
    /// New frames of a render (boxed: a snapshot is many times the size of a failure).
    Frames(Box<Snapshot>),
    /// A render could not start (the BVH or the integrator could not be built).
    Failed {
        /// The job's generation.
        generation: u64,
        /// What went wrong.
        message: String,
    },
}

/// The handle of the render worker thread; dropping it stops the thread after its frame.
pub struct Renderer {
    requests: Option<Sender<Request>>,
    latest: Arc<Mutex<Option<Update>>>,
    thread: Option<JoinHandle<()>>,
}

impl Renderer {
    /// Starts the worker. It measures relMSE against `reference` when a render has its size,
    /// and calls `notify` after every update (to wake the UI).
    pub fn spawn(
        reference: Option<RgbImage>,
        notify: impl Fn() + Send + 'static,
    ) -> std::io::Result<Renderer> {
        let (jobs, inbox) = std::sync::mpsc::channel();
        let latest = Arc::new(Mutex::new(None));
        let worker = Worker {
            latest: Arc::clone(&latest),
            notify: Box::new(notify),
            reference,
            traversal: None,
            choices: Vec::new(),
        };
        let thread = std::thread::Builder::new()
            .name("render worker".into())
            .spawn(move || worker.run(&inbox))?;
        Ok(Renderer {
            requests: Some(jobs),
            latest,
            thread: Some(thread),
        })
    }

    /// Replaces the current render with `job` (after the frame in progress).
    pub fn submit(&self, job: Job) {
        self.send(Request::Job(job));
    }

    /// Asks for a copy of the current render's film, taken after the frame in progress (or
    /// at once when the render has reached its frame limit); the UI is notified when it is
    /// there. The sender is dropped unanswered when there is no render (none started, or it
    /// failed) or a newer job was submitted before.
    pub fn request_film(&self) -> Receiver<FilmCopy> {
        let (reply, copy) = std::sync::mpsc::channel();
        self.send(Request::Film(reply));
        copy
    }

    fn send(&self, request: Request) {
        if let Some(requests) = &self.requests {
            // Sending fails only when the worker has ended, which it does only when dropped.
            let _ = requests.send(request);
        }
    }

    /// The latest update since the last call, if any.
    pub fn take_update(&self) -> Option<Update> {
        self.latest
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        self.requests = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The scene's BVH, kept while jobs render the same scene on the same backend.
struct CachedTraversal {
    scene: Arc<Scene>,
    backend: Backend,
    built: BuiltTraversal,
}

/// The worker thread's state.
struct Worker {
    latest: Arc<Mutex<Option<Update>>>,
    notify: Box<dyn Fn() + Send>,
    reference: Option<RgbImage>,
    traversal: Option<CachedTraversal>,
    /// The latest `auto` choices, newest last (at most [`KEPT_CHOICES`]).
    choices: Vec<(ChoiceKey, Algorithm, String)>,
}

/// `auto` choices kept: those of the full-size render and its preview while the camera
/// moves, and a few settings before.
const KEPT_CHOICES: usize = 8;

/// What an `auto` choice is kept for: the scene as loaded (its serial number in the session,
/// whatever the camera), the backend, the integrator's options and the image size.
#[derive(PartialEq)]
struct ChoiceKey {
    scene: u64,
    backend: Backend,
    shading: Shading,
    options: IntegratorOptions,
    size: (u32, u32),
}

/// How `choice` was made, in a few words for the statistics panel.
fn describe(choice: &Choice) -> String {
    let (width, height) = choice.pilot_size;
    match choice.unpiloted {
        Some(Unpiloted::SmallImage) => "auto: too small an image for pilots".into(),
        Some(Unpiloted::OnlyMergingFindsAllLight) => {
            "auto: only merging finds all of the light".into()
        }
        None => format!(
            "auto: pilots at {width}×{height}, {:.2} s",
            choice.time().as_secs_f64()
        ),
    }
}

/// A job's integrator, ready to render.
struct Started {
    integrator: Box<dyn Integrator>,
    /// The algorithm it renders.
    algorithm: Algorithm,
    /// With `auto`, how the algorithm was chosen.
    chosen: Option<String>,
}

/// Why a render stopped.
enum Next {
    /// A new job replaced it (boxed: a job is far larger than `Quit`).
    Job(Box<Job>),
    /// The renderer was dropped.
    Quit,
}

impl Worker {
    fn run(mut self, inbox: &Receiver<Request>) {
        let mut next = wait_for_job(inbox);
        while let Next::Job(job) = next {
            next = match self.start(&job) {
                Ok(started) => self.render(*job, started, inbox),
                Err(message) => {
                    self.publish(Update::Failed {
                        generation: job.generation,
                        message,
                    });
                    wait_for_job(inbox)
                }
            };
        }
    }

    /// Builds (or reuses) the BVH of `job`, settles its algorithm and builds its integrator.
    fn start(&mut self, job: &Job) -> Result<Started, String> {
        let settings = &job.view.settings;
        let built = self.traversal(&job.scene, settings.backend)?;
        let scene = if job.scene.camera == job.view.camera {
            Arc::clone(&job.scene)
        } else {
            Arc::new(Scene {
                camera: job.view.camera,
                ..Scene::clone(&job.scene)
            })
        };
        let (algorithm, chosen) = match settings.algorithm {
            AlgorithmOption::Fixed(algorithm) => (algorithm, None),
            AlgorithmOption::Auto => {
                let (algorithm, how) = self.choose(job, &scene, &built)?;
                (algorithm, Some(how))
            }
        };
        let name = algorithm.name();
        let integrator = Frames::new(settings.schedule, settings.backend)
            .shaded_integrator(
                (algorithm, settings.shading),
                &scene,
                &built,
                job.view.size,
                &settings.integrator,
                None,
            )
            .map_err(|e| format!("cannot start {name}: {e}"))?;
        Ok(Started {
            integrator,
            algorithm,
            chosen,
        })
    }

    /// The algorithm `auto` renders `job` with, and how it was chosen: kept from an earlier
    /// job of the same scene, backend, options and size (a moved camera does not choose
    /// again), else chosen by pilots on `scene` (the job's camera). The pilots run to their
    /// end: a job that replaces this one waits for them (a few seconds at most).
    fn choose(
        &mut self,
        job: &Job,
        scene: &Arc<Scene>,
        built: &BuiltTraversal,
    ) -> Result<(Algorithm, String), String> {
        let settings = &job.view.settings;
        let key = ChoiceKey {
            scene: job.view.scene,
            backend: settings.backend,
            shading: settings.shading,
            options: settings.integrator.clone(),
            size: job.view.size,
        };
        if let Some((_, algorithm, how)) = self.choices.iter().find(|(kept, ..)| *kept == key) {
            return Ok((*algorithm, format!("{how} (kept)")));
        }
        let pilots = Pilots::of(built, settings.shading)
            .map_err(|e| format!("cannot choose the algorithm: {e}"))?;
        let choice = choice::choose(
            scene,
            pilots,
            job.view.size,
            &settings.integrator,
            &StopFlag::default(),
        )
        .map_err(|e| format!("cannot choose the algorithm: {e}"))?;
        let how = describe(&choice);
        if self.choices.len() == KEPT_CHOICES {
            self.choices.remove(0);
        }
        self.choices.push((key, choice.algorithm, how.clone()));
        Ok((choice.algorithm, how))
    }

    /// The scene's BVH on `backend` (with the GPU backend's hierarchy), built or kept.
    fn traversal(
        &mut self,
        scene: &Arc<Scene>,
        backend: Backend,
    ) -> Result<BuiltTraversal, String> {
        if let Some(cached) = &self.traversal
            && Arc::ptr_eq(&cached.scene, scene)
            && cached.backend == backend
        {
            return Ok(cached.built.clone());
        }
        self.traversal = None;
        let built = backend.build(scene).map_err(|e| {
            format!(
                "{}: cannot build the {} BVH: {e}",
                scene.path.display(),
                backend.name()
            )
        })?;
        self.traversal = Some(CachedTraversal {
            scene: Arc::clone(scene),
            backend,
            built: built.clone(),
        });
        Ok(built)
    }

    /// Renders frames of `job` until another job arrives or the renderer is dropped; once the
    /// frame limit is reached it keeps the film (for copies) and waits.
    fn render(&self, job: Job, started: Started, inbox: &Receiver<Request>) -> Next {
        let Started {
            mut integrator,
            algorithm,
            chosen,
        } = started;
        let (width, height) = job.view.size;
        let settings = &job.view.settings;
        let Resume {
            mut film,
            samples: held,
        } = job.resume.map_or_else(
            || Resume {
                film: Film::new(width, height),
                samples: SampleRanges::new(),
            },
            |resume| *resume,
        );
        if (film.width(), film.height()) != (width, height) {
            self.publish(Update::Failed {
                generation: job.generation,
                message: format!(
                    "cannot continue a {}×{} film at {width}×{height}",
                    film.width(),
                    film.height()
                ),
            });
            return wait_for_job(inbox);
        }
        let mut totals = FrameStats::default();
        let mut elapsed = Duration::ZERO;
        let mut frames = Frames::new(settings.schedule, settings.backend).starting_at(held.end());
        let snapshot = |film: &Film, frames: &Frames, totals: FrameStats, elapsed: Duration| {
            let mean = film.mean();
            Snapshot {
                generation: job.generation,
                size: job.view.size,
                algorithm,
                chosen: chosen.clone(),
                relmse: self.relmse(job.view.size, &mean),
                mean,
                spp: frames.samples(),
                resumed_spp: held.count(),
                elapsed,
                totals,
                dropped: film.dropped(),
            }
        };
        if !held.is_empty() {
            // The continued film is on screen before the first new frame.
            self.publish(Update::Frames(Box::new(snapshot(
                &film, &frames, totals, elapsed,
            ))));
        }
        loop {
            let done = job
                .frame_limit
                .is_some_and(|limit| frames.counts().count >= limit);
            let request = if done {
                inbox.recv().map_err(|_| TryRecvError::Disconnected)
            } else {
                inbox.try_recv()
            };
            match request {
                Ok(Request::Job(newer)) => return latest_job(newer, inbox),
                Ok(Request::Film(reply)) => {
                    let mut samples = held.clone();
                    samples.insert(held.end()..frames.next_sample());
                    let copy = FilmCopy {
                        generation: job.generation,
                        film: film.clone(),
                        samples,
                    };
                    // The UI may have stopped waiting: then nobody needs the copy.
                    let _ = reply.send(copy);
                    (self.notify)();
                    continue;
                }
                Err(TryRecvError::Disconnected) => return Next::Quit,
                Err(TryRecvError::Empty) => {}
            }
            let start = Instant::now();
            match frames.render_next(integrator.as_mut(), &mut film, Remaining::default()) {
                Ok(stats) => totals.accumulate(&stats),
                Err(e) => {
                    let name = algorithm.name();
                    self.publish(Update::Failed {
                        generation: job.generation,
                        message: format!("cannot schedule {name}: {e}"),
                    });
                    return wait_for_job(inbox);
                }
            }
            elapsed += start.elapsed();
            self.publish(Update::Frames(Box::new(snapshot(
                &film, &frames, totals, elapsed,
            ))));
        }
    }

    /// relMSE of `mean` against the reference, if there is one of the same size.
    fn relmse(&self, (width, height): (u32, u32), mean: &[Vec3]) -> Option<f64> {
        let reference = self.reference.as_ref()?;
        let same_size = (reference.width, reference.height) == (width as usize, height as usize);
        if !same_size {
            return None;
        }
        vcm::metrics::compare(mean, &reference.pixels).map(|m| m.relmse)
    }

    fn publish(&self, update: Update) {
        *self.latest.lock().unwrap_or_else(PoisonError::into_inner) = Some(update);
        (self.notify)();
    }
}

/// Blocks until a job arrives (the latest one, if several are queued). Requests for a film
/// meanwhile are dropped unanswered: there is none.
fn wait_for_job(inbox: &Receiver<Request>) -> Next {
    loop {
        match inbox.recv() {
            Ok(Request::Job(job)) => return latest_job(job, inbox),
            Ok(Request::Film(_)) => {}
            Err(_) => return Next::Quit,
        }
    }
}

/// `job`, or the newest job queued behind it: older ones are outdated, and so are requests
/// for their films (dropped unanswered).
fn latest_job(mut job: Job, inbox: &Receiver<Request>) -> Next {
    loop {
        match inbox.try_recv() {
            Ok(Request::Job(newer)) => job = newer,
            Ok(Request::Film(_)) => {}
            Err(TryRecvError::Empty) => return Next::Job(Box::new(job)),
            Err(TryRecvError::Disconnected) => return Next::Quit,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::ops::Range;
    use std::path::Path;
    use std::sync::mpsc;

    use vcm_rs::Shading;
    use vcm_rs::integrators::{self, Algorithm, AlgorithmOption, IntegratorOptions, MergeRadius};
    use vcm_rs::render_loop::ScheduleOptions;

    use crate::settings::RenderSettings;

    pub(crate) fn cornell_box() -> Arc<Scene> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf");
        Arc::new(Scene::load(path).unwrap())
    }

    pub(crate) fn settings(algorithm: Algorithm) -> RenderSettings {
        RenderSettings {
            algorithm: AlgorithmOption::Fixed(algorithm),
            backend: Backend::Cpu,
            shading: Shading::Cpu,
            integrator: IntegratorOptions {
                seed: 3,
                max_depth: Some(6),
                connections: 1,
                radius: MergeRadius::SceneFraction(0.01),
                alpha: 0.75,
                ..IntegratorOptions::default()
            },
            // Frames of two samples: the worker must apply the schedule.
            schedule: ScheduleOptions {
                spp_per_frame: Some(2),
                ..ScheduleOptions::default()
            },
        }
    }

    pub(crate) fn job(
        generation: u64,
        scene: &Arc<Scene>,
        size: (u32, u32),
        limit: Option<u32>,
    ) -> Job {
        Job {
            generation,
            scene: Arc::clone(scene),
            view: View {
                scene: 1,
                settings: settings(Algorithm::Vcm),
                camera: scene.camera,
                size,
            },
            frame_limit: limit,
            resume: None,
        }
    }

    /// A renderer whose updates also arrive on a channel.
    pub(crate) fn spawn(reference: Option<RgbImage>) -> (Renderer, mpsc::Receiver<()>) {
        let (sender, woken) = mpsc::channel();
        let renderer = Renderer::spawn(reference, move || {
            let _ = sender.send(());
        })
        .unwrap();
        (renderer, woken)
    }

    /// Waits (up to a minute) for an update that `accept` takes.
    pub(crate) fn wait_for<T>(
        renderer: &Renderer,
        woken: &mpsc::Receiver<()>,
        mut accept: impl FnMut(Update) -> Option<T>,
    ) -> T {
        let deadline = Instant::now() + Duration::from_secs(60);
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            let _ = woken.recv_timeout(left);
            if let Some(found) = renderer.take_update().and_then(&mut accept) {
                return found;
            }
        }
        panic!("no such update within a minute");
    }

    pub(crate) fn frames(update: Update, generation: u64, spp: u32) -> Option<Snapshot> {
        match update {
            Update::Frames(s) if s.generation == generation && s.spp >= spp => Some(*s),
            _ => None,
        }
    }

    /// For [`wait_for`]: the message of job `generation`'s failure.
    pub(crate) fn failed(update: Update, generation: u64) -> Option<String> {
        match update {
            Update::Failed {
                generation: failed,
                message,
            } if failed == generation => Some(message),
            _ => None,
        }
    }

    /// The film of `samples` rendered directly by the integrator, one sample per pixel per
    /// frame (the VCM family's frames of two samples add the same as two of one).
    pub(crate) fn direct_film(scene: &Arc<Scene>, size: (u32, u32), samples: Range<u32>) -> Film {
        let settings = settings(Algorithm::Vcm);
        let traversal = Backend::Cpu.traversal(scene).unwrap();
        let mut integrator =
            integrators::build(Algorithm::Vcm, scene, traversal, size, &settings.integrator)
                .unwrap();
        let mut film = Film::new(size.0, size.1);
        for sample in samples {
            integrator.render_frame(&mut film, sample);
        }
        film
    }

    /// The mean of `frames` frames of one sample per pixel rendered directly.
    fn direct_render(scene: &Arc<Scene>, size: (u32, u32), frames: u32) -> Vec<Vec3> {
        direct_film(scene, size, 0..frames).mean()
    }

    /// The worker's copy of its film (waits up to a minute).
    pub(crate) fn film_copy(renderer: &Renderer) -> FilmCopy {
        renderer
            .request_film()
            .recv_timeout(Duration::from_secs(60))
            .expect("a copy of the film within a minute")
    }

    #[test]
    fn auto_renders_the_algorithm_pilots_choose_and_keeps_it_while_the_camera_moves() {
        let scene = cornell_box();
        let size = (64, 64);
        let (renderer, woken) = spawn(None);
        let mut first = job(1, &scene, size, Some(1));
        first.view.settings.algorithm = AlgorithmOption::Auto;
        let options = first.view.settings.integrator.clone();
        let mut moved = first.view.clone();
        moved.camera.position.x += 0.05;
        renderer.submit(first);
        let shown = wait_for(&renderer, &woken, |u| frames(u, 1, 1));
        let traversal = Backend::Cpu.traversal(&scene).unwrap();
        let stop = StopFlag::default();
        let pilots = Pilots::Cpu(&traversal);
        let expected = choice::choose(&scene, pilots, size, &options, &stop).unwrap();
        assert_eq!(shown.algorithm, expected.algorithm);
        let chosen = shown.chosen.expect("auto says how it chose");
        assert!(chosen.starts_with("auto: pilots at 64×64"), "{chosen}");
        // The camera moved: the same algorithm, without pilots.
        let second = Job {
            generation: 2,
            view: moved,
            ..job(2, &scene, size, Some(1))
        };
        renderer.submit(second);
        let shown = wait_for(&renderer, &woken, |u| frames(u, 2, 1));
        assert_eq!(shown.algorithm, expected.algorithm);
        assert_eq!(shown.chosen, Some(format!("{chosen} (kept)")));
        // Other options choose again.
        let mut third = job(3, &scene, size, Some(1));
        third.view.settings.algorithm = AlgorithmOption::Auto;
        third.view.settings.integrator.seed += 1;
        renderer.submit(third);
        let shown = wait_for(&renderer, &woken, |u| frames(u, 3, 1));
        let chosen = shown.chosen.expect("auto says how it chose");
        assert!(!chosen.ends_with("(kept)"), "{chosen}");
        // A fixed algorithm says nothing of a choice.
        renderer.submit(job(4, &scene, size, Some(1)));
        let shown = wait_for(&renderer, &woken, |u| frames(u, 4, 1));
        assert_eq!((shown.algorithm, shown.chosen), (Algorithm::Vcm, None));
    }

    #[test]
    fn the_worker_renders_what_the_integrator_renders() {
        let scene = cornell_box();
        let (renderer, woken) = spawn(None);
        renderer.submit(job(1, &scene, (24, 16), Some(2)));
        let snapshot = wait_for(&renderer, &woken, |u| frames(u, 1, 4));
        assert_eq!(snapshot.size, (24, 16));
        assert_eq!(snapshot.mean, direct_render(&scene, (24, 16), 4));
        assert!(snapshot.totals.camera_rays == 4 * 24 * 16);
        assert_eq!(snapshot.relmse, None, "no reference");
        assert_eq!(snapshot.resumed_spp, 0);
        // The film itself, after the frame limit: exact sums, bit for bit.
        let copy = film_copy(&renderer);
        assert_eq!(
            (copy.generation, copy.samples.to_string()),
            (1, "0..4".into())
        );
        assert_eq!(copy.film, direct_film(&scene, (24, 16), 0..4));
    }

    #[test]
    fn the_worker_continues_a_film_as_the_uninterrupted_render() {
        let scene = cornell_box();
        let size = (20, 12);
        let (renderer, woken) = spawn(None);
        let resume = Resume {
            film: direct_film(&scene, size, 0..3),
            samples: SampleRanges::from_range(0..3),
        };
        // The continued film is shown before the first new frame (none here).
        let mut shown = job(1, &scene, size, Some(0));
        shown.resume = Some(Box::new(resume.clone()));
        renderer.submit(shown);
        let first = wait_for(&renderer, &woken, |u| frames(u, 1, 0));
        assert_eq!((first.spp, first.resumed_spp), (0, 3));
        assert_eq!(first.mean, resume.film.mean());
        assert_eq!(film_copy(&renderer).film, resume.film);
        // Two frames of two samples go on from sample 3.
        let mut continued = job(2, &scene, size, Some(2));
        continued.resume = Some(Box::new(resume));
        renderer.submit(continued);
        let last = wait_for(&renderer, &woken, |u| frames(u, 2, 4));
        assert_eq!((last.spp, last.resumed_spp), (4, 3));
        assert_eq!(last.totals.camera_rays, 4 * 20 * 12, "only the new samples");
        let copy = film_copy(&renderer);
        assert_eq!(copy.samples.to_string(), "0..7");
        assert_eq!(copy.film, direct_film(&scene, size, 0..7));
    }

    #[test]
    fn a_film_of_another_size_is_refused_and_copies_need_a_render() {
        let scene = cornell_box();
        let (renderer, woken) = spawn(None);
        let no_render = renderer.request_film();
        let mut wrong = job(1, &scene, (8, 8), None);
        wrong.resume = Some(Box::new(Resume {
            film: Film::new(4, 8),
            samples: SampleRanges::from_range(0..1),
        }));
        renderer.submit(wrong);
        let message = wait_for(&renderer, &woken, |u| match u {
            Update::Failed { message, .. } => Some(message),
            Update::Frames(_) => None,
        });
        assert!(
            message.contains("4×8") && message.contains("8×8"),
            "{message}"
        );
        assert!(no_render.recv().is_err(), "no render, no copy");
        let failed = renderer.request_film();
        assert!(failed.recv().is_err(), "a failed render has no film");
    }

    #[test]
    fn a_new_job_replaces_the_running_one() {
        let scene = cornell_box();
        let (renderer, woken) = spawn(None);
        renderer.submit(job(1, &scene, (32, 32), None));
        wait_for(&renderer, &woken, |u| frames(u, 1, 2));
        let mut moved = job(2, &scene, (8, 8), Some(1));
        moved.view.camera.position.y += 0.1;
        renderer.submit(moved);
        let snapshot = wait_for(&renderer, &woken, |u| frames(u, 2, 2));
        assert_eq!(snapshot.size, (8, 8));
        assert_eq!(
            snapshot.totals.camera_rays,
            2 * 8 * 8,
            "accumulation restarted"
        );
    }

    /// With GPU shading the worker renders the GPU path tracer's film (exact sums: bit for
    /// bit, whatever the frames), and VCM's too. Skipped without a graphics adapter unless
    /// VCM_REQUIRE_GPU=1.
    #[test]
    fn the_worker_shades_on_the_gpu_when_asked() {
        let scene = cornell_box();
        if vcm_rs::traversal_wgpu::device_or_skip().is_none() {
            return;
        }
        let bvh = vcm_rs::gpu_traversal(&scene).unwrap();
        let size = (16, 12);
        let (renderer, woken) = spawn(None);
        let mut gpu_job = job(1, &scene, size, Some(2));
        gpu_job.view.settings = RenderSettings {
            backend: Backend::Gpu,
            shading: Shading::Gpu,
            ..settings(Algorithm::Pt)
        };
        renderer.submit(gpu_job);
        wait_for(&renderer, &woken, |u| frames(u, 1, 4));
        let copy = film_copy(&renderer);
        let settings = settings(Algorithm::Pt);
        let mut direct =
            integrators::build_on_gpu(Algorithm::Pt, &scene, &bvh, size, &settings.integrator)
                .unwrap();
        let mut film = Film::new(size.0, size.1);
        for sample in 0..copy.samples.count() as u32 {
            direct.render_frame(&mut film, sample);
        }
        assert_eq!(copy.film, film);

        // VCM shades on the GPU too.
        let mut vcm_job = job(2, &scene, size, Some(1));
        vcm_job.view.settings.backend = Backend::Gpu;
        vcm_job.view.settings.shading = Shading::Gpu;
        renderer.submit(vcm_job);
        wait_for(&renderer, &woken, |u| frames(u, 2, 1));
        assert!(
            film_copy(&renderer)
                .film
                .mean()
                .iter()
                .any(|p| p.max_element() > 0.0)
        );
    }

    #[test]
    fn a_render_that_cannot_start_is_reported() {
        let scene = cornell_box();
        let (renderer, woken) = spawn(None);
        renderer.submit(job(5, &scene, (0, 4), None));
        let message = wait_for(&renderer, &woken, |u| failed(u, 5));
        assert!(
            message.contains("vcm") && message.contains("0×4"),
            "{message}"
        );
        // The worker goes on with the next job.
        renderer.submit(job(6, &scene, (4, 4), Some(1)));
        wait_for(&renderer, &woken, |u| frames(u, 6, 2));
    }

    #[test]
    fn relmse_is_measured_against_a_reference_of_the_same_size() {
        let scene = cornell_box();
        let reference = RgbImage {
            width: 16,
            height: 12,
            pixels: direct_render(&scene, (16, 12), 2),
        };
        let (renderer, woken) = spawn(Some(reference));
        renderer.submit(job(1, &scene, (16, 12), Some(1)));
        let same = wait_for(&renderer, &woken, |u| frames(u, 1, 2));
        assert_eq!(same.relmse, Some(0.0), "the same frames give zero error");
        renderer.submit(job(2, &scene, (12, 16), Some(1)));
        let other = wait_for(&renderer, &woken, |u| frames(u, 2, 2));
        assert_eq!(other.relmse, None, "another size has no error");
    }
}
