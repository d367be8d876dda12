//! The fixed-function machine: one GL context (`Context`) follows its calls and turns what it
//! draws into a `Frame` of lit, eye-space triangles and instances. Commands arrive as recorded
//! calls (an `Op` and its `Value`s), the same from a trace file as from the live library, so the
//! two paths cannot drift apart.
//!
//! `Context` routes each command to the part of the context it concerns (gl-spec/capture.txt's
//! `[concern]` sections, `Op::concern`), each in its own module with its state, its commands and
//! its tests, as Mesa's main/ splits light.c, matrix.c, texparam.c:
//!
//! | concern | module | state |
//! |---|---|---|
//! | matrices | `matrices` | the matrix stacks |
//! | lighting | `lighting` | lights, materials, light model, colour material, shading |
//! | raster | `raster` | facing, culling, polygon modes, depth/alpha/scissor tests, blending, fog, lines and points, clip planes, viewport, clears |
//! | texturing | `texturing` | texture objects, bindings, environment, coordinate generation |
//! | lists | `lists` | display lists: compiling, calling |
//! | arrays | `arrays` | client arrays, buffer objects, array draws (`client_draws`: big client draws kept) |
//! | immediate | `immediate` | glBegin/glEnd and the current attributes (`immediate_meshes`: long glBegins kept) |
//! | context | here | enables, clears, the attribute stack, programs, framebuffers |
//! | programs | `crate::programs` (`program_draws` here) | GLSL programs, uniforms, vertex arrays: draws a profile recognises |
//!
//! Beside them: `vertex` (the vertex stage: transform, lighting, texture coordinates),
//! `draw` (a draw's vertices into the frame's triangles), `mesh_builder` (meshes made from
//! calls), `list_effects` (what a list changed, for the real GL).

mod arrays;
mod client_draws;
mod draw;
pub mod immediate;
mod immediate_meshes;
mod lighting;
pub mod list_effects;
pub mod lists;
pub mod matrices;
pub mod mesh_builder;
mod program_draws;
mod raster;
mod texturing;
mod vertex;

use glray_gl::{
    GL_COLOR_BUFFER_BIT, GL_CURRENT_BIT, GL_DEPTH_BUFFER_BIT, GL_DRAW_FRAMEBUFFER, GL_FRAMEBUFFER, GL_TEXTURE_2D,
};
use std::collections::HashMap;
use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3, DVec4, Vec4};
use glray_core::trace::{ArrayData, Value};
use glray_scene::camera::Viewport;
use glray_scene::frame::{DepthClear, Frame, MaskedClear, ScissoredClear};
use glray_scene::texture::{Level, Texture};

use crate::args;
use crate::error::{ErrorFlag, GlError, GlResult};
use crate::ops::{Concern, Op};
use crate::texture::{self, Unpack};
use arrays::{BufferDraw, Client};
use client_draws::ClientDraws;
use immediate::{Current, Immediate};
use lighting::LightingState;
use lists::{DisplayLists, Item};
use matrices::Matrices;
use mesh_builder::{Compiled, MeshBuilder};
use raster::Raster;
use texturing::TextureUnit;

/// A vertex after the vertex stage: eye position, lit colours of both faces, texture
/// coordinates.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EyeVertex {
    pub(crate) eye: DVec4,
    pub(crate) colors: [DVec4; 2],
    pub(crate) secondary: [DVec4; 2],
    pub(crate) tex: DVec4,
    /// Eye-space normal as lighting used it, and the current colour.
    pub(crate) normal: DVec3,
    pub(crate) base: DVec4,
}

/// A vertex as an array draw fetched it, before the vertex stage (what a list keeps of a
/// draw, so that buffers and client memory changed later do not change the list).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Fetched {
    pub(crate) position: Option<DVec4>,
    pub(crate) normal: Option<DVec3>,
    pub(crate) color: Option<DVec4>,
    pub(crate) tex: Option<DVec4>,
}

