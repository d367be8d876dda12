//! From a draw's vertices to the frame's triangles: the draw's surface and camera, primitive
//! assembly, facing from the clip-space winding, culling, polygon modes, flat shading, and
//! lines and points as the screen-aligned quads a rasterizer fills.

use glray_gl::{GL_FILL, GL_LINE, GL_POINT, GL_POLYGON, GL_QUADS, GL_QUAD_STRIP};
use std::sync::Arc;

use glam::{DMat4, DVec2, DVec4, Vec2, Vec3, Vec4};

use crate::fixed::mesh_builder::Compiled;
use crate::fixed::{vec4, Context, EyeVertex};
use crate::primitive::{assemble, QuadSplit};
use glray_scene::camera::Viewport;
use glray_scene::facing::{culled, facing_flip, window_facing};
use glray_scene::frame::{Solid, View};
use glray_scene::instance::Instance;
use glray_scene::surface::{Coverage, Surface, Texturing};
use glray_scene::triangle::{Triangle, NO_LIGHTING};

/// What `draw_setup` decided for a draw.
struct Setup {
    projection: DMat4,
    viewport: Viewport,
    camera: u32,
    surface: u32,
    lighting: u32,
    sequence: u32,
}

/// The point a fraction `s` of the way from `a` to `b` (glam's `lerp`), but `b` itself at the
/// end: `a + (b - a) * 1` can round off `b`, and a line not clipped keeps its vertices' numbers
/// (at the start, `a + (b - a) * 0` is `a` already).
macro_rules! toward {
    ($a:expr, $b:expr, $s:expr) => {
        if $s == 1.0 {
            $b
        } else {
            $a.lerp($b, $s)
        }
    };
}

/// The part of the segment from clip position `a` to `b` in front of the near plane (z >= -w),
/// as the fractions of the way from `a` where it starts and ends; None when it is all behind.
pub(crate) fn near_part(a: DVec4, b: DVec4) -> Option<(f64, f64)> {
    let (da, db) = (a.z + a.w, b.z + b.w);
    match (da >= 0.0, db >= 0.0) {
        (true, true) => Some((0.0, 1.0)),
        (false, false) => None,
        (true, false) => Some((0.0, da / (da - db))),
        (false, true) => Some((da / (da - db), 1.0)),
    }
}

impl Context {
    /// The draw's per-fragment state, as an index into the frame's surfaces (the last one
    /// again when nothing changed); `polygons`: the draw fills polygons (glPolygonOffset
    /// applies to them only).
    pub(crate) fn surface(&mut self, polygons: bool) -> u32 {
        // GL_TEXTURE_2D, enabled, takes precedence over GL_TEXTURE_1D.
        let bound = self.texturing.enabled_texture();
        let texturing = bound.and_then(|name| {
            self.shared.textures.get(&name).filter(|t| t.complete()).map(|t| Texturing {
                texture: t.clone(),
                env_mode: self.texturing.env_mode,
                env_color: self.texturing.env_color,
            })
        });
        let surface = Surface {
            texturing,
            fog: self.raster.fog_enabled.then_some(self.raster.fog),
            depth_test: self.raster.depth_test,
            depth_func: self.raster.depth_func,
            depth_mask: self.raster.depth_mask,
            blend: self.raster.blend.then_some(self.raster.blend_func),
            logic_op: self.raster.logic_op_enabled.then_some(self.raster.logic_op),
            alpha_test: self.raster.alpha_test.then_some(self.raster.alpha_func),
            clip_planes: self.raster.clip_planes.iter().filter(|p| p.0).map(|p| p.1).collect(),
            polygon_offset: (polygons && self.raster.polygon_offset_fill).then_some(self.raster.polygon_offset),
            color_mask: self.raster.color_mask,
            coverage: None,
        };
        self.add_surface(surface)
    }

    /// Surface `index` for the antialiased lines or points of its draw (`Coverage`).
    fn covered_surface(&mut self, index: u32, coverage: Coverage) -> u32 {
        let Some(base) = self.frame.surfaces.get(index as usize) else { return index };
        let surface = Surface { coverage: Some(coverage), ..base.clone() };
        self.add_surface(surface)
    }

