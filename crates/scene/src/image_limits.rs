//! Bounds on the images read whole (textures, environment maps, reference renders): a header
//! claiming more texels than [`MAX_TEXELS`], or more than its file's bytes can describe, is
//! refused before anything is allocated for it, so that a few bytes cannot ask for more memory
//! than the machine has (which would abort the process).

use std::io::{Cursor, Read};

/// Most texels such an image may have: 16384 × 16384, 3 GiB as linear RGB.
pub const MAX_TEXELS: u64 = 1 << 28;

/// Refuses an image of `width` × `height` texels larger than [`MAX_TEXELS`].
pub fn check_texels(width: usize, height: usize) -> Result<(), String> {
    let texels = (width as u64).saturating_mul(height as u64);
    if texels > MAX_TEXELS {
        return Err(format!(
            "{width} × {height} texels, more than the {MAX_TEXELS} an image may have"
        ));
    }
    Ok(())
}

/// Most texels one byte of an image file can describe: 8 × 1032.
///
/// Every format read here stores each texel in at least one bit before compression (PNG
/// packs 1-bit images eight to a byte; OpenEXR's halves and Radiance's RGBE take more), and
/// none compresses by more than 1032 : 1, the limit of deflate (PNG, OpenEXR ZIP) whose
/// longest match (258 bytes) costs at least two bits; run-length coding (OpenEXR RLE,
/// Radiance) and JPEG's entropy coding stay far below that. A header claiming more texels
/// than its file's bytes × this bound cannot be honest, only a way to make a reader allocate.
pub const MAX_TEXELS_PER_BYTE: u64 = 8 * 1032;

/// [`check_texels`], and refuses an image of `width` × `height` texels that a file of
/// `file_bytes` bytes cannot hold (more than [`MAX_TEXELS_PER_BYTE`] texels per byte).
pub fn check_image_size(width: usize, height: usize, file_bytes: usize) -> Result<(), String> {
    check_texels(width, height)?;
    let texels = (width as u64).saturating_mul(height as u64);
    if texels > (file_bytes as u64).saturating_mul(MAX_TEXELS_PER_BYTE) {
        return Err(format!(
            "the header claims {width} × {height} texels, more than a {file_bytes}-byte file \
             can hold"
        ));
    }
    Ok(())
}

/// [`check_texels`] for every layer of the OpenEXR file `reader` starts, from its headers
/// alone.
pub fn check_exr_layers(reader: impl Read) -> Result<(), String> {
    exr_layer_sizes(reader)?
        .into_iter()
        .try_for_each(|(width, height)| check_texels(width, height))
}

/// [`check_image_size`] for every layer of the OpenEXR file `bytes`, from its headers alone.
pub fn check_exr_file(bytes: &[u8]) -> Result<(), String> {
    exr_layer_sizes(Cursor::new(bytes))?
        .into_iter()
        .try_for_each(|(width, height)| check_image_size(width, height, bytes.len()))
}

/// The width and height of each layer an OpenEXR file's headers declare.
fn exr_layer_sizes(reader: impl Read) -> Result<Vec<(usize, usize)>, String> {
    let meta =
        exr::meta::MetaData::read_from_unbuffered(reader, false).map_err(|e| e.to_string())?;
    Ok(meta
        .headers
        .iter()
        .map(|h| (h.layer_size.width(), h.layer_size.height()))
        .collect())
}

/// A decoder for the PNG, JPEG or Radiance HDR image `bytes` (told apart by their first
/// bytes), once its header's size has passed [`check_image_size`]: nothing is allocated for
/// the texels yet, so the caller may check their number against a budget of its own before
/// [`image::DynamicImage::from_decoder`] decodes them.
pub fn image_decoder(bytes: &[u8]) -> Result<impl image::ImageDecoder + '_, String> {
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot decode: {e}"))?;
    let decoder = reader
        .into_decoder()
        .map_err(|e| format!("cannot decode: {e}"))?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    check_image_size(width as usize, height as usize, bytes.len())?;
    Ok(decoder)
}

/// Decodes a PNG, JPEG or Radiance HDR image, refusing a header whose size
/// [`check_image_size`] refuses before decoding anything.
pub fn decode_image(bytes: &[u8]) -> Result<image::DynamicImage, String> {
    let decoder = image_decoder(bytes)?;
    image::DynamicImage::from_decoder(decoder).map_err(|e| format!("cannot decode: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_more_than_the_limit() {
        assert!(check_texels(16384, 16384).is_ok());
        assert!(check_texels(16384, 16385).is_err());
        let message = check_texels(usize::MAX, usize::MAX).unwrap_err();
        assert!(message.contains("more than the 268435456"), "{message}");
    }

    #[test]
    fn refuses_an_exr_header_claiming_too_much() {
        use crate::testing::exr_claiming;
        assert!(check_exr_layers(exr_claiming(1, 1).as_slice()).is_ok());
        let message = check_exr_layers(exr_claiming(40000, 40000).as_slice()).unwrap_err();
        assert!(message.contains("40000 × 40000 texels"), "{message}");
    }

    #[test]
    fn refuses_more_texels_than_the_file_can_hold() {
        assert!(check_image_size(1, 1, 1).is_ok());
        assert!(check_image_size(8256, 1, 1).is_ok());
        assert!(check_image_size(8257, 1, 1).is_err());
        let message = check_image_size(16384, 16384, 373).unwrap_err();
        assert!(
            message.contains("16384 × 16384 texels, more than a 373-byte file can hold"),
            "{message}"
        );
        // The few hundred bytes of an EXR header claiming 16384² texels (3 GB as linear
        // RGB): within `MAX_TEXELS`, but not within what its bytes can describe.
        use crate::testing::exr_claiming;
        let lying = exr_claiming(16384, 16384);
        assert!(check_exr_layers(lying.as_slice()).is_ok());
        let message = check_exr_file(&lying).unwrap_err();
        assert!(message.contains("16384 × 16384 texels"), "{message}");
        assert!(check_exr_file(&exr_claiming(1, 1)).is_ok());
    }

    #[test]
    fn decoding_refuses_a_header_claiming_more_than_its_bytes() {
        use crate::testing::png_claiming;
        let honest = decode_image(&png_claiming(4, 1)).unwrap();
        assert_eq!((honest.width(), honest.height()), (4, 1));
        // 10000² grey texels (100 MB, under the image crate's own 512 MB limit) in a file
        // of a hundred bytes: refused before the decoder allocates.
        let lying = png_claiming(10000, 10000);
        let message = decode_image(&lying).unwrap_err();
        assert!(
            message.contains("10000 × 10000 texels, more than a"),
            "{message}"
        );
    }
}