/// What the contexts of a share group share (glXCreateContext's shareList, eglCreateContext's
/// share_context, OSMesa's sharelist): display lists, textures and buffer objects.
#[derive(Default)]
pub struct Shared {
    pub(crate) lists: DisplayLists<Item>,
    pub(crate) buffers: HashMap<u32, Vec<u8>>,
    /// Meshes of array draws that read buffer objects only, while the buffers are unchanged.
    pub(crate) buffer_draws: HashMap<BufferDraw, Arc<Compiled>>,
    pub(crate) textures: HashMap<u32, Arc<Texture>>,
}

/// What glPushAttrib saves (glPopAttrib takes back the groups its mask names).
#[derive(Debug, Clone)]
pub(crate) struct PushedAttribs {
    lighting: LightingState,
    raster: Raster,
    texturing: TextureUnit,
    current: Current,
}

/// How deep glPushAttrib's stack goes (GL_MAX_ATTRIB_STACK_DEPTH, 16 in Mesa).
pub(crate) const MAX_ATTRIB_DEPTH: usize = 16;

/// One GL context's state, and the frame it is drawing.
pub struct Context {
    pub errors: ErrorFlag,
    /// Errors the real GL cannot raise: those of calls it did not get (geometry glray takes
    /// instead, `unseen`), and of calls inside a glBegin it did not get.
    pub(crate) unseen_error: ErrorFlag,
    /// The call being followed did not reach the real GL.
    pub unseen: bool,
    pub matrices: Matrices,
    pub(crate) imm: Immediate,
    /// Vertices of the open glBegin, after the vertex stage.
    pub(crate) open: Vec<EyeVertex>,
    /// Display lists, textures and buffers: shared with the context's share group.
    pub(crate) shared: Shared,
    pub(crate) nesting: usize,
    /// Lighting and materials.
    pub(crate) lighting: LightingState,
    /// Rasterization and per-fragment state.
    pub(crate) raster: Raster,
    /// Texture unit 0's bindings, environment and coordinate generation.
    pub(crate) texturing: TextureUnit,
    /// glPushAttrib's stack: the mask, and the state it saved.
    pub(crate) attrib_stack: Vec<(u32, PushedAttribs)>,
    pub(crate) client: Client,
    /// Client arrays of the next draw (the trace's arrays event that precedes it).
    pub(crate) arrays: Vec<ArrayData<'static>>,
    pub(crate) array_bytes: Vec<Vec<u8>>,
    /// Each big array's `content_hash`, of the bytes in `array_bytes` (None for a small one:
    /// hashed only if a draw's key needs it).
    pub(crate) array_hashes: Vec<Option<[i64; 2]>>,
    /// Meshes of big draws from client memory, kept by what they read.
    pub(crate) client_draws: ClientDraws,
    pub(crate) frame: Frame,
    pub(crate) sequence: u32,
    pub(crate) normal_matrix: Option<(DMat4, DMat3)>,
    /// A shader program is in use: draws go to the program layer (`program_draws`).
    pub(crate) programmable: bool,
    /// Programs, vertex arrays and texture units (the program layer's state).
    pub programs: crate::programs::Programs,
    /// The return value of the call being followed (a program's name, a location).
    pub returned: Option<i64>,
    /// Draws left to the real GL since the context was made (`Frame::passed_draws` counts a
    /// frame's, up to its clear): the statistics report them.
    pub passed_total: u64,
    /// The viewport of the last glClear of the colour buffer: where program draws make the
    /// frame's 3D scene (`program_draws`).
    pub(crate) cleared_viewport: Option<Viewport>,
    /// The context is a core profile: it has no fixed-function commands (GL raises
    /// INVALID_OPERATION for glBegin, glCallList... and draws nothing) and every draw goes through
    /// shaders: capture follows only what core GL has (`follows_in_core`).
    pub core_profile: bool,
    /// Counts changes to the frame (draws, clears), so that a frame is presented once.
    pub(crate) revision: u64,
    /// The framebuffer object draws go to (0: the window's or OSMesa's buffer).
    pub(crate) framebuffer: u32,
    /// The glBegin/glEnd being compiled into a list, as a mesh.
    pub(crate) building: Option<MeshBuilder>,
    /// The watch over the open glBegin, and its recording as a mesh once it is taken from
    /// the vertex stage (`immediate_meshes`).
    pub(crate) recording: immediate_meshes::Recordings,
}

