//! Splitting an image into square tiles, and handing them out to whichever worker asks first.

use std::sync::atomic::{AtomicUsize, Ordering};

use crate::StopFlag;

/// A rectangle of pixels `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Tile {
    /// Pixels in the tile.
    pub fn len(&self) -> usize {
        ((self.x1 - self.x0) * (self.y1 - self.y0)) as usize
    }

    /// Whether the tile has no pixels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Pixel indices (`y · width + x`) of the tile in row order.
    pub fn pixels(&self, width: u32) -> impl Iterator<Item = u32> + '_ {
        (self.y0..self.y1).flat_map(move |y| (self.x0..self.x1).map(move |x| y * width + x))
    }
}

/// An image cut into tiles of `size × size` pixels (smaller at the right and bottom edges),
/// numbered row by row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileGrid {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Tile side in pixels (at least 1).
    pub size: u32,
}

impl TileGrid {
    /// Tiles of `size` (at least 1) over a `width × height` image.
    pub fn new(width: u32, height: u32, size: u32) -> Self {
        Self {
            width,
            height,
            size: size.max(1),
        }
    }

    fn columns(&self) -> u32 {
        self.width.div_ceil(self.size)
    }

    /// Number of tiles.
    pub fn len(&self) -> usize {
        (self.columns() * self.height.div_ceil(self.size)) as usize
    }

    /// Whether the image has no pixels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Tile `index` (row by row).
    pub fn tile(&self, index: usize) -> Tile {
        let columns = self.columns() as usize;
        let (tx, ty) = ((index % columns) as u32, (index / columns) as u32);
        let (x0, y0) = (tx * self.size, ty * self.size);
        Tile {
            x0,
            y0,
            x1: (x0 + self.size).min(self.width),
            y1: (y0 + self.size).min(self.height),
        }
    }
}

/// The tiles of a [`TileGrid`] taken one by one, in order, from a shared counter, until the
/// last is taken or a stop is requested.
pub(crate) struct TileCounter<'a> {
    grid: TileGrid,
    next: AtomicUsize,
    stop: &'a StopFlag,
}

impl<'a> TileCounter<'a> {
    /// Every tile of `grid`, none taken yet; none is handed out once `stop` is raised.
    pub fn new(grid: TileGrid, stop: &'a StopFlag) -> Self {
        Self {
            grid,
            next: AtomicUsize::new(0),
            stop,
        }
    }

    /// The next tile nobody has taken, if any is left and no stop is requested.
    pub fn take(&self) -> Option<Tile> {
        if self.stop.is_raised() {
            return None;
        }
        let index = self.next.fetch_add(1, Ordering::Relaxed);
        (index < self.grid.len()).then(|| self.grid.tile(index))
    }

    /// Whether every tile has been taken, or a stop is requested.
    pub fn exhausted(&self) -> bool {
        self.stop.is_raised() || self.next.load(Ordering::Relaxed) >= self.grid.len()
    }

    /// Whether a stop is requested.
    pub fn stopped(&self) -> bool {
        self.stop.is_raised()
    }

    /// Number of tiles, taken or not.
    pub fn len(&self) -> usize {
        self.grid.len()
    }

    /// The active paths below which a wavefront pulls in the next tile: `merge_below` of a
    /// full tile (0 for a negative fraction).
    pub fn merge_at(&self, merge_below: f32) -> usize {
        (merge_below.max(0.0) * (self.grid.size * self.grid.size) as f32) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_every_pixel_once() {
        for (w, h, s) in [(1, 1, 64), (100, 37, 16), (64, 64, 64), (65, 1, 8)] {
            let grid = TileGrid::new(w, h, s);
            let mut seen = vec![0u32; (w * h) as usize];
            for t in 0..grid.len() {
                let tile = grid.tile(t);
                assert!(!tile.is_empty() && tile.len() <= (s * s) as usize);
                for p in tile.pixels(w) {
                    seen[p as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{w}x{h} tiles of {s}");
        }
    }
}
