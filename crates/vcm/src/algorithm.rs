//! [`Algorithm`]: the light transport algorithms, the one list every part of vcm-rs names them
//! from (the command line, the viewer, the Python package, render states).

/// Light transport algorithms: the path tracer ([`crate::PathTracer`]) and the algorithms of
/// the VCM integrator ([`crate::Vcm`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Algorithm {
    /// Path tracing with next event estimation and MIS (the reference unidirectional tracer).
    Pt,
    /// Light tracing: light paths connected to the camera (plus emission seen directly).
    #[cfg_attr(feature = "clap", value(name = "lt"))]
    LightTracing,
    /// Bidirectional path tracing: every connection technique (light vertex cache
    /// connections), no merging.
    Bpt,
    /// Progressive photon mapping: merging at the first diffuse or glossy camera vertex.
    Ppm,
    /// Bidirectional photon mapping: merging at every camera vertex, no connections.
    //
    // Emission found by the camera path is weighted against the merges (a glossy vertex lit
    // by a light is found by its own sampling, not only by a light vertex in its lobe).
    Bpm,
    /// Vertex connection and merging: all of the above, combined by MIS.
    Vcm,
}

impl Algorithm {
    /// Every algorithm, in the order user interfaces list them.
    pub const ALL: [Algorithm; 6] = [
        Algorithm::Pt,
        Algorithm::LightTracing,
        Algorithm::Bpt,
        Algorithm::Ppm,
        Algorithm::Bpm,
        Algorithm::Vcm,
    ];

    /// The lower-case short name used on the command line (pt, lt, bpt, ppm, bpm, vcm).
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Pt => "pt",
            Algorithm::LightTracing => "lt",
            Algorithm::Bpt => "bpt",
            Algorithm::Ppm => "ppm",
            Algorithm::Bpm => "bpm",
            Algorithm::Vcm => "vcm",
        }
    }

    /// Whether the [VCM integrator](crate::Vcm) renders it (all but path tracing).
    pub fn is_bidirectional(self) -> bool {
        self != Algorithm::Pt
    }

    /// Whether camera vertices connect to light samples and light vertices, and light
    /// vertices to the camera (of the VCM integrator's algorithms).
    pub fn connects(self) -> bool {
        matches!(self, Algorithm::Bpt | Algorithm::Vcm)
    }

    /// Whether camera vertices merge with light vertices (needs the hash grid).
    pub fn merges(self) -> bool {
        matches!(self, Algorithm::Ppm | Algorithm::Bpm | Algorithm::Vcm)
    }

    /// Whether light vertices are splatted onto the image through the camera.
    pub(crate) fn splats(self) -> bool {
        matches!(
            self,
            Algorithm::LightTracing | Algorithm::Bpt | Algorithm::Vcm
        )
    }

    /// Whether light vertices are kept in the cache (for connections or merging).
    pub(crate) fn caches(self) -> bool {
        self.connects() || self.merges()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_algorithm_is_listed_once_under_its_own_name() {
        let names: Vec<_> = Algorithm::ALL.iter().map(|a| a.name()).collect();
        assert_eq!(names, ["pt", "lt", "bpt", "ppm", "bpm", "vcm"]);
        let bidirectional = Algorithm::ALL.iter().filter(|a| a.is_bidirectional());
        assert_eq!(bidirectional.count(), 5);
    }
}
