//! The command line's progressive render: the library's loop with a progress bar, the error
//! against a reference recorded at 1, 2, 4, … seconds and at the end, the CPU utilization and
//! periodic checkpoints.

use std::time::{Duration, Instant};

use anyhow::bail;
use glam::Vec3;
use vcm::metrics::{ErrorMetrics, compare};
use vcm::{Film, FrameStats, Integrator, StopFlag};
use vcm_rs::render_loop::{self, FrameCounts, Frames, Rendered};

pub use vcm_rs::render_loop::Budget;

use crate::process::cpu_seconds;

/// The budget of `--spp` / `--time` (16 samples when neither is given).
pub fn budget_from_options(spp: Option<u32>, time: Option<f64>) -> anyhow::Result<Budget> {
    Ok(match (spp, time) {
        (_, Some(t)) if !(t.is_finite() && t > 0.0) => {
            bail!("--time must be a positive number of seconds")
        }
        (_, Some(t)) => Budget::Seconds(t),
        (Some(0), _) => bail!("--spp must be at least 1"),
        (spp, None) => Budget::Samples(spp.unwrap_or(16)),
    })
}

/// A progress bar for `budget`: samples per pixel, or tenths of a second; after `label`,
/// where there is one.
fn progress_bar(budget: Budget, label: Option<&str>) -> indicatif::ProgressBar {
    let (length, template) = match budget {
        Budget::Samples(n) => (
            u64::from(n),
            "{prefix}{bar:40} {pos}/{len} spp, {elapsed} elapsed, {eta} left",
        ),
        Budget::Seconds(s) => (
            (s * 10.0) as u64,
            "{prefix}{bar:40} {elapsed} of the time budget",
        ),
    };
    let bar = indicatif::ProgressBar::new(length);
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    if let Some(label) = label {
        bar.set_prefix(format!("{label} "));
    }
    bar
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
    /// A row written by [`Checkpoint::csv_row`] read back (`None` if it is not one).
    pub fn from_csv_row(row: &str) -> Option<Checkpoint> {
        let fields: Vec<&str> = row.split(',').collect();
        let [seconds, spp, rmse, relmse, mae] = fields[..] else {
            return None;
        };
        Some(Checkpoint {
            seconds: seconds.parse().ok()?,
            spp: spp.parse().ok()?,
            metrics: ErrorMetrics {
                rmse: rmse.parse().ok()?,
                relmse: relmse.parse().ok()?,
                mae: mae.parse().ok()?,
            },
        })
    }

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
    /// Why the render ended early, if its device failed; the whole frames before it are in
    /// the film.
    pub failure: Option<String>,
}

/// Something to do with the film every so often while rendering (write a checkpoint).
pub struct Periodic<'a> {
    /// At least this long between two calls.
    pub every: Duration,
    /// Called after a whole frame with the film and the samples per pixel rendered so far.
    pub action: &'a mut dyn FnMut(&Film, u32) -> anyhow::Result<()>,
}

/// What a render does besides rendering: all optional.
#[derive(Default)]
pub struct Watch<'a> {
    /// The image to record the error against, at 1, 2, 4, … seconds and at the end.
    pub reference: Option<&'a [Vec3]>,
    /// Something to do with the film every so often.
    pub periodic: Option<Periodic<'a>>,
    /// Shown before the progress bar (where in an experiment the render is).
    pub label: Option<String>,
    /// The longer job the render is a part of, whose bar moves on with the render's.
    pub part: Option<Part<'a>>,
    /// When the render began, if before this call: the time the algorithm's choice took
    /// counts against a time budget and shows in the error's timeline.
    pub started: Option<Instant>,
}

/// A render as a part of a longer job (one run of an experiment): the job's bar stays on
/// screen above the render's own, and covers `span` of its length while the render runs.
pub struct Part<'a> {
    /// The bars on screen, the job's among them.
    pub bars: &'a indicatif::MultiProgress,
    /// The job's bar.
    pub job: &'a indicatif::ProgressBar,
    /// Where the render begins and ends on the job's bar.
    pub span: std::ops::Range<u64>,
}