impl Default for Context {
    fn default() -> Self {
        Context {
            errors: ErrorFlag::default(),
            unseen_error: ErrorFlag::default(),
            unseen: false,
            matrices: Matrices::default(),
            imm: Immediate::default(),
            open: Vec::new(),
            shared: Shared::default(),
            nesting: 0,
            lighting: LightingState::default(),
            raster: Raster::default(),
            texturing: TextureUnit::default(),
            attrib_stack: Vec::new(),
            client: Client { unpack: Unpack::default(), ..Client::default() },
            arrays: Vec::new(),
            array_bytes: Vec::new(),
            array_hashes: Vec::new(),
            client_draws: ClientDraws::default(),
            frame: Frame { depth_range: (0.0, 1.0), ..Frame::default() },
            sequence: 0,
            normal_matrix: None,
            programmable: false,
            programs: Default::default(),
            returned: None,
            passed_total: 0,
            cleared_viewport: None,
            core_profile: false,
            revision: 0,
            framebuffer: 0,
            building: None,
            recording: Default::default(),
        }
    }
}

pub(crate) fn vec4(v: DVec4) -> Vec4 {
    v.as_vec4()
}

/// Whether capture follows `op` in a core-profile context: what core GL has (programs, buffers,
/// textures, rasterization and per-fragment state, clears, framebuffers, draws); not the
/// fixed-function commands, which core GL refuses.
fn follows_in_core(op: Op) -> bool {
    match op.concern() {
        Concern::Programs | Concern::Raster | Concern::Context => true,
        Concern::Immediate | Concern::Lighting | Concern::Lists => false,
        Concern::Matrices => op == Op::ActiveTexture,
        Concern::Texturing => !matches!(op, Op::TexEnv | Op::TexGen),
        Concern::Arrays => !matches!(
            op,
            Op::ClientActiveTexture
                | Op::EnableClientState
                | Op::DisableClientState
                | Op::VertexPointer
                | Op::NormalPointer
                | Op::ColorPointer
                | Op::TexCoordPointer
                | Op::InterleavedArrays
                | Op::ArrayElement
        ),
    }
}

impl Context {
    /// The drawable size, when the trace or the library knows it.
    /// Whether the scissor test keeps a clear from part of the drawable.
    fn scissored(&self) -> bool {
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        match (self.raster.scissor_test, self.raster.scissor) {
            (true, Some(b)) => {
                let (x, y) = (b.x as i64, b.y as i64);
                x > 0 || y > 0 || (x + b.width as i64) < w || (y + b.height as i64) < h
            }
            _ => false,
        }
    }

    pub fn set_drawable(&mut self, width: u32, height: u32) {
        self.frame.width = width;
        self.frame.height = height;
        if self.raster.viewport.width == 0 && self.raster.viewport.height == 0 {
            // GL sets the viewport to the drawable at the first MakeCurrent.
            self.raster.viewport = Viewport { x: 0, y: 0, width: width as i32, height: height as i32 };
        }
    }

    /// Client arrays the next draw reads (a trace's arrays event).
    pub fn set_arrays(&mut self, arrays: &[ArrayData]) {
        // Arrays from this size on are hashed before they are copied (see below); smaller ones
        // (a glArrayElement's one element, a small draw's) are copied as they are.
        const HASHED_FROM: usize = 1 << 16;
        self.array_bytes.resize_with(arrays.len(), Vec::new);
        self.array_hashes.resize(arrays.len(), None);
        for ((kept, hash), a) in self.array_bytes.iter_mut().zip(&mut self.array_hashes).zip(arrays) {
            // A program drawing from client memory hands over the same arrays frame after
            // frame: hashed where they are (as the draw's key needs anyway), the same bytes as
            // the last draw's are not copied again (10M triangles' positions and normals were
            // 120 MB copied every frame).
            let h = (a.bytes.len() >= HASHED_FROM).then(|| glray_core::hash::content_hash(a.bytes));
            if h.is_some() && h == *hash && kept.len() == a.bytes.len() {
                continue;
            }
            // Into the last draw's allocations: fresh ones were a page fault every 4 KiB of a
            // big draw's arrays, every frame. One much bigger than needed is let go.
            if kept.capacity() > (16 << 20).max(4 * a.bytes.len()) {
                *kept = Vec::new();
            }
            kept.clear();
            kept.extend_from_slice(a.bytes);
            *hash = h;
        }
        self.arrays = arrays.iter().map(|a| ArrayData { bytes: &[], ..a.clone() }).collect();
    }

