//! `--backend gpu` from the command line: the same images as the CPU backend, and a clear
//! message when there is no adapter. Set `VCM_REQUIRE_GPU=1` (as `.ci/run` does) to make a
//! missing adapter a failure instead of a skip.

use std::process::{Command, Output};
use std::sync::Arc;

use vcm::image_io::RgbImage;
use vcm_rs::scene::texture::ColorEncoding;
use vcm_rs::scene::{Filter, Texture, UvTransform};
use vcm_rs::traversal::{HitBatch, RayBatch, Traversal};
use vcm_rs::traversal_wgpu::{GpuBvh, GpuBvhOptions};

fn vcm(args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(args)
        .envs(env.iter().copied())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the vcm binary runs")
}

fn have_gpu() -> bool {
    vcm_rs::traversal_wgpu::device_or_skip().is_some()
}

/// Both backends find the same triangle for every ray (the parity test in
/// vcm-traversal-wgpu); their hit distances may differ in the last bits, so the images
/// agree to rounding, far below the renders' own noise. The GPU backend paces its frames
/// (1 sample, then more: a frame of 64 × 64 pixels takes far less than the second a paced
/// frame may take) where the CPU renders one sample per frame, and still renders the same
/// samples.
#[test]
fn gpu_renders_match_cpu_renders() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for algo in ["pt", "vcm"] {
        let render = |backend: &str| {
            let path = dir.path().join(format!("{algo}-{backend}.exr"));
            let args = [
                "render",
                "--algo",
                algo,
                "--backend",
                backend,
                "--spp",
                "4",
                "--width",
                "64",
                "-o",
                path.to_str().unwrap(),
            ];
            let output = vcm(&args, &[]);
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert!(output.status.success(), "{stderr}");
            assert!(
                stderr.contains(&format!("traversal: {backend}")),
                "{stderr}"
            );
            let stdout = String::from_utf8_lossy(&output.stdout);
            let frames = stdout
                .lines()
                .find_map(|line| line.strip_prefix("frames: "))
                .and_then(|rest| rest.split(' ').next()?.parse::<u32>().ok())
                .unwrap_or_else(|| panic!("no frame count: {stdout}"));
            let expected = if backend == "cpu" { 4..=4 } else { 2..=3 };
            assert!(expected.contains(&frames), "{backend}: {stdout}");
            RgbImage::read_exr(&path).unwrap()
        };
        let (cpu, gpu) = (render("cpu"), render("gpu"));
        let metrics = vcm::metrics::compare(&gpu.pixels, &cpu.pixels).unwrap();
        let mean = cpu.pixels.iter().map(|p| p.element_sum()).sum::<f32>();
        assert!(mean > 0.0);
        assert!(metrics.relmse < 1e-9, "{algo}: {metrics:?}");
    }
}

/// The queue scheduler keeps several GPU jobs in flight (`Traversal::submit`) while it shades;
/// every ray is still traced on its own, so the image is the one batch per pass gives, bit for
/// bit.
#[test]
fn the_queue_scheduler_renders_the_same_gpu_image() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for algo in ["pt", "vcm"] {
        let render = |name: &str, schedule: &[&str]| {
            let path = dir.path().join(format!("{algo}-{name}.exr"));
            let mut args = vec![
                "render",
                "--algo",
                algo,
                "--backend",
                "gpu",
                "--spp",
                "2",
                "--width",
                "48",
            ];
            args.extend_from_slice(schedule);
            args.extend_from_slice(&["-o", path.to_str().unwrap()]);
            let output = vcm(&args, &[]);
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert!(output.status.success(), "{stderr}");
            RgbImage::read_exr(&path).unwrap().pixels
        };
        let one_batch = render("none", &["--scheduler", "none"]);
        let queues = ["--scheduler", "queue", "--queues", "4", "--tile-size", "8"];
        assert!(one_batch.iter().any(|p| p.max_element() > 0.0));
        assert!(render("queue", &queues) == one_batch, "{algo}");
    }
}