    /// `surface`'s index among the frame's surfaces: the last one again when they are the same.
    fn add_surface(&mut self, surface: Surface) -> u32 {
        let same = |a: &Surface, b: &Surface| {
            // Every field named, so that a new one is not forgotten here.
            let Surface {
                texturing,
                fog,
                depth_test,
                depth_func,
                depth_mask,
                blend,
                logic_op,
                alpha_test,
                clip_planes,
                polygon_offset,
                color_mask,
                coverage,
            } = a;
            *fog == b.fog
                && *depth_test == b.depth_test
                && *depth_func == b.depth_func
                && *depth_mask == b.depth_mask
                && *blend == b.blend
                && *logic_op == b.logic_op
                && *alpha_test == b.alpha_test
                && *clip_planes == b.clip_planes
                && *polygon_offset == b.polygon_offset
                && *color_mask == b.color_mask
                && *coverage == b.coverage
                && match (texturing, &b.texturing) {
                    (None, None) => true,
                    (Some(x), Some(y)) => {
                        Arc::ptr_eq(&x.texture, &y.texture) && x.env_mode == y.env_mode && x.env_color == y.env_color
                    }
                    _ => false,
                }
        };
        if let Some(last) = self.frame.surfaces.last() {
            if same(last, &surface) {
                return (self.frame.surfaces.len() - 1) as u32;
            }
        }
        self.frame.surfaces.push(surface);
        (self.frame.surfaces.len() - 1) as u32
    }

    /// What every draw records in the frame: its camera (the first 3D draw's is the frame's),
    /// surface, lighting and place in drawing order.
    fn draw_setup(&mut self, polygons: bool) -> Setup {
        let projection = *self.matrices.projection.top();
        let viewport = self.raster.viewport;
        if self.frame.projection.is_none() {
            self.frame.projection = Some(projection);
            self.frame.viewport = Some(viewport);
            self.frame.depth_range = self.raster.depth_range;
            if self.framebuffer != 0 {
                // Drawn into a framebuffer object, not the drawable: traced at the size its
                // first draw's viewport reaches (VTK's render target; not the window's).
                self.frame.width = (viewport.x + viewport.width).max(0) as u32;
                self.frame.height = (viewport.y + viewport.height).max(0) as u32;
            }
        }
        let view = View { projection, viewport };
        let camera = match self.frame.cameras.iter().rposition(|c| *c == view) {
            Some(i) => i as u32,
            None => {
                self.frame.cameras.push(view);
                (self.frame.cameras.len() - 1) as u32
            }
        };
        let surface = self.surface(polygons);
        let lighting = if self.lighting.lighting {
            // The last draw's lighting again when made of the same state (most draws): compared
            // before a new one is made, whose lights are copied and prepared (~1,400
            // instructions, most of a small draw's set-up).
            let color_material = self.lighting.color_material();
            let enabled = self.lighting.lights.iter().filter(|l| l.enabled);
            let same =
                self.frame.lightings.last().is_some_and(|l| {
                    l.is_made_of(enabled, &self.lighting.model, &self.lighting.materials, color_material)
                });
            if !same {
                let l = self.lighting.lighting();
                self.frame.lightings.push(l);
            }
            (self.frame.lightings.len() - 1) as u32
        } else {
            NO_LIGHTING
        };
        let sequence = self.sequence;
        self.sequence += 1;
        Setup { projection, viewport, camera, surface, lighting, sequence }
    }

    /// Whether a vertex at `clip` (clip coordinates) and `eye` (eye coordinates) is outside
    /// the view volume or an enabled clip plane: Mesa then cuts a direct draw's quads as an
    /// indexed draw's (`draw`).
    pub(crate) fn clipped(&self, clip: DVec4, eye: DVec4) -> bool {
        let c = clip;
        [c.x, -c.x, c.y, -c.y, c.z, -c.z].iter().any(|&d| d > c.w)
            || self.raster.clip_planes.iter().any(|(on, plane)| *on && plane.dot(eye) < 0.0)
    }