    /// The frame drawn since the last one was taken; the context starts a new one.
    pub fn take_frame(&mut self) -> Frame {
        let next = Frame {
            width: self.frame.width,
            height: self.frame.height,
            clear_color: self.frame.clear_color,
            depth_range: self.raster.depth_range,
            // Room for as many triangles as this frame drew: grown by doubling, a program's
            // million immediate-mode triangles were copied over and over every frame.
            triangles: Vec::with_capacity(self.frame.triangles.len()),
            ..Frame::default()
        };
        self.sequence = 0;
        self.client_draws.frame_ended();
        std::mem::replace(&mut self.frame, next)
    }

    /// Hands the share group's objects over (to the group's context that runs next).
    pub fn take_shared(&mut self) -> Shared {
        std::mem::take(&mut self.shared)
    }

    /// Receives the share group's objects.
    pub fn put_shared(&mut self, shared: Shared) {
        self.shared = shared;
    }

    /// The first error since the last call that the real GL could not raise (0: none).
    pub fn take_unseen_error(&mut self) -> u32 {
        self.unseen_error.take()
    }

    /// Records a command's outcome in the error flag (and, for a call the real GL did not get,
    /// in the flag glGetError adds to the real one).
    pub(crate) fn raise(&mut self, r: GlResult) {
        if self.unseen {
            self.unseen_error.record(r);
        }
        self.errors.record(r);
    }

    /// Changes whenever the frame does.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Whether a draw now would be taken by capture alone, so that the real GL need not
    /// rasterize it: fixed-function, not being compiled into a list (the real list must keep
    /// its geometry), and into the default framebuffer (a framebuffer object may be a texture
    /// the program draws with later, which capture does not follow); or a draw a profile
    /// recognises as the frame's 3D scene (VTK's, into its render target, which the picture is
    /// put into whole: colour and depth).
    pub fn takes_draws(&self) -> bool {
        if self.programmable {
            return self.shared.lists.compiling().is_none()
                && self.recognised_draw().is_some_and(|d| !Self::declined(&d));
        }
        !self.core_profile && self.shared.lists.compiling().is_none() && self.framebuffer == 0
    }

    /// Whether draws go to a framebuffer object (not the window's or OSMesa's buffer).
    pub fn draws_offscreen(&self) -> bool {
        self.framebuffer != 0
    }

    /// Whether a display list is being compiled.
    pub fn compiling(&self) -> bool {
        self.shared.lists.compiling().is_some()
    }

    /// The frame so far.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Follows one call. Errors go to the context's error flag, as GL would raise them.
    pub fn call(&mut self, op: Op, ty: u32, a: &[Value]) {
        if self.core_profile && !follows_in_core(op) {
            return;
        }
        if let Some((_, execute)) = self.shared.lists.compiling() {
            if op.compiled() && !matches!(op, Op::NewList | Op::EndList) {
                for item in self.compile_items(op, ty, a) {
                    self.shared.lists.compile(item);
                }
                if !execute {
                    self.arrays.clear();
                    return;
                }
            }
        }
        let r = self.execute(op, ty, a);
        self.raise(r);
    }

