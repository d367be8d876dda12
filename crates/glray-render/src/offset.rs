//! Where a secondary ray (ambient occlusion, a shadow, a reflection) starts: just off the
//! surface it leaves, on the side it goes to, so that it does not hit that surface again.

use glam::Vec3;
use obvhs::ray::Ray;

/// A ray from `p` along `d` that starts past the surface it leaves.
pub(crate) fn leaving(p: Vec3, n: Vec3, d: Vec3, eps: f32, tmax: f32) -> Ray {
    let o = p + n * eps * n.dot(d).signum();
    crate::bvh::ray(o.into(), d.into(), 0.0, tmax)
}

/// Where a secondary ray starts: the point, its surface's normal, and the draw it is on (whose
/// own line and point solids do not count).
pub struct Origin {
    pub p: Vec3,
    pub n: Vec3,
    pub draw: u32,
}
