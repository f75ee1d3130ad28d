//! The scheduler sweep (the thesis's Table 4.2 and Figure 4.8 on this machine): the Cornell box
//! rendered by `vcm render` under every scheduler, several tile sizes and samples per pixel per
//! frame, for the path tracer and VCM (with merging: `--no-prune`), on the CPU backend and,
//! where an adapter exists, the GPU backend.
//!
//! Run with `cargo bench --bench schedulers` (about 15 minutes on 2 cores; `-- --quick` runs a
//! reduced sweep once, `-- --cpu-only` leaves the GPU out). Each configuration is rendered in
//! every round, rounds one after another so that a disturbance hits all configurations alike;
//! the best samples/s of the rounds counts. Writes `target/schedulers/sweep.csv`, one plot of
//! speed-ups against samples per frame per (algorithm, backend), and prints the tables in
//! Markdown for `docs/schedulers.md`. It measures with the CLI's own statistics (samples/s and
//! CPU utilization as `vcm render` prints them).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use vcm_rs::plot::{Series, plot_speedup};

/// How one configuration groups its paths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Grouping {
    /// One batch of all paths per pass.
    None,
    /// Tiles of this side.
    Tile(u32),
    /// The queue scheduler with its default pool and tile size.
    Queue,
}

impl Grouping {
    fn label(self) -> String {
        match self {
            Grouping::None => "none".into(),
            Grouping::Tile(size) => format!("tile {size}"),
            Grouping::Queue => "queue".into(),
        }
    }

    fn args(self) -> Vec<String> {
        match self {
            Grouping::None => vec!["--scheduler".into(), "none".into()],
            Grouping::Tile(size) => vec![
                "--scheduler".into(),
                "tile".into(),
                "--tile-size".into(),
                size.to_string(),
            ],
            Grouping::Queue => vec!["--scheduler".into(), "queue".into()],
        }
    }
}

/// What is rendered for one (algorithm, backend) pair.
#[derive(Clone, Copy, Debug)]
struct Workload {
    algorithm: &'static str,
    backend: &'static str,
    /// Image side in pixels.
    side: u32,
    /// Samples per pixel (raised to the samples per frame where that is more).
    spp: u32,
}

/// What `vcm render` reported for one configuration.
#[derive(Clone, Copy, Debug)]
struct Measurement {
    samples_per_second: f64,
    utilization: f64,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let cpu_only = args.iter().any(|a| a == "--cpu-only");
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/schedulers");
    std::fs::create_dir_all(&out).expect("cannot create target/schedulers");

    let mut workloads = vec![
        Workload {
            algorithm: "pt",
            backend: "cpu",
            side: 512,
            spp: 16,
        },
        Workload {
            algorithm: "vcm",
            backend: "cpu",
            side: 512,
            spp: 4,
        },
    ];
    if !cpu_only && gpu_available(&out) {
        workloads.push(Workload {
            algorithm: "pt",
            backend: "gpu",
            side: 256,
            spp: 16,
        });
        workloads.push(Workload {
            algorithm: "vcm",
            backend: "gpu",
            side: 256,
            spp: 4,
        });
    } else if !cpu_only {
        eprintln!("no GPU adapter (install mesa-vulkan-drivers for lavapipe): CPU only");
    }
    let (groupings, per_frame, rounds): (Vec<Grouping>, &[u32], usize) = if quick {
        (
            vec![Grouping::None, Grouping::Tile(32), Grouping::Queue],
            &[1, 4],
            1,
        )
    } else {
        (
            vec![
                Grouping::None,
                Grouping::Tile(32),
                Grouping::Tile(64),
                Grouping::Tile(128),
                Grouping::Tile(256),
                Grouping::Queue,
            ],
            &[1, 4, 16],
            2,
        )
    };

    let mut best: BTreeMap<(usize, Grouping, u32), Measurement> = BTreeMap::new();
    for round in 1..=rounds {
        for (w, workload) in workloads.iter().enumerate() {
            for &grouping in &groupings {
                for &k in per_frame {
                    let m = render(workload, grouping, k, &out);
                    eprintln!(
                        "round {round}: {} {} {} {k}/frame: {:.3} M/s, {:.0}% CPU",
                        workload.algorithm,
                        workload.backend,
                        grouping.label(),
                        m.samples_per_second / 1e6,
                        m.utilization
                    );
                    let entry = best.entry((w, grouping, k)).or_insert(m);
                    if m.samples_per_second > entry.samples_per_second {
                        *entry = m;
                    }
                }
            }
        }
    }