    /// Follows one command: the part of the context it concerns (gl-spec/capture.txt's
    /// `[concern]`) follows it. GL refuses most commands between glBegin and glEnd.
    fn execute(&mut self, op: Op, ty: u32, a: &[Value]) -> GlResult {
        // Commands allowed between glBegin and glEnd (GL 2.1 section 2.6.3; gl-spec/classes.txt).
        if !op.inside_begin() && self.imm.inside() {
            self.unseen_error.record::<()>(Err(GlError::InvalidOperation));
            return Err(GlError::InvalidOperation);
        }
        if matches!(op, Op::Material | Op::CallList | Op::CallLists) && self.recording.is_open() {
            // Inside a glBegin recorded as a mesh: a call the mesh cannot keep.
            self.stop_recording();
        }
        let modelview = *self.matrices.modelview.top();
        self.programs.observe(op, a);
        match op.concern() {
            Concern::Immediate => self.immediate_command(op, ty, a),
            Concern::Matrices => self.matrices.command(op, ty, a),
            Concern::Lighting => self.lighting.command(op, ty, a, &modelview),
            Concern::Raster => self.raster.command(op, ty, a, &modelview),
            Concern::Texturing => {
                self.texturing.command(&mut self.shared.textures, op, ty, a, &self.client.unpack, &modelview)
            }
            Concern::Lists => self.list_command(op, a),
            Concern::Arrays => self.array_command(op, a),
            Concern::Context => self.context_command(op, a),
            Concern::Programs if op == Op::UnfollowedDraw => {
                // The real GL draws it amid the scene, where the ray-traced picture would cover
                // it: the frame is left to the real GL (and the program told why, once).
                self.revision += 1;
                self.frame.unsupported_draws += 1;
                Ok(())
            }
            Concern::Programs => {
                let returned = self.returned.take();
                self.programs.command(op, ty, a, returned, self.client.array_buffer)
            }
        }
    }

    /// Follows a command of the context itself (`Concern::Context`): enables (each part takes
    /// its own), clears, the attribute stack, programs and framebuffers.
    fn context_command(&mut self, op: Op, a: &[Value]) -> GlResult {
        match op {
            Op::Enable | Op::Disable => self.set_cap(args::uint(a, 0), op == Op::Enable),
            Op::Clear => {
                let (color, depth) =
                    (args::uint(a, 0) & GL_COLOR_BUFFER_BIT != 0, args::uint(a, 0) & GL_DEPTH_BUFFER_BIT != 0);
                // With every colour channel masked, glClear leaves the colour buffer alone. With
                // red, green or blue masked, it sets the others and keeps what was drawn (in
                // drawing order, as a draw would). With alpha alone masked it counts as a clear
                // of the whole buffer: the picture starts afresh (its alpha is the clear's).
                let mask = self.raster.color_mask;
                let keeps = color && mask.contains(&true) && mask[..3].contains(&false);
                if keeps && !self.scissored() {
                    self.revision += 1;
                    let clear = MaskedClear { before: self.sequence, color: self.raster.clear_color, mask };
                    self.frame.masked_clears.push(clear);
                }
                let color = color && !keeps && mask.contains(&true);
                // A clear of the depth buffer alone changes the picture only through the draws
                // after it (which count themselves): the frame put in before it (VTK's scene,
                // before its orientation axes) is not traced again for it.
                if color || self.frame.is_empty() {
                    self.revision += 1;
                }
                if let Some(rect) = self.raster.scissor.filter(|_| self.scissored()) {
                    // One view of several clearing its own part of the window: what was drawn
                    // elsewhere stays, and the box is filled before the frame is traced.
                    if color || depth {
                        let color = color.then_some(self.raster.clear_color);
                        let depth = depth.then_some(self.raster.clear_depth);
                        self.frame.scissored_clears.push(ScissoredClear { rect, color, depth });
                    }
                    return Ok(());
                }
                if depth {
                    let drawn = !self.frame.triangles.is_empty() || !self.frame.instances.is_empty();
                    let cleared = DepthClear { before: self.sequence, depth: self.raster.clear_depth };
                    if color || !drawn {
                        self.frame.depth_cleared = Some(cleared.depth);
                    } else if let Some(last) = self.frame.depth_clears.last_mut().filter(|c| c.before == self.sequence)
                    {
                        // Two clears with no draw between them: the last one's depth stands.
                        *last = cleared;
                    } else {
                        // Between draws: the ones after it land over the ones before.
                        self.frame.depth_clears.push(cleared);
                    }
                }
                if color {
                    // What was drawn before is covered: the frame starts again.
                    self.frame.unsupported_draws = 0;
                    self.frame.passed_draws = 0;
                    self.frame.triangles.clear();
                    self.frame.instances.clear();
                    self.frame.solids.clear();
                    self.frame.surfaces.clear();
                    self.frame.lightings.clear();
                    self.frame.projection = None;
                    self.frame.viewport = None;
                    self.frame.cameras.clear();
                    self.frame.scissored_clears.clear();
                    self.frame.depth_clears.clear();
                    self.frame.masked_clears.clear();
                    self.frame.clear_color = self.raster.clear_color;
                    self.frame.cleared = true;
                    // Draws are numbered from the frame's start: a program that never swaps
                    // (pvbatch) draws the same frame with the same numbers again, which
                    // progressive refinement must see as the same frame.
                    self.sequence = 0;
                    self.cleared_viewport = Some(self.raster.viewport);
                }
            }
            Op::PushAttrib => {
                if self.attrib_stack.len() >= MAX_ATTRIB_DEPTH {
                    return Err(GlError::StackOverflow);
                }
                let saved = PushedAttribs {
                    lighting: self.lighting.clone(),
                    raster: self.raster.clone(),
                    texturing: self.texturing.clone(),
                    current: self.imm.current,
                };
                self.attrib_stack.push((args::uint(a, 0), saved));
            }
            Op::PopAttrib => {
                let (mask, saved) = self.attrib_stack.pop().ok_or(GlError::StackUnderflow)?;
                self.lighting.restore(mask, &saved.lighting);
                self.raster.restore(mask, &saved.raster);
                self.texturing.restore(mask, &saved.texturing);
                if mask & GL_CURRENT_BIT != 0 {
                    self.imm.current = saved.current;
                }
            }
            Op::GetError => {
                // The real GL answered; capture's own errors are checked by its tests.
            }
            Op::UseProgram => self.programmable = args::uint(a, 0) != 0,
            Op::BindFramebuffer => {
                // GL_FRAMEBUFFER or GL_DRAW_FRAMEBUFFER: where draws go.
                if matches!(args::uint(a, 0), GL_FRAMEBUFFER | GL_DRAW_FRAMEBUFFER) {
                    self.framebuffer = args::uint(a, 1);
                }
            }
            _ => unreachable!("{op:?} is not a context command"),
        }
        Ok(())
    }

