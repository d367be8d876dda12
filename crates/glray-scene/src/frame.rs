//! A frame's scene (`Frame`): what capture hands the renderer for one frame. Triangles in eye
//! coordinates with the colours the rasterizer would interpolate (already lit, with the face
//! and flat shading decided), instances of meshes that make such triangles when a ray hits
//! them, the surface state each was drawn with, the lighting of lit draws, every camera, the
//! clears. Lines and points arrive as the screen-aligned quads a rasterizer fills for them, so
//! that the GL look needs no other primitive, and as solids for secondary rays.

use glam::{DMat4, DVec4, Vec3, Vec4};
use glray_core::prefetch;
use serde::{Deserialize, Serialize};

use crate::camera::Viewport;
use crate::draw_lighting::Lighting;
use crate::instance::Instance;
use crate::surface::Surface;
use crate::triangle::{Triangle, NO_LIGHTING};

/// A line or point as the solid that casts shadows and occludes: a capsule around the segment
/// from `a` to `b` (a ball when they are the same point), as thick as it is on the screen. Rays
/// from the camera see the rasterizer's quad instead (the GL look); this is what secondary
/// rays see.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Solid {
    pub a: Vec3,
    pub b: Vec3,
    pub radius: f32,
    /// The draw it belongs to (a point on the draw's own quads ignores its solids).
    pub sequence: u32,
    pub camera: u32,
}

/// A projection and viewport draws were made with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct View {
    pub projection: DMat4,
    pub viewport: Viewport,
}

impl View {
    /// Whether `other` is this view but for rounding: the same viewport, and every entry of the
    /// projection within a millionth of itself. The ranks of a parallel program each work out
    /// the camera they draw with, and the last bits differ (ParaView's clipping range from each
    /// rank's own sum over the data: -201.69076835 against -201.69078374); the rays they stand
    /// for are the same to a millionth of a pixel's width.
    pub fn same_but_for_rounding(&self, other: &View) -> bool {
        let (a, b) = (self.projection.to_cols_array(), other.projection.to_cols_array());
        let scale = a.iter().chain(&b).fold(0.0f64, |m, v| m.max(v.abs()));
        self.viewport == other.viewport
            && a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-6 * x.abs().max(y.abs()) + 1e-12 * scale)
    }
}

/// A glClear within a scissor box: the colour it fills the box with (None when the colour buffer
/// was not cleared), and the depth (glClearDepth; None when the depth buffer was not cleared).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScissoredClear {
    pub rect: Viewport,
    pub color: Option<Vec4>,
    pub depth: Option<f32>,
}

/// A glClear of the depth buffer alone between a frame's draws.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthClear {
    /// The sequence number of the draw after it (`Triangle::sequence`).
    pub before: u32,
    /// The depth it cleared to (glClearDepth).
    pub depth: f32,
}

/// A glClear of the colour buffer with some of its channels masked (glColorMask) between a
/// frame's draws: it sets those channels only, and keeps what was drawn. glplanet clears the
/// alpha of its day side so, then blends its night side by that alpha.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MaskedClear {
    /// The sequence number of the draw after it (`Triangle::sequence`).
    pub before: u32,
    /// glClearColor's colour, and which channels it sets.
    pub color: Vec4,
    pub mask: [bool; 4],
}

/// Which triangle of a frame: one of `Frame::triangles`, or one of an instance's mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct TriangleId {
    /// Index into `Frame::instances`, or `TriangleId::FLAT` for `Frame::triangles`.
    pub instance: u32,
    pub index: u32,
}

impl TriangleId {
    pub const FLAT: u32 = u32::MAX;
}

