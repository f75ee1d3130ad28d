//! Bounds and type checks for glTF accessors, done before the `gltf` crate's readers touch the
//! data, so a malformed file gives an error instead of a panic or garbage.

use gltf::accessor::{Accessor, DataType, Dimensions};

/// Checks that a buffer view lies inside its (loaded) buffer.
pub(super) fn check_view(view: &gltf::buffer::View, buffers: &[Vec<u8>]) -> Result<(), String> {
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("buffer view {} refers to a missing buffer", view.index()))?;
    let end = view.offset().checked_add(view.length());
    match end {
        Some(end) if end <= buffer.len() => Ok(()),
        _ => Err(format!(
            "buffer view {} ({} bytes at offset {}) exceeds buffer {} ({} bytes)",
            view.index(),
            view.length(),
            view.offset(),
            view.buffer().index(),
            buffer.len()
        )),
    }
}

/// Checks that `count` elements of `size` bytes at `offset` with the view's stride fit the view.
fn check_span(
    view: &gltf::buffer::View,
    buffers: &[Vec<u8>],
    offset: usize,
    count: usize,
    size: usize,
) -> Result<(), String> {
    check_view(view, buffers)?;
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "buffer view {} has stride {stride} below the element size {size}",
            view.index()
        ));
    }
    let span = count
        .checked_sub(1)
        .and_then(|n| n.checked_mul(stride))
        .and_then(|n| n.checked_add(size))
        .and_then(|n| n.checked_add(offset));
    match span {
        Some(end) if end <= view.length() => Ok(()),
        _ => Err(format!(
            "{count} elements of {size} bytes at offset {offset} exceed buffer view {} ({} bytes)",
            view.index(),
            view.length()
        )),
    }
}

/// Checks an accessor's element type and that all its data (dense and sparse) is in bounds.
pub(super) fn check_accessor(
    accessor: &Accessor,
    buffers: &[Vec<u8>],
    dimensions: Dimensions,
    data_types: &[DataType],
) -> Result<(), String> {
    let index = accessor.index();
    if accessor.dimensions() != dimensions || !data_types.contains(&accessor.data_type()) {
        return Err(format!(
            "accessor {index} is {:?} {:?}, expected {dimensions:?} of {data_types:?}",
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    if accessor.count() == 0 {
        return Err(format!("accessor {index} is empty"));
    }
    let size = accessor.size();
    match (accessor.view(), accessor.sparse()) {
        (None, None) => return Err(format!("accessor {index} has no data")),
        (Some(view), _) => check_span(&view, buffers, accessor.offset(), accessor.count(), size)?,
        (None, Some(_)) => {}
    }
    if let Some(sparse) = accessor.sparse() {
        let count = sparse.count();
        if count == 0 || count > accessor.count() {
            return Err(format!("accessor {index} has {count} sparse elements"));
        }
        let indices = sparse.indices();
        let index_size = indices.index_type().size();
        check_span(
            &indices.view(),
            buffers,
            indices.offset(),
            count,
            index_size,
        )?;
        let values = sparse.values();
        check_span(&values.view(), buffers, values.offset(), count, size)?;
    }
    Ok(())
}
