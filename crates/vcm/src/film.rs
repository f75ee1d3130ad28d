//! Accumulation of radiance samples per pixel.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::exact_sum::ExactSum;
use crate::image_io::RgbImage;
use crate::prefetch::prefetch_all;

/// Additions [`FilmBand::add_each`] loads a pixel's sums ahead of.
const LOOK_AHEAD: usize = 8;

/// The exact sums of a pixel's red, green and blue samples.
pub type PixelSum = [ExactSum; 3];

/// Radiance samples accumulated per pixel, with a box pixel filter: each sample's position is
/// uniform over its pixel, so a pixel's value is the plain mean of its samples.
///
/// The sums are exact ([`ExactSum`]): the film a set of samples and splats gives does not
/// depend on the order they are added in, so frames, resumed renders and merged shards of
/// the same samples give the same film bit for bit. They are rounded once, to `f64`, when
/// the mean is read.
///
/// Pixels are indexed row by row from the top-left corner: `pixel = y · width + x`.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    /// Sum of the accepted samples per pixel (radiance, W·sr⁻¹·m⁻² in scene units, RGB).
    sum: Vec<PixelSum>,
    /// Number of samples taken per pixel, dropped ones included.
    samples: Vec<u64>,
    /// Samples dropped because a channel was NaN or infinite.
    dropped: u64,
}

impl Film {
    /// Bytes a film holds per pixel: its exact RGB sums and its sample count.
    pub const BYTES_PER_PIXEL: u64 = (size_of::<PixelSum>() + size_of::<u64>()) as u64;

    /// An empty film of `width` × `height` pixels.
    pub fn new(width: u32, height: u32) -> Film {
        let pixels = width as usize * height as usize;
        Film {
            width,
            height,
            sum: vec![[ExactSum::ZERO; 3]; pixels],
            samples: vec![0; pixels],
            dropped: 0,
        }
    }

    /// A film of `width` × `height` pixels holding `sum` and `samples` per pixel and
    /// `dropped` non-finite samples ([`Film::sums`], [`Film::sample_counts`],
    /// [`Film::dropped`] of another film); `None` when the lengths are not the pixel count.
    pub fn from_parts(
        (width, height): (u32, u32),
        sum: Vec<PixelSum>,
        samples: Vec<u64>,
        dropped: u64,
    ) -> Option<Film> {
        let pixels = width as usize * height as usize;
        (sum.len() == pixels && samples.len() == pixels).then_some(Film {
            width,
            height,
            sum,
            samples,
            dropped,
        })
    }

    /// The exact sum of each pixel's samples and splats, per channel.
    pub fn sums(&self) -> &[PixelSum] {
        &self.sum
    }

    /// The samples taken per pixel (dropped ones included).
    pub fn sample_counts(&self) -> &[u64] {
        &self.samples
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Records one radiance sample (RGB, W·sr⁻¹·m⁻² in scene units) for `pixel`.
    ///
    /// A sample with a NaN or infinite channel is not added: it counts as a sample of zero
    /// radiance (so the pixel's mean stays an average over the samples taken) and is counted in
    /// [`Film::dropped`]. Panics if `pixel` is outside the image.
    pub fn add(&mut self, pixel: usize, rgb: Vec3) {
        self.samples[pixel] += 1;
        accumulate(&mut self.sum[pixel], &mut self.dropped, rgb);
    }

    /// Adds a light tracing splat to `pixel`: radiance that reaches the pixel from a light
    /// path, already divided by the number of light paths of its frame. Unlike
    /// [`Film::add`] it does not count as a sample (each frame's camera samples do). A
    /// non-finite splat is dropped and counted. Panics if `pixel` is outside the image.
    pub fn add_splat(&mut self, pixel: usize, rgb: Vec3) {
        accumulate(&mut self.sum[pixel], &mut self.dropped, rgb);
    }

    /// Runs `add` once for each band of consecutive pixels (one band per thread of the
    /// rayon pool), the bands in parallel. Each call is meant to offer the band every
    /// sample and splat, in one order: the band takes those of its own pixels. A pixel so
    /// receives its additions in the order the calls make them, and its sums are bit for bit
    /// those of calling [`Film::add`] and [`Film::add_splat`] in that order on one thread.
    pub fn add_in_bands(&mut self, add: impl Fn(&mut FilmBand<'_>) + Sync) {
        let pixels = self.sum.len();
        let size = pixels.div_ceil(rayon::current_num_threads()).max(1);
        let dropped: u64 = self
            .sum
            .par_chunks_mut(size)
            .zip(self.samples.par_chunks_mut(size))
            .enumerate()
            .map(|(band, (sum, samples))| {
                let mut band = FilmBand {
                    first: band * size,
                    pixels,
                    sum,
                    samples,
                    dropped: 0,
                };
                add(&mut band);
                band.dropped
            })
            .sum();
        self.dropped += dropped;
    }

    /// Number of samples dropped as non-finite, over all pixels.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Number of samples taken for `pixel` (dropped ones included).
    pub fn samples(&self, pixel: usize) -> u64 {
        self.samples[pixel]
    }

    /// Mean radiance per pixel (W·sr⁻¹·m⁻², RGB), zero for pixels without samples.
    pub fn mean(&self) -> Vec<Vec3> {
        self.sum
            .iter()
            .zip(&self.samples)
            .map(|(sum, &n)| {
                if n == 0 {
                    Vec3::ZERO
                } else {
                    (rounded_sum(sum) / n as f64).as_vec3()
                }
            })
            .collect()
    }

    /// The [mean](Film::mean) as an image, to write as EXR or tone-mapped PNG.
    pub fn image(&self) -> RgbImage {
        RgbImage {
            width: self.width as usize,
            height: self.height as usize,
            pixels: self.mean(),
        }
    }

    /// Adds the samples of `other`, a film of the same size (panics otherwise). The sums are
    /// exact, so merging films is associative and commutative.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!(
            (self.width, self.height),
            (other.width, other.height),
            "merging films of different sizes"
        );
        for (sum, o) in self.sum.iter_mut().zip(&other.sum) {
            for (channel, o) in sum.iter_mut().zip(o) {
                channel.add(o);
            }
        }
        for (n, o) in self.samples.iter_mut().zip(&other.samples) {
            *n += o;
        }
        self.dropped += other.dropped;
    }
}

