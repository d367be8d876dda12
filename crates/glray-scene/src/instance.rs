//! One glCallList of a display list's mesh: the transform and the state of that call. Its
//! triangles are made when a ray needs one (`Instance::triangle`), with what the vertex stage
//! and primitive assembly would have made of them then: eye positions, facing and culling,
//! lighting of the visible face at each corner (or the provoking one's, flat), texture
//! coordinates through the texture matrix. A frame therefore costs its instances, and the
//! lighting of what is seen, not a pass over every vertex.

use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3, DVec4, Vec2, Vec3, Vec3A, Vec4};

use serde::{Deserialize, Serialize};

use crate::draw_lighting::Lighting;
use crate::facing::{culled, facing_flip, window_facing, Face};
use crate::lighting::{eye_normal, light_face};
use crate::mesh::Mesh;
use crate::triangle::{Triangle, NO_LIGHTING};

fn vec4(v: DVec4) -> Vec4 {
    v.as_vec4()
}

/// What the vertex stage makes of one vertex (`Instance::vertex`).
#[derive(Debug, Clone, Copy)]
struct Vertex {
    primary: Vec4,
    secondary: Vec3,
    /// Eye-space normal (of the front face).
    normal: DVec3,
    /// The colour before lighting.
    color: Vec4,
}

/// A mesh drawn once, with the state of that draw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Instance {
    /// Encoded as its id: the byte encoding sends a mesh once (`encode`).
    #[serde(with = "crate::objects::shared_mesh")]
    pub mesh: Arc<Mesh>,
    /// Object to eye coordinates (the modelview of the call).
    pub modelview: DMat4,
    /// Object to clip coordinates (the projection of the call times the modelview): facing.
    pub object_to_clip: DMat4,
    pub normal_matrix: DMat3,
    pub normalize: bool,
    pub rescale_normal: bool,
    pub texture_matrix: DMat4,
    /// The attribute values current at the call, for vertices the list gave none.
    pub normal: DVec3,
    pub color: DVec4,
    pub texcoord: DVec4,
    pub surface: u32,
    pub camera: u32,
    pub sequence: u32,
    /// Index into `Frame::lightings`, or `NO_LIGHTING`.
    pub lighting: u32,
    pub flat: bool,
    pub front_ccw: bool,
    /// glCullFace's face when GL_CULL_FACE is on.
    pub cull: Option<Face>,
    /// Whether the window winding is the opposite of the object-space one as seen along the
    /// view (a mirroring modelview or projection): see `facing_flip`.
    pub mirrored: bool,
}

impl Instance {
    /// `mesh` drawn with `modelview` and `projection` and GL's initial state otherwise (smooth,
    /// counter-clockwise front faces, no culling, no normalization, identity texture matrix,
    /// white, normal +z), as the first surface, camera and lighting of its frame: for frames
    /// made without a program (benchmarks, tests).
    pub fn new(mesh: Arc<Mesh>, modelview: DMat4, projection: DMat4) -> Instance {
        Instance {
            mesh,
            modelview,
            object_to_clip: projection * modelview,
            normal_matrix: DMat3::from_mat4(modelview).inverse().transpose(),
            normalize: false,
            rescale_normal: false,
            texture_matrix: DMat4::IDENTITY,
            normal: DVec3::Z,
            color: DVec4::ONE,
            texcoord: DVec4::W,
            surface: 0,
            camera: 0,
            sequence: 0,
            lighting: 0,
            flat: false,
            front_ccw: true,
            cull: None,
            mirrored: facing_flip(&modelview, &projection),
        }
    }

    /// Clip coordinates of triangle `index`'s corners.
    #[inline]
    fn clip(&self, m: &Mesh, index: usize) -> [DVec4; 3] {
        m.corner_indices(index).map(|i| self.object_to_clip * m.position(i))
    }

    /// Whether a triangle a camera ray meets is drawn at all (not culled), from the dot product
    /// of its object-space normal (right-handed from its winding) with the ray's direction.
    #[inline]
    pub fn keeps_seen(&self, normal_dot_ray: f32) -> bool {
        let Some(cull) = self.cull else { return true };
        let ccw_seen = normal_dot_ray < 0.0;
        let front = (ccw_seen != self.mirrored) == self.front_ccw;
        !culled(Some(cull), front)
    }

