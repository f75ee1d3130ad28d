//! Starts the viewer under Xvfb with `--frames N --screenshot FILE` and checks that the window
//! shows the Cornell box: the image area of the screenshot must match renders of the same
//! scene and settings made through the library, within a tolerance derived from their noise.
//!
//! The window is drawn by eframe's wgpu renderer on whatever adapter the X server offers: on
//! CI that is lavapipe, Mesa's Vulkan driver on the CPU (`mesa-vulkan-drivers`). Without
//! `xvfb-run`, or when no window can be opened (the viewer exits with status 3), the test
//! is skipped with a message, unless `VCM_REQUIRE_GPU=1` (set by `.ci/run`): then it fails.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

use vcm::Film;
use vcm::image_io::linear_to_srgb_byte;
use vcm_rs::Backend;
use vcm_rs::integrators::{self, Algorithm, IntegratorOptions, image_size};
use vcm_scene::Scene;

/// Frames (samples per pixel) the viewer renders before its screenshot.
const FRAMES: u32 = 16;
/// Render width; the height follows from the camera.
const WIDTH: u32 = 128;
/// The viewer's seed; the library renders use others, so their noise is independent.
const VIEWER_SEED: u64 = 7;
/// Exit status of the viewer when it cannot open a window.
const NO_WINDOW: i32 = 3;
/// The grid of blocks whose means are compared (blocks per side).
const BLOCKS: usize = 4;
/// How long the viewer may take (it renders 16 small frames on the CPU).
const TIMEOUT: Duration = Duration::from_secs(300);

fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf")
}

fn required() -> bool {
    std::env::var("VCM_REQUIRE_GPU").is_ok_and(|v| v == "1")
}

/// Skips (returns `None`) or, when required, fails with `reason`.
fn skip<T>(reason: &str) -> Option<T> {
    assert!(!required(), "VCM_REQUIRE_GPU=1 but {reason}");
    eprintln!("skipped: {reason} (set VCM_REQUIRE_GPU=1 to make this an error)");
    None
}

/// An sRGB 8-bit image as floats, RGB per pixel.
struct Srgb {
    width: usize,
    height: usize,
    pixels: Vec<[f64; 3]>,
}

impl Srgb {
    /// Indices of the pixels of block (`bx`, `by`) of a `BLOCKS`² grid.
    fn block(&self, bx: usize, by: usize) -> Vec<usize> {
        let (x0, x1) = (bx * self.width / BLOCKS, (bx + 1) * self.width / BLOCKS);
        let (y0, y1) = (by * self.height / BLOCKS, (by + 1) * self.height / BLOCKS);
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| y * self.width + x))
            .collect()
    }

    /// The mean of each channel over block (`bx`, `by`).
    fn block_mean(&self, bx: usize, by: usize) -> [f64; 3] {
        let block = self.block(bx, by);
        let mut sum = [0.0; 3];
        for &i in &block {
            (0..3).for_each(|c| sum[c] += self.pixels[i][c]);
        }
        sum.map(|s| s / block.len() as f64)
    }
}

/// The path tracer's render of the Cornell box at `seed`, tone mapped as the viewer shows it
/// (exposure 0).
fn library_render(scene: &Arc<Scene>, seed: u64) -> Srgb {
    let size = image_size(scene, WIDTH, None);
    let options = IntegratorOptions {
        seed,
        max_depth: None,
        connections: 1,
        radius: vcm::MergeRadius::default(),
        alpha: vcm::DEFAULT_ALPHA,
        ..IntegratorOptions::default()
    };
    let traversal = Backend::Cpu.traversal(scene).unwrap();
    let mut integrator =
        integrators::build(Algorithm::Pt, scene, traversal, size, &options).unwrap();
    let mut film = Film::new(size.0, size.1);
    for iteration in 0..FRAMES {
        integrator.render_frame(&mut film, iteration);
    }
    Srgb {
        width: size.0 as usize,
        height: size.1 as usize,
        pixels: film
            .mean()
            .iter()
            .map(|p| p.to_array().map(|c| f64::from(linear_to_srgb_byte(c))))
            .collect(),
    }
}

/// Runs the viewer under Xvfb; `None` when the test is skipped.
fn run_viewer(screenshot: &Path) -> Option<Output> {
    let (width, seed, frames) = (
        WIDTH.to_string(),
        VIEWER_SEED.to_string(),
        FRAMES.to_string(),
    );
    let scene = scene_path();
    let output = under_xvfb(&[
        scene.as_os_str(),
        "--algo".as_ref(),
        "pt".as_ref(),
        "--width".as_ref(),
        width.as_ref(),
        "--seed".as_ref(),
        seed.as_ref(),
        "--frames".as_ref(),
        frames.as_ref(),
        "--screenshot".as_ref(),
        screenshot.as_os_str(),
    ])?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the viewer failed: {stderr}");
    Some(output)
}