impl Part<'_> {
    /// The job's position when the render is at `position` of `length`:
    /// start + (end − start) · min(position / length, 1).
    fn job_position(&self, position: u64, length: u64) -> u64 {
        let done = if length == 0 {
            1.0
        } else {
            (position as f64 / length as f64).min(1.0)
        };
        let width = self.span.end - self.span.start;
        self.span.start + (width as f64 * done) as u64
    }
}

/// Renders `frames` into `film` until `budget` is spent or `stop` is raised (which also cuts
/// the frame in progress short, dropping it whole), showing a progress bar, recording the
/// CPU utilization and doing what `watch` asks between frames.
pub fn render(
    integrator: &mut dyn Integrator,
    mut frames: Frames,
    film: &mut Film,
    budget: Budget,
    stop: &StopFlag,
    watch: Watch<'_>,
) -> anyhow::Result<Outcome> {
    let Watch {
        reference,
        mut periodic,
        label,
        part,
        started,
    } = watch;
    let progress = progress_bar(budget, label.as_deref());
    let progress = match &part {
        Some(part) => part.bars.add(progress),
        None => progress,
    };
    let mut checkpoints = Vec::new();
    let mut next_checkpoint = 1.0;
    let mut utilization = Vec::new();
    let threads = rayon::current_num_threads() as f64;
    let cpu_start = cpu_seconds();
    let mut interval_start = (0.0, cpu_start);
    let mut last_periodic = Instant::now();
    let start = (budget, started.unwrap_or_else(Instant::now));
    let rendered = render_loop::render(integrator, &mut frames, film, start, stop, |frame| {
        if let Some(periodic) = &mut periodic
            && last_periodic.elapsed() >= periodic.every
        {
            (periodic.action)(frame.film, frame.spp)?;
            last_periodic = Instant::now();
        }
        let seconds = frame.elapsed.as_secs_f64();
        if seconds - interval_start.0 >= UTILIZATION_INTERVAL {
            let interval_end = (seconds, cpu_seconds());
            if let ((t0, Some(cpu0)), (t1, Some(cpu1))) = (interval_start, interval_end) {
                utilization.push((t1, (cpu1 - cpu0) / ((t1 - t0) * threads)));
            }
            interval_start = interval_end;
        }
        progress.set_position(match budget {
            Budget::Samples(_) => u64::from(frame.spp),
            Budget::Seconds(_) => (seconds * 10.0) as u64,
        });
        if let Some(part) = &part {
            let length = progress.length().unwrap_or(0);
            part.job
                .set_position(part.job_position(progress.position(), length));
        }
        if let Some(reference) = reference
            && seconds >= next_checkpoint
        {
            checkpoints.push(checkpoint(frame.film, reference, seconds, frame.spp));
            while next_checkpoint <= seconds {
                next_checkpoint *= 2.0;
            }
        }
        Ok(())
    })?;
    progress.finish_and_clear();
    if let Some(part) = &part {
        part.bars.remove(&progress);
        part.job.set_position(part.span.end);
    }
    let Rendered {
        spp,
        frames,
        seconds,
        totals,
        failure,
    } = rendered;
    let mean_utilization = cpu_seconds()
        .zip(cpu_start)
        .map(|(end, begin)| (end - begin) / (seconds.max(1e-9) * threads));
    if let Some(reference) = reference {
        checkpoints.push(checkpoint(film, reference, seconds, spp));
    }
    Ok(Outcome {
        spp,
        frames,
        seconds,
        totals,
        checkpoints,
        utilization,
        mean_utilization,
        failure,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_part_moves_the_job_bar_across_its_span_only() {
        let bars = indicatif::MultiProgress::new();
        let job = indicatif::ProgressBar::hidden();
        let part = Part {
            bars: &bars,
            job: &job,
            span: 300..400,
        };
        assert_eq!(part.job_position(0, 16), 300);
        assert_eq!(part.job_position(4, 16), 325);
        assert_eq!(part.job_position(16, 16), 400);
        // A time budget's last frame can end past it; an empty budget counts as done.
        assert_eq!(part.job_position(130, 100), 400);
        assert_eq!(part.job_position(0, 0), 400);
    }
}