    /// Whether a list's mesh can be drawn now as an instance: triangles filled, texture
    /// coordinates not generated from positions, positions with w = 1, an invertible affine
    /// modelview (rays go into the mesh's space through its inverse).
    pub(crate) fn instances(&self, compiled: &Compiled) -> bool {
        !compiled.lines_or_points && compiled.mesh.ws.is_none() && self.instances_now()
    }

    /// The state's part of `instances`: what no call between glBegin and glEnd can change.
    pub(crate) fn instances_now(&self) -> bool {
        let mv = self.matrices.modelview.top();
        !self.programmable
            && self.raster.polygon_mode == [GL_FILL, GL_FILL]
            && !self.texturing.texgen.iter().any(|g| g.enabled)
            && mv.determinant().is_normal()
            && mv.row(3) == DVec4::W
    }

    /// A list's mesh drawn as an instance (the caller checked `instances`).
    pub(crate) fn instance(&mut self, compiled: &Compiled) {
        let mesh = &compiled.mesh;
        self.revision += 1;
        if mesh.triangles.is_empty() {
            return;
        }
        // `instances`: filled triangles only.
        let setup = self.draw_setup(true);
        let modelview = *self.matrices.modelview.top();
        let normal_matrix = self.normal_matrix(&modelview);
        let cur = &self.imm.current;
        self.frame.instances.push(Instance {
            mesh: mesh.clone(),
            modelview,
            object_to_clip: setup.projection * modelview,
            normal_matrix,
            normalize: self.lighting.normalize,
            rescale_normal: self.lighting.rescale_normal,
            texture_matrix: *self.matrices.texture[0].top(),
            normal: cur.normal,
            color: cur.color,
            texcoord: cur.texcoords[0],
            surface: setup.surface,
            camera: setup.camera,
            sequence: setup.sequence,
            lighting: setup.lighting,
            flat: self.lighting.flat,
            front_ccw: self.raster.front_ccw,
            cull: self.raster.culling(),
            mirrored: facing_flip(&modelview, &setup.projection),
        });
    }

