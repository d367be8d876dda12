//! The per-context GL state machine: follows the calls of one GL context (matrices, immediate
//! mode, client arrays and buffers, display lists, lighting, textures, fog, attribute stacks)
//! and turns what it draws into a `Frame` of lit, eye-space triangles. Commands arrive as
//! recorded calls (an `Op` and its `Value`s), the same from a trace file as from the live
//! library, so the two paths cannot drift apart.

use glray_gl::{
    GL_ALPHA_TEST, GL_AMBIENT, GL_AMBIENT_AND_DIFFUSE, GL_ARRAY_BUFFER, GL_BACK, GL_BLEND, GL_CCW, GL_CLIP_PLANE0,
    GL_COLOR_ARRAY, GL_COLOR_BUFFER_BIT, GL_COLOR_INDEXES, GL_COLOR_LOGIC_OP, GL_COLOR_MATERIAL,
    GL_CONSTANT_ATTENUATION, GL_CULL_FACE, GL_CURRENT_BIT, GL_CW, GL_DEPTH_BUFFER_BIT, GL_DEPTH_TEST, GL_DIFFUSE,
    GL_DOUBLE, GL_DRAW_FRAMEBUFFER, GL_ELEMENT_ARRAY_BUFFER, GL_EMISSION, GL_EYE_PLANE, GL_FILL, GL_FLAT, GL_FLOAT,
    GL_FOG, GL_FOG_COLOR, GL_FOG_DENSITY, GL_FOG_END, GL_FOG_MODE, GL_FOG_START, GL_FRAMEBUFFER, GL_FRONT,
    GL_FRONT_AND_BACK, GL_INT, GL_LIGHT0, GL_LIGHTING, GL_LIGHT_MODEL_AMBIENT, GL_LIGHT_MODEL_COLOR_CONTROL,
    GL_LIGHT_MODEL_LOCAL_VIEWER, GL_LIGHT_MODEL_TWO_SIDE, GL_LINE, GL_LINEAR_ATTENUATION, GL_LINE_SMOOTH, GL_NORMALIZE,
    GL_NORMAL_ARRAY, GL_OBJECT_PLANE, GL_POINT, GL_POINT_SMOOTH, GL_POLYGON, GL_POLYGON_OFFSET_FILL, GL_POSITION,
    GL_QUADRATIC_ATTENUATION, GL_RESCALE_NORMAL, GL_S, GL_SCISSOR_TEST, GL_SEPARATE_SPECULAR_COLOR, GL_SHININESS,
    GL_SMOOTH, GL_SPECULAR, GL_SPOT_CUTOFF, GL_SPOT_DIRECTION, GL_SPOT_EXPONENT, GL_T, GL_TEXTURE0, GL_TEXTURE_1D,
    GL_TEXTURE_2D, GL_TEXTURE_COORD_ARRAY, GL_TEXTURE_ENV_COLOR, GL_TEXTURE_ENV_MODE, GL_TEXTURE_GEN_MODE,
    GL_TEXTURE_GEN_S, GL_TEXTURE_GEN_T, GL_TRIANGLES, GL_UNPACK_ALIGNMENT, GL_UNPACK_ROW_LENGTH, GL_UNPACK_SKIP_PIXELS,
    GL_UNPACK_SKIP_ROWS, GL_UNSIGNED_INT, GL_VERTEX_ARRAY,
};
use std::collections::HashMap;
use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3, DVec4, Vec4};
use glray_core::threads::copy_of;
use glray_core::trace::{ArrayData, Value};

use crate::args;
use crate::arrays::{quad_split, BufferDraw, Client};
use crate::client_draws::ClientDraws;
use crate::error::{ErrorFlag, GlError, GlResult};
use crate::immediate::{Immediate, TEXCOORD_UNITS};
use crate::lists::{DisplayLists, MAX_NESTING};
use crate::matrix::{from_gl, Matrices};
use crate::mesh_builder::{Compiled, MeshBuilder};
use crate::ops::{Attr, AttrForm, Op};
use crate::primitive::QuadSplit;
use crate::state::{State, MAX_ATTRIB_DEPTH};
use crate::texture::{self, Unpack};
use crate::vertex::{decode_attribute, Given};
use glray_scene::camera::Viewport;
use glray_scene::facing::Face;
use glray_scene::frame::{DepthClear, Frame, ScissoredClear};
use glray_scene::lighting::ColorMaterialMode;
use glray_scene::surface::{BlendFactor, CompareFunc, FogMode, LogicOp, TexEnvMode};
use glray_scene::texture::{Level, Texture};

/// A vertex after the vertex stage: eye position, lit colours of both faces, texture
/// coordinates.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Out {
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

/// How many buffer draws' meshes a share group keeps (a program that makes new draws every
/// frame must not grow it without end).
const MAX_BUFFER_DRAWS: usize = 256;

/// An array draw's fetched vertices as a mesh, its quads cut as `quads` says.
fn fetched_mesh(mode: u32, verts: &[Fetched], quads: QuadSplit) -> Compiled {
    let mut b = MeshBuilder::new(true, quads);
    b.begin(mode);
    for v in verts {
        b.give(v);
    }
    b.finish()
}

/// An argument kept by a display list.
#[derive(Debug, Clone)]
pub(crate) enum Kept {
    Int(i64),
    Float(f64),
    Bytes(Vec<u8>),
    Null,
}

/// What a display list holds.
#[derive(Debug, Clone)]
pub(crate) enum Item {
    Call(Op, u32, Vec<Kept>),
    /// A glBegin/glEnd, or an array draw resolved to its vertices at compile time.
    Mesh(Arc<Compiled>),
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
    pub(crate) open: Vec<Out>,
    /// Display lists, textures and buffers: shared with the context's share group.
    pub(crate) shared: Shared,
    pub(crate) nesting: usize,
    pub(crate) s: State,
    pub(crate) attrib_stack: Vec<(u32, State, crate::immediate::Current)>,
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
    /// A shader program is in use: draws go through shaders capture cannot follow.
    pub(crate) programmable: bool,
    /// The context is a core profile: it has no fixed-function commands (GL raises
    /// INVALID_OPERATION for glBegin, glCallList... and draws nothing) and every draw goes through
    /// shaders, so capture follows none of its calls and its frames stay the real GL's.
    pub core_profile: bool,
    /// Counts changes to the frame (draws, clears), so that a frame is presented once.
    pub(crate) revision: u64,
    /// The framebuffer object draws go to (0: the window's or OSMesa's buffer).
    pub(crate) framebuffer: u32,
    /// The glBegin/glEnd being compiled into a list, as a mesh.
    pub(crate) building: Option<MeshBuilder>,
    /// The watch over the open glBegin, and its recording as a mesh once it is taken from
    /// the vertex stage (`immediate_meshes`).
    pub(crate) recording: crate::immediate_meshes::Recordings,
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
            s: State::default(),
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

fn keep(v: &Value) -> Kept {
    match v {
        Value::Int(x) => Kept::Int(*x),
        Value::UInt(x) | Value::Opaque(x) | Value::Offset(x) => Kept::Int(*x as i64),
        Value::F32(x) => Kept::Float(*x as f64),
        Value::F64(x) => Kept::Float(*x),
        Value::Blob(b) | Value::Str(b) => Kept::Bytes(b.to_vec()),
        _ => Kept::Null,
    }
}

fn unkeep(k: &Kept) -> Value<'_> {
    match k {
        Kept::Int(x) => Value::Int(*x),
        Kept::Float(x) => Value::F64(*x),
        Kept::Bytes(b) => Value::Blob(b),
        Kept::Null => Value::Null,
    }
}

