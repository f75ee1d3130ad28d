//! Resolution switching: while the camera moves the render runs at a reduced resolution, so
//! that it keeps up with the motion, and returns to full resolution once the camera has been
//! still for [`SETTLE_TIME`].

use std::time::{Duration, Instant};

/// Each side of the preview image is the full side divided by this (rounded down, ≥ 1).
pub const PREVIEW_DIVISOR: u32 = 4;

/// How long the camera must be still before the full resolution returns.
pub const SETTLE_TIME: Duration = Duration::from_millis(250);

/// The preview size of a `full` (width, height) image.
pub fn preview_size((width, height): (u32, u32)) -> (u32, u32) {
    (
        (width / PREVIEW_DIVISOR).max(1),
        (height / PREVIEW_DIVISOR).max(1),
    )
}

/// Chooses between the full and the preview resolution from the time of the last camera move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolutionSwitch {
    full: (u32, u32),
    last_move: Option<Instant>,
}

impl ResolutionSwitch {
    /// A switch for images of `full` (width, height) pixels; the camera has not moved.
    pub fn new(full: (u32, u32)) -> ResolutionSwitch {
        ResolutionSwitch {
            full,
            last_move: None,
        }
    }

    /// The full resolution (width, height).
    pub fn full(&self) -> (u32, u32) {
        self.full
    }

    /// Records that the camera moved at `now`.
    pub fn camera_moved(&mut self, now: Instant) {
        self.last_move = Some(now);
    }

    /// Whether the camera moved less than [`SETTLE_TIME`] before `now`.
    pub fn is_moving(&self, now: Instant) -> bool {
        self.settles_in(now).is_some()
    }

    /// How long after `now` the full resolution returns, or `None` when it already has.
    pub fn settles_in(&self, now: Instant) -> Option<Duration> {
        let since = now.saturating_duration_since(self.last_move?);
        SETTLE_TIME.checked_sub(since).filter(|d| !d.is_zero())
    }

    /// The (width, height) to render at `now`.
    pub fn size(&self, now: Instant) -> (u32, u32) {
        if self.is_moving(now) {
            preview_size(self.full)
        } else {
            self.full
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_resolution_until_the_camera_moves() {
        let switch = ResolutionSwitch::new((512, 384));
        assert_eq!(switch.size(Instant::now()), (512, 384));
        assert!(!switch.is_moving(Instant::now()));
    }

    #[test]
    fn preview_while_moving_and_full_again_once_still() {
        let start = Instant::now();
        let mut switch = ResolutionSwitch::new((512, 384));
        switch.camera_moved(start);
        assert_eq!(switch.size(start), (128, 96));
        // Moving again keeps the preview past the first move's settle time.
        let later = start + SETTLE_TIME / 2;
        switch.camera_moved(later);
        assert_eq!(switch.size(start + SETTLE_TIME), (128, 96));
        assert_eq!(
            switch.settles_in(start + SETTLE_TIME),
            Some(SETTLE_TIME / 2)
        );
        assert_eq!(switch.size(later + SETTLE_TIME), (512, 384));
        assert_eq!(switch.settles_in(later + SETTLE_TIME), None);
    }

    #[test]
    fn preview_of_tiny_images_keeps_a_pixel() {
        assert_eq!(preview_size((3, 1)), (1, 1));
        assert_eq!(preview_size((9, 4)), (2, 1));
    }
}