    /// glEnable/glDisable: the part of the context whose capability it is takes it.
    fn set_cap(&mut self, cap: u32, on: bool) {
        let _ = self.lighting.set_cap(cap, on) || self.raster.set_cap(cap, on) || self.texturing.set_cap(cap, on);
    }

    /// Level `level` of the bound 2D texture as the real GL holds it after a copy from the
    /// framebuffer (glCopyTexImage2D, glCopyTexSubImage2D): `texels` as glGetTexImage gives
    /// them in RGBA, `internal` the level's internal format. Capture cannot see what a copy
    /// took, so the live layer reads the level back and hands it here.
    pub fn copied_texture(&mut self, level: usize, internal: u32, width: usize, height: usize, texels: Vec<Vec4>) {
        if level >= 16 || texels.len() != width * height {
            return;
        }
        let base = texture::base_format(internal);
        let texels = texels.into_iter().map(|c| texture::to_base(c, base)).collect();
        let t = self.texturing.texture_to_replace(&mut self.shared.textures, GL_TEXTURE_2D, level);
        if level == 0 {
            t.base_format = base;
        }
        t.levels[level] = Level { width, height, texels };
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::ops::op_for;
    use glam::Vec3;
    use glray_gl::*;

    use glray_gl::GL_TEXTURE;
    use glray_scene::facing::Face;

    /// Calls a command by name with scalar arguments (floats as F64, the rest as Int).
    pub(crate) fn call(c: &mut Context, name: &str, args: &[Value]) {
        let (op, ty) = op_for(name).unwrap_or_else(|| panic!("{name} is not followed"));
        c.call(op, ty, args);
    }

    pub(crate) fn i(v: i64) -> Value<'static> {
        Value::Int(v)
    }