/// Consecutive pixels of a [`Film`], for [`Film::add_in_bands`]: additions to other pixels
/// are left to the other bands.
pub struct FilmBand<'a> {
    /// The band's first pixel.
    first: usize,
    /// Pixels in the whole image.
    pixels: usize,
    sum: &'a mut [PixelSum],
    samples: &'a mut [u64],
    dropped: u64,
}

impl FilmBand<'_> {
    /// [`Film::add`] if `pixel` lies in the band. Panics if it is outside the image.
    #[inline]
    pub fn add(&mut self, pixel: usize, rgb: Vec3) {
        if let Some(i) = self.index(pixel) {
            self.samples[i] += 1;
            accumulate(&mut self.sum[i], &mut self.dropped, rgb);
        }
    }

    /// [`Film::add_splat`] if `pixel` lies in the band. Panics if it is outside the image.
    #[inline]
    pub fn add_splat(&mut self, pixel: usize, rgb: Vec3) {
        if let Some(i) = self.index(pixel) {
            accumulate(&mut self.sum[i], &mut self.dropped, rgb);
        }
    }

    /// Adds each of `items` at the pixel and radiance `addition` gives it: as a sample
    /// ([`FilmBand::add`]) where `counted`, else as a splat ([`FilmBand::add_splat`]), in
    /// the order of `items`. Loads the sums of the pixel 8 items ahead (`LOOK_AHEAD`) while it
    /// adds to the current one: a film is larger than the caches, and one sum's cache misses
    /// would otherwise each wait alone.
    #[inline]
    pub fn add_each<T>(
        &mut self,
        (items, counted): (&[T], bool),
        addition: impl Fn(&T) -> (usize, Vec3),
    ) {
        for (k, item) in items.iter().enumerate() {
            if let Some(ahead) = items.get(k + LOOK_AHEAD) {
                self.prefetch(addition(ahead).0);
            }
            let (pixel, rgb) = addition(item);
            if counted {
                self.add(pixel, rgb);
            } else {
                self.add_splat(pixel, rgb);
            }
        }
    }

    /// Starts loading `pixel`'s sums if it lies in the band (a hint: changes nothing).
    #[inline]
    fn prefetch(&self, pixel: usize) {
        if let Some(sum) = pixel.checked_sub(self.first).and_then(|i| self.sum.get(i)) {
            prefetch_all(sum);
        }
    }

    /// `pixel`'s index in the band, if it lies there.
    #[inline]
    fn index(&self, pixel: usize) -> Option<usize> {
        assert!(pixel < self.pixels, "pixel {pixel} outside the image");
        pixel
            .checked_sub(self.first)
            .filter(|&i| i < self.sum.len())
    }
}

/// Adds `rgb` to `sum` if every channel is finite, else counts it in `dropped`.
#[inline]
fn accumulate(sum: &mut PixelSum, dropped: &mut u64, rgb: Vec3) {
    if rgb.is_finite() {
        for (channel, value) in sum.iter_mut().zip(rgb.to_array()) {
            channel.add_f32(value);
        }
    } else {
        *dropped += 1;
    }
}