/// A captured frame.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Triangles made this frame (immediate mode, array draws, lines and points), in eye
    /// coordinates.
    pub triangles: Vec<Triangle>,
    /// Display-list meshes drawn this frame, each with the state of its call.
    pub instances: Vec<Instance>,
    /// Lines and points as solids, for shadows and occlusion.
    pub solids: Vec<Solid>,
    pub surfaces: Vec<Surface>,
    /// The projection and viewport of the frame's first 3D draw: the camera.
    pub projection: Option<DMat4>,
    pub viewport: Option<Viewport>,
    pub depth_range: (f64, f64),
    /// glClearColor at the last glClear of the colour buffer.
    pub clear_color: Vec4,
    /// Whether the colour buffer was cleared this frame; if not, the frame is drawn over the
    /// previous one (programs that leave trails rely on the buffer keeping its contents).
    pub cleared: bool,
    /// The depth the depth buffer was cleared to before the frame's draws (glClearDepth; None
    /// when it was not cleared this frame).
    pub depth_cleared: Option<f32>,
    /// Where a glClear of the depth buffer alone came between the frame's draws. Draws from
    /// there on are depth tested against the cleared depth only, so they land over all that
    /// came before (skytentacles draws each tentacle so).
    pub depth_clears: Vec<DepthClear>,
    /// Where a glClear of some of the colour buffer's channels came between the frame's draws.
    #[serde(default)]
    pub masked_clears: Vec<MaskedClear>,
    /// Clears within a scissor box smaller than the drawable since the last full one (each view
    /// of several clearing its own part of the window), in order.
    pub scissored_clears: Vec<ScissoredClear>,
    /// The lighting of lit draws (`Triangle::lighting` indexes it).
    pub lightings: Vec<Lighting>,
    /// Every projection and viewport the frame's draws used (3D scene, backgrounds, 2D
    /// overlays); `unified` brings them into one camera.
    pub cameras: Vec<View>,
    /// Draws capture cannot follow (shaders, generic vertex attributes): a frame with any
    /// is not ray traced, the real GL's picture stands.
    pub unsupported_draws: u32,
    /// Draws through shader programs no profile recognised (or outside the 3D viewport): left
    /// to the real GL, drawn over the ray-traced picture; the frame is still ray traced.
    pub passed_draws: u32,
    /// Drawable size, when known.
    pub width: u32,
    pub height: u32,
}