    pub(crate) fn f(v: f64) -> Value<'static> {
        Value::F64(v)
    }

    pub(crate) fn context() -> Context {
        let mut c = Context::default();
        c.set_drawable(100, 100);
        call(&mut c, "glMatrixMode", &[i(0x1701)]);
        call(&mut c, "glOrtho", &[f(-1.0), f(1.0), f(-1.0), f(1.0), f(-1.0), f(1.0)]);
        call(&mut c, "glMatrixMode", &[i(0x1700)]);
        c
    }

    pub(crate) fn triangle(c: &mut Context, ccw: bool) {
        call(c, "glBegin", &[i(4)]);
        let pts = if ccw { [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] } else { [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)] };
        for (x, y) in pts {
            call(c, "glVertex2f", &[f(x), f(y)]);
        }
        call(c, "glEnd", &[]);
    }

    #[test]
    pub(crate) fn commands_inside_begin_end_raise_invalid_operation() {
        let mut c = context();
        call(&mut c, "glBegin", &[i(4)]);
        call(&mut c, "glMatrixMode", &[i(0x1700)]);
        call(&mut c, "glColor3f", &[f(1.0), f(0.0), f(0.0)]); // allowed
        call(&mut c, "glEnd", &[]);
        assert_eq!(c.errors.take(), 0x0502);
        assert_eq!(c.take_unseen_error(), 0x0502, "kept apart for glGetError");
        assert_eq!(c.take_unseen_error(), 0);
        call(&mut c, "glEnd", &[]);
        assert_eq!(c.errors.take(), 0x0502, "glEnd without glBegin");
        call(&mut c, "glBegin", &[i(10)]);
        assert_eq!(c.errors.take(), 0x0500, "a mode that is not a primitive");
        call(&mut c, "glShadeModel", &[i(0)]);
        assert_eq!(c.errors.take(), 0x0500);
        call(&mut c, "glLineWidth", &[f(0.0)]);
        assert_eq!(c.errors.take(), 0x0501);
    }

    #[test]
    pub(crate) fn attribute_stack_overflows_and_restores_by_mask() {
        let mut c = context();
        call(&mut c, "glPopAttrib", &[]);
        assert_eq!(c.errors.take(), 0x0504);
        call(&mut c, "glPushAttrib", &[i(GL_ENABLE_BIT as i64)]);
        call(&mut c, "glEnable", &[i(GL_CULL_FACE as i64)]);
        call(&mut c, "glCullFace", &[i(GL_FRONT as i64)]);
        call(&mut c, "glPopAttrib", &[]);
        assert!(!c.raster.cull, "GL_ENABLE_BIT restores the enable");
        assert_eq!(c.raster.cull_face, Face::Front, "but not the face, which GL_POLYGON_BIT saves");
        for _ in 0..MAX_ATTRIB_DEPTH {
            call(&mut c, "glPushAttrib", &[i(0xFFFFF)]);
        }
        assert_eq!(c.errors.take(), 0);
        call(&mut c, "glPushAttrib", &[i(0xFFFFF)]);
        assert_eq!(c.errors.take(), 0x0503);
    }

    /// The state a list mesh's instance and the same draw made at once are compared under:
    /// lighting with colour material, two sides, rescaled normals, a texture matrix.
    pub(crate) fn lit_scene(c: &mut Context) {
        for cap in [GL_LIGHTING, GL_LIGHT0, GL_COLOR_MATERIAL, GL_RESCALE_NORMAL] {
            call(c, "glEnable", &[i(cap as i64)]);
        }
        call(c, "glLightModeli", &[i(GL_LIGHT_MODEL_TWO_SIDE as i64), i(1)]);
        call(c, "glLightfv", &[i(GL_LIGHT0 as i64), i(0x1203), Value::Blob(&f32s(&[0.3, 0.4, 1.0, 0.0]))]);
        call(c, "glMatrixMode", &[i(GL_TEXTURE as i64)]); // GL_TEXTURE
        call(c, "glScalef", &[f(2.0), f(1.0), f(1.0)]);
        call(c, "glMatrixMode", &[i(0x1700)]);
        call(c, "glRotatef", &[f(30.0), f(1.0), f(1.0), f(0.0)]);
        call(c, "glScalef", &[f(0.5), f(0.5), f(0.5)]);
    }

    /// A client array of 2D float positions, as the trace's arrays event gives it.
    pub(crate) fn positions_2d(floats: &[u8]) -> ArrayData<'_> {
        ArrayData { kind: 0, index: 0, size: 2, gl_type: 0x1406, stride: 0, normalized: false, first: 0, bytes: floats }
    }

    pub(crate) fn f32s(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_ne_bytes()).collect()
    }

    /// A strip with a colour and normal given part-way, after a colour current at the call.
    pub(crate) fn strip(c: &mut Context) {
        call(c, "glBegin", &[i(5)]); // GL_TRIANGLE_STRIP
        for (k, (x, y)) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].into_iter().enumerate() {
            if k == 1 {
                call(c, "glNormal3f", &[f(0.0), f(0.6), f(0.8)]);
                call(c, "glTexCoord2f", &[f(0.25), f(0.5)]);
            }
            if k == 2 {
                call(c, "glColor3f", &[f(0.0), f(1.0), f(0.0)]);
            }
            call(c, "glVertex3f", &[f(x), f(y), f(0.25)]);
        }
        call(c, "glEnd", &[]);
    }

    /// Whether an instance's triangle is kept by GL's own rule: its window winding.
    pub(crate) fn on_window(inst: &glray_scene::instance::Instance, k: usize) -> bool {
        let clip = inst.mesh.triangles[k].map(|v| inst.object_to_clip * inst.mesh.position(v));
        let front = glray_scene::facing::window_facing(clip, inst.front_ccw).unwrap_or(true);
        !glray_scene::facing::culled(inst.cull, front)
    }

    pub(crate) fn t_positions(floats: &[u8], idx: [usize; 3]) -> [Vec3; 3] {
        let f = |k: usize| f32::from_ne_bytes(floats[4 * k..4 * k + 4].try_into().unwrap());
        idx.map(|i| Vec3::new(f(2 * i), f(2 * i + 1), 0.0))
    }

    /// glTexImage2D into the bound 2D texture: a `size` x `size` image of `texel` (four bytes,
    /// given as `format`: GL_RGBA is 0x1908).
    pub(crate) fn tex_image(c: &mut Context, level: i64, size: i64, format: i64, texel: [u8; 4]) {
        let pixels = texel.repeat((size * size) as usize);
        let args = [i(GL_TEXTURE_2D as i64), i(level), i(0x1908), i(size), i(size), i(0), i(format), i(0x1401)];
        call(c, "glTexImage2D", &[&args[..], &[Value::Blob(&pixels)]].concat());
    }

    #[test]
    fn depth_clears_take_gl_clear_depths_value_through_the_attribute_stack() {
        let mut c = context();
        let depth = || [i(GL_DEPTH_BUFFER_BIT as i64)];
        call(&mut c, "glClearDepth", &[f(0.25)]);
        call(&mut c, "glPushAttrib", &depth());
        call(&mut c, "glClearDepthf", &[f(2.0)]);
        call(&mut c, "glClear", &depth());
        assert_eq!(c.frame().depth_cleared, Some(1.0), "clamped to [0, 1]");
        call(&mut c, "glPopAttrib", &[]);
        call(&mut c, "glClear", &depth());
        assert_eq!(c.frame().depth_cleared, Some(0.25), "the value before glPushAttrib");
        // Between draws: a clear each, two with no draw between them one (the last value).
        triangle(&mut c, true);
        call(&mut c, "glClearDepth", &[f(0.5)]);
        call(&mut c, "glClear", &depth());
        triangle(&mut c, true);
        call(&mut c, "glClear", &depth());
        call(&mut c, "glClearDepth", &[f(0.75)]);
        call(&mut c, "glClear", &depth());
        let clears: Vec<_> = c.frame().depth_clears.iter().map(|c| c.depth).collect();
        assert_eq!(clears, [0.5, 0.75]);
        assert_eq!(c.frame().depth_cleared, Some(0.25), "the frame still starts at the first");
    }

    #[test]
    pub(crate) fn a_color_clear_starts_the_frame_again() {
        let mut c = context();
        triangle(&mut c, true);
        call(&mut c, "glClearColor", &[f(0.5), f(0.25), f(0.0), f(1.0)]);
        call(&mut c, "glClear", &[i(GL_COLOR_BUFFER_BIT as i64)]);
        assert!(c.frame().triangles.is_empty() && c.frame().cleared);
        assert_eq!(c.frame().clear_color, Vec4::new(0.5, 0.25, 0.0, 1.0));
        call(&mut c, "glUseProgram", &[i(3)]);
        triangle(&mut c, true);
        assert_eq!(c.frame().unsupported_draws, 1, "shaders are not followed");
    }
}