    /// The instance's lighting, if it draws lit.
    #[inline]
    fn lighting<'a>(&self, lightings: &'a [Lighting]) -> Option<&'a Lighting> {
        lightings.get(self.lighting as usize).filter(|_| self.lighting != NO_LIGHTING)
    }

    /// Whether object to eye coordinates is an affine map: an affine modelview and positions
    /// with w = 1 (what `Context::instances` lets through), so that eye w is 1.
    #[inline]
    pub fn is_affine(&self) -> bool {
        self.modelview.row(3) == DVec4::W && self.mesh.ws.is_none()
    }

    /// Vertex `i`'s eye-space position.
    #[inline]
    /// The eye-space z of triangle `index`'s corners (what fog is worked out from).
    pub fn corner_depths(&self, index: usize) -> [f32; 3] {
        self.corner_depths_of(&self.mesh, index)
    }

    /// `corner_depths` of triangle `index` of `m`, a part of the instance's mesh (paging).
    pub fn corner_depths_of(&self, m: &Mesh, index: usize) -> [f32; 3] {
        m.corner_indices(index).map(|i| self.eye(m, i).z as f32)
    }

    fn eye(&self, m: &Mesh, i: u32) -> DVec3 {
        // Affine: the division by eye w (exactly 1) can go; glam's affine transform adds the
        // same products, so the numbers are the same.
        if self.is_affine() {
            self.modelview.transform_point3(m.positions[i as usize].as_dvec3())
        } else {
            let eye = self.modelview * m.position(i);
            eye.truncate() / if eye.w != 0.0 { eye.w } else { 1.0 }
        }
    }

    /// What the vertex stage makes of vertex `i` at eye-space point `eye`: its colours, lit
    /// for `face` when `lit` (flat shading lights only the provoking vertex), its eye normal
    /// and its colour before lighting.
    #[inline]
    fn vertex(&self, m: &Mesh, i: u32, eye: DVec3, lighting: Option<&Lighting>, lit: bool, face: usize) -> Vertex {
        let color = m.colors.at(i).map_or(self.color, |c| c.as_dvec4());
        let (primary, secondary, normal) = match lighting {
            Some(l) => {
                let object_normal = m.normals.at(i).map_or(self.normal, |n| n.as_dvec3());
                let n = eye_normal(&self.normal_matrix, object_normal, self.normalize, self.rescale_normal);
                if !lit {
                    return Vertex { primary: Vec4::ZERO, secondary: Vec3::ZERO, normal: n, color: vec4(color) };
                }
                let mats = l.materials(color);
                let (a, b) = light_face(eye, n, &mats, l.lights(), l.prepared(), l.model(), face);
                (a, b, n)
            }
            None => (color.clamp(DVec4::ZERO, DVec4::ONE), DVec4::ZERO, DVec3::Z),
        };
        Vertex { primary: vec4(primary), secondary: vec4(secondary).truncate(), normal, color: vec4(color) }
    }

    /// The colours of triangle `index`'s corners seen from its front (`front`) or back face,
    /// primary and secondary: what `triangle` gives it, for a caller that needs nothing else
    /// (a lit corner's position is transformed only when a light or the viewer is local, and
    /// is not read otherwise).
    #[inline]
    pub fn corner_colors(&self, index: usize, lightings: &[Lighting], front: bool) -> ([Vec4; 3], [Vec3; 3]) {
        self.corner_colors_of(&self.mesh, index, lightings, front)
    }

    /// `corner_colors` of triangle `index` of `m`, a part of the instance's mesh (paging).
    #[inline]
    pub fn corner_colors_of(
        &self,
        m: &Mesh,
        index: usize,
        lightings: &[Lighting],
        front: bool,
    ) -> ([Vec4; 3], [Vec3; 3]) {
        let lighting = self.lighting(lightings);
        let face = usize::from(!front);
        if let Some(sunlit) = lighting.and_then(Lighting::sunlit) {
            // Lights at infinity seen from infinity (most programs): single precision.
            let nm = self.normal_matrix.as_mat3();
            let (normal, color) = (self.normal.as_vec3a(), self.color.as_vec4());
            let vertex = |i: u32| {
                let n = m.normals.at(i).map_or(normal, Vec3A::from);
                let n = crate::sunlit::eye_normal(&nm, n, self.normalize, self.rescale_normal);
                sunlit.light(n, m.colors.at(i).unwrap_or(color), face)
            };
            if self.flat {
                let (primary, secondary) = vertex(m.provoking[index]);
                return ([primary; 3], [secondary; 3]);
            }
            let vs = m.corner_indices(index).map(vertex);
            return (vs.map(|v| v.0), vs.map(|v| v.1));
        }
        let positional = lighting.is_some_and(Lighting::reads_position);
        let vertex = |i: u32| {
            let eye = if positional { self.eye(m, i) } else { DVec3::ZERO };
            self.vertex(m, i, eye, lighting, true, face)
        };
        if self.flat {
            let v = vertex(m.provoking[index]);
            return ([v.primary; 3], [v.secondary; 3]);
        }
        let vs = m.corner_indices(index).map(vertex);
        (vs.map(|v| v.primary), vs.map(|v| v.secondary))
    }

    /// Whether a camera ray sees a triangle's front face, from the dot product of its eye-space
    /// normal (right-handed from its winding) with the ray's eye-space direction, and whether
    /// the camera's projection flips the window's winding (`projection_flips`): the facing the
    /// rasterizer would have found on the window, as `keeps_seen` finds it in object space.
    #[inline]
    pub fn front_seen(&self, eye_normal_dot_ray: f32, projection_flips: bool) -> bool {
        let ccw_seen = eye_normal_dot_ray < 0.0;
        (ccw_seen != projection_flips) == self.front_ccw
    }

    /// Triangle `index` as the rasterizer would have drawn it; None if culled. Without
    /// `texcoords` (its surface does not texture), its texture coordinates are left zero: three
    /// corners through the texture matrix that nothing would read, for every hit.
    #[inline]
    pub fn triangle(&self, index: usize, lightings: &[Lighting], texcoords: bool) -> Option<Triangle> {
        self.triangle_of(&self.mesh, index, lightings, texcoords)
    }

    /// `triangle` for triangle `index` of `m`, a part of the instance's mesh (a block of a paged
    /// mesh, drawn with the instance's transform and state).
    #[inline]
    pub fn triangle_of(&self, m: &Mesh, index: usize, lightings: &[Lighting], texcoords: bool) -> Option<Triangle> {
        let clip = self.clip(m, index);
        let front = window_facing(clip, self.front_ccw).unwrap_or(true);
        if culled(self.cull, front) {
            return None;
        }
        let face = usize::from(!front);
        let corners = m.corner_indices(index);
        let lighting = self.lighting(lightings);
        let eyes = corners.map(|i| self.eye(m, i));
        let vs = [0, 1, 2].map(|k| self.vertex(m, corners[k], eyes[k], lighting, !self.flat, face));
        let pv = if self.flat {
            let i = m.provoking[index];
            Some(self.vertex(m, i, self.eye(m, i), lighting, true, face))
        } else {
            None
        };
        let pick = |k: usize| pv.unwrap_or(vs[k]);
        let tex = |i: u32| {
            let t = self.texture_matrix * m.texcoords.at(i).map_or(self.texcoord, |t| t.as_dvec4());
            let q = if t.w != 0.0 { t.w } else { 1.0 };
            Vec2::new((t.x / q) as f32, (t.y / q) as f32)
        };
        Some(Triangle {
            positions: eyes.map(|p| p.as_vec3()),
            colors: [0, 1, 2].map(|k| pick(k).primary),
            secondary: [0, 1, 2].map(|k| pick(k).secondary),
            texcoords: if texcoords { corners.map(tex) } else { [Vec2::ZERO; 3] },
            surface: self.surface,
            sequence: self.sequence,
            camera: self.camera,
            clip_w: clip.map(|c| c.w as f32),
            normals: vs.map(|v| (if front { v.normal } else { -v.normal }).as_vec3()),
            base_colors: [0, 1, 2].map(|k| pick(k).color),
            lighting: self.lighting,
            back: !front,
        })
    }

    /// Every triangle of the instance that is drawn.
    pub fn triangles(&self, lightings: &[Lighting]) -> Vec<Triangle> {
        (0..self.mesh.triangles.len()).filter_map(|i| self.triangle(i, lightings, true)).collect()
    }
}