impl Context {
    /// The drawable size, when the trace or the library knows it.
    /// Whether the scissor test keeps a clear from part of the drawable.
    fn scissored(&self) -> bool {
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        match (self.s.scissor_test, self.s.scissor) {
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
        if self.s.viewport.width == 0 && self.s.viewport.height == 0 {
            // GL sets the viewport to the drawable at the first MakeCurrent.
            self.s.viewport = Viewport { x: 0, y: 0, width: width as i32, height: height as i32 };
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
            depth_range: self.s.depth_range,
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
    /// the program draws with later, which capture does not follow).
    pub fn takes_draws(&self) -> bool {
        !self.programmable && !self.core_profile && self.shared.lists.compiling().is_none() && self.framebuffer == 0
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
        if self.core_profile {
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

    /// What the open list keeps of a call. Consecutive glBegin/glEnd of vertex attributes, and
    /// attributes given between them, become one mesh (glMaterial or a nested glCallList inside
    /// a glBegin, which a mesh cannot keep, turn that glBegin back into calls); array draws
    /// become meshes of the vertices they fetch now.
    fn compile_items(&mut self, op: Op, ty: u32, a: &[Value]) -> Vec<Item> {
        let draw = matches!(
            op,
            Op::DrawArrays | Op::DrawElements | Op::DrawRangeElements | Op::MultiDrawArrays | Op::MultiDrawElements
        );
        let mut items = Vec::new();
        // glArrayElement's client data is copied at compile time: the element's values now.
        let element = (op == Op::ArrayElement && args::int(a, 0) >= 0).then(|| self.element(args::int(a, 0) as u64));
        let given = match op {
            Op::Attr(f) if self.building.is_some() => decode_attribute(f, a).ok(),
            _ => None,
        };
        if given.is_some_and(|g| self.compile_given(&g)) {
            return items;
        }
        if let Some(b) = self.building.as_mut() {
            let open = b.is_open();
            let kept = match op {
                Op::End if open => {
                    b.end();
                    true
                }
                Op::Begin if !open && args::uint(a, 0) <= GL_POLYGON => {
                    b.begin(args::uint(a, 0));
                    true
                }
                Op::ArrayElement if open && element.is_some() => {
                    b.give(&element.expect("fetched"));
                    true
                }
                _ => false,
            };
            if kept {
                return items;
            }
            items = self.spill();
            if open {
                // Inside glBegin, a call a mesh cannot keep: the glBegin stays calls.
                items.push(Item::Call(op, ty, a.iter().map(keep).collect()));
                return items;
            }
        }
        if draw {
            // Client data is copied at compile time: keep the vertices the draw would fetch.
            if let Some(mesh) = self.indexed_triangles(op, a) {
                items.push(Item::Mesh(Arc::new(mesh)));
                return items;
            }
            let runs = self.fetch_draw(op, a).unwrap_or_default();
            // Mesa compiles every list into indexed draws, glDrawArrays' quads too.
            let mesh = |(mode, verts): (u32, Vec<Fetched>)| fetched_mesh(mode, &verts, QuadSplit::Indexed);
            items.extend(runs.into_iter().map(|run| Item::Mesh(Arc::new(mesh(run)))));
            return items;
        }
        if op == Op::Begin && args::uint(a, 0) <= GL_POLYGON {
            let mut b = MeshBuilder::new(false, QuadSplit::Indexed);
            b.begin(args::uint(a, 0));
            self.building = Some(b);
            return items;
        }
        items.push(Item::Call(op, ty, a.iter().map(keep).collect()));
        items
    }

    /// What an attribute command gives, kept by the mesh the open list is making from its
    /// glBegin/glEnd runs, if it is making one and can keep it (all but another texture unit's
    /// coordinates and edge flags).
    pub(crate) fn compile_given(&mut self, given: &Given) -> bool {
        let Some(b) = self.building.as_mut() else { return false };
        match *given {
            Given::Normal(n) => b.normal(n),
            Given::Color(c) => b.color(c),
            Given::TexCoord(0, t) => b.texcoord(t),
            // (Outside glBegin a vertex does nothing: the builder ignores it.)
            Given::Vertex(p) => b.vertex(p),
            Given::SecondaryColor => {}
            Given::TexCoord(..) | Given::EdgeFlag(_) => return false,
        }
        true
    }

    /// Ends the mesh being compiled: its closed glBegin/glEnd as a mesh, an open one back as
    /// the calls that made it.
    fn spill(&mut self) -> Vec<Item> {
        let Some(b) = self.building.take() else { return Vec::new() };
        if !b.is_open() {
            return vec![Item::Mesh(Arc::new(b.finish()))];
        }
        let (closed, mode, given) = b.split_open();
        let attr = |attr, n| Op::Attr(AttrForm { attr, n, ty: GL_DOUBLE, vector: false });
        let call = |op, v: &[f64]| Item::Call(op, GL_DOUBLE, v.iter().map(|x| Kept::Float(*x)).collect());
        let mut items: Vec<Item> = closed.map(|m| Item::Mesh(Arc::new(m))).into_iter().collect();
        items.push(Item::Call(Op::Begin, GL_FLOAT, vec![Kept::Int(mode as i64)]));
        items.extend(given.into_iter().map(|g| match g {
            Given::Vertex(p) => call(attr(Attr::Vertex, 4), &p.to_array()),
            Given::Normal(n) => call(attr(Attr::Normal, 3), &n.to_array()),
            Given::Color(c) => call(attr(Attr::Color, 4), &c.to_array()),
            Given::TexCoord(_, t) => call(attr(Attr::TexCoord, 4), &t.to_array()),
            Given::SecondaryColor | Given::EdgeFlag(_) => unreachable!("a builder keeps neither"),
        }));
        items
    }

    /// The mesh of an array draw (one run: glDrawArrays, glDrawElements, glDrawRangeElements),
    /// for keeping; None when it draws nothing.
    fn array_mesh(&mut self, op: Op, a: &[Value]) -> GlResult<Option<Arc<Compiled>>> {
        if let Some(mesh) = self.indexed_triangles(op, a) {
            return Ok(Some(Arc::new(mesh)));
        }
        let runs = self.fetch_draw(op, a)?;
        Ok(runs.first().map(|(mode, verts)| Arc::new(fetched_mesh(*mode, verts, quad_split(op)))))
    }

    fn run_list(&mut self, list: u32) -> GlResult {
        if self.nesting >= MAX_NESTING {
            return Ok(()); // GL ignores calls nested deeper
        }
        let Some(items) = self.shared.lists.get(list) else { return Ok(()) };
        self.nesting += 1;
        for item in items.iter() {
            match item {
                Item::Call(op, ty, kept) => {
                    let a: Vec<Value> = kept.iter().map(unkeep).collect();
                    let r = self.execute(*op, *ty, &a);
                    self.raise(r);
                }
                Item::Mesh(mesh) => {
                    let r = self.run_mesh(mesh);
                    self.raise(r);
                }
            }
        }
        self.nesting -= 1;
        Ok(())
    }

    /// A list's mesh, called: an instance when the state allows, else its vertices through
    /// the vertex stage as the calls that made it would have gone. The attribute values it
    /// gave last stay current either way.
    pub(crate) fn run_mesh(&mut self, compiled: &Arc<Compiled>) -> GlResult {
        if self.imm.inside() && !compiled.from_arrays {
            // The list's glBegin, inside the caller's.
            self.unseen_error.record::<()>(Err(GlError::InvalidOperation));
            return Err(GlError::InvalidOperation);
        }
        let saved = self.imm.current;
        let mesh = &compiled.mesh;
        if self.instances(compiled) {
            self.instance(compiled);
        } else {
            let mut outs = Vec::with_capacity(mesh.positions.len());
            for i in 0..mesh.vertex_count() {
                let cur = &mut self.imm.current;
                if let Some(n) = mesh.normals.at(i) {
                    cur.normal = n.as_dvec3();
                }
                if let Some(c) = mesh.colors.at(i) {
                    cur.color = c.as_dvec4();
                }
                if let Some(t) = mesh.texcoords.at(i) {
                    cur.texcoords[0] = t.as_dvec4();
                }
                outs.push(self.vertex_stage(mesh.position(i)));
            }
            if compiled.runs.is_empty() {
                // An indexed mesh: its triangles.
                let corners: Vec<Out> = mesh.triangles.iter().flatten().map(|&i| outs[i as usize]).collect();
                self.draw(GL_TRIANGLES, &corners, compiled.quads);
            }
            for r in &compiled.runs {
                self.draw(r.mode, &outs[r.start as usize..(r.start + r.count) as usize], compiled.quads);
            }
        }
        // GL leaves the current values of enabled arrays undefined after a draw; Mesa keeps
        // the last one of a colour array only.
        let cur = &mut self.imm.current;
        *cur = saved;
        if !compiled.from_arrays || compiled.end_color.is_some() {
            cur.normal = compiled.end_normal.unwrap_or(cur.normal);
            cur.color = compiled.end_color.unwrap_or(cur.color);
            cur.texcoords[0] = compiled.end_texcoord.unwrap_or(cur.texcoords[0]);
        }
        Ok(())
    }

    fn floats(&self, a: &[Value], i: usize, ty: u32, n: usize) -> Vec<f64> {
        match a.get(i) {
            Some(Value::Blob(b)) => args::array(b, ty, n),
            Some(_) => vec![args::float(a, i)],
            None => Vec::new(),
        }
    }

    /// Colour parameters: integer forms map the integer range to [-1, 1].
    fn color_param(&self, a: &[Value], i: usize, ty: u32) -> DVec4 {
        let v = self.floats(a, i, ty, 4);
        let get = |k: usize| {
            let x = v.get(k).copied().unwrap_or(0.0);
            if ty == GL_INT {
                x / 2147483647.0
            } else {
                x
            }
        };
        DVec4::new(get(0), get(1), get(2), get(3))
    }

    fn matrix_arg(&self, a: &[Value], ty: u32) -> Option<DMat4> {
        let v = self.floats(a, 0, ty, 16);
        let m: [f64; 16] = v.try_into().ok()?;
        Some(from_gl(&m))
    }

    fn set_cap(&mut self, cap: u32, on: bool) {
        let s = &mut self.s;
        match cap {
            GL_LIGHTING => s.lighting = on,
            c if (GL_LIGHT0..GL_LIGHT0 + 8).contains(&c) => s.lights[(c - GL_LIGHT0) as usize].enabled = on,
            GL_COLOR_MATERIAL => s.color_material = on,
            GL_NORMALIZE => s.normalize = on,
            GL_RESCALE_NORMAL => s.rescale_normal = on,
            GL_CULL_FACE => s.cull = on,
            GL_POLYGON_OFFSET_FILL => s.polygon_offset_fill = on,
            GL_LINE_SMOOTH => s.line_smooth = on,
            GL_SCISSOR_TEST => s.scissor_test = on,
            GL_POINT_SMOOTH => s.point_smooth = on,
            GL_DEPTH_TEST => s.depth_test = on,
            GL_TEXTURE_2D => s.texture_2d = on,
            GL_TEXTURE_1D => s.texture_1d = on,
            GL_FOG => s.fog_enabled = on,
            GL_BLEND => s.blend = on,
            GL_COLOR_LOGIC_OP => s.logic_op_enabled = on,
            GL_ALPHA_TEST => s.alpha_test = on,
            GL_TEXTURE_GEN_S => s.texgen[0].enabled = on,
            GL_TEXTURE_GEN_T => s.texgen[1].enabled = on,
            c if (GL_CLIP_PLANE0..GL_CLIP_PLANE0 + 6).contains(&c) => {
                s.clip_planes[(c - GL_CLIP_PLANE0) as usize].0 = on
            }
            _ => {}
        }
    }

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
        match op {
            Op::Attr(form) => self.attribute(form, a)?,
            Op::Begin => {
                let mode = args::uint(a, 0);
                self.imm.begin(mode)?;
                self.record_begin(mode);
            }
            Op::End => {
                let mode = self.imm.end()?;
                if !self.end_recording(mode) {
                    self.draw_open(mode);
                }
            }
            Op::Rect => {
                let v = if a.len() == 2 {
                    let p = self.floats(a, 0, ty, 2);
                    let q = self.floats(a, 1, ty, 2);
                    [p.first(), p.get(1), q.first(), q.get(1)].map(|x| x.copied().unwrap_or(0.0))
                } else {
                    [0, 1, 2, 3].map(|i| args::float(a, i))
                };
                let corners = [(v[0], v[1]), (v[2], v[1]), (v[2], v[3]), (v[0], v[3])];
                let verts: Vec<Out> =
                    corners.iter().map(|&(x, y)| self.vertex_stage(DVec4::new(x, y, 0.0, 1.0))).collect();
                self.draw(GL_POLYGON, &verts, QuadSplit::Direct);
            }
            Op::MatrixMode => self.matrices.matrix_mode(args::uint(a, 0))?,
            Op::LoadIdentity => self.matrices.load_identity(),
            Op::LoadMatrix => {
                if let Some(m) = self.matrix_arg(a, ty) {
                    self.matrices.load(m)
                }
            }
            Op::MultMatrix => {
                if let Some(m) = self.matrix_arg(a, ty) {
                    self.matrices.mult(m)
                }
            }
            Op::LoadTransposeMatrix => {
                if let Some(m) = self.matrix_arg(a, ty) {
                    self.matrices.load_transpose(m)
                }
            }
            Op::MultTransposeMatrix => {
                if let Some(m) = self.matrix_arg(a, ty) {
                    self.matrices.mult_transpose(m)
                }
            }
            Op::Rotate => {
                self.matrices.rotate(args::float(a, 0), args::float(a, 1), args::float(a, 2), args::float(a, 3))
            }
            Op::Translate => self.matrices.translate(args::float(a, 0), args::float(a, 1), args::float(a, 2)),
            Op::Scale => self.matrices.scale(args::float(a, 0), args::float(a, 1), args::float(a, 2)),
            Op::Frustum | Op::Ortho => {
                let v: [f64; 6] = std::array::from_fn(|i| args::float(a, i));
                if op == Op::Frustum {
                    self.matrices.frustum(v[0], v[1], v[2], v[3], v[4], v[5])?
                } else {
                    self.matrices.ortho(v[0], v[1], v[2], v[3], v[4], v[5])?
                }
            }
            Op::PushMatrix => self.matrices.push()?,
            Op::PopMatrix => self.matrices.pop()?,
            Op::Viewport => {
                let (width, height) = (args::int(a, 2) as i32, args::int(a, 3) as i32);
                if width < 0 || height < 0 {
                    return Err(GlError::InvalidValue);
                }
                self.s.viewport = Viewport { x: args::int(a, 0) as i32, y: args::int(a, 1) as i32, width, height };
            }
            Op::DepthRange => {
                self.s.depth_range = (args::float(a, 0).clamp(0.0, 1.0), args::float(a, 1).clamp(0.0, 1.0))
            }
            Op::ActiveTexture => self.matrices.active_texture(args::uint(a, 0))?,
            Op::ClientActiveTexture => {
                let unit = args::uint(a, 0).wrapping_sub(GL_TEXTURE0) as usize;
                if unit >= TEXCOORD_UNITS {
                    return Err(GlError::InvalidEnum);
                }
                self.client.active_texcoord = unit;
            }
            Op::Enable | Op::Disable => self.set_cap(args::uint(a, 0), op == Op::Enable),
            Op::EnableClientState | Op::DisableClientState => {
                let on = op == Op::EnableClientState;
                match self.client_array(args::uint(a, 0)) {
                    Some(p) => p.enabled = on,
                    None => return Err(GlError::InvalidEnum),
                }
            }
            Op::Material => self.material(a, ty)?,
            Op::ColorMaterial => {
                let face = Face::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?;
                let mode = ColorMaterialMode::from_gl(args::uint(a, 1)).ok_or(GlError::InvalidEnum)?;
                self.s.color_material_face = face;
                self.s.color_material_mode = mode;
            }
            Op::Light => self.light(a, ty)?,
            Op::LightModel => {
                let pname = args::uint(a, 0);
                let v = self.floats(a, 1, ty, 4);
                let first = v.first().copied().unwrap_or(0.0);
                match pname {
                    GL_LIGHT_MODEL_AMBIENT => self.s.model.ambient = self.color_param(a, 1, ty),
                    GL_LIGHT_MODEL_LOCAL_VIEWER => self.s.model.local_viewer = first != 0.0,
                    GL_LIGHT_MODEL_TWO_SIDE => self.s.model.two_side = first != 0.0,
                    GL_LIGHT_MODEL_COLOR_CONTROL => {
                        self.s.model.separate_specular = first as u32 == GL_SEPARATE_SPECULAR_COLOR
                    }
                    _ => return Err(GlError::InvalidEnum),
                }
            }
            Op::ShadeModel => match args::uint(a, 0) {
                GL_FLAT => self.s.flat = true,
                GL_SMOOTH => self.s.flat = false,
                _ => return Err(GlError::InvalidEnum),
            },
            Op::FrontFace => match args::uint(a, 0) {
                GL_CCW => self.s.front_ccw = true,
                GL_CW => self.s.front_ccw = false,
                _ => return Err(GlError::InvalidEnum),
            },
            Op::CullFace => self.s.cull_face = Face::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?,
            Op::ClearColor => {
                self.s.clear_color =
                    Vec4::from_array(std::array::from_fn(|i| args::float(a, i) as f32)).clamp(Vec4::ZERO, Vec4::ONE)
            }
            Op::ClearDepth => self.s.clear_depth = (args::float(a, 0) as f32).clamp(0.0, 1.0),
            Op::Clear => {
                self.revision += 1;
                let (color, depth) =
                    (args::uint(a, 0) & GL_COLOR_BUFFER_BIT != 0, args::uint(a, 0) & GL_DEPTH_BUFFER_BIT != 0);
                // With every colour channel masked, glClear leaves the colour buffer alone.
                let color = color && self.s.color_mask.contains(&true);
                if let Some(rect) = self.s.scissor.filter(|_| self.scissored()) {
                    // One view of several clearing its own part of the window: what was drawn
                    // elsewhere stays, and the box is filled before the frame is traced.
                    if color || depth {
                        let color = color.then_some(self.s.clear_color);
                        let depth = depth.then_some(self.s.clear_depth);
                        self.frame.scissored_clears.push(ScissoredClear { rect, color, depth });
                    }
                    return Ok(());
                }
                if depth {
                    let drawn = !self.frame.triangles.is_empty() || !self.frame.instances.is_empty();
                    let cleared = DepthClear { before: self.sequence, depth: self.s.clear_depth };
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
                    self.frame.clear_color = self.s.clear_color;
                    self.frame.cleared = true;
                }
            }
            Op::NewList => self.shared.lists.new_list(args::uint(a, 0), args::uint(a, 1))?,
            Op::EndList => {
                // The mesh being compiled ends; a glBegin left open stays calls.
                for item in self.spill() {
                    self.shared.lists.compile(item);
                }
                self.shared.lists.end_list()?
            }
            Op::CallList => self.run_list(args::uint(a, 0))?,
            Op::CallLists => {
                let names =
                    self.shared.lists.call_lists_names(args::int(a, 0) as i32, args::uint(a, 1), args::bytes(a, 2))?;
                for n in names {
                    self.run_list(n)?;
                }
            }
            Op::ListBase => self.shared.lists.list_base(args::uint(a, 0)),
            Op::GenLists => {
                self.shared.lists.gen_lists(args::int(a, 0) as i32)?;
            }
            Op::DeleteLists => self.shared.lists.delete_lists(args::uint(a, 0), args::int(a, 1) as i32)?,
            Op::PushAttrib => {
                if self.attrib_stack.len() >= MAX_ATTRIB_DEPTH {
                    return Err(GlError::StackOverflow);
                }
                self.attrib_stack.push((args::uint(a, 0), self.s.clone(), self.imm.current));
            }
            Op::PopAttrib => {
                let (mask, saved, current) = self.attrib_stack.pop().ok_or(GlError::StackUnderflow)?;
                self.s.restore(mask, saved);
                if mask & GL_CURRENT_BIT != 0 {
                    self.imm.current = current;
                }
            }
            Op::VertexPointer => self.set_pointer(
                GL_VERTEX_ARRAY,
                args::int(a, 0) as i32,
                args::uint(a, 1),
                args::int(a, 2) as i32,
                a.get(3).unwrap_or(&Value::Null),
            ),
            Op::NormalPointer => self.set_pointer(
                GL_NORMAL_ARRAY,
                3,
                args::uint(a, 0),
                args::int(a, 1) as i32,
                a.get(2).unwrap_or(&Value::Null),
            ),
            Op::ColorPointer => self.set_pointer(
                GL_COLOR_ARRAY,
                args::int(a, 0) as i32,
                args::uint(a, 1),
                args::int(a, 2) as i32,
                a.get(3).unwrap_or(&Value::Null),
            ),
            Op::TexCoordPointer => self.set_pointer(
                GL_TEXTURE_COORD_ARRAY,
                args::int(a, 0) as i32,
                args::uint(a, 1),
                args::int(a, 2) as i32,
                a.get(3).unwrap_or(&Value::Null),
            ),
            Op::InterleavedArrays => {
                // The client memory arrives with each draw; only which arrays are on matters.
                self.client.vertex.enabled = true;
                self.client.vertex.buffer = 0;
            }
            Op::DrawArrays | Op::DrawElements | Op::DrawRangeElements | Op::MultiDrawArrays | Op::MultiDrawElements => {
                if let Some(key) = self.buffer_draw_key(op, a) {
                    // Buffer objects only: the mesh (and its BVH) lives as long as the buffers
                    // stay as they are.
                    let mesh = match self.shared.buffer_draws.get(&key) {
                        Some(m) => m.clone(),
                        None => {
                            let Some(mesh) = self.array_mesh(op, a)? else { return Ok(()) };
                            if self.shared.buffer_draws.len() >= MAX_BUFFER_DRAWS {
                                self.shared.buffer_draws.clear();
                            }
                            self.shared.buffer_draws.insert(key, mesh.clone());
                            mesh
                        }
                    };
                    return self.run_mesh(&mesh);
                }
                if let Some(key) = self.client_draw_key(op, a) {
                    // Client memory only, and big: the mesh is kept while the program draws
                    // the same bytes, frame after frame.
                    let mesh = match self.client_draws.get(&key) {
                        Some(mesh) => Ok(Some(mesh)),
                        None => self.array_mesh(op, a),
                    };
                    // The draw's client memory is read.
                    self.arrays.clear();
                    let Some(mesh) = mesh? else { return Ok(()) };
                    self.client_draws.insert(key, mesh.clone());
                    return self.run_mesh(&mesh);
                }
                for (mode, verts) in self.fetch_draw(op, a)? {
                    self.draw_fetched(mode, &verts, quad_split(op));
                }
            }
            Op::ArrayElement => self.array_element(args::int(a, 0)),
            Op::BindBuffer => match args::uint(a, 0) {
                GL_ARRAY_BUFFER => self.client.array_buffer = args::uint(a, 1),
                GL_ELEMENT_ARRAY_BUFFER => self.client.element_buffer = args::uint(a, 1),
                _ => {}
            },
            Op::BufferData => {
                if let Some(name) = self.bound_buffer(args::uint(a, 0)) {
                    let size = args::int(a, 1).max(0) as usize;
                    let mut data = copy_of(args::bytes(a, 2));
                    data.resize(size.min(1 << 31), 0);
                    self.shared.buffers.insert(name, data);
                    self.buffer_changed(name);
                }
            }
            Op::BufferSubData => {
                if let Some(name) = self.bound_buffer(args::uint(a, 0)) {
                    let offset = args::int(a, 1).max(0) as usize;
                    let data = args::bytes(a, 3);
                    let buf = self.shared.buffers.entry(name).or_default();
                    if let Some(dst) = buf.get_mut(offset..offset + data.len()) {
                        dst.copy_from_slice(data);
                    }
                    self.buffer_changed(name);
                }
            }
            Op::DeleteBuffers => {
                for name in args::array(args::bytes(a, 1), GL_UNSIGNED_INT, args::int(a, 0).max(0) as usize) {
                    self.shared.buffers.remove(&(name as u32));
                    self.buffer_changed(name as u32);
                }
            }
            Op::BindTexture => match args::uint(a, 0) {
                GL_TEXTURE_2D => self.s.bound_texture = args::uint(a, 1),
                GL_TEXTURE_1D => self.s.bound_texture_1d = args::uint(a, 1),
                _ => {}
            },
            Op::DeleteTextures => {
                for name in args::array(args::bytes(a, 1), GL_UNSIGNED_INT, args::int(a, 0).max(0) as usize) {
                    let name = name as u32;
                    self.shared.textures.remove(&name);
                    if self.s.bound_texture == name {
                        self.s.bound_texture = 0;
                    }
                    if self.s.bound_texture_1d == name {
                        self.s.bound_texture_1d = 0;
                    }
                }
            }
            Op::TexImage2D => self.tex_image(a, false)?,
            Op::TexSubImage2D => self.tex_image(a, true)?,
            Op::TexImage1D | Op::TexSubImage1D => {
                // A 1D texture is a 2D one of one row: the arguments a 2D call would have.
                let (i, u) = (|k: usize| Value::Int(args::int(a, k)), |k: usize| Value::Int(args::uint(a, k) as i64));
                let (target, level) = (Value::Int(GL_TEXTURE_1D as i64), i(1));
                let data = a.get(if op == Op::TexImage1D { 7 } else { 6 }).cloned().unwrap_or(Value::Null);
                let a2 = if op == Op::TexImage1D {
                    // (internal format, width, height 1, border, format, type, pixels)
                    vec![target, level, u(2), i(3), Value::Int(1), i(4), u(5), u(6), data]
                } else {
                    // (x, y 0, width, height 1, format, type, pixels)
                    vec![target, level, i(2), Value::Int(0), i(3), Value::Int(1), u(4), u(5), data]
                };
                self.tex_image(&a2, op == Op::TexSubImage1D)?
            }
            Op::TexParameter => {
                let target = args::uint(a, 0);
                if target == GL_TEXTURE_2D || target == GL_TEXTURE_1D {
                    let value = self.floats(a, 2, ty, 1).first().copied().unwrap_or(0.0);
                    // Only a value that changes touches the texture: a change is a new version
                    // to the renderer (no unchanged frame shown again), and a texture this frame
                    // has drawn with is copied to be changed, every level of it. Programs set
                    // the same parameters before every draw (VTK does).
                    let name = self.bound_texture_name(target);
                    let now = self.shared.textures.get(&name);
                    // The sampling state alone (every field but the levels is a number).
                    let mut set = match now {
                        Some(t) => Texture { levels: Vec::new(), ..**t },
                        None => Texture { version: 0, ..Texture::default() },
                    };
                    let before = Texture { levels: Vec::new(), ..set };
                    match texture::set_parameter(&mut set, args::uint(a, 1), value) {
                        Some(Err(e)) => return Err(e),
                        Some(Ok(())) if set != before => {
                            let t = self.texture_mut(target);
                            (t.min_filter, t.mag_filter, t.wrap_s, t.wrap_t, t.lod) =
                                (set.min_filter, set.mag_filter, set.wrap_s, set.wrap_t, set.lod);
                        }
                        _ => {}
                    }
                }
            }
            Op::TexEnv => match args::uint(a, 1) {
                GL_TEXTURE_ENV_MODE => {
                    let mode = self.floats(a, 2, ty, 1).first().copied().unwrap_or(0.0) as u32;
                    self.s.env_mode = TexEnvMode::from_gl(mode).ok_or(GlError::InvalidEnum)?
                }
                GL_TEXTURE_ENV_COLOR => self.s.env_color = vec4(self.color_param(a, 2, ty)),
                _ => {}
            },
            Op::TexGen => {
                let coord = match args::uint(a, 0) {
                    GL_S => 0,
                    GL_T => 1,
                    _ => return Ok(()), // r and q are not generated by glray yet
                };
                let v = self.floats(a, 2, ty, 4);
                match args::uint(a, 1) {
                    GL_TEXTURE_GEN_MODE => self.s.texgen[coord].mode = v.first().copied().unwrap_or(0.0) as u32,
                    GL_OBJECT_PLANE => {
                        if let Ok(p) = <[f64; 4]>::try_from(v) {
                            self.s.texgen[coord].object_plane = DVec4::from_array(p)
                        }
                    }
                    GL_EYE_PLANE => {
                        if let Ok(p) = <[f64; 4]>::try_from(v) {
                            // Eye planes are taken through the inverse modelview of the moment.
                            let mv = *self.matrices.modelview.top();
                            self.s.texgen[coord].eye_plane = mv.inverse().transpose() * DVec4::from_array(p);
                        }
                    }
                    _ => return Err(GlError::InvalidEnum),
                }
            }
            Op::PixelStore => {
                let v = args::float(a, 1).max(0.0) as usize;
                let u = &mut self.client.unpack;
                match args::uint(a, 0) {
                    GL_UNPACK_ALIGNMENT => u.alignment = v,
                    GL_UNPACK_ROW_LENGTH => u.row_length = v,
                    GL_UNPACK_SKIP_ROWS => u.skip_rows = v,
                    GL_UNPACK_SKIP_PIXELS => u.skip_pixels = v,
                    _ => {}
                }
            }
            Op::Fog => {
                let v = self.floats(a, 1, ty, 4);
                let first = v.first().copied().unwrap_or(0.0);
                let color = vec4(self.color_param(a, 1, ty));
                let f = &mut self.s.fog;
                match args::uint(a, 0) {
                    GL_FOG_MODE => f.mode = FogMode::from_gl(first as u32).ok_or(GlError::InvalidEnum)?,
                    GL_FOG_DENSITY => f.density = first as f32,
                    GL_FOG_START => f.start = first as f32,
                    GL_FOG_END => f.end = first as f32,
                    GL_FOG_COLOR => f.color = color,
                    _ => {}
                }
            }
            Op::BlendFunc => {
                let factor = |k| BlendFactor::from_gl(args::uint(a, k)).ok_or(GlError::InvalidEnum);
                self.s.blend_func = (factor(0)?, factor(1)?)
            }
            Op::AlphaFunc => {
                let func = CompareFunc::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?;
                self.s.alpha_func = (func, args::float(a, 1).clamp(0.0, 1.0) as f32)
            }
            Op::DepthFunc => self.s.depth_func = CompareFunc::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?,
            Op::DepthMask => self.s.depth_mask = args::int(a, 0) != 0,
            Op::ColorMask => self.s.color_mask = std::array::from_fn(|k| args::int(a, k) != 0),
            Op::LogicOp => self.s.logic_op = LogicOp::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?,
            Op::Scissor => {
                let (width, height) = (args::int(a, 2), args::int(a, 3));
                if width < 0 || height < 0 {
                    return Err(GlError::InvalidValue);
                }
                let (x, y) = (args::int(a, 0) as i32, args::int(a, 1) as i32);
                self.s.scissor = Some(Viewport { x, y, width: width as i32, height: height as i32 });
            }
            Op::PolygonOffset => {
                let (factor, units) = (args::float(a, 0), args::float(a, 1));
                self.s.polygon_offset = (factor as f32, units as f32);
            }
            Op::PolygonMode => {
                let mode = args::uint(a, 1);
                if !matches!(mode, GL_POINT | GL_LINE | GL_FILL) {
                    return Err(GlError::InvalidEnum);
                }
                match args::uint(a, 0) {
                    GL_FRONT => self.s.polygon_mode[0] = mode,
                    GL_BACK => self.s.polygon_mode[1] = mode,
                    GL_FRONT_AND_BACK => self.s.polygon_mode = [mode; 2],
                    _ => return Err(GlError::InvalidEnum),
                }
            }
            Op::LineWidth | Op::PointSize => {
                let v = args::float(a, 0);
                if v <= 0.0 {
                    return Err(GlError::InvalidValue);
                }
                if op == Op::LineWidth {
                    self.s.line_width = v
                } else {
                    self.s.point_size = v
                }
            }
            Op::ClipPlane => {
                let i = args::uint(a, 0).wrapping_sub(GL_CLIP_PLANE0) as usize;
                if i >= 6 {
                    return Err(GlError::InvalidEnum);
                }
                if let Ok(p) = <[f64; 4]>::try_from(self.floats(a, 1, GL_DOUBLE, 4)) {
                    let mv = *self.matrices.modelview.top();
                    self.s.clip_planes[i].1 = mv.inverse().transpose() * DVec4::from_array(p);
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
            Op::VertexAttribPointer => {}
        }
        Ok(())
    }

    /// The texture bound to `target` (GL_TEXTURE_2D or GL_TEXTURE_1D).
    fn bound_texture_name(&self, target: u32) -> u32 {
        if target == GL_TEXTURE_1D {
            self.s.bound_texture_1d
        } else {
            self.s.bound_texture
        }
    }

    /// The bound texture, to be changed: in place when nothing else holds it (a frame drawn
    /// with it, until the frame is taken or cleared), else a copy.
    fn texture_mut(&mut self, target: u32) -> &mut Texture {
        let name = self.bound_texture_name(target);
        let t = Arc::make_mut(self.shared.textures.entry(name).or_default());
        t.changed();
        t
    }

    /// The bound texture, its level `level` about to be replaced whole (a new image), with room
    /// for that level. A texture a frame still holds is copied, as `Arc::make_mut` would, but
    /// without the texels of the level being replaced: a program uploading a 2048x2048 image
    /// every frame had the old 64 MB copied only to be thrown away.
    fn texture_to_replace(&mut self, target: u32, level: usize) -> &mut Texture {
        let name = self.bound_texture_name(target);
        let t = self.shared.textures.entry(name).or_default();
        if Arc::get_mut(t).is_none() {
            // Every field named, so that a new one is not forgotten here.
            let Texture { levels, base_format, min_filter, mag_filter, wrap_s, wrap_t, one_d, lod, version } = &**t;
            let levels =
                levels.iter().enumerate().map(|(i, l)| if i == level { Level::default() } else { l.clone() }).collect();
            let (base_format, min_filter, mag_filter, wrap_s, wrap_t, one_d, lod) =
                (*base_format, *min_filter, *mag_filter, *wrap_s, *wrap_t, *one_d, *lod);
            let version = *version;
            *t = Arc::new(Texture { levels, base_format, min_filter, mag_filter, wrap_s, wrap_t, one_d, lod, version });
        }
        let t = Arc::get_mut(t).expect("a texture held here alone");
        t.changed();
        if t.levels.len() <= level {
            t.levels.resize(level + 1, Level::default());
        }
        t
    }

    fn tex_image(&mut self, a: &[Value], sub: bool) -> GlResult {
        let target = args::uint(a, 0);
        if target != GL_TEXTURE_2D && target != GL_TEXTURE_1D {
            return Ok(()); // proxies, cube maps: not captured
        }
        let level = args::int(a, 1);
        if !(0..16).contains(&level) {
            return Err(GlError::InvalidValue);
        }
        let level = level as usize;
        let unpack = self.client.unpack;
        if sub {
            let (x, y, w, h) = (args::int(a, 2), args::int(a, 3), args::int(a, 4), args::int(a, 5));
            let (format, ty, data) = (args::uint(a, 6), args::uint(a, 7), args::bytes(a, 8));
            let Some(texels) = texture::decode(w.max(0) as usize, h.max(0) as usize, format, ty, &unpack, data) else {
                return Ok(());
            };
            let t = self.texture_mut(target);
            let base = t.base_format;
            let Some(l) = t.levels.get_mut(level) else { return Err(GlError::InvalidOperation) };
            for row in 0..h.max(0) {
                for col in 0..w.max(0) {
                    let (tx, ty) = ((x + col) as usize, (y + row) as usize);
                    if tx < l.width && ty < l.height {
                        l.texels[ty * l.width + tx] = texture::to_base(texels[(row * w + col) as usize], base);
                    }
                }
            }
            return Ok(());
        }
        let internal = args::uint(a, 2);
        let (w, h) = (args::int(a, 3), args::int(a, 4));
        if w < 0 || h < 0 {
            return Err(GlError::InvalidValue);
        }
        let (format, ty, data) = (args::uint(a, 6), args::uint(a, 7), args::bytes(a, 8));
        let base = texture::base_format(internal);
        let (w, h) = (w as usize, h as usize);
        let t = self.texture_to_replace(target, level);
        // Into the replaced level's memory (when no frame holds the texture), unless that is
        // over 16 MB and four times what this image needs.
        let mut texels = std::mem::take(&mut t.levels[level].texels);
        if texels.capacity() > (1 << 20).max(4 * w * h) {
            texels = Vec::new();
        }
        if texture::decode_into(&mut texels, w, h, format, ty, &unpack, data).is_some() {
            texels.iter_mut().for_each(|c| *c = texture::to_base(*c, base));
        } else {
            texels.clear();
            texels.resize(w * h, Vec4::ONE);
        }
        if level == 0 {
            t.base_format = base;
        }
        t.one_d = target == GL_TEXTURE_1D;
        t.levels[level] = Level { width: w, height: h, texels };
        Ok(())
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
        let t = self.texture_to_replace(GL_TEXTURE_2D, level);
        if level == 0 {
            t.base_format = base;
        }
        t.levels[level] = Level { width, height, texels };
    }

    fn material(&mut self, a: &[Value], ty: u32) -> GlResult {
        let (face, pname) = (args::uint(a, 0), args::uint(a, 1));
        let faces: &[usize] = match face {
            GL_FRONT => &[0],
            GL_BACK => &[1],
            GL_FRONT_AND_BACK => &[0, 1],
            _ => return Err(GlError::InvalidEnum),
        };
        let c = self.color_param(a, 2, ty);
        let first = self.floats(a, 2, ty, 1).first().copied().unwrap_or(0.0);
        for &f in faces {
            let m = &mut self.s.materials[f];
            match pname {
                GL_AMBIENT => m.ambient = c,
                GL_DIFFUSE => m.diffuse = c,
                GL_SPECULAR => m.specular = c,
                GL_EMISSION => m.emission = c,
                GL_AMBIENT_AND_DIFFUSE => {
                    m.ambient = c;
                    m.diffuse = c;
                }
                GL_SHININESS => {
                    if !(0.0..=128.0).contains(&first) {
                        return Err(GlError::InvalidValue);
                    }
                    m.shininess = first
                }
                GL_COLOR_INDEXES => {} // GL_COLOR_INDEXES
                _ => return Err(GlError::InvalidEnum),
            }
        }
        Ok(())
    }

    fn light(&mut self, a: &[Value], ty: u32) -> GlResult {
        let index = args::uint(a, 0).wrapping_sub(GL_LIGHT0) as usize;
        if index >= 8 {
            return Err(GlError::InvalidEnum);
        }
        let v = self.floats(a, 2, ty, 4);
        let get = |k: usize| v.get(k).copied().unwrap_or(0.0);
        let mv = *self.matrices.modelview.top();
        let c = self.color_param(a, 2, ty);
        let l = &mut self.s.lights[index];
        match args::uint(a, 1) {
            GL_AMBIENT => l.ambient = c,
            GL_DIFFUSE => l.diffuse = c,
            GL_SPECULAR => l.specular = c,
            // Positions and directions are taken through the modelview of the moment.
            GL_POSITION => l.position = mv * DVec4::new(get(0), get(1), get(2), get(3)),
            GL_SPOT_DIRECTION => l.spot_direction = DMat3::from_mat4(mv) * DVec3::new(get(0), get(1), get(2)),
            GL_SPOT_EXPONENT => {
                if !(0.0..=128.0).contains(&get(0)) {
                    return Err(GlError::InvalidValue);
                }
                l.spot_exponent = get(0)
            }
            GL_SPOT_CUTOFF => {
                let c = get(0);
                if !((0.0..=90.0).contains(&c) || c == 180.0) {
                    return Err(GlError::InvalidValue);
                }
                l.spot_cutoff = c
            }
            p @ (GL_CONSTANT_ATTENUATION | GL_LINEAR_ATTENUATION | GL_QUADRATIC_ATTENUATION) => {
                if get(0) < 0.0 {
                    return Err(GlError::InvalidValue);
                }
                match p {
                    GL_CONSTANT_ATTENUATION => l.constant_attenuation = get(0),
                    GL_LINEAR_ATTENUATION => l.linear_attenuation = get(0),
                    _ => l.quadratic_attenuation = get(0),
                }
            }
            _ => return Err(GlError::InvalidEnum),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::op_for;
    use glam::Vec3;
    use glray_gl::GL_ENABLE_BIT;
    use glray_gl::{
        GL_CLAMP_TO_EDGE, GL_COMPILE, GL_COMPILE_AND_EXECUTE, GL_LINEAR, GL_NEAREST, GL_RGBA, GL_TEXTURE,
        GL_TEXTURE_LOD_BIAS, GL_TEXTURE_MAX_LEVEL, GL_TEXTURE_MAX_LOD, GL_TEXTURE_MIN_LOD,
    };
    use glray_scene::frame::TriangleId;
    use glray_scene::texture::{Filter, Wrap};
    use glray_scene::triangle::Triangle;

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
        assert!(!c.s.cull, "GL_ENABLE_BIT restores the enable");
        assert_eq!(c.s.cull_face, Face::Front, "but not the face, which GL_POLYGON_BIT saves");
        for _ in 0..MAX_ATTRIB_DEPTH {
            call(&mut c, "glPushAttrib", &[i(0xFFFFF)]);
        }
        assert_eq!(c.errors.take(), 0);
        call(&mut c, "glPushAttrib", &[i(0xFFFFF)]);
        assert_eq!(c.errors.take(), 0x0503);
    }

    #[test]
    pub(crate) fn culling_facing_and_flat_shading() {
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
    pub(crate) fn lists_compile_execute_and_nest() {
        let mut c = context();
        call(&mut c, "glNewList", &[i(1), i(GL_COMPILE as i64)]); // GL_COMPILE
        triangle(&mut c, true);
        call(&mut c, "glEndList", &[]);
        assert_eq!(c.frame().triangles.len(), 0, "GL_COMPILE draws nothing");
        call(&mut c, "glNewList", &[i(2), i(GL_COMPILE_AND_EXECUTE as i64)]); // COMPILE_AND_EXECUTE, calling list 1
        call(&mut c, "glTranslatef", &[f(0.5), f(0.0), f(0.0)]);
        call(&mut c, "glCallList", &[i(1)]);
        call(&mut c, "glEndList", &[]);
        assert_eq!(c.frame().instances.len(), 1, "list 1's mesh, instanced");
        call(&mut c, "glLoadIdentity", &[]);
        call(&mut c, "glListBase", &[i(1)]);
        call(&mut c, "glCallLists", &[i(2), i(0x1401), Value::Blob(&[0, 1])]);
        let t = &c.frame().all_triangles();
        assert_eq!(t.len(), 3, "lists 1 and 2 through glListBase");
        assert!(c.frame().triangles.is_empty() && c.frame().instances.len() == 3);
        assert_eq!(t[1].positions[0].x, 0.0);
        assert_eq!(t[2].positions[0].x, 0.5, "list 2's translate, then list 1 nested");
        call(&mut c, "glNewList", &[i(3), i(0x1300)]);
        call(&mut c, "glNewList", &[i(4), i(0x1300)]);
        assert_eq!(c.errors.take(), 0x0502, "glNewList inside glNewList");
    }

    /// The state a list mesh's instance and the same draw made at once are compared under:
    /// lighting with colour material, two sides, rescaled normals, a texture matrix.
    fn lit_scene(c: &mut Context) {
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
    fn positions_2d(floats: &[u8]) -> ArrayData<'_> {
        ArrayData { kind: 0, index: 0, size: 2, gl_type: 0x1406, stride: 0, normalized: false, first: 0, bytes: floats }
    }

    fn f32s(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_ne_bytes()).collect()
    }

    /// A strip with a colour and normal given part-way, after a colour current at the call.
    fn strip(c: &mut Context) {
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

    #[test]
    pub(crate) fn list_meshes_are_instanced_as_the_vertex_stage_would_draw_them() {
        let mut c = context();
        lit_scene(&mut c);
        call(&mut c, "glNewList", &[i(1), i(0x1300)]);
        strip(&mut c);
        call(&mut c, "glEndList", &[]);
        for (flat, front_face) in [(false, GL_CCW), (true, GL_CCW), (false, GL_CW)] {
            call(&mut c, "glShadeModel", &[i(if flat { GL_FLAT } else { GL_SMOOTH } as i64)]);
            call(&mut c, "glFrontFace", &[i(front_face as i64)]);
            let current = |c: &mut Context| {
                call(c, "glColor3f", &[f(1.0), f(0.0), f(0.0)]);
                call(c, "glNormal3f", &[f(0.0), f(0.0), f(1.0)]);
                call(c, "glTexCoord2f", &[f(0.125), f(0.0)]);
            };
            current(&mut c);
            strip(&mut c);
            current(&mut c);
            call(&mut c, "glCallList", &[i(1)]);
            assert_eq!(c.imm.current.color, DVec4::new(0.0, 1.0, 0.0, 1.0), "the list's last colour stays current");
            let frame = c.take_frame();
            assert_eq!(frame.instances.len(), 1);
            let direct = &frame.triangles;
            let instanced = frame.instances[0].triangles(&frame.lightings);
            assert_eq!(direct.len(), 2);
            assert_eq!(instanced.len(), 2);
            for (a, b) in direct.iter().zip(&instanced) {
                let close = |x: &[f32], y: &[f32]| x.iter().zip(y).all(|(p, q)| (p - q).abs() < 1e-5);
                let flat4 = |v: [Vec4; 3]| v.iter().flat_map(|c| c.to_array()).collect::<Vec<_>>();
                let flat3 = |v: [Vec3; 3]| v.iter().flat_map(|c| c.to_array()).collect::<Vec<_>>();
                assert!(close(&flat3(a.positions), &flat3(b.positions)), "{a:?}\n{b:?}");
                assert!(close(&flat4(a.colors), &flat4(b.colors)), "flat {flat}: {:?} vs {:?}", a.colors, b.colors);
                assert!(close(&flat3(a.normals), &flat3(b.normals)));
                assert!(close(&flat4(a.base_colors), &flat4(b.base_colors)));
                let uv = |t: &Triangle| t.texcoords.iter().flat_map(|c| c.to_array()).collect::<Vec<_>>();
                assert!(close(&uv(a), &uv(b)), "{:?} vs {:?}", a.texcoords, b.texcoords);
                assert_eq!((a.back, a.clip_w), (b.back, b.clip_w));
                assert_eq!(a.sequence + 1, b.sequence);
            }
        }
    }

    #[test]
    pub(crate) fn instances_cull_and_fall_back_to_the_vertex_stage_when_they_must() {
        let mut c = context();
        call(&mut c, "glNewList", &[i(1), i(0x1300)]);
        triangle(&mut c, true);
        triangle(&mut c, false);
        call(&mut c, "glEndList", &[]);
        call(&mut c, "glEnable", &[i(GL_CULL_FACE as i64)]);
        call(&mut c, "glCallList", &[i(1)]);
        let frame = c.take_frame();
        assert_eq!(frame.instances.len(), 1, "the list's two glBegin/glEnd make one mesh");
        let id = |index| TriangleId { instance: 0, index };
        assert!(frame.triangle(id(0)).is_some() && frame.triangle(id(1)).is_none(), "the back one is culled");
        assert_eq!(frame.all_triangles().len(), 1);
        // Outlines are screen-space quads: the list's vertices go through the vertex stage.
        call(&mut c, "glPolygonMode", &[i(GL_FRONT_AND_BACK as i64), i(GL_LINE as i64)]);
        call(&mut c, "glCallList", &[i(1)]);
        let frame = c.take_frame();
        assert!(frame.instances.is_empty());
        assert_eq!(frame.triangles.len(), 6, "three edges of the front triangle");
    }

    /// Whether an instance's triangle is kept by GL's own rule: its window winding.
    fn on_window(inst: &glray_scene::instance::Instance, k: usize) -> bool {
        let clip = inst.mesh.triangles[k].map(|v| inst.object_to_clip * inst.mesh.position(v));
        let front = glray_scene::facing::window_facing(clip, inst.front_ccw).unwrap_or(true);
        !glray_scene::facing::culled(inst.cull, front)
    }

    #[test]
    pub(crate) fn the_facing_a_ray_sees_is_the_facing_on_the_window() {
        // Triangles of both windings at several places, under modelviews that rotate and mirror,
        // with either front face: the one dot product a camera ray gives must cull as the
        // window winding does.
        for (mv, front) in [("glRotatef", GL_CCW), ("glScalef", GL_CCW), ("glScalef", GL_CW), ("glRotatef", GL_CW)] {
            let mut c = Context::default();
            c.set_drawable(64, 64);
            call(&mut c, "glMatrixMode", &[i(0x1701)]);
            call(&mut c, "glFrustum", &[f(-0.5), f(0.5), f(-0.5), f(0.5), f(1.0), f(20.0)]);
            call(&mut c, "glMatrixMode", &[i(0x1700)]);
            call(&mut c, "glNewList", &[i(1), i(0x1300)]);
            call(&mut c, "glBegin", &[i(4)]);
            for k in 0..8 {
                let (x, z) = ((k % 4) as f64 - 1.5, -3.0 - (k / 4) as f64);
                let pts = if k % 2 == 0 {
                    [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5)]
                } else {
                    [(0.0, 0.0), (0.0, 0.5), (0.5, 0.2)]
                };
                for (dx, dy) in pts {
                    call(&mut c, "glVertex3f", &[f(x + dx), f(dy - 0.2), f(z + dx * 0.7)]);
                }
            }
            call(&mut c, "glEnd", &[]);
            call(&mut c, "glEndList", &[]);
            call(&mut c, "glFrontFace", &[i(front as i64)]);
            call(&mut c, "glEnable", &[i(GL_CULL_FACE as i64)]);
            call(&mut c, "glTranslatef", &[f(0.0), f(0.0), f(-2.0)]);
            match mv {
                "glScalef" => call(&mut c, "glScalef", &[f(-1.0), f(1.0), f(1.0)]),
                _ => call(&mut c, "glRotatef", &[f(35.0), f(0.3), f(1.0), f(0.2)]),
            }
            call(&mut c, "glTranslatef", &[f(0.0), f(0.0), f(2.0)]);
            call(&mut c, "glCallList", &[i(1)]);
            let frame = c.take_frame();
            let inst = &frame.instances[0];
            let eye = inst.modelview.inverse() * DVec4::new(0.0, 0.0, 0.0, 1.0);
            for (k, t) in inst.mesh.triangles.iter().enumerate() {
                let p = t.map(|v| inst.mesh.positions[v as usize].as_dvec3());
                let normal = (p[1] - p[0]).cross(p[2] - p[0]);
                let toward = (p[0] + p[1] + p[2]) / 3.0 - eye.truncate() / eye.w;
                assert_eq!(
                    inst.keeps_seen(normal.dot(toward) as f32),
                    on_window(inst, k),
                    "{mv} {front:#x} triangle {k}"
                );
            }
            let kept = (0..8).filter(|&k| on_window(inst, k)).count();
            assert!(kept > 0 && kept < 8, "{mv} {front:#x}: both facings present ({kept} kept)");
        }
    }

    #[test]
    pub(crate) fn a_glbegin_a_mesh_cannot_keep_stays_calls() {
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_LIGHTING as i64)]);
        call(&mut c, "glNewList", &[i(1), i(0x1300)]);
        call(&mut c, "glBegin", &[i(4)]);
        call(&mut c, "glVertex2f", &[f(0.0), f(0.0)]);
        // glMaterial between glBegin and glEnd: allowed, but not in a mesh.
        call(&mut c, "glMaterialfv", &[i(GL_FRONT as i64), i(0x1200), Value::Blob(&f32s(&[1.0, 0.0, 0.0, 1.0]))]);
        call(&mut c, "glVertex2f", &[f(1.0), f(0.0)]);
        call(&mut c, "glVertex2f", &[f(0.0), f(1.0)]);
        call(&mut c, "glEnd", &[]);
        // Left open: stays calls too, and raises INVALID_OPERATION at the next glBegin.
        call(&mut c, "glBegin", &[i(4)]);
        call(&mut c, "glEndList", &[]);
        call(&mut c, "glCallList", &[i(1)]);
        let frame = c.take_frame();
        assert!(frame.instances.is_empty());
        assert_eq!(frame.triangles.len(), 1);
        assert!(frame.triangles[0].colors[2].x > 0.1, "the material changed mid-glBegin: {:?}", frame.triangles[0]);
        assert_eq!(c.errors.take(), 0, "the list's glBegin is open, not an error yet");
        triangle(&mut c, true);
        assert_eq!(c.errors.take(), 0x0502, "glBegin inside the list's glBegin");
    }

    #[test]
    pub(crate) fn polygon_mode_line_keeps_quad_diagonals_hidden() {
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
    pub(crate) fn lines_and_points_are_also_solids_as_thick_as_on_the_screen() {
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
    pub(crate) fn a_line_reaching_behind_the_viewer_keeps_its_part_in_front() {
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

    #[test]
    pub(crate) fn arrays_from_buffers_and_client_memory() {
        let mut c = context();
        let floats: Vec<u8> = [0f32, 0.0, 1.0, 0.0, 0.0, 1.0].iter().flat_map(|v| v.to_ne_bytes()).collect();
        // A buffer object.
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(7)]);
        call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(24), Value::Blob(&floats), i(0x88E4)]);
        call(&mut c, "glVertexPointer", &[i(2), i(0x1406), i(0), Value::Offset(0)]);
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        call(&mut c, "glDrawArrays", &[i(4), i(0), i(3)]);
        assert_eq!(c.frame().all_triangles().len(), 1);
        // Client memory, as the trace's arrays event gives it, with client indices.
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(0)]);
        c.set_arrays(&[positions_2d(&floats)]);
        call(&mut c, "glDrawElements", &[i(4), i(3), i(0x1401), Value::Blob(&[2, 1, 0])]);
        let t = &c.frame().triangles;
        assert_eq!(t.len(), 1, "client memory: made this frame");
        assert_eq!(t[0].positions[0], Vec3::new(0.0, 1.0, 0.0), "index 2 first");
        // Indices in an element buffer from offset 0: a null pointer in the recording.
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(7)]);
        call(&mut c, "glVertexPointer", &[i(2), i(0x1406), i(0), Value::Null]);
        call(&mut c, "glBindBuffer", &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(8)]);
        call(&mut c, "glBufferData", &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(3), Value::Blob(&[1, 2, 0]), i(0x88E4)]);
        call(&mut c, "glDrawElements", &[i(4), i(3), i(0x1401), Value::Null]);
        let t = &c.frame().instances;
        assert_eq!(t.len(), 2);
        assert_eq!(
            c.frame().triangle(TriangleId { instance: 1, index: 0 }).unwrap().positions[0],
            Vec3::new(1.0, 0.0, 0.0),
            "index 1 first"
        );
        call(&mut c, "glDrawArrays", &[i(4), i(-1), i(3)]);
        assert_eq!(c.errors.take(), 0x0501);
    }

    #[test]
    fn indexed_buffer_draws_fetch_each_vertex_once() {
        // A 4 x 4 grid of vertices with a colour each, 18 triangles through an element buffer.
        let mut c = context();
        let (mut positions, mut colors) = (Vec::new(), Vec::new());
        for k in 0..16 {
            positions.extend([(k % 4) as f32, (k / 4) as f32, 0.0]);
            colors.extend([k as f32 / 16.0, 0.5, 1.0 - k as f32 / 16.0, 1.0]);
        }
        let mut indices: Vec<u16> = Vec::new();
        for y in 0..3u16 {
            for x in 0..3u16 {
                let k = y * 4 + x;
                indices.extend([k, k + 1, k + 5, k, k + 5, k + 4]);
            }
        }
        indices.push(0); // not a whole triangle: GL draws 18
        let index_bytes: Vec<u8> = indices.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let (p, q) = (f32s(&positions), f32s(&colors));
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(1)]);
        call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(p.len() as i64), Value::Blob(&p), i(0x88E4)]);
        call(&mut c, "glVertexPointer", &[i(3), i(0x1406), i(0), Value::Null]);
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(2)]);
        call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(q.len() as i64), Value::Blob(&q), i(0x88E4)]);
        call(&mut c, "glColorPointer", &[i(4), i(0x1406), i(0), Value::Null]);
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        call(&mut c, "glEnableClientState", &[i(GL_COLOR_ARRAY as i64)]); // GL_COLOR_ARRAY
        call(&mut c, "glBindBuffer", &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(3)]);
        let n = index_bytes.len() as i64;
        call(&mut c, "glBufferData", &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(n), Value::Blob(&index_bytes), i(0x88E4)]);
        call(&mut c, "glDrawElements", &[i(4), i(indices.len() as i64), i(0x1403), Value::Null]);
        assert_eq!(c.errors.take(), 0);
        let frame = c.frame();
        assert_eq!(frame.instances.len(), 1);
        let mesh = &frame.instances[0].mesh;
        assert_eq!((mesh.vertex_count(), mesh.triangles.len()), (16, 18), "each vertex once, whole triangles");
        for (t, corners) in indices.chunks_exact(3).enumerate() {
            let tri = frame.triangle(TriangleId { instance: 0, index: t as u32 }).expect("drawn");
            for (k, &v) in corners.iter().enumerate() {
                let v = v as usize;
                assert_eq!(tri.positions[k], Vec3::new(positions[3 * v], positions[3 * v + 1], 0.0));
                assert_eq!(tri.colors[k], Vec4::from_slice(&colors[4 * v..4 * v + 4]));
            }
        }
        // The colour array's last vertex stays current, as Mesa leaves it (as with every array
        // draw here: the last index read, whole triangle or not).
        let last = indices[indices.len() - 1] as usize;
        assert_eq!(c.imm.current.color, Vec4::from_slice(&colors[4 * last..4 * last + 4]).as_dvec4());
    }

    #[test]
    fn a_big_indexed_draw_is_read_in_pieces_as_a_small_one_would_be() {
        // 400,000 triangles over as many vertices from index 7 on (more than one piece of the
        // threads' share-out each), and a trailing index below them: triangles, positions,
        // normals, colours, the provoking corners and the box as read one by one, with and
        // without glray's threads.
        let check = || {
            let mut c = context();
            let (n, first) = (400_000u32, 7u32);
            let value = |v: u32, k: u32| ((v * 7 + k * 13) % 1000) as f32 / 100.0 - 5.0 + k as f32;
            let positions: Vec<f32> = (0..n + first).flat_map(|v| [value(v, 0), value(v, 1), value(v, 2)]).collect();
            let normals: Vec<f32> = (0..n + first).flat_map(|v| [value(v, 3), 0.5, value(v, 4)]).collect();
            let colors: Vec<f32> = (0..n + first).flat_map(|v| [value(v, 5), value(v, 6), 0.25, 1.0]).collect();
            let mut indices: Vec<u32> = (0..1_200_000u32).map(|k| first + (k * 7919) % n).collect();
            indices.push(first - 1); // not a whole triangle, and the lowest index
            let (p, q, r) = (f32s(&positions), f32s(&normals), f32s(&colors));
            let index_bytes: Vec<u8> = indices.iter().flat_map(|v| v.to_ne_bytes()).collect();
            call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(1)]);
            call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(p.len() as i64), Value::Blob(&p), i(0x88E4)]);
            call(&mut c, "glVertexPointer", &[i(3), i(0x1406), i(0), Value::Null]);
            call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(2)]);
            call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(q.len() as i64), Value::Blob(&q), i(0x88E4)]);
            call(&mut c, "glNormalPointer", &[i(0x1406), i(0), Value::Null]);
            call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(4)]);
            call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(r.len() as i64), Value::Blob(&r), i(0x88E4)]);
            call(&mut c, "glColorPointer", &[i(4), i(0x1406), i(0), Value::Null]);
            call(&mut c, "glEnableClientState", &[i(GL_COLOR_ARRAY as i64)]); // GL_COLOR_ARRAY
            call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
            call(&mut c, "glEnableClientState", &[i(GL_NORMAL_ARRAY as i64)]); // GL_NORMAL_ARRAY
            call(&mut c, "glBindBuffer", &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(3)]);
            let size = index_bytes.len() as i64;
            call(
                &mut c,
                "glBufferData",
                &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(size), Value::Blob(&index_bytes), i(0x88E4)],
            );
            call(&mut c, "glDrawElements", &[i(4), i(indices.len() as i64), i(0x1405), Value::Null]);
            assert_eq!(c.errors.take(), 0);
            let frame = c.frame();
            let mesh = &frame.instances[0].mesh;
            let base = first - 1;
            let triangles: Vec<[u32; 3]> = indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| t[k] - base)).collect();
            assert!(mesh.triangles == triangles, "triangles, less the lowest index");
            assert_eq!(mesh.provoking, triangles.iter().map(|t| t[2]).collect::<Vec<_>>());
            let at = |a: &[f32], v: u32| Vec3::from_slice(&a[3 * (v + base) as usize..]);
            assert_eq!(mesh.vertex_count(), n + 1);
            assert!((0..=n).all(|v| mesh.positions[v as usize] == at(&positions, v)), "positions");
            assert!((0..=n).all(|v| mesh.normals.at(v) == Some(at(&normals, v))), "normals");
            let color = |v: u32| Vec4::from_slice(&colors[4 * (v + base) as usize..]);
            assert!((0..=n).all(|v| mesh.colors.at(v) == Some(color(v))), "colours");
            let (lo, hi) = (0..=n).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(at(&positions, v)), hi.max(at(&positions, v)))
            });
            assert_eq!((mesh.min, mesh.max), (lo, hi));
        };
        check();
        glray_core::threads::publish(rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap());
        check();
    }

    #[test]
    fn a_long_glbegin_is_drawn_whole_in_the_order_given_and_its_vertices_are_not_all_held() {
        // 39,999 vertices of separate triangles (more than three chunks) and of a strip: every
        // triangle, in order; for the first, fewer vertices held at once than given. Texture
        // coordinates generated: a state no instance can be drawn with, so the vertex stage
        // keeps the run (below, without it, the run is taken as a mesh).
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_TEXTURE_GEN_S as i64)]); // GL_TEXTURE_GEN_S
        let n = 39_999;
        let give = |c: &mut Context, mode: i64| {
            call(c, "glBegin", &[i(mode)]);
            for k in 0..n {
                call(c, "glColor3f", &[f(k as f64 / n as f64), f(0.0), f(0.0)]);
                let (x, y) = ((k % 3 == 1) as i32 as f64 * 0.5, (k % 3 == 2) as i32 as f64 * 0.5);
                call(c, "glVertex2f", &[f(x - 0.5 + k as f64 / n as f64 * 0.1), f(y - 0.5)]);
            }
            call(c, "glEnd", &[]);
        };
        give(&mut c, 4); // GL_TRIANGLES
        assert!(c.open.capacity() < n, "{}", c.open.capacity());
        let frame = c.take_frame();
        assert_eq!(frame.triangles.len(), n / 3);
        for (t, tri) in frame.triangles.iter().enumerate() {
            let first = (3 * t) as f32 / n as f32;
            let reds: Vec<f32> = tri.colors.iter().map(|c| c.x).collect();
            assert!(reds.iter().all(|r| (r - first).abs() < 3.0 / n as f32), "triangle {t}: {reds:?}");
        }
        assert!(frame.triangles.windows(2).all(|w| w[0].sequence <= w[1].sequence), "in drawing order");
        give(&mut c, 5); // GL_TRIANGLE_STRIP
        assert_eq!(c.take_frame().triangles.len(), n - 2);
        // Without generated coordinates the run is taken from the vertex stage as one mesh,
        // drawn as an instance: the same triangles, in order, with the same colours.
        call(&mut c, "glDisable", &[i(0x0C60)]);
        give(&mut c, 4);
        let frame = c.take_frame();
        assert_eq!((frame.triangles.len(), frame.instances.len()), (0, 1));
        let all = frame.all_triangles();
        assert_eq!(all.len(), n / 3);
        for (t, tri) in all.iter().enumerate() {
            let first = (3 * t) as f32 / n as f32;
            let reds: Vec<f32> = tri.colors.iter().map(|c| c.x).collect();
            assert!(reds.iter().all(|r| (r - first).abs() < 3.0 / n as f32), "instanced triangle {t}: {reds:?}");
        }
        assert_eq!(c.errors.take(), 0);
    }

    #[test]
    fn a_glbegin_is_taken_as_a_mesh_from_its_4096th_vertex_and_kept_while_it_gives_the_same() {
        use crate::immediate_meshes::MESH_FROM_VERTICES;
        let mut c = context();
        // Vertex k of separate triangles, none of them degenerate.
        let corner = |c: &mut Context, k: usize| {
            let (x, y) = ((k % 3 == 1) as i32 as f64 * 0.5, (k % 3 == 2) as i32 as f64 * 0.5);
            call(c, "glVertex2f", &[f(x - 0.5 + k as f64 * 1e-5), f(y - 0.5)]);
        };
        let give = |c: &mut Context, vertices: usize, mode: i64, red: f64| {
            call(c, "glBegin", &[i(mode)]);
            for k in 0..vertices {
                call(c, "glColor3f", &[f(red * (k % 2) as f64), f(0.0), f(0.0)]);
                corner(c, k);
            }
            call(c, "glEnd", &[]);
        };
        let n = MESH_FROM_VERTICES - MESH_FROM_VERTICES % 3;
        // One vertex short: the vertex stage's. Lines: never a mesh.
        give(&mut c, n - 3, 4, 1.0);
        let frame = c.take_frame();
        assert_eq!((frame.instances.len(), frame.triangles.len()), (0, (n - 3) / 3));
        give(&mut c, MESH_FROM_VERTICES + 10, 1, 1.0);
        assert_eq!(c.take_frame().instances.len(), 0, "lines");
        // Long enough: one mesh, the same one the next frame while the calls give the same.
        give(&mut c, n + 3, 4, 1.0);
        let first = c.take_frame();
        assert_eq!((first.instances.len(), first.triangles.len()), (1, 0));
        assert_eq!(first.instances[0].mesh.triangles.len(), n / 3 + 1);
        give(&mut c, n + 3, 4, 1.0);
        let second = c.take_frame();
        assert!(Arc::ptr_eq(&first.instances[0].mesh, &second.instances[0].mesh), "kept by what it gives");
        give(&mut c, n + 3, 4, 0.5);
        let third = c.take_frame();
        assert!(!Arc::ptr_eq(&second.instances[0].mesh, &third.instances[0].mesh), "new colours, a new mesh");
        // A colour given once is the instance's, not the mesh's: the same mesh.
        for red in [1.0, 0.5] {
            call(&mut c, "glColor3f", &[f(red), f(0.0), f(0.0)]);
            call(&mut c, "glBegin", &[i(4)]);
            (0..n + 3).for_each(|k| corner(&mut c, k));
            call(&mut c, "glEnd", &[]);
        }
        let frame = c.take_frame();
        assert!(Arc::ptr_eq(&frame.instances[0].mesh, &frame.instances[1].mesh));
        assert_eq!((frame.instances[0].color.x, frame.instances[1].color.x), (1.0, 0.5));
        // A glMaterial inside after the run was taken: back to the vertex stage, whole.
        call(&mut c, "glBegin", &[i(4)]);
        for k in 0..n + 3 {
            if k == n {
                call(&mut c, "glMaterialf", &[i(0x0408), i(0x1601), f(10.0)]);
            }
            corner(&mut c, k);
        }
        call(&mut c, "glEnd", &[]);
        let frame = c.take_frame();
        assert_eq!((frame.instances.len(), frame.triangles.len()), (0, n / 3 + 1));
        assert_eq!(c.errors.take(), 0);
    }

    #[test]
    fn big_client_draws_are_kept_by_the_bytes_they_read() {
        use crate::client_draws::KEEP_FROM_ELEMENTS;
        // A unit square's corners, and enough indices over them for the draw to be kept.
        let mut c = context();
        let corners = f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        let n = KEEP_FROM_ELEMENTS as usize;
        let indices: Vec<u8> = [0u16, 1, 2, 2, 1, 3].iter().cycle().take(n).flat_map(|v| v.to_ne_bytes()).collect();
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        let draw = |c: &mut Context, positions: &[u8], count: usize| {
            c.set_arrays(&[positions_2d(positions)]);
            let indices = Value::Blob(&indices[..2 * count]);
            call(c, "glDrawElements", &[i(4), i(count as i64), i(0x1403), indices]);
        };
        // The same bytes twice in a frame: one mesh, drawn twice.
        draw(&mut c, &corners, n);
        draw(&mut c, &corners, n);
        let first = c.take_frame();
        assert!(first.triangles.is_empty(), "drawn as instances");
        assert_eq!(first.instances.len(), 2);
        let kept = first.instances[0].mesh.clone();
        assert!(Arc::ptr_eq(&kept, &first.instances[1].mesh));
        assert_eq!(kept.triangles.len(), n / 3);
        // The next frame, the same bytes from other memory: the same mesh.
        draw(&mut c, &corners.clone(), n);
        assert!(Arc::ptr_eq(&kept, &c.take_frame().instances[0].mesh), "kept from frame to frame");
        // One corner moved: a new mesh, with the corner where it is now.
        let mut moved = corners.clone();
        moved[..4].copy_from_slice(&0.5f32.to_ne_bytes());
        draw(&mut c, &moved, n);
        let frame = c.take_frame();
        assert!(!Arc::ptr_eq(&kept, &frame.instances[0].mesh), "a changed byte makes a new mesh");
        let tri = frame.triangle(TriangleId { instance: 0, index: 0 }).expect("drawn");
        assert_eq!(tri.positions[0], Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(c.client_draws.len(), 1, "only what the last frame drew is kept");
        c.take_frame();
        assert_eq!(c.client_draws.len(), 0, "a frame without the draw lets its mesh go");
        // Fewer elements than kept draws have: the frame's own triangles.
        draw(&mut c, &corners, n - 4);
        let frame = c.take_frame();
        assert!(frame.instances.is_empty() && frame.triangles.len() == (n - 4) / 3, "{}", frame.triangles.len());
        // The same small arrays twice, then others in the same memory: each draw reads the
        // arrays it was given (big ones: `big_arrays_the_same_as_the_last_draws_...`).
        for positions in [&moved, &moved, &corners] {
            draw(&mut c, positions, n - 4);
            let frame = c.take_frame();
            let corner = f32::from_ne_bytes(positions[..4].try_into().unwrap());
            assert_eq!(frame.triangles.len(), (n - 4) / 3);
            assert_eq!(frame.triangles[0].positions[0].x, corner, "the draw reads the arrays it was given");
        }
        assert_eq!(c.errors.take(), 0);
    }

    #[test]
    fn big_arrays_the_same_as_the_last_draws_are_not_copied_and_changed_ones_are() {
        // 9,000 triangles of 2D positions (216 KB: hashed before copying): drawn, drawn again
        // from other memory holding the same bytes (not copied), then with the last triangle
        // moved in place (the same length: copied anew, and the new mesh has it moved).
        let mut c = context();
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        let n = 27_000usize;
        let mut floats: Vec<f32> = (0..2 * n).map(|k| (k % 7) as f32).collect();
        let draw = |c: &mut Context, floats: &[f32]| {
            let bytes = f32s(floats);
            c.set_arrays(&[positions_2d(&bytes)]);
            call(c, "glDrawArrays", &[i(4), i(0), i(n as i64)]);
            let frame = c.take_frame();
            let last = TriangleId { instance: 0, index: (n / 3 - 1) as u32 };
            (frame.instances[0].mesh.clone(), frame.triangle(last).expect("drawn").positions[2])
        };
        let (first, _) = draw(&mut c, &floats);
        let (again, _) = draw(&mut c, &floats.clone());
        assert!(Arc::ptr_eq(&first, &again), "the same bytes, the same mesh");
        floats[2 * n - 2] = 100.0;
        let (moved, corner) = draw(&mut c, &floats);
        assert!(!Arc::ptr_eq(&first, &moved), "a changed byte makes a new mesh");
        assert_eq!(corner.x, 100.0, "the new mesh has the moved corner");
        assert_eq!(c.errors.take(), 0);
    }

    #[test]
    pub(crate) fn array_elements_give_vertices_inside_glbegin_and_in_lists() {
        let mut c = context();
        let floats = f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
        let colors = [255u8, 0, 0, 0, 255, 0, 0, 0, 255];
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        call(&mut c, "glEnableClientState", &[i(GL_COLOR_ARRAY as i64)]);
        // What the recorder captures before each glArrayElement: that element's memory.
        let element = |c: &mut Context, k: usize| {
            c.set_arrays(&[
                ArrayData {
                    kind: 0,
                    index: 0,
                    size: 2,
                    gl_type: 0x1406,
                    stride: 0,
                    normalized: false,
                    first: k as u64,
                    bytes: &floats[8 * k..8 * k + 8],
                },
                ArrayData {
                    kind: 2,
                    index: 0,
                    size: 3,
                    gl_type: 0x1401,
                    stride: 0,
                    normalized: true,
                    first: k as u64,
                    bytes: &colors[3 * k..3 * k + 3],
                },
            ]);
            call(c, "glArrayElement", &[i(k as i64)]);
        };
        let triangle = |c: &mut Context| {
            call(c, "glBegin", &[i(4)]);
            for k in [2, 0, 1] {
                element(c, k);
            }
            call(c, "glEnd", &[]);
        };
        triangle(&mut c);
        let t = c.frame().triangles[0];
        assert_eq!(t.positions[0], Vec3::new(0.0, 1.0, 0.0), "element 2 first");
        assert_eq!(t.colors[0], Vec4::new(0.0, 0.0, 1.0, 1.0), "with its colour");
        assert_eq!(c.imm.current.color, DVec4::new(0.0, 1.0, 0.0, 1.0), "the last colour stays current");
        // Compiled: the elements' values are copied into the list.
        call(&mut c, "glNewList", &[i(1), i(0x1300)]);
        triangle(&mut c);
        call(&mut c, "glEndList", &[]);
        call(&mut c, "glDisableClientState", &[i(GL_COLOR_ARRAY as i64)]);
        call(&mut c, "glCallList", &[i(1)]);
        let frame = c.take_frame();
        assert_eq!(frame.instances.len(), 1);
        let listed = frame.all_triangles()[1];
        assert_eq!((listed.positions, listed.colors), (t.positions, t.colors));
    }

    #[test]
    pub(crate) fn multi_draw_elements_draws_each_index_array() {
        let mut c = context();
        let floats = f32s(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]);
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        c.set_arrays(&[positions_2d(&floats)]);
        let counts: Vec<u8> = [3i32, 3].iter().flat_map(|x| x.to_ne_bytes()).collect();
        let lists = Value::Strings(vec![&[0u8, 1, 2][..], &[0u8, 2, 3][..]]);
        call(&mut c, "glMultiDrawElements", &[i(4), Value::Blob(&counts), i(0x1401), lists, i(2)]);
        let t = &c.frame().triangles;
        assert_eq!(t.len(), 2);
        assert_eq!(t[1].positions[2], Vec3::new(0.0, 1.0, 0.0), "the second draw's last index, 3");
        // Offsets into an element buffer.
        call(&mut c, "glBindBuffer", &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(8)]);
        call(
            &mut c,
            "glBufferData",
            &[i(GL_ELEMENT_ARRAY_BUFFER as i64), i(6), Value::Blob(&[0, 1, 2, 0, 2, 3]), i(0x88E4)],
        );
        let offsets: Vec<u8> = [3usize].iter().flat_map(|x| x.to_ne_bytes()).collect();
        c.set_arrays(&[positions_2d(&floats)]);
        call(&mut c, "glMultiDrawElements", &[i(4), Value::Blob(&counts[..4]), i(0x1401), Value::Blob(&offsets), i(1)]);
        assert_eq!(c.frame().triangles[2].positions, t_positions(&floats, [0, 2, 3]));
        call(&mut c, "glMultiDrawElements", &[i(4), Value::Blob(&counts), i(0x1406), Value::Null, i(2)]);
        assert_eq!(c.errors.take(), 0x0500, "GL_FLOAT indices");
    }

    fn t_positions(floats: &[u8], idx: [usize; 3]) -> [Vec3; 3] {
        let f = |k: usize| f32::from_ne_bytes(floats[4 * k..4 * k + 4].try_into().unwrap());
        idx.map(|i| Vec3::new(f(2 * i), f(2 * i + 1), 0.0))
    }

    #[test]
    pub(crate) fn draws_of_unchanged_buffers_keep_their_mesh() {
        let mut c = context();
        let floats = f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(7)]);
        call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(24), Value::Blob(&floats), i(0x88E4)]);
        call(&mut c, "glVertexPointer", &[i(2), i(0x1406), i(0), Value::Null]);
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        let draw = |c: &mut Context| call(c, "glDrawArrays", &[i(4), i(0), i(3)]);
        draw(&mut c);
        draw(&mut c);
        let frame = c.take_frame();
        assert_eq!((frame.instances.len(), frame.triangles.len()), (2, 0));
        assert_eq!(frame.instances[0].mesh.id, frame.instances[1].mesh.id, "one mesh for the same draw");
        // New contents: a new mesh, with the new positions.
        call(&mut c, "glBufferSubData", &[i(GL_ARRAY_BUFFER as i64), i(0), i(4), Value::Blob(&f32s(&[0.5]))]);
        draw(&mut c);
        let next = c.take_frame();
        assert_ne!(next.instances[0].mesh.id, frame.instances[0].mesh.id);
        assert_eq!(next.all_triangles()[0].positions[0].x, 0.5);
        // Client memory is not kept: its draws stay per frame.
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(0)]);
        call(&mut c, "glVertexPointer", &[i(2), i(0x1406), i(0), Value::Opaque(64)]);
        c.set_arrays(&[positions_2d(&floats)]);
        draw(&mut c);
        let client = c.take_frame();
        assert_eq!((client.instances.len(), client.triangles.len()), (0, 1));
    }

    #[test]
    pub(crate) fn lighting_uses_color_material_and_two_sides() {
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_LIGHTING as i64)]);
        call(&mut c, "glEnable", &[i(GL_LIGHT0 as i64)]);
        call(&mut c, "glEnable", &[i(GL_COLOR_MATERIAL as i64)]);
        call(&mut c, "glLightModeli", &[i(GL_LIGHT_MODEL_TWO_SIDE as i64), i(1)]);
        call(&mut c, "glColor3f", &[f(1.0), f(0.0), f(0.0)]);
        triangle(&mut c, true);
        triangle(&mut c, false);
        let t = &c.frame().triangles;
        // Front: red diffuse 1 * light 1 * n.l 1 + ambient 0.2 * 1 (scene ambient).
        assert!((t[0].colors[0] - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-6, "{:?}", t[0].colors[0]);
        // Back face: the normal is flipped, the light does not reach it; only ambient is left.
        assert!((t[1].colors[0] - Vec4::new(0.2, 0.0, 0.0, 1.0)).length() < 1e-6, "{:?}", t[1].colors[0]);
    }

    /// glTexImage2D into the bound 2D texture: a `size` x `size` image of `texel` (four bytes,
    /// given as `format`: GL_RGBA is 0x1908).
    fn tex_image(c: &mut Context, level: i64, size: i64, format: i64, texel: [u8; 4]) {
        let pixels = texel.repeat((size * size) as usize);
        let args = [i(GL_TEXTURE_2D as i64), i(level), i(0x1908), i(size), i(size), i(0), i(format), i(0x1401)];
        call(c, "glTexImage2D", &[&args[..], &[Value::Blob(&pixels)]].concat());
    }

    #[test]
    fn a_new_image_leaves_a_held_texture_alone_and_keeps_the_other_levels() {
        let mut c = context();
        call(&mut c, "glBindTexture", &[i(GL_TEXTURE_2D as i64), i(7)]);
        call(&mut c, "glTexParameteri", &[i(GL_TEXTURE_2D as i64), i(0x2801), i(GL_NEAREST as i64)]); // MIN_FILTER NEAREST
        tex_image(&mut c, 0, 2, 0x1908, [255, 0, 0, 255]);
        tex_image(&mut c, 1, 1, 0x1908, [0, 255, 0, 255]);
        // A frame still holds the texture when the program uploads level 0 again.
        let held = c.shared.textures[&7].clone();
        tex_image(&mut c, 0, 2, 0x1908, [0, 0, 255, 255]);
        let now = &c.shared.textures[&7];
        let texel = |t: &Texture, level: usize| t.levels[level].texels[0];
        assert_eq!(texel(&held, 0), Vec4::new(1.0, 0.0, 0.0, 1.0), "the held texture keeps its image");
        assert_eq!(texel(now, 0), Vec4::new(0.0, 0.0, 1.0, 1.0));
        assert_eq!(texel(now, 1), texel(&held, 1), "the other level is kept");
        assert_eq!(now.levels.len(), 2);
        assert_eq!(now.min_filter, held.min_filter);
        assert_eq!(now.min_filter, Filter::Nearest);
        assert_eq!(c.errors.take(), 0);
    }

    #[test]
    fn a_sub_image_changes_a_texture_in_place_unless_a_frame_holds_it() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(5)]);
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2801), i(GL_NEAREST as i64)]); // MIN_FILTER NEAREST
        tex_image(&mut c, 0, 2, 0x1908, [255, 0, 0, 255]);
        call(&mut c, "glEnable", std::slice::from_ref(&tex));
        let sub = |c: &mut Context, texel: [u8; 4]| {
            // One texel at (0, 0), GL_RGBA bytes.
            let part = [tex.clone(), i(0), i(0), i(0), i(1), i(1), i(0x1908), i(0x1401)];
            call(c, "glTexSubImage2D", &[&part[..], &[Value::Blob(&texel)]].concat());
        };
        let first = c.shared.textures[&5].clone();
        let (address, version) = (Arc::as_ptr(&first), first.version);
        drop(first);
        // Nothing else holds it: changed in place, a new version.
        sub(&mut c, [0, 0, 255, 255]);
        let now = &c.shared.textures[&5];
        assert_eq!(Arc::as_ptr(now), address, "in place");
        assert_ne!(now.version, version);
        assert_eq!(now.levels[0].texels[0], Vec4::new(0.0, 0.0, 1.0, 1.0));
        // A draw of this frame holds it: the frame keeps what it drew with.
        triangle(&mut c, true);
        sub(&mut c, [0, 255, 0, 255]);
        let frame = c.frame();
        let drawn = frame.surfaces[frame.triangles[0].surface as usize].texturing.as_ref().unwrap();
        let now = &c.shared.textures[&5];
        assert!(!Arc::ptr_eq(&drawn.texture, now));
        assert_eq!(drawn.texture.levels[0].texels[0], Vec4::new(0.0, 0.0, 1.0, 1.0));
        assert_eq!(now.levels[0].texels[0], Vec4::new(0.0, 1.0, 0.0, 1.0));
        assert_ne!(drawn.texture.version, now.version);
        assert_eq!(c.errors.take(), 0);
    }

    #[test]
    fn an_image_of_the_same_size_is_decoded_into_the_last_ones_memory() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(6)]);
        let upload = |c: &mut Context, size: i64, format: i64, texel: [u8; 4]| {
            tex_image(c, 0, size, format, texel);
            let level = &c.shared.textures[&6].levels[0];
            (level.texels.capacity(), level.texels.clone())
        };
        upload(&mut c, 4, 0x1908, [255, 0, 0, 255]);
        let (_, texels) = upload(&mut c, 4, 0x1908, [0, 0, 255, 255]);
        assert_eq!(texels, vec![Vec4::new(0.0, 0.0, 1.0, 1.0); 16]);
        // Smaller: in the 4x4 image's memory (a new vector would hold 4).
        let (room, texels) = upload(&mut c, 2, 0x1908, [0, 255, 0, 255]);
        assert!(room >= 16, "room for {room}");
        assert_eq!(texels, vec![Vec4::new(0.0, 1.0, 0.0, 1.0); 4]);
        // A format glray cannot read: white, as before (nothing of the last image is left).
        let (_, texels) = upload(&mut c, 2, 0x8000, [0, 255, 0, 255]); // not a format
        assert_eq!(texels, vec![Vec4::ONE; 4]);
    }

    #[test]
    fn setting_a_texture_parameter_to_its_value_leaves_the_texture_as_it_is() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(3)]);
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2801), i(GL_LINEAR as i64)]); // MIN_FILTER LINEAR
        let held = c.shared.textures[&3].clone();
        // The same value again, and a parameter glray does not follow: the same texture (no
        // copy; the renderer sees the frame unchanged).
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2801), i(0x2601)]);
        call(&mut c, "glTexParameterf", &[tex.clone(), i(0x2801), f(f64::from(0x2601))]);
        call(&mut c, "glTexParameteri", &[tex.clone(), i(GL_TEXTURE_MAX_LEVEL as i64), i(4)]); // GL_TEXTURE_MAX_LEVEL
        assert!(Arc::ptr_eq(&held, &c.shared.textures[&3]));
        // A new value: a new texture with it, the held one as it was.
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2803), i(GL_CLAMP_TO_EDGE as i64)]); // WRAP_T CLAMP_TO_EDGE
        let now = &c.shared.textures[&3];
        assert!(!Arc::ptr_eq(&held, now));
        assert_eq!((now.wrap_t, held.wrap_t), (Wrap::ClampToEdge, Wrap::Repeat)); // GL_REPEAT held
        assert_eq!(now.min_filter, Filter::Linear);
        // A texture not made yet takes a value that is not its default.
        call(&mut c, "glBindTexture", &[tex.clone(), i(4)]);
        call(&mut c, "glTexParameteri", &[tex, i(0x2800), i(GL_NEAREST as i64)]); // MAG_FILTER NEAREST
        assert_eq!(c.shared.textures[&4].mag_filter, Filter::Nearest);
    }

    #[test]
    fn draws_share_a_lighting_while_its_state_is_unchanged() {
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_LIGHTING as i64)]);
        call(&mut c, "glEnable", &[i(GL_LIGHT0 as i64)]);
        triangle(&mut c, true);
        triangle(&mut c, true);
        // Each change below makes the next draw's lighting a new one.
        call(&mut c, "glLightf", &[i(GL_LIGHT0 as i64), i(GL_CONSTANT_ATTENUATION as i64), f(2.0)]); // GL_CONSTANT_ATTENUATION
        triangle(&mut c, true);
        call(&mut c, "glMaterialf", &[i(GL_FRONT_AND_BACK as i64), i(GL_SHININESS as i64), f(50.0)]); // GL_FRONT_AND_BACK, GL_SHININESS
        triangle(&mut c, true);
        call(&mut c, "glEnable", &[i(GL_LIGHT0 as i64 + 1)]);
        triangle(&mut c, true);
        call(&mut c, "glDisable", &[i(GL_LIGHT0 as i64 + 1)]);
        triangle(&mut c, true);
        call(&mut c, "glEnable", &[i(GL_COLOR_MATERIAL as i64)]);
        triangle(&mut c, true);
        call(&mut c, "glLightModeli", &[i(GL_LIGHT_MODEL_TWO_SIDE as i64), i(1)]);
        triangle(&mut c, true);
        let frame = c.frame();
        let used: Vec<u32> = frame.triangles.iter().map(|t| t.lighting).collect();
        assert_eq!(used, [0, 0, 1, 2, 3, 4, 5, 6]);
        let l = &frame.lightings;
        assert_eq!(l.len(), 7);
        assert_eq!(l[1].lights()[0].constant_attenuation, 2.0);
        assert_eq!(l[0].lights()[0].constant_attenuation, 1.0);
        assert_eq!((l[3].lights().len(), l[4].lights().len()), (2, 1));
        assert_eq!(l[4], l[2], "the same state again, after another");
        assert!(l[6].model().two_side && !l[5].model().two_side);
        // Each is what the state of its draw makes.
        assert_eq!(l[6], c.lighting_state());
    }

    #[test]
    fn a_textures_level_of_detail_bias_and_bounds_are_followed() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(1)]);
        tex_image(&mut c, 0, 2, GL_RGBA as i64, [255; 4]);
        call(&mut c, "glTexParameterf", &[tex.clone(), i(GL_TEXTURE_LOD_BIAS as i64), f(0.25)]); // GL_TEXTURE_LOD_BIAS
        call(&mut c, "glTexParameteri", &[tex.clone(), i(GL_TEXTURE_MAX_LOD as i64), i(3)]); // GL_TEXTURE_MAX_LOD
        let t = c.shared.textures[&1].clone();
        assert_eq!((t.lod.bias, t.lod.min, t.lod.max), (0.25, -1000.0, 3.0));
        // The same value again leaves the same texture.
        call(&mut c, "glTexParameterf", &[tex.clone(), i(0x8501), f(0.25)]);
        assert_eq!(c.shared.textures[&1].version, t.version);
        call(&mut c, "glTexParameterf", &[tex, i(GL_TEXTURE_MIN_LOD as i64), f(-2.0)]); // GL_TEXTURE_MIN_LOD
        assert_eq!(c.shared.textures[&1].lod.min, -2.0);
        assert_ne!(c.shared.textures[&1].version, t.version);
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