/// A pixel's sums, each rounded to the nearest `f64`.
pub fn rounded_sum(sum: &PixelSum) -> DVec3 {
    DVec3::from_array(sum.each_ref().map(ExactSum::to_f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_averages_the_samples_of_each_pixel() {
        let mut film = Film::new(2, 1);
        film.add(0, Vec3::new(1.0, 2.0, 3.0));
        film.add(0, Vec3::new(3.0, 2.0, 1.0));
        assert_eq!(film.mean(), vec![Vec3::splat(2.0), Vec3::ZERO]);
        assert_eq!((film.samples(0), film.samples(1)), (2, 0));
        let image = film.image();
        assert_eq!((image.width, image.height), (2, 1));
        assert_eq!(image.pixels, film.mean());
    }

    #[test]
    fn non_finite_samples_are_dropped_and_counted() {
        let mut film = Film::new(1, 1);
        film.add(0, Vec3::splat(4.0));
        film.add(0, Vec3::new(f32::NAN, 1.0, 1.0));
        film.add(0, Vec3::new(1.0, f32::INFINITY, 1.0));
        film.add(0, Vec3::new(1.0, 1.0, f32::NEG_INFINITY));
        assert_eq!(film.dropped(), 3);
        assert_eq!(film.samples(0), 4);
        assert_eq!(film.mean(), vec![Vec3::splat(1.0)]);
    }

    #[test]
    fn splats_add_radiance_without_counting_samples() {
        let mut film = Film::new(1, 1);
        film.add(0, Vec3::ONE);
        film.add_splat(0, Vec3::splat(2.0));
        film.add_splat(0, Vec3::splat(f32::NAN));
        assert_eq!(film.samples(0), 1);
        assert_eq!(film.dropped(), 1);
        assert_eq!(film.mean(), vec![Vec3::splat(3.0)]);
    }

    /// Adds samples and splats, some non-finite, over every pixel of a 7 × 5 film.
    fn offer(mut add: impl FnMut(bool, usize, Vec3)) {
        for k in 0..300u32 {
            let pixel = (k as usize * 17) % 35;
            let value = Vec3::new(k as f32 * 0.1, 1.0 / (k + 1) as f32, (k % 7) as f32);
            let value = if k % 41 == 0 { Vec3::NAN } else { value };
            add(k % 3 == 0, pixel, value);
        }
    }

    #[test]
    fn bands_add_bit_for_bit_what_one_thread_adds() {
        let mut serial = Film::new(7, 5);
        offer(|splat, pixel, rgb| match splat {
            true => serial.add_splat(pixel, rgb),
            false => serial.add(pixel, rgb),
        });
        for threads in [1, 2, 3, 8, 64] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
            let mut banded = Film::new(7, 5);
            pool.expect("a thread pool").install(|| {
                banded.add_in_bands(|band| {
                    offer(|splat, pixel, rgb| match splat {
                        true => band.add_splat(pixel, rgb),
                        false => band.add(pixel, rgb),
                    })
                })
            });
            assert_eq!(banded, serial, "{threads} threads");
        }
        assert!(serial.dropped() > 0);
    }

    #[test]
    fn lists_added_with_look_ahead_give_what_single_additions_give() {
        let mut offered = Vec::new();
        offer(|splat, pixel, rgb| offered.push((splat, pixel, rgb)));
        let mut single = Film::new(7, 5);
        single.add_in_bands(|band| {
            for &(splat, pixel, rgb) in &offered {
                match splat {
                    true => band.add_splat(pixel, rgb),
                    false => band.add(pixel, rgb),
                }
            }
        });
        // The splats as one list, then the samples as another (each list is added in its
        // order; a pixel's sums do not depend on the order of its additions).
        let mut listed = Film::new(7, 5);
        listed.add_in_bands(|band| {
            for counted in [false, true] {
                let list: Vec<_> = offered.iter().filter(|o| o.0 != counted).collect();
                band.add_each((&list, counted), |&&(_, pixel, rgb)| (pixel, rgb));
            }
        });
        assert_eq!(listed, single);
        assert!(single.samples(0) > 0 && single.dropped() > 0);
    }

    #[test]
    #[should_panic(expected = "outside the image")]
    fn a_band_rejects_pixels_outside_the_image() {
        Film::new(2, 2).add_in_bands(|band| band.add(4, Vec3::ONE));
    }

    #[test]
    fn merge_adds_samples_and_drop_counts() {
        let mut a = Film::new(1, 2);
        a.add(1, Vec3::ONE);
        let mut b = Film::new(1, 2);
        b.add(1, Vec3::splat(3.0));
        b.add(0, Vec3::splat(f32::NAN));
        a.merge(&b);
        assert_eq!(a.mean(), vec![Vec3::ZERO, Vec3::splat(2.0)]);
        assert_eq!((a.samples(0), a.dropped()), (1, 1));
    }
}
