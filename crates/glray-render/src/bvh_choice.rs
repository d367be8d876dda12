//! Which way each BVH is built (setting `bvh`): by binned SAH (the better tree), or fast
//! (`bvh::Quality::Fast`, a linear BVH: the build in about half the time, its tree walked
//! 13-20% more slowly; docs/performance.md has the figures).
//!
//! A tree the next frame builds again (the frame's own triangles, or a mesh the program
//! replaces every frame: simulation time steps, a surface deformed frame after frame) is paid
//! for by one frame's rays. `auto` builds such a tree fast when the build would cost more than
//! the slower walk: when its triangles outnumber a share of the frame's rays (`FAST_PER_RAY`).
//! Trees kept across frames (a mesh drawn again) are built by SAH under `auto`: a mesh built
//! fast that turns out to stay gets its SAH tree in its second frame (`scene::Meshes`).

use crate::bvh::Quality;
use crate::options::{BvhBuild, Effects};

/// Under `auto`, a tree built again next frame is built fast from this many triangles per ray
/// the frame traces (camera-ray equivalents, `ray_work`). Measured at 10M triangles on the
/// anchors' mesh (docs/performance.md, "A linear BVH for trees built every frame"): the fast
/// build saves ~100 ns a triangle, its tree costs ~13-18 ns more a camera-ray equivalent; a
/// quarter leaves the fast build a margin.
const FAST_PER_RAY: f64 = 1.0 / 4.0;

/// Nor below this many triangles, whose SAH build takes a few milliseconds.
pub(crate) const BIG_MESH: usize = 1 << 16;

/// An ambient-occlusion ray costs about half a camera ray (an any-hit walk over a short
/// distance): its weight in `ray_work`.
const AO_RAY: f64 = 0.5;

impl BvhBuild {
    /// How to build a tree over `triangles` triangles, which the next frame builds again when
    /// `rebuilt`, for a frame tracing `ray_work` rays (`ray_work`).
    pub fn quality(self, triangles: usize, rebuilt: bool, ray_work: f64) -> Quality {
        match self {
            BvhBuild::Sah => Quality::Sah,
            BvhBuild::Fast => Quality::Fast,
            BvhBuild::Auto => {
                let worth = triangles >= BIG_MESH && triangles as f64 >= FAST_PER_RAY * ray_work;
                if rebuilt && worth {
                    Quality::Fast
                } else {
                    Quality::Sah
                }
            }
        }
    }
}

/// The rays a frame of `pixels` pixels traces with `effects`, in camera-ray equivalents: per
/// sample a camera ray, the ambient-occlusion rays at `AO_RAY` each, a shadow ray (a light's;
/// most programs light with one or two) and a ray per reflection. An upper bound: a pixel
/// that misses traces only its camera ray.
pub fn ray_work(pixels: u64, effects: &Effects) -> f64 {
    let shadows = if effects.shadows { 1.0 } else { 0.0 };
    let per_sample = 1.0 + f64::from(effects.ao_samples) * AO_RAY + shadows + f64::from(effects.reflections);
    pixels as f64 * f64::from(effects.samples.max(1)) * per_sample
}

#[cfg(test)]
mod tests {
    use super::*;

    const HD: u64 = 1280 * 720;

    #[test]
    fn auto_builds_fast_only_trees_built_again_whose_build_outweighs_the_frames_rays() {
        let gl = ray_work(HD, &Effects::GL);
        let ao = ray_work(HD, &Effects::preset("ao").unwrap());
        let full = ray_work(HD, &Effects::preset("full").unwrap());
        assert!(gl < ao && ao < full);
        let auto = BvhBuild::Auto;
        // 10M triangles replaced every frame: fast in the GL look and with AO, not for the
        // full look's 4 samples of 39 rays.
        assert_eq!(auto.quality(10_000_000, true, gl), Quality::Fast);
        assert_eq!(auto.quality(10_000_000, true, ao), Quality::Fast);
        assert_eq!(auto.quality(10_000_000, true, full), Quality::Sah);
        // Kept across frames, or small: SAH.
        assert_eq!(auto.quality(10_000_000, false, gl), Quality::Sah);
        assert_eq!(auto.quality(100_000, true, gl), Quality::Sah);
        assert_eq!(auto.quality(BIG_MESH - 1, true, 0.0), Quality::Sah);
        // The other two choices whatever the tree.
        assert_eq!(BvhBuild::Sah.quality(10_000_000, true, gl), Quality::Sah);
        assert_eq!(BvhBuild::Fast.quality(10, false, full), Quality::Fast);
    }

    #[test]
    fn every_value_the_setting_allows_is_a_choice() {
        for value in crate::options::BVH_CHOICES {
            assert!(BvhBuild::from_setting(value).is_some(), "{value}");
        }
        assert_eq!(BvhBuild::from_setting("SAH"), None);
        assert_eq!(BvhBuild::default(), BvhBuild::Auto);
    }
}
