//! A top level over boxes (a frame's instances, a paged mesh's blocks): tried one after the
//! other when they are few (cheaper than a walk: a big mesh drawn once is the common case),
//! under obvhs's CWBVH when they are many.

use std::time::Duration;

use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::BvhBuildParams;

/// Up to this many boxes are tried one after the other.
pub const FEW: usize = 8;

pub struct Top {
    pub boxes: Vec<Aabb>,
    /// The tree over them, when they are more than `FEW`.
    pub tree: Option<CwBvh>,
}

impl Top {
    pub fn new(boxes: Vec<Aabb>) -> Top {
        let tree =
            (boxes.len() > FEW).then(|| build_cwbvh(&boxes, BvhBuildParams::fast_build(), &mut Duration::default()));
        Top { boxes, tree }
    }

    /// Offers `visit` every box the ray meets (by index). `visit` returns where it hit
    /// (infinity: nowhere); a hit shortens the ray for the boxes after it; with `first`, the
    /// first hit ends the search. True if anything was hit.
    pub fn visit(&self, ray: Ray, first: bool, mut visit: impl FnMut(&Ray, usize) -> f32) -> bool {
        match &self.tree {
            Some(top) if first => !top.ray_traverse_miss(ray, |r, slot| visit(r, top.primitive_indices[slot] as usize)),
            Some(top) => {
                let mut hit = RayHit::none();
                top.ray_traverse(ray, &mut hit, |r, slot| visit(r, top.primitive_indices[slot] as usize))
            }
            None => {
                let mut r = ray;
                let mut any = false;
                for (k, b) in self.boxes.iter().enumerate() {
                    if b.intersect_ray(&r) == f32::INFINITY {
                        continue;
                    }
                    let t = visit(&r, k);
                    if t < r.tmax {
                        any = true;
                        if first {
                            break;
                        }
                        r.tmax = t;
                    }
                }
                any
            }
        }
    }
}