    /// Assembles one draw's vertices into the frame's triangles, its quads cut as `quads` says.
    pub(crate) fn draw(&mut self, mode: u32, verts: &[EyeVertex], quads: QuadSplit) {
        self.revision += 1;
        if self.programmable {
            self.frame.unsupported_draws += 1;
            return;
        }
        let Ok(asm) = assemble(mode, verts.len(), quads) else { return };
        if verts.is_empty() || (asm.triangles.is_empty() && asm.lines.is_empty() && asm.points.is_empty()) {
            return;
        }
        // Polygons filled on both faces (a face drawn as lines or points is not offset: the
        // rare mixed case is taken as lines).
        let polygons = asm.lines.is_empty() && asm.points.is_empty() && self.raster.polygon_mode == [GL_FILL; 2];
        let Setup { projection, viewport, camera, surface, lighting, sequence } = self.draw_setup(polygons);
        let clip: Vec<DVec4> = verts.iter().map(|v| projection * v.eye).collect();
        // Mesa's clipping path cuts quads along 1-3 too: a glBegin/glEnd or glDrawArrays of
        // quads with any vertex outside the view volume (or a clip plane) is cut as an
        // indexed draw is. (Mesa decides by everything it draws at once, which may be several
        // glBegin/glEnd with the same state; glray looks at one.)
        let outside = |(c, v): (&DVec4, &EyeVertex)| self.clipped(*c, v.eye);
        let asm = if mode == GL_QUADS && quads == QuadSplit::Direct && clip.iter().zip(verts).any(outside) {
            assemble(mode, verts.len(), QuadSplit::Indexed).unwrap_or(asm)
        } else {
            asm
        };
        let flat = self.lighting.flat;
        let color = |v: &EyeVertex, face: usize| vec4(v.colors[face]);
        let secondary = |v: &EyeVertex, face: usize| v.secondary[face].truncate().as_vec3();
        let tex = |v: &EyeVertex| {
            let q = if v.tex.w != 0.0 { v.tex.w } else { 1.0 };
            Vec2::new((v.tex.x / q) as f32, (v.tex.y / q) as f32)
        };
        let eye3 = |v: &EyeVertex| (v.eye.truncate() / if v.eye.w != 0.0 { v.eye.w } else { 1.0 }).as_vec3();
        let mut tris = Vec::new();
        // Lines and points with the face whose colours they take: a polygon drawn as lines or
        // points takes its own face's (two-sided lighting's back colours on a back face, as
        // GL's polygon rasterization does; moebius's wireframe strip); lines and points drawn
        // as such, the front's.
        let mut lines: Vec<([u32; 2], u32, usize)> = asm.lines.iter().map(|&(l, p)| (l, p, 0)).collect();
        let mut points: Vec<(u32, usize)> = asm.points.iter().map(|&i| (i, 0)).collect();
        let polygon_of = |mode: u32, triangle: usize| match mode {
            GL_QUADS | GL_QUAD_STRIP => triangle / 2,
            GL_POLYGON => 0,
            _ => triangle,
        };
        // Edges two triangles of one polygon share: the diagonals of the split.
        let mut diagonals = std::collections::HashSet::new();
        if self.raster.polygon_mode.contains(&GL_LINE) && matches!(mode, GL_QUADS | GL_QUAD_STRIP | GL_POLYGON) {
            let mut seen = std::collections::HashSet::new();
            for (index, (t, _)) in asm.triangles.iter().enumerate() {
                let polygon = polygon_of(mode, index);
                for (x, y) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    let key = (polygon, x.min(y), x.max(y));
                    if !seen.insert(key) {
                        diagonals.insert(key);
                    }
                }
            }
        }
        for (index, &(t, provoking)) in asm.triangles.iter().enumerate() {
            let Some(front) = window_facing(t.map(|i| clip[i as usize]), self.raster.front_ccw) else { continue };
            if culled(self.raster.culling(), front) {
                continue;
            }
            let face = if front { 0 } else { 1 };
            match self.raster.polygon_mode[face] {
                GL_LINE => {
                    // The edges of the polygon the program drew: a quad or polygon split into
                    // triangles keeps its diagonals hidden (GL's edge flags for the split).
                    let polygon = polygon_of(mode, index);
                    for (x, y) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                        if !diagonals.contains(&(polygon, x.min(y), x.max(y))) {
                            lines.push(([x, y], provoking, face));
                        }
                    }
                    continue;
                }
                GL_POINT => {
                    points.extend(t.map(|i| (i, face)));
                    continue;
                }
                _ => {}
            }
            let vs = t.map(|i| &verts[i as usize]);
            let pv = &verts[provoking as usize];
            tris.push(Triangle {
                positions: vs.map(eye3),
                colors: if flat { [color(pv, face); 3] } else { vs.map(|v| color(v, face)) },
                secondary: if flat { [secondary(pv, face); 3] } else { vs.map(|v| secondary(v, face)) },
                texcoords: vs.map(tex),
                surface,
                sequence,
                camera,
                clip_w: t.map(|i| clip[i as usize].w as f32),
                normals: vs.map(|v| (if front { v.normal } else { -v.normal }).as_vec3()),
                base_colors: if flat { [vec4(pv.base); 3] } else { vs.map(|v| vec4(v.base)) },
                lighting,
                back: !front,
            });
        }
        // Only lines and points need it: most draws are triangles alone.
        let inverse = std::cell::OnceCell::new();
        let (hw, hh) = (viewport.width.max(1) as f64 / 2.0, viewport.height.max(1) as f64 / 2.0);
        // A quad around window-space offsets of clip positions, back in eye space.
        let quad = |corners: [(DVec4, DVec2); 4]| -> Option<[Vec3; 4]> {
            let mut out = [Vec3::ZERO; 4];
            for (o, (c, off)) in out.iter_mut().zip(corners) {
                if c.w <= 0.0 {
                    return None;
                }
                let moved = DVec4::new(c.x + off.x / hw * c.w, c.y + off.y / hh * c.w, c.z, c.w);
                let e = *inverse.get_or_init(|| projection.inverse()) * moved;
                *o = (e.truncate() / e.w).as_vec3();
            }
            Some(out)
        };
        let mut solids = Vec::new();
        // Antialiased lines and points: quads half a pixel wider all round, their own surface
        // saying how much of each pixel they cover.
        let (line_smooth, point_smooth) = (self.raster.line_smooth, self.raster.point_smooth);
        let line_surface = if line_smooth && !lines.is_empty() {
            self.covered_surface(surface, Coverage::Line(self.raster.line_width as f32))
        } else {
            surface
        };
        let point_surface = if point_smooth && !points.is_empty() {
            self.covered_surface(surface, Coverage::Point(self.raster.point_size as f32))
        } else {
            surface
        };
        let line_half = self.raster.line_width / 2.0 + if line_smooth { 0.5 } else { 0.0 };
        for &([i, j], provoking, face) in &lines {
            let (ca, cb) = (clip[i as usize], clip[j as usize]);
            // The part in front of the near plane, as GL clips it: a floor grid's lines that
            // run past the viewer (winduprobot's, handsy's) keep what is in view.
            let Some((sa, sb)) = near_part(ca, cb) else { continue };
            let (ca, cb) = (ca.lerp(cb, sa), toward!(ca, cb, sb));
            if ca.w <= 0.0 || cb.w <= 0.0 {
                continue;
            }
            let d = DVec2::new((cb.x / cb.w - ca.x / ca.w) * hw, (cb.y / cb.w - ca.y / ca.w) * hh);
            // GL widens an aliased line along its minor axis (OpenGL 2.1, 3.4.2.1): an x-major
            // line is a parallelogram `width` pixels tall, one pixel per column at width 1, not a
            // rectangle across the line (which covers 1/cos of a pixel per column and rounds
            // to other pixels: a grid of thin lines came out thicker and a pixel off).
            // (An antialiased line is a rectangle across the line.)
            let perp = if line_smooth {
                DVec2::new(-d.y, d.x).normalize_or_zero() * line_half
            } else if d.x.abs() >= d.y.abs() {
                DVec2::new(0.0, line_half)
            } else {
                DVec2::new(line_half, 0.0)
            };
            let Some(q) = quad([(ca, -perp), (ca, perp), (cb, perp), (cb, -perp)]) else { continue };
            // The solid shadows and occlusion see: the segment between the vertices, as thick
            // as the line is on the screen (the quad's width at each end, averaged).
            let radius = ((q[1] - q[0]).length() + (q[2] - q[3]).length()) / 4.0;
            let (va, vb, pv) = (&verts[i as usize], &verts[j as usize], &verts[provoking as usize]);
            // Clip coordinates are linear in eye coordinates: the clipped ends' attributes are
            // the same mix of the vertices'.
            let (sa, sb) = (sa as f32, sb as f32);
            let (ea, eb) = (eye3(va), eye3(vb));
            solids.push(Solid { a: ea.lerp(eb, sa), b: toward!(ea, eb, sb), radius, sequence, camera });
            let (c0, c1) = if flat {
                (color(pv, face), color(pv, face))
            } else {
                let (ca, cb) = (color(va, face), color(vb, face));
                (ca.lerp(cb, sa), toward!(ca, cb, sb))
            };
            let (ta, tb) = (tex(va), tex(vb));
            let (t0, t1) = (ta.lerp(tb, sa), toward!(ta, tb, sb));
            // Corners 0-1 across the line, 1-2 along it, in both triangles (`Coverage`).
            for tri in [[0, 1, 2], [2, 3, 0]] {
                let pick = |k: usize| if k < 2 { (c0, t0) } else { (c1, t1) };
                tris.push(Triangle {
                    positions: tri.map(|k| q[k]),
                    colors: tri.map(|k| pick(k).0),
                    secondary: [Vec3::ZERO; 3],
                    texcoords: tri.map(|k| pick(k).1),
                    surface: line_surface,
                    sequence,
                    camera,
                    clip_w: tri.map(|k| if k < 2 { ca.w } else { cb.w } as f32),
                    normals: [Vec3::Z; 3],
                    base_colors: [Vec4::ONE; 3],
                    lighting: NO_LIGHTING,
                    back: false,
                });
            }
        }
        // An aliased point is GL's square of its size rounded to a whole number of pixels (as
        // Mesa rounds: halves down, at least 1), its centre moved to a pixel's centre (odd
        // sizes) or corner (even ones), so that its edges fall between pixel centres, never on
        // one; an antialiased point is a disc of its own size, half a pixel wider all round for
        // its coverage.
        let point_size =
            if point_smooth { self.raster.point_size } else { (self.raster.point_size - 0.5).ceil().max(1.0) };
        let point_half = point_size / 2.0 + if point_smooth { 0.5 } else { 0.0 };
        let snap = |at: f64| {
            if point_smooth {
                0.0
            } else if point_size % 2.0 == 1.0 {
                at.floor() + 0.5 - at
            } else {
                (at + 0.5).floor() - at
            }
        };
        for &(i, face) in &points {
            let c = clip[i as usize];
            let h = point_half;
            // Window position within the viewport (its origin is a whole pixel).
            let (dx, dy) = (snap((c.x / c.w + 1.0) * hw), snap((c.y / c.w + 1.0) * hh));
            let corners = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(x, y)| (c, DVec2::new(x + dx, y + dy)));
            let Some(q) = quad(corners) else { continue };
            let v = &verts[i as usize];
            let center = eye3(v);
            solids.push(Solid { a: center, b: center, radius: (q[1] - q[0]).length() / 2.0, sequence, camera });
            // Corners 0 and 2 opposite in both triangles (`Coverage`).
            for tri in [[0, 1, 2], [2, 3, 0]] {
                tris.push(Triangle {
                    positions: tri.map(|k| q[k]),
                    colors: [color(v, face); 3],
                    secondary: [Vec3::ZERO; 3],
                    texcoords: [tex(v); 3],
                    surface: point_surface,
                    sequence,
                    camera,
                    clip_w: [c.w as f32; 3],
                    normals: [Vec3::Z; 3],
                    base_colors: [Vec4::ONE; 3],
                    lighting: NO_LIGHTING,
                    back: false,
                });
            }
        }
        self.frame.triangles.extend(tris);
        self.frame.solids.extend(solids);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed::tests::*;
    use glam::{Vec3, Vec4};

    use glray_gl::*;

    #[test]
    fn culling_facing_and_flat_shading() {
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_CULL_FACE as i64)]);
        triangle(&mut c, true);
        triangle(&mut c, false);
        assert_eq!(c.frame().triangles.len(), 1, "the clockwise (back) one is culled");
        call(&mut c, "glFrontFace", &[i(GL_CW as i64)]);
        triangle(&mut c, false);
        assert_eq!(c.frame().triangles.len(), 2, "with GL_CW it is the front one");
        // Flat shading takes the provoking (last) vertex's colour.
        call(&mut c, "glShadeModel", &[i(GL_FLAT as i64)]);
        call(&mut c, "glBegin", &[i(4)]);
        for (k, (x, y)) in [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)].into_iter().enumerate() {
            call(&mut c, "glColor3f", &[f(k as f64 / 2.0), f(0.0), f(0.0)]);
            call(&mut c, "glVertex2f", &[f(x), f(y)]);
        }
        call(&mut c, "glEnd", &[]);
        let t = c.frame().triangles.last().unwrap();
        assert!(t.colors.iter().all(|col| col.x == 1.0), "{:?}", t.colors);
    }
    #[test]
    fn polygon_mode_line_keeps_quad_diagonals_hidden() {
        let mut c = context();
        call(&mut c, "glPolygonMode", &[i(GL_FRONT_AND_BACK as i64), i(GL_LINE as i64)]);
        call(&mut c, "glBegin", &[i(7)]); // GL_QUADS
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            call(&mut c, "glVertex2f", &[f(x), f(y)]);
        }
        call(&mut c, "glEnd", &[]);
        assert_eq!(c.frame().triangles.len(), 8, "four edges, two triangles each");
    }
    #[test]
    fn lines_and_points_are_also_solids_as_thick_as_on_the_screen() {
        // 100 pixels over 2 eye units: a pixel is 0.02.
        let mut c = context();
        call(&mut c, "glLineWidth", &[f(4.0)]);
        call(&mut c, "glBegin", &[i(1)]); // GL_LINES
        call(&mut c, "glVertex2f", &[f(-0.5), f(0.0)]);
        call(&mut c, "glVertex2f", &[f(0.5), f(0.0)]);
        call(&mut c, "glEnd", &[]);
        call(&mut c, "glPointSize", &[f(6.0)]);
        call(&mut c, "glBegin", &[i(0)]); // GL_POINTS
        call(&mut c, "glVertex2f", &[f(0.25), f(0.5)]);
        call(&mut c, "glEnd", &[]);
        let s = &c.frame().solids;
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].a, s[0].b), (Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)));
        assert!((s[0].radius - 0.04).abs() < 1e-6, "two pixels: {}", s[0].radius);
        assert_eq!((s[1].a, s[1].b), (Vec3::new(0.25, 0.5, 0.0), Vec3::new(0.25, 0.5, 0.0)));
        assert!((s[1].radius - 0.06).abs() < 1e-6, "three pixels: {}", s[1].radius);
        assert_ne!(s[0].sequence, s[1].sequence);
    }
    #[test]
    fn a_line_reaching_behind_the_viewer_keeps_its_part_in_front() {
        // A perspective camera (near plane at 1); a line from 4 in front to 4 behind the eye,
        // red to blue. GL clips it at the near plane; glray had dropped it whole.
        let mut c = context();
        call(&mut c, "glMatrixMode", &[i(0x1701)]);
        call(&mut c, "glLoadIdentity", &[]);
        call(&mut c, "glFrustum", &[f(-1.0), f(1.0), f(-1.0), f(1.0), f(1.0), f(100.0)]);
        call(&mut c, "glMatrixMode", &[i(0x1700)]);
        call(&mut c, "glBegin", &[i(1)]); // GL_LINES
        call(&mut c, "glColor3f", &[f(1.0), f(0.0), f(0.0)]);
        call(&mut c, "glVertex3f", &[f(0.0), f(-0.5), f(-4.0)]);
        call(&mut c, "glColor3f", &[f(0.0), f(0.0), f(1.0)]);
        call(&mut c, "glVertex3f", &[f(0.0), f(-0.5), f(4.0)]);
        call(&mut c, "glEnd", &[]);
        let (t, s) = (&c.frame().triangles, &c.frame().solids);
        assert_eq!((t.len(), s.len()), (2, 1));
        // The part from z = -4 to the near plane, z = -1: three eighths of the way.
        assert_eq!(s[0].a, Vec3::new(0.0, -0.5, -4.0));
        assert!((s[0].b - Vec3::new(0.0, -0.5, -1.0)).length() < 1e-5, "{}", s[0].b);
        for p in t.iter().flat_map(|t| t.positions) {
            assert!(p.z <= -1.0 + 1e-5 && p.z >= -4.0 - 1e-4, "{p}");
        }
        let far_end = t.iter().flat_map(|t| t.colors).fold(Vec4::ZERO, |m, c| m.max(c));
        assert!((far_end.z - 0.375).abs() < 1e-5 && far_end.x == 1.0, "{far_end}");
        // All of it behind: nothing.
        call(&mut c, "glBegin", &[i(1)]);
        call(&mut c, "glVertex3f", &[f(0.0), f(0.0), f(0.5)]);
        call(&mut c, "glVertex3f", &[f(0.0), f(0.0), f(4.0)]);
        call(&mut c, "glEnd", &[]);
        assert_eq!(c.frame().triangles.len(), 2);
    }
}