#[test]
fn no_adapter_is_a_clear_error() {
    // Only the Vulkan, Metal and DX12 backends are built in: asking for OpenGL finds nothing.
    let output = vcm(
        &["render", "--backend", "gpu", "--spp", "1", "--width", "8"],
        &[("WGPU_BACKEND", "gl")],
    );
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("no GPU adapter found"), "{stderr}");
    assert!(stderr.contains("mesa-vulkan-drivers"), "{stderr}");
}

/// Alpha masks evaluated on the GPU (the scene's texture lookup, in single precision) cut
/// the same holes as the CPU backend's: the same primitive for camera rays through the
/// Khronos alpha-mode test scene, except a few rays where the filtered alpha lands within
/// rounding of the cutoff. Without the masks many rays would differ, so the check has teeth.
#[test]
fn alpha_masks_match_the_cpu_backend() {
    if !have_gpu() {
        return;
    }
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/scenes/khronos-samples/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf"
    );
    let scene = vcm_rs::scene::Scene::load(path).unwrap();
    assert!(scene.features.alpha_masks);
    assert_masks_agree(&Arc::new(scene));
    // The same masks with their textures moved, turned and stretched (KHR_texture_transform).
    let mut transformed = vcm_rs::scene::Scene::load(path).unwrap();
    let transform = UvTransform::from_offset_rotation_scale(
        glam::Vec2::new(0.3, -0.2),
        0.7,
        glam::Vec2::new(1.6, 0.7),
    );
    for material in &mut transformed.materials {
        if let Some(texture) = &mut material.base_color_texture {
            texture.transform = transform;
        }
    }
    assert_masks_agree(&Arc::new(transformed));
    // The masks' texture replaced by 5 × 3 texels of assorted alpha, each several pixels
    // wide, looked up bilinearly and as nearest texels: both backends cut the nearest-texel
    // holes, which differ from the bilinear ones.
    let magnified = |filter| {
        let mut scene = vcm_rs::scene::Scene::load(path).unwrap();
        let texels = (0..15u8)
            .map(|i| [255, 255, 255, (i * 7 % 5) * 60])
            .collect();
        let mut coarse = Texture::new("coarse".into(), 5, 3, texels, ColorEncoding::Srgb).unwrap();
        coarse.filter = filter;
        for material in &scene.materials {
            if material.alpha_mask().is_some() {
                let texture = material.base_color_texture.unwrap();
                scene.textures[texture.index] = coarse.clone();
            }
        }
        Arc::new(scene)
    };
    let bilinear = assert_masks_agree(&magnified(Filter::Bilinear));
    let nearest = assert_masks_agree(&magnified(Filter::Nearest));
    let changed = bilinear
        .iter()
        .zip(&nearest)
        .filter(|(a, b)| a != b)
        .count();
    eprintln!("nearest texels change {changed} of {} rays", nearest.len());
    // Were the GPU to filter bilinearly anyway, it would miss the CPU's holes in that many
    // rays: far more than the disagreement `assert_masks_agree` tolerates (0.1%).
    assert!(changed as f64 > 5e-3 * nearest.len() as f64);
}

