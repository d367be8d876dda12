//! The short way to shade the hits of a frame that asks for the GL look alone: a hit on an
//! untextured instance drawn with the frame's own camera gets what GL's Gouraud shading gives
//! it, its corners' colours (lit at the corners) mixed with the weights the walk found there.
//!
//! The full way (`Frame::triangle`, then `fragment::shade`) also works out the corners' eye
//! positions, clip coordinates, normals and texture coordinates, a triangle of a few hundred
//! bytes that nothing would read here; and where the lighting does not read a vertex's
//! position (lights at infinity and a viewer at infinity, the common case), the mesh's
//! positions are not looked up at all: on a big mesh that is three cache misses a hit.

use glam::{DVec3, Vec3};
use glray_scene::camera::Camera;
use glray_scene::facing::projection_flips;
use glray_scene::frame::{Frame, TriangleId};

use crate::fragment::{mixed, own_camera, Fragment};
use crate::options::Options;
use crate::recent::Recent;
use crate::scene::{Hit, Scene};

/// The corners' colours of a triangle, primary and secondary (`Instance::corner_colors`).
pub(crate) type Corners = ([glam::Vec4; 3], [Vec3; 3]);

/// Which of a frame's hits take the short way.
pub(crate) struct Gouraud {
    /// Per instance of the frame: whether its hits do.
    short: Vec<bool>,
    /// Per instance: whether its corners' colours read their positions (a local light or
    /// viewer), so that the loads made ahead of shading fetch those too.
    positions: Vec<bool>,
    /// Whether the camera's projection turns the window's winding around (for facing).
    projection_flips: bool,
}

impl Gouraud {
    /// None when the frame asks for more than the GL look at each hit (secondary rays,
    /// lighting per pixel) or when the closest hit alone does not decide a pixel (`simple`
    /// false).
    pub fn new(frame: &Frame, camera: &Camera, options: &Options, simple: bool) -> Option<Gouraud> {
        if !simple || options.per_pixel_lighting || options.effects.secondary_rays() {
            return None;
        }
        let short = frame
            .instances
            .iter()
            .map(|i| {
                let untextured = frame.surfaces.get(i.surface as usize).is_some_and(|s| s.texturing.is_none());
                // Weights found in object space hold in eye space only through an affine map.
                let per_fragment = frame.lightings.get(i.lighting as usize).is_some_and(|l| l.model().per_fragment);
                untextured && !per_fragment && i.is_affine() && own_camera(frame, i.camera, camera)
            })
            .collect();
        let positions = frame
            .instances
            .iter()
            .map(|i| frame.lightings.get(i.lighting as usize).is_some_and(|l| l.reads_position()))
            .collect();
        Some(Gouraud { short, positions, projection_flips: projection_flips(camera.projection()) })
    }

    /// Whether hits on triangle `id` take the short way.
    #[inline]
    pub fn takes(&self, id: TriangleId) -> bool {
        self.short.get(id.instance as usize).copied().unwrap_or(false)
    }

    /// Whether shading triangle `id` reads its corners' positions.
    #[inline]
    pub fn reads_positions(&self, id: TriangleId) -> bool {
        !self.takes(id) || self.positions.get(id.instance as usize).copied().unwrap_or(true)
    }

    /// The fragment of `hit` (one `takes`) at eye-space point `p`, reached along `dir`; its
    /// corners' colours from `recent` when a neighbouring pixel hit the triangle already.
    pub fn fragment(
        &self,
        scene: &Scene,
        camera: &Camera,
        hit: &Hit,
        p: DVec3,
        dir: DVec3,
        recent: &mut Recent<Corners>,
    ) -> Option<Fragment> {
        let frame = scene.frame();
        let instance = frame.instances.get(hit.id.instance as usize)?;
        // (A paged mesh's triangle is in one of its blocks.)
        let part = scene.part(hit.id)?;
        if part.index() >= part.mesh().triangles.len() {
            return None;
        }
        let corners = recent.get(hit.id, || {
            // The walk kept only the faces the instance draws; which one this is matters to
            // two-sided lighting.
            let front = instance.front_seen(hit.normal.dot(dir.as_vec3()), self.projection_flips);
            Some(instance.corner_colors_of(part.mesh(), part.index(), &frame.lightings, front))
        })?;
        let b = Vec3::new(1.0 - hit.uv.x - hit.uv.y, hit.uv.x, hit.uv.y);
        let corner_z = || instance.corner_depths_of(part.mesh(), part.index());
        Some(mixed(frame, camera, instance.surface, corners, b, p, corner_z))
    }
}
