//! What a scene file asks of the render beyond the scene itself: pbrt's `Sampler` and
//! `PixelFilter` directives (or the same recorded in a glTF's `extras`). The command line
//! honours them unless its own flags say otherwise, and records where each choice came from.
use crate::filter::PixelFilter;
use crate::sampler::Sampler;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderHints {
    /// The sampler the file names, mapped onto ours.
    pub sampler: Option<Sampler>,
    /// The pixel filter the file names, with its parameters.
    pub filter: Option<PixelFilter>,
    /// The file's samples per pixel (informational: the command line sets the spp).
    pub spp: Option<u32>,
}

/// Our sampler for a pbrt sampler name (v3 and v4), and whether the match is exact; `None` for
/// a name pbrt does not have.
pub fn sampler_for_pbrt(name: &str) -> Option<(Sampler, bool)> {
    Some(match name {
        "lowdiscrepancy" | "02sequence" => (Sampler::LowDiscrepancy, true),
        "zsobol" => (Sampler::ZSobol, true),
        "paddedsobol" => (Sampler::Sobol, true),
        "stratified" => (Sampler::Stratified, true),
        "random" | "independent" => (Sampler::Independent, true),
        // A global Sobol sequence over the image: ours in Morton order is the nearest.
        "sobol" => (Sampler::ZSobol, false),
        // No Halton or PMJ here: a scrambled (0,2)-sequence per pair is the nearest kin.
        "halton" | "maxmindist" | "pmj02bn" => (Sampler::Sobol, false),
        _ => return None,
    })
}

/// The pbrt name of our sampler, the inverse of [`sampler_for_pbrt`]'s exact matches.
pub fn pbrt_name(sampler: Sampler) -> &'static str {
    match sampler {
        Sampler::Independent => "independent",
        Sampler::Stratified => "stratified",
        Sampler::Sobol => "paddedsobol",
        Sampler::LowDiscrepancy => "lowdiscrepancy",
        Sampler::ZSobol => "zsobol",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pbrt_names_round_trip() {
        for s in Sampler::ALL {
            assert_eq!(sampler_for_pbrt(pbrt_name(s)), Some((s, true)));
        }
        assert_eq!(sampler_for_pbrt("halton"), Some((Sampler::Sobol, false)));
        assert_eq!(sampler_for_pbrt("nonsense"), None);
    }
}