/// The CPU and GPU backends agree on `scene`'s camera rays (closest hits and occlusion),
/// and its masks cut holes: many rays go through where unmasked triangles would stop them.
/// Returns the CPU backend's hit primitives.
fn assert_masks_agree(scene: &Arc<vcm_rs::scene::Scene>) -> Vec<u32> {
    let size = 256;
    let mut rays = RayBatch::default();
    for y in 0..size {
        for x in 0..size {
            let raster = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let direction = scene.camera.direction(size, size, raster);
            rays.push(scene.camera.position, direction, 0.0, f32::INFINITY);
        }
    }
    let trace = |traversal: &dyn Traversal| {
        let mut hits = HitBatch::default();
        traversal.intersect(&rays, &mut hits);
        let mut occluded = Vec::new();
        traversal.occluded(&rays, &mut occluded);
        (hits.prim, occluded)
    };
    let (cpu_prims, cpu_occluded) = trace(&vcm_rs::cpu_traversal(scene).unwrap());
    let (gpu_prims, gpu_occluded) = trace(&vcm_rs::gpu_traversal(scene).unwrap());
    let differ = |a: &[u32], b: &[u32]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    let differences = differ(&cpu_prims, &gpu_prims);
    let occlusion_differences = cpu_occluded
        .iter()
        .zip(&gpu_occluded)
        .filter(|(a, b)| a != b);
    eprintln!("alpha masks: {differences} of {} rays differ", rays.len());
    assert!(
        differences as f64 <= 1e-3 * rays.len() as f64,
        "{differences} rays differ"
    );
    assert!(occlusion_differences.count() as f64 <= 1e-3 * rays.len() as f64);

    let triangles = scene.triangle_corners();
    let unmasked = GpuBvh::open(&triangles, GpuBvhOptions::default()).unwrap();
    let (unmasked_prims, _) = trace(&unmasked);
    let holes = differ(&cpu_prims, &unmasked_prims);
    assert!(
        holes > 100 * differences.max(1),
        "masks cut only {holes} holes"
    );
    cpu_prims
}

/// `--shading gpu`: the GPU path tracer renders the CPU path tracer's image up to rounding
/// (`--algo auto` renders pt: an image this small is not piloted), `--explain` says where
/// paths are shaded, the
/// bidirectional algorithms render on the GPU too (with their parts), GPU shading without the
/// GPU backend fails with the reason before anything is written, and a scene with an
/// environment map renders.
/// `--algo auto` with `--shading gpu` pilots the candidates on the GPU, and chooses what
/// pilots on the CPU choose: VCM for the water's caustics, path tracing for the plain box.
#[test]
fn gpu_shading_pilots_auto_on_the_gpu() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("auto.exr");
    let chosen = |scene: &str, shading: &[&str]| {
        let scene = format!("scenes/{scene}.gltf");
        let common = [
            "render", &scene, "--spp", "1", "--width", "64", "--height", "64",
        ];
        let out = ["-o", out.to_str().unwrap()];
        let args: Vec<&str> = common.iter().chain(shading).chain(&out).copied().collect();
        let output = vcm(&args, &[]);
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "{stderr}");
        let line = stderr.lines().find(|l| l.starts_with("algorithm: "));
        let line = line.unwrap_or_else(|| panic!("no choice told: {stderr}"));
        assert!(line.contains("pilots of"), "{line}");
        line.split_whitespace().nth(1).unwrap().to_owned()
    };
    let on_gpu = ["--backend", "gpu", "--shading", "gpu"];
    for (scene, expected) in [("cornell-water", "vcm"), ("cornell-box", "pt")] {
        assert_eq!(chosen(scene, &[]), expected, "{scene} on the CPU");
        assert_eq!(chosen(scene, &on_gpu), expected, "{scene} on the GPU");
    }
}

