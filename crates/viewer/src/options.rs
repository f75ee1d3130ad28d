//! The command line of `vcm-viewer`.

use std::path::PathBuf;

use clap::Parser;
use vcm_rs::integrators::{AlgorithmOption, IntegratorOptions};
use vcm_rs::render_loop::ScheduleOptions;
use vcm_rs::state::SETTING_OPTIONS;
use vcm_rs::{Backend, Shading};

use crate::settings::RenderSettings;

/// vcm-viewer: watch a scene converge, move the camera, switch algorithms.
#[derive(Debug, Parser)]
#[command(name = "vcm-viewer", version, about)]
pub struct Options {
    /// The scene file (.gltf, .glb or .obj; default scenes/cornell-box.gltf). With --resume:
    /// the scene to continue the render with (default: the one the state names).
    pub scene: Option<PathBuf>,
    /// The scene's camera to start from: its index in the glTF `cameras` array, or its name
    /// or its node's name (default: the first camera the file's nodes place).
    #[arg(long, value_name = "INDEX|NAME")]
    pub camera: Option<String>,
    /// Continue the render whose state is in this file (written by `vcm render --state` or
    /// the viewer's *Save state…*): its scene (checked by content), camera, image size,
    /// algorithm and options, which therefore cannot be given as well.
    #[arg(long, value_name = "FILE", conflicts_with_all = SETTING_OPTIONS)]
    pub resume: Option<PathBuf>,
    /// The light transport algorithm to start with (`auto`: chosen by pilot renders, as by
    /// `vcm render`).
    #[arg(long, value_enum, default_value_t = AlgorithmOption::Auto)]
    pub algo: AlgorithmOption,
    /// Ray traversal backend.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
    /// Where paths are shaded: `gpu` follows whole paths in one WGSL kernel on the GPU
    /// backend's device (with --backend gpu and --algo pt).
    #[arg(long, value_enum, default_value_t = Shading::Cpu)]
    pub shading: Shading,
    /// Image width in pixels at full resolution.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Image height in pixels (default: from the camera's aspect ratio, else square).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: Option<u32>,
    #[command(flatten)]
    pub integrator: IntegratorOptions,
    #[command(flatten)]
    pub schedule: ScheduleOptions,
    /// Exposure in stops (the image is scaled by 2^exposure before tone mapping).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Reference EXR (same size as the render): plots relMSE against time while rendering.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// With --screenshot: render this many frames at full resolution, save the screenshot and
    /// quit.
    #[arg(long, requires = "screenshot", value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: Option<u32>,
    /// Save a PNG of the window once --frames frames are rendered, then quit (for tests and
    /// documentation).
    #[arg(long, requires = "frames")]
    pub screenshot: Option<PathBuf>,
}

impl Options {
    /// The render settings the viewer starts with.
    pub fn settings(&self) -> RenderSettings {
        RenderSettings {
            algorithm: self.algo,
            backend: self.backend,
            shading: self.shading,
            integrator: self.integrator.clone(),
            schedule: self.schedule,
        }
    }

    /// The scripted screenshot: (frames, file), when asked for.
    pub fn screenshot(&self) -> Option<(u32, PathBuf)> {
        Some((self.frames?, self.screenshot.clone()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm_rs::integrators::{Algorithm, MergeRadius};
    use vcm_rs::render_loop::SchedulerKind;

    fn parse(args: &[&str]) -> Result<Options, clap::Error> {
        Options::try_parse_from(std::iter::once("vcm-viewer").chain(args.iter().copied()))
    }

    #[test]
    fn defaults_render_the_cornell_box_with_the_algorithm_chosen_by_pilots() {
        let options = parse(&[]).unwrap();
        assert_eq!(
            options.scene, None,
            "the app opens crate::app::DEFAULT_SCENE"
        );
        assert_eq!(options.resume, None);
        assert_eq!(options.settings().algorithm, AlgorithmOption::Auto);
        assert_eq!(options.settings().schedule, ScheduleOptions::default());
        assert_eq!(options.settings().shading, Shading::Cpu);
        assert_eq!(options.screenshot(), None);
        let gpu = parse(&["--backend", "gpu", "--shading", "gpu"]).unwrap();
        assert_eq!(gpu.settings().shading, Shading::Gpu);
    }

    #[test]
    fn integrator_options_are_those_of_vcm_render() {
        let options = parse(&[
            "s.obj",
            "--algo",
            "vcm",
            "--max-depth",
            "5",
            "--radius",
            "0.01",
            "--scheduler",
            "none",
            "--spp-per-frame",
            "4",
        ])
        .unwrap();
        let settings = options.settings();
        assert_eq!(settings.algorithm, AlgorithmOption::Fixed(Algorithm::Vcm));
        assert_eq!(settings.integrator.max_depth, Some(5));
        assert_eq!(settings.integrator.radius, MergeRadius::SceneFraction(0.01));
        assert_eq!(settings.schedule.scheduler, Some(SchedulerKind::None));
        assert_eq!(settings.schedule.spp_per_frame, Some(4));
        assert_eq!(options.exposure, 0.0);
        assert_eq!(parse(&["--exposure", "-1.5"]).unwrap().exposure, -1.5);
        assert_eq!(options.camera, None);
        let camera = parse(&["--camera", "Top"]).unwrap().camera;
        assert_eq!(camera.as_deref(), Some("Top"));
    }

    #[test]
    fn bad_options_are_clear_errors() {
        for (args, says) in [
            (&["--bogus"][..], "--bogus"),
            (&["--algo", "mlt"], "mlt"),
            (&["--backend", "tpu"], "tpu"),
            (&["--width", "0"], "0"),
            (&["--scheduler", "spiral"], "spiral"),
            (&["--frames", "4"], "--screenshot"),
            (&["--screenshot", "a.png"], "--frames"),
        ] {
            let error = parse(args).unwrap_err().to_string();
            assert!(error.contains(says), "{args:?}: {error}");
        }
        let both = parse(&["--frames", "4", "--screenshot", "a.png"]).unwrap();
        assert_eq!(both.screenshot(), Some((4, PathBuf::from("a.png"))));
    }

    #[test]
    fn resume_takes_the_settings_from_the_state() {
        let options = parse(&["--resume", "a.state", "--backend", "gpu", "--exposure", "1"]);
        let options = options.unwrap();
        assert_eq!(options.resume, Some(PathBuf::from("a.state")));
        assert_eq!(options.scene, None);
        let with_scene = parse(&["box.gltf", "--resume", "a.state"]).unwrap();
        assert_eq!(with_scene.scene, Some(PathBuf::from("box.gltf")));
        let screenshot = [
            "--resume",
            "a.state",
            "--frames",
            "2",
            "--screenshot",
            "s.png",
        ];
        assert!(
            parse(&screenshot).is_ok(),
            "scheduling and display are free"
        );
        for setting in [
            &["--algo", "vcm"][..],
            &["--width", "64"],
            &["--height", "64"],
            &["--camera", "0"],
            &["--seed", "3"],
            &["--sampler", "independent"],
            &["--max-depth", "4"],
            &["--connections", "2"],
            &["--radius", "0.01"],
            &["--alpha", "0.5"],
            &["--no-prune"],
        ] {
            let args: Vec<&str> = ["--resume", "a.state"]
                .iter()
                .chain(setting)
                .copied()
                .collect();
            let error = parse(&args).unwrap_err().to_string();
            assert!(
                error.contains("--resume") && error.contains(setting[0]),
                "{setting:?}: {error}"
            );
        }
    }
}
