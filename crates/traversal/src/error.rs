//! Errors reported while building a traversal backend.

/// Why a backend could not be built from the given triangles.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BuildError {
    /// A vertex coordinate of the triangle is NaN or infinite.
    #[error("triangle {triangle} has a non-finite vertex coordinate")]
    NonFiniteVertex {
        /// Index of the offending triangle in the input slice.
        triangle: usize,
    },
    /// Primitive ids are `u32` and `u32::MAX` is reserved for misses.
    #[error("{count} triangles given, at most {} are supported", u32::MAX - 1)]
    TooManyTriangles {
        /// Number of triangles passed in.
        count: usize,
    },
}