#[test]
fn gpu_shading_renders_the_cpu_path_tracers_image() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let (cpu, gpu) = (path("cpu.exr"), path("gpu.exr"));
    let common = [
        "render",
        "scenes/cornell-water.gltf",
        "--spp",
        "4",
        "--width",
        "48",
    ];
    let run = |extra: &[&str], out: &str| {
        let args: Vec<&str> = common
            .iter()
            .chain(extra)
            .copied()
            .chain(["-o", out])
            .collect();
        let output = vcm(&args, &[]);
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "{stderr}");
        (String::from_utf8_lossy(&output.stdout).into_owned(), stderr)
    };
    run(&["--algo", "pt"], &cpu);
    let (stdout, stderr) = run(&["--backend", "gpu", "--shading", "gpu", "--explain"], &gpu);
    assert!(stdout.contains("shading on the GPU: runs"), "{stdout}");
    assert!(
        stderr.contains("algorithm: pt (an image of fewer"),
        "{stderr}"
    );
    let read = |path: &str| RgbImage::read_exr(std::path::Path::new(path)).unwrap();
    let (a, b) = (read(&cpu), read(&gpu));
    let close = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(p, q)| (**p - **q).abs().max_element() <= 1e-4 * p.max_element().max(1e-2))
        .count();
    assert!(
        close * 100 >= 99 * a.pixels.len(),
        "{close} of {} pixels agree",
        a.pixels.len()
    );

    let parts = [
        ("lt", "light vertex cache: left out"),
        ("bpt", "light vertex cache: runs"),
        ("vcm", "merging and hash grid: runs"),
    ];
    for (algo, part) in parts {
        let args = [
            "--algo",
            algo,
            "--backend",
            "gpu",
            "--shading",
            "gpu",
            "--explain",
        ];
        let (stdout, _) = run(&args, &path(&format!("{algo}.exr")));
        for said in ["shading on the GPU: runs", part] {
            assert!(stdout.contains(said), "{algo}, {said}: {stdout}");
        }
    }

    let refused = [(&["--shading", "gpu"][..], "give --backend gpu too")];
    for (extra, message) in refused {
        let out = path("refused.exr");
        let args: Vec<&str> = common
            .iter()
            .chain(extra)
            .copied()
            .chain(["-o", &out])
            .collect();
        let output = vcm(&args, &[]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            !output.status.success() && stderr.contains(message),
            "{stderr}"
        );
        assert!(!dir.path().join("refused.exr").exists());
    }
    // An image whose films would not fit in memory is refused before they are allocated.
    let out = path("huge.exr");
    let args = [
        "render",
        "--backend",
        "gpu",
        "--shading",
        "gpu",
        "--width",
        "60000",
        "--height",
        "60000",
        "-o",
        &out,
    ];
    let output = vcm(&args, &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && stderr.contains("lower --width or --height"),
        "{stderr}"
    );
    assert!(!dir.path().join("huge.exr").exists());

    // With an environment map (a 2×1 Radiance image) around the Cornell box it renders.
    let mut gltf: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("scenes/cornell-box.gltf").unwrap()).unwrap();
    gltf["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push("VCM_environment".into());
    gltf["extensions"] = serde_json::json!({"VCM_environment": {"image": "sky.hdr"}});
    let mut sky = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
    sky.extend([128, 128, 128, 129, 64, 64, 128, 129]);
    std::fs::write(dir.path().join("sky.hdr"), sky).unwrap();
    let scene = path("sky.gltf");
    std::fs::write(&scene, gltf.to_string()).unwrap();
    let out = path("sky.exr");
    let args = [
        "render",
        &scene,
        "--backend",
        "gpu",
        "--shading",
        "gpu",
        "--spp",
        "1",
        "--width",
        "16",
        "-o",
        &out,
    ];
    let output = vcm(&args, &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(dir.path().join("sky.exr").exists());
}

/// Alpha masks with GPU shading: the kernels trace with the GPU backend's mask test, so on
/// the Khronos alpha-mode model (lit by a point light and a sky) they render the paths of the
/// CPU's path tracer and light tracer, which test the masks on the CPU: at least 99% of the
/// pixels within 10⁻⁴ (98% for light tracing, whose paths each reach several pixels); BPT's
/// image the CPU's in expectation (sums within 1%).
#[test]
fn gpu_shading_tests_alpha_masks_as_the_cpu_does() {
    use vcm::{Algorithm, Film, Integrator, Schedule};
    use vcm_rs::integrators::{IntegratorOptions, build, build_on_gpu};
    use vcm_rs::scene::Scene;
    use vcm_rs::scene::relight::lit_by_bulb_and_sky;

    if !have_gpu() {
        return;
    }
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/scenes/khronos-samples/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf"
    );
    let scene = Arc::new(lit_by_bulb_and_sky(Scene::load(path).unwrap()));
    assert!(scene.features.alpha_masks);
    let (size, spp) = ((48, 36), 4);
    let render = |integrator: &mut dyn Integrator| {
        let schedule = Schedule {
            samples_per_frame: spp,
            ..Schedule::ONE_BATCH
        };
        integrator.set_schedule(schedule).unwrap();
        let mut film = Film::new(size.0, size.1);
        integrator.render_frame(&mut film, 0);
        film.mean()
    };
    let options = IntegratorOptions::default();
    let cpu_traversal = Arc::new(vcm_rs::cpu_traversal(&scene).unwrap());
    let bvh = vcm_rs::gpu_traversal(&scene).unwrap();
    for algorithm in Algorithm::ALL {
        let traversal = Arc::clone(&cpu_traversal) as Arc<dyn vcm_rs::traversal::Traversal>;
        let mut cpu = build(algorithm, &scene, traversal, size, &options).unwrap();
        let mut gpu = build_on_gpu(algorithm, &scene, &bvh, size, &options).unwrap();
        let (a, b) = (render(cpu.as_mut()), render(gpu.as_mut()));
        let close = a
            .iter()
            .zip(&b)
            .filter(|(p, q)| (**p - **q).abs().max_element() <= 1e-4 * p.max_element().max(1e-2))
            .count();
        let least = match algorithm {
            Algorithm::Pt => 99,
            Algorithm::Bpt | Algorithm::Bpm | Algorithm::Vcm => {
                // A light path that a rounding difference sends elsewhere (lt: 5 pixels of
                // 1,728 differ here) moves the cache's later vertices, which BPT and VCM pick
                // by index, and changes what BPM merges around it: their images agree in
                // expectation.
                let sum = |image: &[glam::Vec3]| {
                    image
                        .iter()
                        .map(|p| f64::from(p.element_sum()))
                        .sum::<f64>()
                };
                let (x, y) = (sum(&a), sum(&b));
                assert!(
                    (x - y).abs() <= 0.01 * x,
                    "{}: sums {x} and {y}",
                    algorithm.name()
                );
                continue;
            }
            _ => 98,
        };
        assert!(
            close * 100 >= least * a.len(),
            "{}: {close} of {} pixels agree",
            algorithm.name(),
            a.len()
        );
    }
}

