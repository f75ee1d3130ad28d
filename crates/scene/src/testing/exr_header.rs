//! OpenEXR files whose headers claim more texels than they hold.

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
