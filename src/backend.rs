//! The ray traversal backends a render can run on, chosen at run time: the one place where a
//! backend is named and built, shared by `vcm render`, `vcm convergence` and the viewer.

use std::sync::Arc;

use vcm_scene::{Decision, Scene};
use vcm_traversal::{BuildError, Traversal};
use vcm_traversal_wgpu::{GpuBvh, GpuError};

/// Ray traversal backends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Backend {
    /// obvhs 8-wide BVH on rayon threads.
    Cpu,
    /// WGSL compute shaders through wgpu: a hardware GPU, else Mesa lavapipe.
    Gpu,
}

/// Where a frame's paths are shaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Shading {
    /// On rayon threads; rays go to the traversal backend in batches.
    #[default]
    Cpu,
    /// Whole paths in WGSL kernels on the GPU backend's device (every algorithm, and the
    /// scenes [`vcm_gpu::check_scene`] accepts); only the image comes back.
    Gpu,
}

/// Why a backend could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    /// The scene's triangles are invalid.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// No GPU adapter, or the scene does not fit it.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// A built backend with a one-line description of what it runs on.
#[derive(Clone)]
pub struct BuiltTraversal {
    /// The backend.
    pub traversal: Arc<dyn Traversal>,
    /// e.g. `cpu (2 threads)`, or `gpu: ` and the adapter's name and driver.
    pub description: String,
    /// The GPU backend's hierarchy, for kernels that trace rays of their own (GPU shading);
    /// `None` for the CPU backend.
    pub gpu: Option<Arc<GpuBvh>>,
}

impl Backend {
    /// Every backend, in the order user interfaces list them.
    pub const ALL: &'static [Backend] = &[Backend::Cpu, Backend::Gpu];

    /// The lower-case name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
        }
    }

    /// Whether this backend's traversal tests alpha masks for `scene`, and why: the test
    /// (on the CPU a callback, on the GPU the `alpha_masks.wgsl` module and its buffers)
    /// exists only where some material is alpha-masked.
    pub fn decisions(self, scene: &Scene) -> Vec<Decision> {
        let part = match self {
            Backend::Cpu => "alpha test in the cpu traversal",
            Backend::Gpu => "alpha test in the gpu kernels",
        };
        vec![if scene.features.alpha_masks {
            Decision::runs(part, "some material is alpha-masked")
        } else {
            Decision::left_out(part, "no material is alpha-masked")
        }]
    }

    /// Builds this backend's traversal over `scene` (its BVH, once per scene).
    pub fn traversal(self, scene: &Arc<Scene>) -> Result<Arc<dyn Traversal>, BackendError> {
        self.build(scene).map(|built| built.traversal)
    }

    /// Like [`traversal`](Self::traversal), and says what the backend runs on.
    pub fn build(self, scene: &Arc<Scene>) -> Result<BuiltTraversal, BackendError> {
        Ok(match self {
            Backend::Cpu => BuiltTraversal {
                traversal: Arc::new(crate::cpu_traversal(scene)?),
                description: format!("cpu ({} threads)", rayon::current_num_threads()),
                gpu: None,
            },
            Backend::Gpu => {
                let bvh = Arc::new(crate::gpu_traversal(scene)?);
                let description = format!("gpu: {}", bvh.device().describe());
                BuiltTraversal {
                    traversal: Arc::clone(&bvh) as Arc<dyn Traversal>,
                    description,
                    gpu: Some(bvh),
                }
            }
        })
    }
}

/// One scene's traversal structures, one per backend, each built on first use and kept for
/// every later render of the scene (`vcm experiment`'s runs, the Python package's renders).
pub struct Traversals {
    scene: Arc<Scene>,
    built: Vec<(Backend, BuiltTraversal)>,
}

impl Traversals {
    /// None built yet for `scene`.
    pub fn new(scene: Arc<Scene>) -> Traversals {
        Traversals {
            scene,
            built: Vec::new(),
        }
    }

    /// The structure of `backend`, built now if none was yet (then `on_build` is told what
    /// the backend runs on).
    pub fn get(
        &mut self,
        backend: Backend,
        on_build: impl FnOnce(&BuiltTraversal),
    ) -> Result<Arc<dyn Traversal>, BackendError> {
        Ok(Arc::clone(&self.built(backend, on_build)?.traversal))
    }

    /// [`get`](Self::get), with what the backend offers besides traversal (the GPU
    /// backend's hierarchy, for shading on the GPU).
    pub fn built(
        &mut self,
        backend: Backend,
        on_build: impl FnOnce(&BuiltTraversal),
    ) -> Result<&BuiltTraversal, BackendError> {
        let index = match self.built.iter().position(|(b, _)| *b == backend) {
            Some(index) => index,
            None => {
                let built = backend.build(&self.scene)?;
                on_build(&built);
                self.built.push((backend, built));
                self.built.len() - 1
            }
        };
        Ok(&self.built[index].1)
    }
}
