//! What a scene file may make the loader do: how much geometry its instancing may create and
//! which files it may read. A scene file is input like any other: a 2 KB glTF whose nodes list
//! their children twice describes 2^n copies of a mesh, and a URI can name any file.

/// Bounds on the resources a scene file may claim, and the files it may read.
/// [`LoadOptions::default`] is what [`Scene::load`](crate::Scene::load) uses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadOptions {
    /// Most triangles the loaded scene may have, every instance of every mesh counted. For
    /// glTF it is checked against the counts the file declares, before any geometry is read
    /// or expanded; vertices are bounded at three per triangle of this limit (what a triangle
    /// list without shared vertices has) and node instances at this limit. Defaults to
    /// [`LoadOptions::DEFAULT_MAX_TRIANGLES`].
    pub max_triangles: u64,
    /// Most texels the scene's textures may decode to, all images together (each image is
    /// decoded once, however many textures use it), checked against each image's header
    /// before it is decoded. Textures keep 4 bytes per texel. Defaults to
    /// [`LoadOptions::DEFAULT_MAX_TEXELS`].
    pub max_texels: u64,
    /// Whether URIs and file names in the scene may lead outside the scene file's folder
    /// (absolute paths, `..` above the folder, symbolic links out of it). Off by default: a
    /// downloaded scene then reads only what came with it. Device files, FIFOs and other
    /// non-regular files are never read, whatever this says.
    pub allow_outside_files: bool,
}

impl LoadOptions {
    /// The default [`max_texels`](LoadOptions::max_texels): 2³⁰, 4 GiB of texture memory.
    ///
    /// A well-compressed PNG (a flat colour, a 1-bit mask) decodes to a thousand or more
    /// times its size, so a few hundred kilobytes of images can ask for many gigabytes. 2³⁰
    /// texels hold 256 textures of 2048² (a large scene's set, Bistro's among them) or 4 of
    /// 16384², the largest a texture may be.
    pub const DEFAULT_MAX_TEXELS: u64 = 1 << 30;

    /// The default [`max_triangles`](LoadOptions::max_triangles): 20 million.
    ///
    /// Measured on instances of an indexed grid with normals and texture coordinates (about
    /// half a vertex per triangle), loading peaks at some 50 bytes per triangle (16 for its
    /// indices and material, 48 per vertex, which instancing copies), and building the CPU
    /// BVH over the triangles' corners brings the peak to some 330. A mesh without shared
    /// vertices, or with vertex colors, costs more. 20 million triangles thus peak at 6–7 GB:
    /// a large production scene (San Miguel has 10 million, Bistro 3 million) that still fits
    /// a 16 GB machine, while a hostile file expanding to billions is refused in milliseconds
    /// instead of exhausting memory. Raise it for bigger scenes on bigger machines.
    pub const DEFAULT_MAX_TRIANGLES: u64 = 20_000_000;

    /// The most vertices the scene may have under these options: three per triangle of
    /// [`max_triangles`](LoadOptions::max_triangles), and never more than 32-bit indices
    /// address.
    pub fn max_vertices(&self) -> u64 {
        self.max_triangles
            .saturating_mul(3)
            .min(u64::from(u32::MAX))
    }
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            max_triangles: Self::DEFAULT_MAX_TRIANGLES,
            max_texels: Self::DEFAULT_MAX_TEXELS,
            allow_outside_files: false,
        }
    }
}
