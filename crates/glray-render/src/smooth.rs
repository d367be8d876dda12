//! The smooth surface a lit triangle's corner normals describe, for the rays that leave it.
//!
//! A smooth-shaded mesh is lit as if it were curved, but its triangles are flat. Secondary rays
//! that left the flat facets showed the facets: mirror rays bounced about each facet's own
//! normal, so reflections in a curved surface broke into a mosaic of facets; and a shadow ray
//! from the facet met the neighbouring facets wherever a facet turns from the light sooner than
//! its normals do, so the line between light and shade came out in jagged, faceted bands (the
//! "shadow terminator"). Here both follow the shading: a mirror reflects about the normal the
//! lighting interpolates, and rays leave from the point lifted off the facet onto the curved
//! surface (Hanika, "Hacking the Shadow Terminator", Ray Tracing Gems II, ch. 4).

use glam::{DVec3, Vec3};
use glray_scene::triangle::{Triangle, NO_LIGHTING};

use crate::fragment::barycentric;

/// A point of a lit triangle with its corners' normals: where rays leave it, and how it
/// mirrors.
pub(crate) struct Smooth {
    point: DVec3,
    weights: DVec3,
    corners: [DVec3; 3],
    /// The corners' normals, unit length, each turned to the side `n` faces.
    normals: [DVec3; 3],
}

impl Smooth {
    /// Point `p` of triangle `t`, whose facet normal on the side its ray came from is `n`; None
    /// for an unlit triangle, whose normals say nothing about its shape.
    pub fn at(t: &Triangle, p: DVec3, n: Vec3) -> Option<Smooth> {
        if t.lighting == NO_LIGHTING {
            return None;
        }
        let side = n.as_dvec3();
        let normals = t.normals.map(|m| {
            let m = m.as_dvec3().normalize_or_zero();
            if m.dot(side) < 0.0 {
                -m
            } else {
                m
            }
        });
        Some(Smooth { point: p, weights: barycentric(t, p), corners: t.positions.map(|c| c.as_dvec3()), normals })
    }

    /// The point lifted onto the curved surface: each corner's tangent plane (through the
    /// corner, across its normal) that the point lies below pushes it out along that normal,
    /// weighted by the point's barycentric weight of the corner; planes it is above leave it.
    /// A flat facet's point, whose corners share its normal, stays where it is.
    pub fn lifted(&self) -> DVec3 {
        let mut lifted = self.point;
        for k in 0..3 {
            let below = (self.point - self.corners[k]).dot(self.normals[k]).min(0.0);
            lifted -= self.weights[k] * below * self.normals[k];
        }
        lifted
    }

    /// The normal the lighting interpolates at the point (unit length; None where the
    /// corners' normals cancel out).
    pub fn normal(&self) -> Option<Vec3> {
        let n = self.normals[0] * self.weights.x + self.normals[1] * self.weights.y + self.normals[2] * self.weights.z;
        let n = n.normalize_or_zero();
        (n != DVec3::ZERO).then(|| n.as_vec3())
    }
}

/// `d` mirrored about the surface of facet normal `n` (facing where `d` came from) whose
/// smooth normal there is `smooth`; about the facet itself when there is none, or when the
/// smooth normal would send the ray into the facet (at grazing angles near a silhouette).
pub(crate) fn mirror(d: Vec3, n: Vec3, smooth: Option<Vec3>) -> Vec3 {
    let about = |m: Vec3| d - 2.0 * d.dot(m) * m;
    smooth.map(about).filter(|r| r.dot(n) > 0.0).unwrap_or_else(|| about(n))
}

/// The share of light a surface of `reflectivity` (its reflectance head-on) mirrors when a ray
/// along `d` leaves it along `reflected`: Schlick's approximation to Fresnel's equations,
/// reflectivity + (1 - reflectivity) (1 - cos)^5, with cos the angle between the ray and the
/// normal it was mirrored about. Surfaces seen head-on mirror little, at grazing angles much:
/// a floor shows what stands on it, while the facets of a tessellated cylinder or sphere (each a
/// flat mirror turned its own way) no longer show the world in stripes and patches.
pub(crate) fn reflectance(reflectivity: f32, d: Vec3, reflected: Vec3) -> f32 {
    let cos = (reflected - d).normalize_or_zero().dot(-d).clamp(0.0, 1.0);
    let grazing = (1.0 - cos).powi(5);
    reflectivity + (1.0 - reflectivity) * grazing
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A lit triangle in the plane z = 0 with the given corner normals.
    fn triangle(normals: [Vec3; 3]) -> Triangle {
        let mut t = crate::fragment::tests::plain([Vec3::ZERO, Vec3::X, Vec3::Y], [1.0; 3]);
        t.normals = normals;
        t.lighting = 0;
        t
    }

    #[test]
    fn a_flat_facet_stays_and_a_curved_one_is_lifted_toward_its_normals() {
        let centre = DVec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0);
        let flat = Smooth::at(&triangle([Vec3::Z; 3]), centre, Vec3::Z).unwrap();
        assert_eq!(flat.lifted(), centre);
        assert_eq!(flat.normal(), Some(Vec3::Z));
        // Normals leaning away from the middle, as on a ball: the middle lies below each
        // corner's tangent plane and comes up; the normal there is the facet's.
        let out = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(2.0, -1.0, 2.0), Vec3::new(-1.0, 2.0, 2.0)];
        let ball = Smooth::at(&triangle(out.map(|n| n.normalize())), centre, Vec3::Z).unwrap();
        let lifted = ball.lifted();
        assert!(lifted.z > 0.05, "{lifted}");
        // Seen from below (from inside the ball: the facet's normal there is -z), the normals
        // turn with the facet and make a bowl: the point stays.
        let inside = Smooth::at(&triangle(out.map(|n| n.normalize())), centre, -Vec3::Z).unwrap();
        assert_eq!(inside.lifted(), centre);
        // Normals leaning in, as in a bowl: the middle is above their planes and stays.
        let bowl = Smooth::at(&triangle(out.map(|n| (n * Vec3::new(-1.0, -1.0, 1.0)).normalize())), centre, Vec3::Z);
        assert_eq!(bowl.unwrap().lifted(), centre);
        // An unlit triangle has no smooth surface.
        let mut unlit = triangle([Vec3::Z; 3]);
        unlit.lighting = NO_LIGHTING;
        assert!(Smooth::at(&unlit, centre, Vec3::Z).is_none());
    }

    #[test]
    fn mirrors_follow_the_smooth_normal_unless_it_sends_the_ray_into_the_facet() {
        let d = Vec3::new(0.0, 0.0, -1.0);
        let up = Vec3::new(0.0, 0.5, 0.75f32.sqrt());
        let r = mirror(d, Vec3::Z, Some(up));
        assert!((r - Vec3::new(0.0, 0.75f32.sqrt(), 0.5)).length() < 1e-6, "{r}");
        assert_eq!(mirror(d, Vec3::Z, None), Vec3::Z);
        // A grazing ray over a smooth normal leaning its way: mirrored about that normal it
        // would go under the facet, so the facet's own mirror.
        let grazing = Vec3::new(0.0, 1.0, -0.1).normalize();
        let r = mirror(grazing, Vec3::Z, Some(Vec3::new(0.0, 0.6, 0.8)));
        assert!(r.z > 0.0 && (r - (grazing - 2.0 * grazing.z * Vec3::Z)).length() < 1e-6, "{r}");
    }
}
