//! `vcm info`: what a scene file contains, as the renderer understands it.

use std::path::PathBuf;

use anyhow::Context;
use vcm_rs::scene::Scene;

use crate::render::SceneLimits;

/// Arguments of `vcm info`.
#[derive(clap::Args)]
pub struct InfoArgs {
    /// The scene file (.gltf, .glb or .obj).
    #[arg(default_value = "scenes/cornell-box.gltf")]
    scene: PathBuf,
    #[command(flatten)]
    limits: SceneLimits,
}

/// Loads the scene, prints its summary and builds the CPU BVH.
pub fn run(args: &InfoArgs) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    let scene = Scene::load_with(&args.scene, &args.limits.load_options())?;
    let scene = std::sync::Arc::new(scene);
    let load_time = start.elapsed();
    for warning in &scene.warnings {
        tell!("warning: {warning}");
    }
    say!("scene: {}", scene.path.display());
    say!("loaded in {:.3} s", load_time.as_secs_f64());
    say!("{}", scene.features);
    say!(
        "materials: {}, textures: {}, lights: {}, dropped degenerate triangles: {}",
        scene.materials.len(),
        scene.textures.len(),
        scene.lights.len(),
        scene.dropped_triangles
    );
    let c = &scene.camera;
    say!(
        "camera: at {} looking along {}, vertical fov {:.2}°",
        c.position,
        c.forward,
        c.yfov.to_degrees()
    );
    if scene.cameras.len() > 1 {
        let list: Vec<String> = scene.cameras.iter().map(ToString::to_string).collect();
        say!(
            "cameras (render one with --camera INDEX|NAME; the first by default): {}",
            list.join(", ")
        );
    }
    let bvh = vcm_rs::cpu_traversal(&scene).context("building the CPU BVH")?;
    let triangles = scene.mesh.triangle_count().max(1);
    say!(
        "cpu bvh: built in {:.3} s, {:.1} bytes/triangle",
        bvh.build_time().as_secs_f64(),
        bvh.memory_bytes() as f64 / triangles as f64
    );
    Ok(())
}
