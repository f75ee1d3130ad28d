//! The progressive render loop: frames until a sample count or a time budget is reached, with
//! the error against a reference recorded at 1, 2, 4, … seconds and at the end.

use std::time::{Duration, Instant};

use anyhow::bail;
use glam::Vec3;
use vcm::metrics::{ErrorMetrics, compare};
use vcm::{Film, FrameStats, Integrator, StopFlag};
use vcm_rs::frames::{FrameCounts, Frames, Remaining};

use crate::process::cpu_seconds;

/// When to stop rendering.
#[derive(Clone, Copy, Debug)]
pub enum Budget {
    /// This many samples per pixel.
    Samples(u32),
    /// This many seconds of wall-clock time.
    Seconds(f64),
}

impl Budget {
    /// The budget of `--spp` / `--time` (16 samples when neither is given).
    pub fn from_options(spp: Option<u32>, time: Option<f64>) -> anyhow::Result<Budget> {
        Ok(match (spp, time) {
            (_, Some(t)) if !(t.is_finite() && t > 0.0) => {
                bail!("--time must be a positive number of seconds")
            }
            (_, Some(t)) => Budget::Seconds(t),
            (Some(0), _) => bail!("--spp must be at least 1"),
            (spp, None) => Budget::Samples(spp.unwrap_or(16)),
        })
    }

    fn done(&self, spp: u32, elapsed: Duration) -> bool {
        match *self {
            Budget::Samples(n) => spp >= n,
            Budget::Seconds(s) => elapsed.as_secs_f64() >= s,
        }
    }

    /// What is left of the budget after `spp` samples per pixel and `elapsed`.
    fn remaining(&self, spp: u32, elapsed: Duration) -> Remaining {
        match *self {
            Budget::Samples(n) => Remaining {
                samples: Some(n.saturating_sub(spp)),
                time: None,
            },
            Budget::Seconds(s) => Remaining {
                samples: None,
                time: Some(Duration::from_secs_f64(s).saturating_sub(elapsed)),
            },
        }
    }

    fn progress_bar(&self) -> indicatif::ProgressBar {
        let (length, template) = match *self {
            Budget::Samples(n) => (
                u64::from(n),
                "{bar:40} {pos}/{len} spp, {elapsed} elapsed, {eta} left",
            ),
            Budget::Seconds(s) => ((s * 10.0) as u64, "{bar:40} {elapsed} of the time budget"),
        };
        let bar = indicatif::ProgressBar::new(length);
        if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
            bar.set_style(style);
        }
        bar
    }
}

/// Shortest interval CPU utilization is measured over: 25 ticks of the process's CPU clock.
pub const UTILIZATION_INTERVAL: f64 = 0.25;

/// One row of the convergence report.
pub struct Checkpoint {
    /// Seconds since the render started.
    pub seconds: f64,
    /// Samples per pixel so far.
    pub spp: u32,
    /// Error of the running mean against the reference.
    pub metrics: ErrorMetrics,
}

impl Checkpoint {
    /// `seconds,spp,rmse,relmse,mae` as a CSV row (no line break).
    pub fn csv_row(&self) -> String {
        let m = &self.metrics;
        format!(
            "{:.3},{},{:.6e},{:.6e},{:.6e}",
            self.seconds, self.spp, m.rmse, m.relmse, m.mae
        )
    }
}

/// What a progressive render did.
pub struct Outcome {
    /// Samples per pixel rendered.
    pub spp: u32,
    /// The frames they came in.
    pub frames: FrameCounts,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Work summed over all frames.
    pub totals: FrameStats,
    /// The error over time (empty without a reference).
    pub checkpoints: Vec<Checkpoint>,
    /// (seconds, CPU utilization as a fraction of all worker threads) over intervals of
    /// whole frames at least [`UTILIZATION_INTERVAL`] long; empty where the CPU time is
    /// unknown.
    pub utilization: Vec<(f64, f64)>,
    /// CPU utilization over the whole render as a fraction of all worker threads; `None`
    /// where the CPU time is unknown.
    pub mean_utilization: Option<f64>,
}

/// Something to do with the film every so often while rendering (write a checkpoint).
pub struct Periodic<'a> {
    /// At least this long between two calls.
    pub every: Duration,
    /// Called after a whole frame with the film and the samples per pixel rendered so far.
    pub action: &'a mut dyn FnMut(&Film, u32) -> anyhow::Result<()>,
}

/// Renders `frames` into `film` until `budget` is spent or `stop` is raised (which also cuts
/// the frame in progress short, dropping it whole), calling `periodic` between frames.
pub fn render(
    integrator: &mut dyn Integrator,
    mut frames: Frames,
    film: &mut Film,
    budget: Budget,
    reference: Option<&[Vec3]>,
    stop: &StopFlag,
    mut periodic: Option<Periodic<'_>>,
) -> anyhow::Result<Outcome> {
    integrator.set_stop(stop.clone());
    let progress = budget.progress_bar();
    let mut totals = FrameStats::default();
    let mut checkpoints = Vec::new();
    let mut next_checkpoint = 1.0;
    let mut utilization = Vec::new();
    let threads = rayon::current_num_threads() as f64;
    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let mut frame_start = (0.0, cpu_start);
    let mut last_periodic = Instant::now();
    while !budget.done(frames.samples(), start.elapsed()) && !stop.is_raised() {
        let remaining = budget.remaining(frames.samples(), start.elapsed());
        let stats = frames.render_next(integrator, film, remaining)?;
        if stats.interrupted {
            break;
        }
        totals.accumulate(&stats);
        let spp = frames.samples();
        if let Some(periodic) = &mut periodic
            && last_periodic.elapsed() >= periodic.every
        {
            (periodic.action)(film, spp)?;
            last_periodic = Instant::now();
        }
        let seconds = start.elapsed().as_secs_f64();
        if seconds - frame_start.0 >= UTILIZATION_INTERVAL {
            let frame_end = (seconds, cpu_seconds());
            if let ((t0, Some(cpu0)), (t1, Some(cpu1))) = (frame_start, frame_end) {
                utilization.push((t1, (cpu1 - cpu0) / ((t1 - t0) * threads)));
            }
            frame_start = frame_end;
        }
        progress.set_position(match budget {
            Budget::Samples(_) => u64::from(spp),
            Budget::Seconds(_) => (seconds * 10.0) as u64,
        });
        if let Some(reference) = reference
            && seconds >= next_checkpoint
        {
            checkpoints.push(checkpoint(film, reference, seconds, spp));
            while next_checkpoint <= seconds {
                next_checkpoint *= 2.0;
            }
        }
    }
    progress.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let mean_utilization = cpu_seconds()
        .zip(cpu_start)
        .map(|(end, begin)| (end - begin) / (seconds.max(1e-9) * threads));
    let spp = frames.samples();
    if let Some(reference) = reference {
        checkpoints.push(checkpoint(film, reference, seconds, spp));
    }
    Ok(Outcome {
        spp,
        frames: frames.counts(),
        seconds,
        totals,
        checkpoints,
        utilization,
        mean_utilization,
    })
}

fn checkpoint(film: &Film, reference: &[Vec3], seconds: f64, spp: u32) -> Checkpoint {
    let metrics = compare(&film.mean(), reference).expect("sizes were checked when loading");
    Checkpoint {
        seconds,
        spp,
        metrics,
    }
}
