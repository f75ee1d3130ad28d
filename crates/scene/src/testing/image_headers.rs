//! OpenEXR and PNG files whose headers claim more texels than they hold.

use std::io::Cursor;

use exr::prelude::{Image, SpecificChannels, WritableImage};

/// A valid 1 × 1 OpenEXR file with its data window widened to `width` × `height` texels (its
/// one scan line stays): what a reader sizing its buffers from the header would allocate.
pub fn exr_claiming(width: i32, height: i32) -> Vec<u8> {
    let mut bytes = Cursor::new(Vec::new());
    let white = SpecificChannels::rgb(|_| (1.0f32, 1.0f32, 1.0f32));
    Image::from_channels((1, 1), white)
        .write()
        .to_buffered(&mut bytes)
        .expect("a 1 × 1 image encodes");
    let mut bytes = bytes.into_inner();
    let window = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(window.len())
        .position(|w| w == window)
        .expect("every OpenEXR header has a data window")
        + window.len()
        + 4;
    let corners = [0, 0, width - 1, height - 1].map(i32::to_le_bytes).concat();
    bytes[at..at + 16].copy_from_slice(&corners);
    bytes
}

/// A PNG file of `width` × `height` grey texels: a valid header, and compressed data for one
/// row of zeros only (a hundred bytes or so for any width).
pub fn png_claiming(width: u32, height: u32) -> Vec<u8> {
    let mut png = Vec::new();
    let row = vec![0u8; width as usize];
    let encoder = image::codecs::png::PngEncoder::new(&mut png);
    image::ImageEncoder::write_image(encoder, &row, width, 1, image::ExtendedColorType::L8)
        .expect("a one-row image encodes");
    // IHDR's height is bytes 20..24 (after the 8-byte signature, the chunk's length and type
    // and the width); its CRC, over the chunk's type and data, follows them at 29..33.
    png[20..24].copy_from_slice(&height.to_be_bytes());
    let crc = crc32(&png[12..29]);
    png[29..33].copy_from_slice(&crc.to_be_bytes());
    png
}

/// The CRC-32 (ISO 3309, as PNG chunks use it) of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &byte in bytes {
        crc ^= u32::from(byte);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}