impl Frame {
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty() && self.instances.is_empty()
    }

    /// Whether the depth buffer can start the frame nearer than the far plane somewhere: the
    /// last frame's depth under a frame that did not clear the colour buffer, or a glClearDepth
    /// below 1 (a clear of the whole buffer or of a scissor box). Then even the closest hit
    /// of a pixel is depth tested against what the buffer held.
    pub fn depth_starts_near(&self) -> bool {
        !self.cleared
            || self.depth_cleared.is_some_and(|d| d < 1.0)
            || self.scissored_clears.iter().any(|c| c.depth.is_some_and(|d| d < 1.0))
    }

    /// About the bytes shading a hit reads from: the frame's own triangles and each mesh its
    /// instances draw (once, however many instances draw it).
    pub fn shading_bytes(&self) -> usize {
        let mut seen = std::collections::HashSet::new();
        let meshes: usize = self.instances.iter().filter(|i| seen.insert(i.mesh.id)).map(|i| i.mesh.bytes()).sum();
        self.triangles.len() * std::mem::size_of::<Triangle>() + meshes
    }

    /// Triangles drawn, counting every instance's mesh (before culling).
    pub fn triangle_count(&self) -> usize {
        self.triangles.len() + self.instances.iter().map(|i| i.mesh.triangles.len()).sum::<usize>()
    }

    /// A triangle as the rasterizer would have drawn it; None for an instance's triangle that
    /// is culled or has no area on the screen. An instance's triangle on an untextured surface
    /// has zero texture coordinates (see `Instance::triangle`).
    #[inline]
    pub fn triangle(&self, id: TriangleId) -> Option<Triangle> {
        if id.instance == TriangleId::FLAT {
            return self.triangles.get(id.index as usize).copied();
        }
        let instance = self.instances.get(id.instance as usize)?;
        let textured = self.surfaces.get(instance.surface as usize).is_none_or(|s| s.texturing.is_some());
        instance.triangle(id.index as usize, &self.lightings, textured)
    }

    /// Starts loading what `triangle(id)` will read, without waiting for it: `vertices` false,
    /// the triangle (or, for an instance, its vertex indices); true, the vertices those indices
    /// name (positions, when `positions`, normals, colours), which needs the indices loaded by
    /// then. The renderer calls both a few hits ahead of shading them (first the indices, then
    /// the vertices): on big meshes each hit's vertices are cache misses, and these let them
    /// overlap the shading of the hits before instead of stalling one after another.
    #[inline]
    pub fn prefetch_triangle(&self, id: TriangleId, vertices: bool, positions: bool) {
        if id.instance == TriangleId::FLAT {
            if let Some(t) = self.triangles.get(id.index as usize).filter(|_| !vertices) {
                prefetch::all(t);
            }
            return;
        }
        let Some(mesh) = self.instances.get(id.instance as usize).map(|i| &i.mesh) else { return };
        mesh.load_ahead(id.index as usize, vertices, |v| {
            if let Some(p) = mesh.positions.get(v as usize).filter(|_| positions) {
                prefetch::line(p);
            }
            if let Some(n) = mesh.normals.value(v) {
                prefetch::line(n);
            }
            if let Some(c) = mesh.colors.value(v) {
                prefetch::line(c);
            }
        });
    }

    /// Every triangle drawn, instances' made flat: for dumps and tests.
    pub fn all_triangles(&self) -> Vec<Triangle> {
        let mut out = self.triangles.clone();
        for i in &self.instances {
            out.extend(i.triangles(&self.lightings));
        }
        out
    }

    /// The size to render the frame at: the drawable, else the viewport's extent.
    pub fn size(&self) -> (u32, u32) {
        if self.width > 0 && self.height > 0 {
            return (self.width, self.height);
        }
        self.viewport.map_or((0, 0), |v| ((v.x + v.width).max(0) as u32, (v.y + v.height).max(0) as u32))
    }

    /// The camera most triangles were drawn with (the one `unified` keeps).
    pub fn main_camera(&self) -> u32 {
        let mut counts = vec![0usize; self.cameras.len()];
        for t in &self.triangles {
            if let Some(c) = counts.get_mut(t.camera as usize) {
                *c += 1;
            }
        }
        for i in &self.instances {
            if let Some(c) = counts.get_mut(i.camera as usize) {
                *c += i.mesh.triangles.len();
            }
        }
        (0..counts.len()).max_by_key(|&i| (counts[i], std::cmp::Reverse(i))).unwrap_or(0) as u32
    }

    /// The frame split by viewport when it draws in more than one (views side by side in one
    /// window: antmaze's three, a layout of several views): one frame per viewport, in the order
    /// they were first drawn in, each with only the draws made in it, to be traced through its
    /// own camera into its own part of the window, each over what the ones before left (they
    /// share the colour and depth buffers, as in GL). None when every draw went to one viewport:
    /// other projections within it (backgrounds, overlays) are brought into one camera by
    /// `unified`.
    pub fn by_viewport(&self) -> Option<Vec<Frame>> {
        let used = |camera: u32| {
            self.triangles.iter().any(|t| t.camera == camera)
                || self.instances.iter().any(|i| i.camera == camera)
                || self.solids.iter().any(|s| s.camera == camera)
        };
        let mut viewports: Vec<Viewport> = Vec::new();
        for (k, view) in self.cameras.iter().enumerate() {
            if !viewports.contains(&view.viewport) && used(k as u32) {
                viewports.push(view.viewport);
            }
        }
        if viewports.len() < 2 {
            return None;
        }
        let parts = viewports
            .iter()
            .enumerate()
            .map(|(n, &viewport)| {
                let inside = |camera: u32| self.cameras.get(camera as usize).is_some_and(|v| v.viewport == viewport);
                let first = self.cameras.iter().position(|v| v.viewport == viewport).unwrap_or(0);
                Frame {
                    triangles: self.triangles.iter().filter(|t| inside(t.camera)).copied().collect(),
                    instances: self.instances.iter().filter(|i| inside(i.camera)).cloned().collect(),
                    solids: self.solids.iter().filter(|s| inside(s.camera)).copied().collect(),
                    projection: Some(self.cameras[first].projection),
                    viewport: Some(viewport),
                    // The views after the first draw over what the ones before left.
                    cleared: self.cleared && n == 0,
                    depth_cleared: self.depth_cleared.filter(|_| n == 0),
                    scissored_clears: if n == 0 { self.scissored_clears.clone() } else { Vec::new() },
                    ..self.clone_without_draws()
                }
            })
            .collect();
        Some(parts)
    }

    /// The frame's state without its draws (for `by_viewport`, which hands them out). Every
    /// field named, so that a new one is not forgotten here.
    fn clone_without_draws(&self) -> Frame {
        let Frame {
            triangles: _,
            instances: _,
            solids: _,
            surfaces,
            projection,
            viewport,
            depth_range,
            clear_color,
            cleared,
            depth_cleared,
            depth_clears,
            masked_clears,
            scissored_clears,
            lightings,
            cameras,
            unsupported_draws,
            passed_draws,
            width,
            height,
        } = self;
        Frame {
            triangles: Vec::new(),
            instances: Vec::new(),
            solids: Vec::new(),
            surfaces: surfaces.clone(),
            projection: *projection,
            viewport: *viewport,
            depth_range: *depth_range,
            clear_color: *clear_color,
            cleared: *cleared,
            depth_cleared: *depth_cleared,
            depth_clears: depth_clears.clone(),
            masked_clears: masked_clears.clone(),
            scissored_clears: scissored_clears.clone(),
            lightings: lightings.clone(),
            cameras: cameras.clone(),
            unsupported_draws: *unsupported_draws,
            passed_draws: *passed_draws,
            width: *width,
            height: *height,
        }
    }

    /// The frame seen through one camera: the one most triangles were drawn with. Triangles
    /// drawn with another projection or viewport (a background, a 2D overlay, an inset) are
    /// carried into that camera's eye space through clip space, which keeps every pixel they
    /// cover and every window depth they have: the rasterizer's picture, traced by one camera.
    pub fn unified(&self) -> Frame {
        if self.cameras.is_empty() {
            return self.clone();
        }
        let main = self.main_camera() as usize;
        let to = self.cameras[main];
        let to_inverse = to.projection.inverse();
        let maps: Vec<DMat4> = self
            .cameras
            .iter()
            .map(|from| {
                // Window coordinates of `from`'s viewport, as NDC of `to`'s, applied in clip space.
                let (fv, tv) = (from.viewport, to.viewport);
                let sx = fv.width as f64 / tv.width.max(1) as f64;
                let sy = fv.height as f64 / tv.height.max(1) as f64;
                let tx = (2.0 * (fv.x - tv.x) as f64 + fv.width as f64) / tv.width.max(1) as f64 - 1.0;
                let ty = (2.0 * (fv.y - tv.y) as f64 + fv.height as f64) / tv.height.max(1) as f64 - 1.0;
                let window = DMat4::from_cols(
                    DVec4::new(sx, 0.0, 0.0, 0.0),
                    DVec4::new(0.0, sy, 0.0, 0.0),
                    DVec4::new(0.0, 0.0, 1.0, 0.0),
                    DVec4::new(tx, ty, 0.0, 1.0),
                );
                window * from.projection
            })
            .collect();
        let mut out = self.clone();
        // Instances drawn with another camera are made flat, to be carried over below.
        let (keep, carry): (Vec<Instance>, Vec<Instance>) =
            std::mem::take(&mut out.instances).into_iter().partition(|i| i.camera as usize == main);
        out.instances = keep;
        // Lines and points of overlays and insets cast no shadows in the 3D scene.
        out.solids.retain(|s| s.camera as usize == main);
        for i in &carry {
            out.triangles.extend(i.triangles(&self.lightings));
        }
        out.projection = Some(to.projection);
        out.viewport = Some(to.viewport);
        for t in &mut out.triangles {
            if t.camera as usize != main {
                // Carried over from another camera: lit as drawn (the eye space differs).
                t.lighting = NO_LIGHTING;
                let m = maps[t.camera as usize];
                t.positions = t.positions.map(|p| {
                    let mut c = m * p.as_dvec3().extend(1.0);
                    // Backgrounds drawn exactly on the near or far plane (z = +-1 with an
                    // identity projection) stay a hair inside, where rays reach them.
                    const INSIDE: f64 = 1.0 - 1e-5;
                    c.z = c.z.clamp(-INSIDE * c.w.abs(), INSIDE * c.w.abs());
                    let e = to_inverse * c;
                    (e.truncate() / e.w).as_vec3()
                });
                t.camera = main as u32;
            }
        }
        out
    }
}