/// Runs the viewer with `args` under Xvfb and returns what it did, or `None` when the test
/// is skipped: no `xvfb-run`, or the viewer could not open a window (exit status 3).
pub fn under_xvfb(args: &[&OsStr]) -> Option<Output> {
    let found = Command::new("xvfb-run").arg("--help").output().is_ok();
    if !found {
        return skip("xvfb-run is not installed (Debian: apt-get install xvfb xauth)");
    }
    let mut child = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x1024x24"])
        .arg(env!("CARGO_BIN_EXE_vcm-viewer"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starting xvfb-run");
    let start = Instant::now();
    while child.try_wait().expect("waiting for the viewer").is_none() {
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            panic!("the viewer did not finish within {TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let output = child
        .wait_with_output()
        .expect("reading the viewer's output");
    let stderr = String::from_utf8_lossy(&output.stderr);
    if output.status.code() == Some(NO_WINDOW) {
        return skip(&format!(
            "the viewer could not open a window under Xvfb: {stderr}"
        ));
    }
    Some(output)
}

/// The image area of the screenshot, from the viewer's report
/// `… image at X,Y size WxH`.
fn image_area(stdout: &str, screenshot: &Path) -> Srgb {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("screenshot"))
        .unwrap_or_else(|| panic!("no screenshot report in {stdout:?}"));
    let numbers: Vec<usize> = line
        .split_once("image at ")
        .expect("the report names the image area")
        .1
        .split([',', ' ', 'x'])
        .filter_map(|n| n.parse().ok())
        .collect();
    let [x0, y0, width, height] = numbers[..] else {
        panic!("cannot read the image area from {line:?}")
    };
    let window = image::open(screenshot)
        .expect("the screenshot is a PNG")
        .to_rgb8();
    assert!(x0 + width <= window.width() as usize && y0 + height <= window.height() as usize);
    let mut pixels = Vec::with_capacity(width * height);
    for y in y0..y0 + height {
        for x in x0..x0 + width {
            let p = window.get_pixel(x as u32, y as u32).0;
            pixels.push(p.map(f64::from));
        }
    }
    Srgb {
        width,
        height,
        pixels,
    }
}

#[test]
fn the_window_shows_the_cornell_box() {
    let dir = tempfile::tempdir().unwrap();
    let screenshot = dir.path().join("viewer.png");
    let Some(output) = run_viewer(&screenshot) else {
        return;
    };
    let shown = image_area(&String::from_utf8_lossy(&output.stdout), &screenshot);

    let scene = Arc::new(Scene::load(scene_path()).unwrap());
    let (a, b) = (library_render(&scene, 0), library_render(&scene, 1));
    assert_eq!(
        (shown.width, shown.height),
        (a.width, a.height),
        "the image is drawn one pixel per screen pixel"
    );

    // Not blank: the box has bright walls and dark shadows.
    let luminance: Vec<f64> = shown
        .pixels
        .iter()
        .map(|p| p.iter().sum::<f64>() / 3.0)
        .collect();
    let mean = luminance.iter().sum::<f64>() / luminance.len() as f64;
    let spread =
        (luminance.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / luminance.len() as f64).sqrt();
    assert!(
        mean > 20.0 && spread > 20.0,
        "blank? mean {mean:.1}, spread {spread:.1}"
    );

    // Each block's mean must match the library renders' within their noise. A block mean of
    // one render has variance σ² = Var(a − b) / 2 over the block's pixels divided by their
    // count (pixels are independent); the viewer's block minus the mean of a and b has
    // variance 1.5 σ². The tolerance is 5 of those standard deviations plus 1.5 levels for
    // 8-bit rounding and the display's conversions.
    let mut worst: f64 = 0.0;
    for by in 0..BLOCKS {
        for bx in 0..BLOCKS {
            let (sa, sb, sv) = (
                a.block_mean(bx, by),
                b.block_mean(bx, by),
                shown.block_mean(bx, by),
            );
            for c in 0..3 {
                let sigma = block_noise(&a, &b, bx, by, c);
                let expected = 0.5 * (sa[c] + sb[c]);
                let tolerance = 5.0 * (1.5f64).sqrt() * sigma + 1.5;
                worst = worst.max((sv[c] - expected).abs() / tolerance);
                assert!(
                    (sv[c] - expected).abs() <= tolerance,
                    "block ({bx}, {by}) channel {c}: viewer {:.2}, library {expected:.2} \
                     (renders {:.2} and {:.2}), tolerance {tolerance:.2}",
                    sv[c],
                    sa[c],
                    sb[c]
                );
            }
        }
    }
    eprintln!(
        "largest block difference: {:.0}% of its tolerance",
        100.0 * worst
    );
}

/// The standard deviation of one render's mean of channel `c` over block (`bx`, `by`),
/// estimated from two independent renders `a` and `b` of the same size.
fn block_noise(a: &Srgb, b: &Srgb, bx: usize, by: usize, c: usize) -> f64 {
    let differences: Vec<f64> = a
        .block(bx, by)
        .into_iter()
        .map(|i| a.pixels[i][c] - b.pixels[i][c])
        .collect();
    let n = differences.len() as f64;
    let mean = differences.iter().sum::<f64>() / n;
    let variance = differences.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (variance / 2.0 / n).sqrt()
}
