//! Plots as PNG, one curve per series: relMSE against seconds on log-log axes (convergence),
//! CPU utilization against seconds on linear axes, and schedulers' speed-ups against samples
//! per pixel per frame.
//!
//! Text needs a TrueType font: `VCM_PLOT_FONT` names one, else common system fonts (DejaVu,
//! Liberation) are tried; without any, the plot is drawn without labels and a warning says so.

use std::io::Write;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::bail;
use plotters::coord::combinators::{BindKeyPoints, LogCoord, WithKeyPoints};
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
        x: log_axis(t0 / 1.5..t1 * 1.5),
        y: log_axis(e0 / 2.0..e1 * 2.0),
        x_desc: "seconds",
        y_desc: "relMSE",
        // Errors fall over time, leaving the upper right empty.
        legend_at: SeriesLabelPosition::UpperRight,
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
        // Utilization stays near the top.
        legend_at: SeriesLabelPosition::LowerRight,
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
        x: log_axis(1.0..x_end * 1.2),
        y: 0.0..y_end * 1.15,
        x_desc: "samples per pixel per frame",
        y_desc: "speed-up over one batch, 1 sample per frame",
        // Speed-ups grow with the samples per frame, leaving the upper left empty.
        legend_at: SeriesLabelPosition::UpperLeft,
    };
    plot(path, title, series, axes)
}

/// The x and y ranges of a plot, the axes' names and where the legend goes.
struct Axes<X, Y> {
    x: X,
    y: Y,
    x_desc: &'static str,
    y_desc: &'static str,
    /// A corner the curves usually leave empty.
    legend_at: SeriesLabelPosition,
}

/// A logarithmic axis over `range` with ticks of our own: plotters' own log ticks crowd
/// (and repeat) labels near a power of ten.
///
/// Labelled ticks at 1, 2 and 5 times each power of ten, or at the powers of ten alone where
/// the range spans more than three decades, or at every integer multiple of a power of ten
/// where the range is too narrow to hold two of 1, 2 and 5; light grid lines at every integer
/// multiple of each power of ten.
fn log_axis(range: Range<f64>) -> WithKeyPoints<LogCoord<f64>> {
    let decades = (range.end / range.start).log10();
    let labelled_multiples: &[f64] = if decades > 3.0 {
        &[1.0]
    } else {
        &[1.0, 2.0, 5.0]
    };
    let within = |multiples: &[f64]| -> Vec<f64> {
        let first = range.start.log10().floor() as i32;
        let last = range.end.log10().ceil() as i32;
        (first..=last)
            .flat_map(|power| multiples.iter().map(move |m| m * 10f64.powi(power)))
            .filter(|v| range.contains(v))
            .collect()
    };
    let light = within(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    let mut labelled = within(labelled_multiples);
    if labelled.len() < 2 {
        labelled.clone_from(&light);
    }
    range
        .clone()
        .log_scale()
        .with_key_points(labelled)
        .with_light_points(light)
}

/// A tick's label, as short as its value allows at six significant digits: `20`, `1.5`,
/// `0.01`; `1e-3` and `2e5` outside 0.01 … 10⁵. (plotters writes every value of a float axis
/// with a decimal point and in full: `10.0`, `0.30000000000000004`.)
fn tick_label(value: &f64) -> String {
    // Rounding drops the last bits of ticks computed as multiples (3 · 0.1).
    let rounded: f64 = format!("{value:.5e}").parse().unwrap_or(*value);
    if rounded == 0.0 || (0.01..1e5).contains(&rounded.abs()) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
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
    let legend_at = axes.legend_at;
    let mut chart = builder.build_cartesian_2d(axes.x, axes.y)?;
    let mut mesh = chart.configure_mesh();
    if labels {
        mesh.x_desc(axes.x_desc)
            .y_desc(axes.y_desc)
            .x_label_formatter(&tick_label)
            .y_label_formatter(&tick_label)
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
            .position(legend_at)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
    }
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use plotters::coord::ranged1d::{BoldPoints, LightPoints, Ranged};

    use super::*;

    #[test]
    fn log_axis_labels_one_two_five_within_the_range() {
        let axis = log_axis(0.75..45.0);
        assert_eq!(
            axis.key_points(BoldPoints(100)),
            [1.0, 2.0, 5.0, 10.0, 20.0]
        );
        let light = axis.key_points(LightPoints::new(100, 100));
        assert_eq!(light.first(), Some(&0.8));
        assert_eq!(light.last(), Some(&40.0));
        assert_eq!(light.len(), 2 + 9 + 4);
    }

    #[test]
    fn log_axis_over_many_decades_labels_powers_of_ten_only() {
        let axis = log_axis(3e-5..0.2);
        assert_eq!(axis.key_points(BoldPoints(100)), [1e-4, 1e-3, 1e-2, 1e-1]);
    }

    #[test]
    fn narrow_log_axis_labels_every_multiple() {
        let axis = log_axis(2.1..4.6);
        assert_eq!(axis.key_points(BoldPoints(100)), [3.0, 4.0]);
    }

    #[test]
    fn tick_labels_are_short() {
        let ticks = [
            0.0,
            1.0,
            2.0,
            10.0,
            20.0,
            0.5,
            1.5,
            0.1 * 3.0,
            0.05,
            0.01,
            1e-3,
            2e-4,
            250.0,
            2e5,
        ];
        let labels: Vec<String> = ticks.iter().map(tick_label).collect();
        let expected = [
            "0", "1", "2", "10", "20", "0.5", "1.5", "0.3", "0.05", "0.01", "1e-3", "2e-4", "250",
            "2e5",
        ];
        assert_eq!(labels, expected);
    }
}