    let mut csv = String::from(
        "algorithm,backend,width,height,scheduler,spp_per_frame,samples_per_s,speedup,utilization\n",
    );
    for (w, workload) in workloads.iter().enumerate() {
        let baseline = best[&(w, Grouping::None, 1)].samples_per_second;
        println!(
            "\n### {} on the {} backend, {}², {} spp\n",
            workload.algorithm, workload.backend, workload.side, workload.spp
        );
        let header: Vec<String> = per_frame.iter().map(|k| format!("{k} spp/frame")).collect();
        println!("| scheduler | {} |", header.join(" | "));
        println!("| --- |{}", " --- |".repeat(per_frame.len()));
        let mut series = Vec::new();
        for &grouping in &groupings {
            let mut cells = Vec::new();
            let mut points = Vec::new();
            for &k in per_frame {
                let m = best[&(w, grouping, k)];
                let speedup = m.samples_per_second / baseline;
                cells.push(format!(
                    "{:.2} M/s ({speedup:.2}×, {:.0}% CPU)",
                    m.samples_per_second / 1e6,
                    m.utilization
                ));
                points.push((f64::from(k), speedup));
                csv.push_str(&format!(
                    "{},{},{},{},{},{k},{:.0},{speedup:.4},{:.1}\n",
                    workload.algorithm,
                    workload.backend,
                    workload.side,
                    workload.side,
                    grouping.label(),
                    m.samples_per_second,
                    m.utilization
                ));
            }
            println!("| {} | {} |", grouping.label(), cells.join(" | "));
            series.push(Series {
                label: grouping.label(),
                points,
            });
        }
        let plot = out.join(format!("{}-{}.png", workload.algorithm, workload.backend));
        let title = format!(
            "{} on the {} backend, Cornell box {}²",
            workload.algorithm, workload.backend, workload.side
        );
        if let Err(e) = plot_speedup(&plot, &title, &series) {
            eprintln!("{e}");
        }
    }
    let csv_path = out.join("sweep.csv");
    std::fs::write(&csv_path, csv).expect("cannot write sweep.csv");
    eprintln!("wrote {} and the plots beside it", csv_path.display());
}

/// Renders one configuration and returns what the summary says.
fn render(workload: &Workload, grouping: Grouping, per_frame: u32, out: &Path) -> Measurement {
    let spp = workload.spp.max(per_frame);
    let mut args: Vec<String> = [
        "render",
        "scenes/cornell-box.gltf",
        "--algo",
        workload.algorithm,
        "--backend",
        workload.backend,
        "--no-prune",
    ]
    .map(String::from)
    .to_vec();
    args.extend(grouping.args());
    for (flag, value) in [
        ("--width", workload.side),
        ("--height", workload.side),
        ("--spp", spp),
        ("--spp-per-frame", per_frame),
    ] {
        args.extend([flag.to_string(), value.to_string()]);
    }
    args.extend(["-o".into(), image_path(out)]);
    let output = Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(&args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cannot run vcm");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "vcm {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&output.stderr)
    );
    Measurement {
        samples_per_second: number_before(&stdout, " M samples/s") * 1e6,
        utilization: number_before(&stdout, "% of "),
    }
}

/// Whether `vcm render --backend gpu` finds an adapter.
fn gpu_available(out: &Path) -> bool {
    Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(["render", "--backend", "gpu", "--spp", "1", "--width", "8"])
        .args(["-o", &image_path(out)])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .is_ok_and(|o| o.status.success())
}

fn image_path(out: &Path) -> String {
    PathBuf::from(out).join("render.exr").display().to_string()
}

/// The number that ends right before `marker` in `text`.
fn number_before(text: &str, marker: &str) -> f64 {
    let end = text
        .find(marker)
        .unwrap_or_else(|| panic!("no '{marker}' in:\n{text}"));
    let start = text[..end]
        .rfind(|c: char| !(c.is_ascii_digit() || c == '.'))
        .map_or(0, |i| i + 1);
    text[start..end]
        .parse()
        .unwrap_or_else(|_| panic!("no number before '{marker}' in:\n{text}"))
}
