//! A bound on the float images read whole (environment maps, reference renders): a header
//! claiming more texels is refused before anything is allocated for it, so that a few bytes
//! cannot ask for more memory than the machine has (which would abort the process).

use std::io::Read;

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

/// [`check_texels`] for every layer of the OpenEXR file `reader` starts, from its headers
/// alone.
pub fn check_exr_layers(reader: impl Read) -> Result<(), String> {
    let meta =
        exr::meta::MetaData::read_from_unbuffered(reader, false).map_err(|e| e.to_string())?;
    meta.headers
        .iter()
        .try_for_each(|h| check_texels(h.layer_size.width(), h.layer_size.height()))
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
}
