//! Plots as PNG, one curve per series: relMSE against seconds on log-log axes (convergence),
//! CPU utilization against seconds on linear axes, and schedulers' speed-ups against samples
//! per pixel per frame.
//!
//! Text needs a TrueType font: `VCM_PLOT_FONT` names one, else common system fonts (DejaVu,
//! Liberation) are tried; without any, the plot is drawn without labels and a warning says so.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::bail;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use vcm::atomic_write::write_atomically;

/// One curve: a label and (seconds, value) points.
pub struct Series {
    /// Legend text (e.g. the algorithm).
    pub label: String,
    /// (x, y) pairs in x order: (seconds, value) for the plots over time.
    pub points: Vec<(f64, f64)>,
}

/// Font files tried, in order, when `VCM_PLOT_FONT` is not set.
const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// Registers a system font as "sans-serif" once; false when none could be loaded.
fn font_available() -> bool {
    static LOADED: OnceLock<bool> = OnceLock::new();
    *LOADED.get_or_init(|| {
        let candidates: Vec<PathBuf> = match std::env::var_os("VCM_PLOT_FONT") {
            Some(path) => vec![path.into()],
            None => FONT_CANDIDATES.iter().map(PathBuf::from).collect(),
        };
        candidates.iter().any(|path| {
            std::fs::read(path).ok().is_some_and(|bytes| {
                // Registered fonts live for the whole process.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok()
            })
        })
    })
}

/// Draws relMSE series on log-log axes into a PNG at `path` (written to a temporary file,
/// then renamed).
pub fn plot_relmse(path: &Path, title: &str, series: &[Series]) -> anyhow::Result<()> {
    let positive = || {
        series
            .iter()
            .flat_map(|s| &s.points)
            .filter(|(t, e)| *t > 0.0 && *e > 0.0 && t.is_finite() && e.is_finite())
    };
    if positive().next().is_none() {
        bail!(
            "{}: no positive (seconds, relMSE) points to plot",
            path.display()
        );
    }
    let (t0, t1) = positive().fold((f64::MAX, f64::MIN), |(a, b), (t, _)| {
        (a.min(*t), b.max(*t))
    });
    let (e0, e1) = positive().fold((f64::MAX, f64::MIN), |(a, b), (_, e)| {
        (a.min(*e), b.max(*e))
    });
    let axes = Axes {
        x: (t0 / 1.5..t1 * 1.5).log_scale(),
        y: (e0 / 2.0..e1 * 2.0).log_scale(),
        x_desc: "seconds",
        y_desc: "relMSE",
    };
    let positive_series: Vec<Series> = series
        .iter()
        .map(|s| Series {
            label: s.label.clone(),
            points: s
                .points
                .iter()
                .copied()
                .filter(|(t, e)| *t > 0.0 && *e > 0.0)
                .collect(),
        })
        .collect();
    plot(path, title, &positive_series, axes)
}

/// Draws CPU utilization (percent of all worker threads) against seconds into a PNG at
/// `path`.
pub fn plot_utilization(path: &Path, title: &str, series: &[Series]) -> anyhow::Result<()> {
    let end = series
        .iter()
        .flat_map(|s| &s.points)
        .map(|(t, _)| *t)
        .fold(0.0, f64::max);
    if end <= 0.0 {
        bail!("{}: no utilization samples to plot", path.display());
    }
    let axes = Axes {
        x: 0.0..end,
        y: 0.0..105.0,
        x_desc: "seconds",
        y_desc: "CPU utilization (%)",
    };
    plot(path, title, series, axes)
}

/// Draws speed-ups (y, linear from 0) against samples per pixel per frame (x, log scale) as
/// a PNG at `path`.
pub fn plot_speedup(path: &Path, title: &str, series: &[Series]) -> anyhow::Result<()> {
    let points = || series.iter().flat_map(|s| &s.points);
    let x_end = points().map(|(x, _)| *x).fold(1.0, f64::max);
    let y_end = points()
        .map(|(_, y)| *y)
        .filter(|y| y.is_finite())
        .fold(1.0, f64::max);
    let axes = Axes {
        x: (1.0..x_end * 1.2).log_scale(),
        y: 0.0..y_end * 1.15,
        x_desc: "samples per pixel per frame",
        y_desc: "speed-up over one batch, 1 sample per frame",
    };
    plot(path, title, series, axes)
}

/// The x and y ranges of a plot and the axes' names.
struct Axes<X, Y> {
    x: X,
    y: Y,
    x_desc: &'static str,
    y_desc: &'static str,
}

/// Draws `series` within `axes` into a PNG at `path`, through a temporary file.
fn plot<X, Y>(path: &Path, title: &str, series: &[Series], axes: Axes<X, Y>) -> anyhow::Result<()>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let labels = font_available();
    if !labels {
        // Not `eprintln!`, which panics when stderr is a pipe nobody reads any more.
        let _ = writeln!(
            std::io::stderr(),
            "warning: no TrueType font found (set VCM_PLOT_FONT); the plot has no labels"
        );
    }
    // The bitmap backend picks the encoder from the extension, which the temporary name keeps.
    write_atomically(
        path,
        |temporary| {
            draw(temporary, title, series, axes, labels)
                .map_err(|e| anyhow::anyhow!("{}: cannot draw the plot: {e}", path.display()))
        },
        |e| anyhow::anyhow!("{}: cannot write: {e}", path.display()),
    )
}

fn draw<X, Y>(
    path: &Path,
    title: &str,
    series: &[Series],
    axes: Axes<X, Y>,
    labels: bool,
) -> Result<(), Box<dyn std::error::Error>>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let root = BitMapBackend::new(path, (800, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut builder = ChartBuilder::on(&root);
    builder.margin(20);
    if labels {
        builder
            .caption(title, ("sans-serif", 22))
            .x_label_area_size(45)
            .y_label_area_size(70);
    }
    let mut chart = builder.build_cartesian_2d(axes.x, axes.y)?;
    let mut mesh = chart.configure_mesh();
    if labels {
        mesh.x_desc(axes.x_desc)
            .y_desc(axes.y_desc)
            .label_style(("sans-serif", 14));
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.draw()?;
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let points = s.points.iter().copied();
        let line = chart.draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))?;
        if labels {
            line.label(s.label.clone()).legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2))
            });
        }
        chart.draw_series(points.map(|p| Circle::new(p, 3, color.filled())))?;
    }
    if labels {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
    }
    root.present()?;
    Ok(())
}