/// `vcm experiment` runs with `--shading gpu` too: PT shaded on the GPU and on the CPU render
/// the same paths, so their errors against the same reference agree to rounding.
#[test]
fn experiments_take_gpu_shading() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-water.gltf");
    let toml = format!(
        "title = \"GPU shading\"\nwidth = 24\nspp = 4\n\
         [reference]\noptions = \"--algo pt --seed 1000\"\nspp = 8\n\
         [[scenes]]\npath = \"{scene}\"\n\
         [[runs]]\nname = \"cpu\"\noptions = \"--algo pt\"\n\
         [[runs]]\nname = \"gpu\"\noptions = \"--backend gpu --shading gpu\"\n"
    );
    let file = dir.path().join("gpu.toml");
    std::fs::write(&file, toml).unwrap();
    let output = vcm(&["experiment", file.to_str().unwrap()], &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let table = std::fs::read_to_string(dir.path().join("gpu/table.csv")).unwrap();
    let relmse = |run: &str| -> f64 {
        let line = table
            .lines()
            .find(|l| l.contains(&format!(",{run},")))
            .unwrap();
        line.split(',').nth(6).unwrap().parse().unwrap()
    };
    let (cpu, gpu) = (relmse("cpu"), relmse("gpu"));
    assert!((cpu - gpu).abs() <= 1e-3 * cpu, "{table}");
}
