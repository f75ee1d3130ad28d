//! Rendering with vcm-rs as a library: a scene rendered by one of the algorithms for a number
//! of samples per pixel, written as a linear EXR and a tone-mapped PNG beside it.
//!
//! ```sh
//! cargo run --release --example render -- [SCENE] [OUT.exr] [ALGORITHM] [SPP]
//! ```
//!
//! Defaults: `scenes/cornell-box.gltf`, `render.exr`, `vcm`, 16 samples per pixel, 320
//! pixels wide (the height from the camera's aspect ratio).

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use clap::ValueEnum;
use vcm_rs::integrators::{self, Algorithm, IntegratorOptions};
use vcm_rs::scene::Scene;
use vcm_rs::vcm::Film;

fn main() -> ExitCode {
    match render() {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::FAILURE
        }
    }
}

fn render() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(args.next().unwrap_or("scenes/cornell-box.gltf".into()));
    let output = PathBuf::from(args.next().unwrap_or("render.exr".into()));
    let png = output.with_extension("png");
    if png == output {
        return Err(format!(
            "{}: name the output .exr (the PNG goes beside it)",
            png.display()
        )
        .into());
    }
    let algorithm = match args.next() {
        Some(name) => Algorithm::from_str(&name, true)
            .map_err(|_| format!("unknown algorithm {name:?} (pt, lt, bpt, ppm, bpm or vcm)"))?,
        None => Algorithm::Vcm,
    };
    let spp = match args.next() {
        Some(n) => n
            .parse::<u32>()
            .map_err(|_| format!("samples per pixel must be a whole number, not {n:?}"))?,
        None => 16,
    };

    // Loading fails with an error naming the file and the problem; features the renderer
    // leaves out are warnings, each reported once.
    let scene = Arc::new(Scene::load(&scene_path)?);
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let traversal = Arc::new(vcm_rs::cpu_traversal(&scene)?);
    let (width, height) = integrators::image_size(&scene, 320, None);
    let options = IntegratorOptions::default();
    let mut integrator =
        integrators::build(algorithm, &scene, traversal, (width, height), &options)?;

    // One sample per pixel per frame: frame i renders sample i of every pixel.
    let mut film = Film::new(width, height);
    let mut rays = 0;
    for sample in 0..spp {
        rays += integrator.render_frame(&mut film, sample).rays();
    }
    let image = film.image();
    image.write_exr(&output)?;
    image.write_png(&png, 0.0)?;
    println!(
        "{}: {spp} spp at {width}×{height} with {}, {rays} rays, {} non-finite samples dropped; wrote {}",
        scene_path.display(),
        algorithm.name(),
        film.dropped(),
        output.display()
    );
    Ok(())
}
