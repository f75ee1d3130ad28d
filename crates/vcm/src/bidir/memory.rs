//! The memory budget of a VCM frame: what its passes, caches and grids hold at once.

use super::{Vcm, camera_pass, light_pass};
use crate::error::RenderError;
use crate::film::Film;
use crate::hash_grid::HashGrid;
use crate::integrator::Schedule;
use crate::light_vertex_cache::LightVertex;
use crate::memory::{MemoryEstimate, bytes_of, check_render};

impl Vcm {
    /// Estimates the memory of a frame with `schedule` and `connections` per camera vertex,
    /// the film it renders into included: the paths in flight (the larger of the two
    /// passes'), the camera samples, the light paths' results, and per sample per pixel a
    /// light vertex cache of the preprocess's capacity and the build of its hash grid.
    pub(super) fn memory_estimate(&self, schedule: Schedule, connections: u32) -> MemoryEstimate {
        let (width, height) = (self.settings.width, self.settings.height);
        let pixels = u64::from(width) * u64::from(height);
        let samples = u64::from(schedule.samples_per_frame);
        let in_flight =
            |grid| (schedule.scheduler).most_paths_in_flight(grid, schedule.samples_per_frame);
        let paths = in_flight((width, height)).max(in_flight(self.settings.light_path_grid()));
        let per_path = camera_pass::bytes_per_path(connections).max(light_pass::BYTES_PER_PATH);
        let vertices = if self.plan.cache {
            samples.saturating_mul(self.cache_capacity as u64)
        } else {
            0
        };
        // A splat per light vertex at most; light tracing keeps no vertices but splats one
        // per path at least.
        let splats = if self.plan.splats {
            vertices.max(self.settings.light_paths() * samples)
        } else {
            0
        };
        // The grids are built side by side: all of their lists at once, at most.
        let grids = if self.plan.merges {
            HashGrid::bytes_to_build(vertices)
        } else {
            0
        };
        MemoryEstimate::default()
            .with("film", pixels.saturating_mul(Film::BYTES_PER_PIXEL))
            .with("paths in flight", paths.saturating_mul(per_path))
            .with(
                "camera samples",
                (pixels * samples).saturating_mul(camera_pass::BYTES_PER_SAMPLE),
            )
            .with(
                "light paths' results",
                vertices
                    .saturating_mul(light_pass::BYTES_PER_RESULT_VERTEX)
                    .saturating_add(splats.saturating_mul(light_pass::BYTES_PER_SPLAT)),
            )
            .with("light vertex caches", bytes_of::<LightVertex>(vertices))
            .with("hash grids", grids)
    }

    /// Fails when a frame with `schedule` would need more memory than is available, past
    /// what a frame with the `current` schedule allocated already.
    pub(super) fn check_memory(
        &self,
        schedule: Schedule,
        current: Option<Schedule>,
    ) -> Result<(), RenderError> {
        Ok(check_render(
            schedule,
            self.settings.connections,
            current,
            |schedule, connections| self.memory_estimate(schedule, connections),
        )?)
    }
}
