//! When the accumulation restarts: a render is a function of its [`View`] (scene, settings,
//! camera, image size); whenever the view differs from the one being rendered, a new render starts.

use vcm_scene::Camera;

use crate::settings::RenderSettings;

/// Everything a render depends on.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Which loaded scene: every scene opened gets the next number.
    pub scene: u64,
    /// Algorithm, backend and options.
    pub settings: RenderSettings,
    /// The camera.
    pub camera: Camera,
    /// Image (width, height) in pixels.
    pub size: (u32, u32),
}

/// The view being rendered, and a count of the renders started.
#[derive(Debug, Default)]
pub struct Session {
    rendering: Option<View>,
    generation: u64,
}

impl Session {
    /// Returns the generation number of a new render when `view` differs from the view being
    /// rendered (or nothing is), and `None` when the current render goes on.
    pub fn restart_if_changed(&mut self, view: &View) -> Option<u64> {
        if self.rendering.as_ref() == Some(view) {
            return None;
        }
        self.rendering = Some(view.clone());
        self.generation += 1;
        Some(self.generation)
    }

    /// The generation of the render going on (0 before the first).
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The view of the render going on, if one is.
    pub fn view(&self) -> Option<&View> {
        self.rendering.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm_rs::integrators::{Algorithm, AlgorithmOption, IntegratorOptions, MergeRadius};
    use vcm_rs::render_loop::{ScheduleOptions, SchedulerKind};
    use vcm_rs::{Backend, Shading};
    use vcm_scene::Bounds;

    fn view() -> View {
        let bounds = Bounds {
            min: glam::Vec3::ZERO,
            max: glam::Vec3::ONE,
        };
        View {
            scene: 1,
            settings: RenderSettings {
                algorithm: AlgorithmOption::Fixed(Algorithm::Pt),
                backend: Backend::Cpu,
                shading: Shading::Cpu,
                integrator: IntegratorOptions {
                    seed: 0,
                    max_depth: None,
                    connections: 1,
                    radius: MergeRadius::SceneFraction(0.003),
                    alpha: 0.75,
                    ..IntegratorOptions::default()
                },
                schedule: ScheduleOptions::default(),
            },
            camera: Camera::framing(&bounds),
            size: (64, 48),
        }
    }

    #[test]
    fn the_first_view_starts_a_render_and_an_unchanged_view_continues_it() {
        let mut session = Session::default();
        assert_eq!(session.view(), None);
        assert_eq!(session.restart_if_changed(&view()), Some(1));
        assert_eq!(session.restart_if_changed(&view()), None);
        assert_eq!(session.generation(), 1);
        assert_eq!(session.view(), Some(&view()));
    }

    #[test]
    fn every_setting_camera_and_size_change_restarts() {
        let changes: [fn(&mut View); 11] = [
            |v| v.scene = 2,
            |v| v.settings.algorithm = AlgorithmOption::Auto,
            |v| v.settings.integrator.max_depth = Some(4),
            |v| v.settings.integrator.radius = MergeRadius::SceneFraction(0.01),
            |v| v.settings.integrator.seed = 7,
            |v| v.settings.integrator.connections = 2,
            |v| v.settings.integrator.alpha = 0.5,
            |v| v.settings.schedule.spp_per_frame = Some(4),
            |v| v.settings.schedule.scheduler = Some(SchedulerKind::None),
            |v| v.camera.position.x += 0.01,
            |v| v.size = (16, 12),
        ];
        let mut session = Session::default();
        session.restart_if_changed(&view());
        for (i, change) in changes.iter().enumerate() {
            let mut changed = view();
            change(&mut changed);
            assert!(
                session.restart_if_changed(&changed).is_some(),
                "change {i} must restart"
            );
            assert_eq!(session.restart_if_changed(&changed), None);
            assert!(session.restart_if_changed(&view()).is_some(), "and back");
        }
        assert_eq!(session.generation(), 1 + 2 * changes.len() as u64);
    }
}
