//! The per-context GL state machine: follows the calls of one GL context (matrices, immediate
//! mode, client arrays and buffers, display lists, lighting, textures, fog, attribute stacks)
//! and turns what it draws into a `Frame` of lit, eye-space triangles. Commands arrive as
//! recorded calls (an `Op` and its `Value`s), the same from a trace file as from the live
//! library, so the two paths cannot drift apart.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DMat3, DMat4, DVec2, DVec3, DVec4, Vec2, Vec3, Vec4};
use glray_core::trace::{ArrayData, Value};

use crate::args::{self, GL_INT, GL_UNSIGNED_BYTE, GL_UNSIGNED_INT, GL_UNSIGNED_SHORT};
use crate::camera::Viewport;
use crate::error::{ErrorFlag, GlError, GlResult};
use crate::frame::{Fog, Frame, Lighting, Surface, Texturing, Triangle, View, NO_LIGHTING};
use crate::immediate::{Immediate, TEXCOORD_UNITS};
use crate::lighting::{light_vertex, Light, LightModel, Material};
use crate::lists::{DisplayLists, MAX_NESTING};
use crate::matrix::{from_gl, Matrices};
use crate::ops::{Attr, AttrForm, Op};
use crate::primitive::{assemble, GL_POLYGON, GL_QUADS, GL_QUAD_STRIP};
use crate::texture::{self, Level, Texture, Unpack};

// Enable caps.
const GL_LIGHTING: u32 = 0x0B50;
const GL_LIGHT0: u32 = 0x4000;
const GL_COLOR_MATERIAL: u32 = 0x0B57;
const GL_NORMALIZE: u32 = 0x0BA1;
const GL_RESCALE_NORMAL: u32 = 0x803A;
const GL_CULL_FACE: u32 = 0x0B44;
const GL_DEPTH_TEST: u32 = 0x0B71;
const GL_TEXTURE_2D: u32 = 0x0DE1;
const GL_FOG: u32 = 0x0B60;
const GL_BLEND: u32 = 0x0BE2;
const GL_ALPHA_TEST: u32 = 0x0BC0;
const GL_TEXTURE_GEN_S: u32 = 0x0C60;
const GL_TEXTURE_GEN_T: u32 = 0x0C61;
const GL_CLIP_PLANE0: u32 = 0x3000;
// Faces and modes.
const GL_FRONT: u32 = 0x0404;
const GL_BACK: u32 = 0x0405;
const GL_FRONT_AND_BACK: u32 = 0x0408;
const GL_CW: u32 = 0x0900;
const GL_CCW: u32 = 0x0901;
const GL_FLAT: u32 = 0x1D00;
const GL_SMOOTH: u32 = 0x1D01;
const GL_POINT: u32 = 0x1B00;
const GL_LINE: u32 = 0x1B01;
const GL_FILL: u32 = 0x1B02;
const GL_LESS: u32 = 0x0201;
const GL_ALWAYS: u32 = 0x0207;
// Material and light parameters.
const GL_AMBIENT: u32 = 0x1200;
const GL_DIFFUSE: u32 = 0x1201;
const GL_SPECULAR: u32 = 0x1202;
const GL_POSITION: u32 = 0x1203;
const GL_SPOT_DIRECTION: u32 = 0x1204;
const GL_SPOT_EXPONENT: u32 = 0x1205;
const GL_SPOT_CUTOFF: u32 = 0x1206;
const GL_CONSTANT_ATTENUATION: u32 = 0x1207;
const GL_LINEAR_ATTENUATION: u32 = 0x1208;
const GL_QUADRATIC_ATTENUATION: u32 = 0x1209;
const GL_EMISSION: u32 = 0x1600;
const GL_SHININESS: u32 = 0x1601;
const GL_AMBIENT_AND_DIFFUSE: u32 = 0x1602;
const GL_LIGHT_MODEL_LOCAL_VIEWER: u32 = 0x0B51;
const GL_LIGHT_MODEL_TWO_SIDE: u32 = 0x0B52;
const GL_LIGHT_MODEL_AMBIENT: u32 = 0x0B53;
const GL_LIGHT_MODEL_COLOR_CONTROL: u32 = 0x81F8;
const GL_SEPARATE_SPECULAR_COLOR: u32 = 0x81FA;
// Client arrays.
const GL_VERTEX_ARRAY: u32 = 0x8074;
const GL_NORMAL_ARRAY: u32 = 0x8075;
const GL_COLOR_ARRAY: u32 = 0x8076;
const GL_TEXTURE_COORD_ARRAY: u32 = 0x8078;
const GL_ARRAY_BUFFER: u32 = 0x8892;
const GL_ELEMENT_ARRAY_BUFFER: u32 = 0x8893;
// Textures, fog, pixel store.
const GL_TEXTURE_MIN_FILTER: u32 = 0x2801;
const GL_TEXTURE_MAG_FILTER: u32 = 0x2800;
const GL_TEXTURE_WRAP_S: u32 = 0x2802;
const GL_TEXTURE_WRAP_T: u32 = 0x2803;
const GL_TEXTURE_ENV_MODE: u32 = 0x2200;
const GL_TEXTURE_ENV_COLOR: u32 = 0x2201;
const GL_MODULATE: u32 = 0x2100;
const GL_TEXTURE_GEN_MODE: u32 = 0x2500;
const GL_OBJECT_PLANE: u32 = 0x2501;
const GL_EYE_PLANE: u32 = 0x2502;
const GL_OBJECT_LINEAR: u32 = 0x2401;
const GL_EYE_LINEAR: u32 = 0x2400;
const GL_SPHERE_MAP: u32 = 0x2402;
const GL_S: u32 = 0x2000;
const GL_T: u32 = 0x2001;
const GL_FOG_MODE: u32 = 0x0B65;
const GL_FOG_DENSITY: u32 = 0x0B62;
const GL_FOG_START: u32 = 0x0B63;
const GL_FOG_END: u32 = 0x0B64;
const GL_FOG_COLOR: u32 = 0x0B66;
const GL_EXP: u32 = 0x0800;
const GL_UNPACK_ROW_LENGTH: u32 = 0x0CF2;
const GL_UNPACK_SKIP_ROWS: u32 = 0x0CF3;
const GL_UNPACK_SKIP_PIXELS: u32 = 0x0CF4;
const GL_UNPACK_ALIGNMENT: u32 = 0x0CF5;
const GL_TEXTURE0: u32 = 0x84C0;
// glClear and glPushAttrib bits.
const GL_COLOR_BUFFER_BIT: u32 = 0x4000;
const GL_CURRENT_BIT: u32 = 0x0001;
const GL_POINT_BIT: u32 = 0x0002;
const GL_LINE_BIT: u32 = 0x0004;
const GL_POLYGON_BIT: u32 = 0x0008;
const GL_LIGHTING_BIT: u32 = 0x0040;
const GL_FOG_BIT: u32 = 0x0080;
const GL_DEPTH_BUFFER_BIT: u32 = 0x0100;
const GL_VIEWPORT_BIT: u32 = 0x0800;
const GL_TRANSFORM_BIT: u32 = 0x1000;
const GL_ENABLE_BIT: u32 = 0x2000;
const GL_TEXTURE_BIT: u32 = 0x40000;
const MAX_ATTRIB_DEPTH: usize = 16;

/// Texture coordinate generation of one coordinate (s or t).
#[derive(Debug, Clone, Copy, PartialEq)]
struct TexGen {
    enabled: bool,
    mode: u32,
    object_plane: DVec4,
    eye_plane: DVec4,
}

/// The server state glPushAttrib saves, grouped by the attribute bit that saves it.
#[derive(Debug, Clone)]
struct State {
    // GL_LIGHTING_BIT
    lighting: bool,
    lights: [Light; 8],
    model: LightModel,
    materials: [Material; 2],
    color_material: bool,
    color_material_face: u32,
    color_material_mode: u32,
    flat: bool,
    // GL_TRANSFORM_BIT
    normalize: bool,
    rescale_normal: bool,
    clip_planes: [(bool, DVec4); 6],
    // GL_POLYGON_BIT
    cull: bool,
    cull_face: u32,
    front_ccw: bool,
    polygon_mode: [u32; 2],
    // GL_DEPTH_BUFFER_BIT
    depth_test: bool,
    depth_func: u32,
    depth_mask: bool,
    // GL_VIEWPORT_BIT
    viewport: Viewport,
    depth_range: (f64, f64),
    // GL_COLOR_BUFFER_BIT
    clear_color: Vec4,
    blend: bool,
    blend_func: (u32, u32),
    alpha_test: bool,
    alpha_func: (u32, f32),
    // GL_TEXTURE_BIT
    texture_2d: bool,
    bound_texture: u32,
    env_mode: u32,
    env_color: Vec4,
    texgen: [TexGen; 2],
    // GL_FOG_BIT
    fog_enabled: bool,
    fog: Fog,
    // GL_LINE_BIT, GL_POINT_BIT
    line_width: f64,
    point_size: f64,
}

impl Default for State {
    fn default() -> Self {
        let texgen = TexGen { enabled: false, mode: GL_EYE_LINEAR, object_plane: DVec4::X, eye_plane: DVec4::X };
        State {
            lighting: false,
            lights: std::array::from_fn(Light::new),
            model: LightModel::default(),
            materials: [Material::default(); 2],
            color_material: false,
            color_material_face: GL_FRONT_AND_BACK,
            color_material_mode: GL_AMBIENT_AND_DIFFUSE,
            flat: false,
            normalize: false,
            rescale_normal: false,
            clip_planes: [(false, DVec4::ZERO); 6],
            cull: false,
            cull_face: GL_BACK,
            front_ccw: true,
            polygon_mode: [GL_FILL; 2],
            depth_test: false,
            depth_func: GL_LESS,
            depth_mask: true,
            viewport: Viewport { x: 0, y: 0, width: 0, height: 0 },
            depth_range: (0.0, 1.0),
            clear_color: Vec4::ZERO,
            blend: false,
            blend_func: (1, 0),
            alpha_test: false,
            alpha_func: (GL_ALWAYS, 0.0),
            texture_2d: false,
            bound_texture: 0,
            env_mode: GL_MODULATE,
            env_color: Vec4::ZERO,
            texgen: [texgen, TexGen { object_plane: DVec4::Y, eye_plane: DVec4::Y, ..texgen }],
            fog_enabled: false,
            fog: Fog { mode: GL_EXP, density: 1.0, start: 0.0, end: 1.0, color: Vec4::ZERO },
            line_width: 1.0,
            point_size: 1.0,
        }
    }
}

impl State {
    /// glPopAttrib: takes back the groups `mask` saved.
    fn restore(&mut self, mask: u32, saved: State) {
        let s = saved;
        if mask & (GL_LIGHTING_BIT | GL_ENABLE_BIT) != 0 {
            self.lighting = s.lighting;
            self.color_material = s.color_material;
            for (l, o) in self.lights.iter_mut().zip(&s.lights) {
                l.enabled = o.enabled;
            }
        }
        if mask & GL_LIGHTING_BIT != 0 {
            self.lights = s.lights;
            self.model = s.model;
            self.materials = s.materials;
            self.color_material_face = s.color_material_face;
            self.color_material_mode = s.color_material_mode;
            self.flat = s.flat;
        }
        if mask & (GL_TRANSFORM_BIT | GL_ENABLE_BIT) != 0 {
            self.normalize = s.normalize;
            self.rescale_normal = s.rescale_normal;
            for (p, o) in self.clip_planes.iter_mut().zip(&s.clip_planes) {
                p.0 = o.0;
            }
        }
        if mask & GL_TRANSFORM_BIT != 0 {
            self.clip_planes = s.clip_planes;
        }
        if mask & (GL_POLYGON_BIT | GL_ENABLE_BIT) != 0 {
            self.cull = s.cull;
        }
        if mask & GL_POLYGON_BIT != 0 {
            self.cull_face = s.cull_face;
            self.front_ccw = s.front_ccw;
            self.polygon_mode = s.polygon_mode;
        }
        if mask & (GL_DEPTH_BUFFER_BIT | GL_ENABLE_BIT) != 0 {
            self.depth_test = s.depth_test;
        }
        if mask & GL_DEPTH_BUFFER_BIT != 0 {
            self.depth_func = s.depth_func;
            self.depth_mask = s.depth_mask;
        }
        if mask & GL_VIEWPORT_BIT != 0 {
            self.viewport = s.viewport;
            self.depth_range = s.depth_range;
        }
        if mask & (GL_COLOR_BUFFER_BIT | GL_ENABLE_BIT) != 0 {
            self.blend = s.blend;
            self.alpha_test = s.alpha_test;
        }
        if mask & GL_COLOR_BUFFER_BIT != 0 {
            self.clear_color = s.clear_color;
            self.blend_func = s.blend_func;
            self.alpha_func = s.alpha_func;
        }
        if mask & (GL_TEXTURE_BIT | GL_ENABLE_BIT) != 0 {
            self.texture_2d = s.texture_2d;
            self.texgen[0].enabled = s.texgen[0].enabled;
            self.texgen[1].enabled = s.texgen[1].enabled;
        }
        if mask & GL_TEXTURE_BIT != 0 {
            self.bound_texture = s.bound_texture;
            self.env_mode = s.env_mode;
            self.env_color = s.env_color;
            self.texgen = s.texgen;
        }
        if mask & (GL_FOG_BIT | GL_ENABLE_BIT) != 0 {
            self.fog_enabled = s.fog_enabled;
        }
        if mask & GL_FOG_BIT != 0 {
            self.fog = s.fog;
        }
        if mask & GL_LINE_BIT != 0 {
            self.line_width = s.line_width;
        }
        if mask & GL_POINT_BIT != 0 {
            self.point_size = s.point_size;
        }
    }
}

/// A vertex after the vertex stage: eye position, lit colours of both faces, texture
/// coordinates.
#[derive(Debug, Clone, Copy)]
struct Out {
    eye: DVec4,
    colors: [DVec4; 2],
    secondary: [DVec4; 2],
    tex: DVec4,
    /// Eye-space normal as lighting used it, and the current colour.
    normal: DVec3,
    base: DVec4,
}

/// A vertex as an array draw fetched it, before the vertex stage (what a list keeps of a
/// draw, so that buffers and client memory changed later do not change the list).
#[derive(Debug, Clone, Copy)]
struct Fetched {
    position: Option<DVec4>,
    normal: Option<DVec3>,
    color: Option<DVec4>,
    tex: Option<DVec4>,
}

/// An argument kept by a display list.
#[derive(Debug, Clone)]
enum Kept {
    Int(i64),
    Float(f64),
    Bytes(Vec<u8>),
    Null,
}

/// What a display list holds.
#[derive(Debug, Clone)]
enum Item {
    Call(Op, u32, Vec<Kept>),
    /// An array draw, resolved to its vertices at compile time.
    Draw(u32, Vec<Fetched>),
}

/// One array's pointer state, for arrays in buffer objects (client memory arrives with the
/// draw, in the trace's arrays event).
#[derive(Debug, Clone, Copy, Default)]
struct ArrayPointer {
    enabled: bool,
    size: i32,
    ty: u32,
    stride: i32,
    offset: u64,
    buffer: u32,
}

/// An array a draw reads: its memory and layout, from element `first` on.
struct Source<'a> {
    size: usize,
    ty: u32,
    stride: usize,
    first: u64,
    bytes: &'a [u8],
}

impl Source<'_> {
    fn fetch(&self, i: u64, normalized: bool) -> Option<DVec4> {
        let at = usize::try_from(i.checked_sub(self.first)?).ok()?.checked_mul(self.stride)?;
        let b = self.bytes.get(at..)?;
        let mut v = DVec4::new(0.0, 0.0, 0.0, 1.0);
        for c in 0..self.size.min(4) {
            let x = args::element(b, self.ty, c)?;
            v[c] = if normalized { args::normalize(x, self.ty) } else { x };
        }
        Some(v)
    }
}

/// Client state: array pointers, buffer bindings, pixel unpacking.
#[derive(Debug, Clone, Default)]
struct Client {
    vertex: ArrayPointer,
    normal: ArrayPointer,
    color: ArrayPointer,
    texcoord: [ArrayPointer; TEXCOORD_UNITS],
    active_texcoord: usize,
    array_buffer: u32,
    element_buffer: u32,
    unpack: Unpack,
}

/// One GL context's state, and the frame it is drawing.
pub struct Context {
    pub errors: ErrorFlag,
    pub matrices: Matrices,
    imm: Immediate,
    /// Vertices of the open glBegin, after the vertex stage.
    open: Vec<Out>,
    lists: DisplayLists<Item>,
    nesting: usize,
    s: State,
    attrib_stack: Vec<(u32, State, crate::immediate::Current)>,
    client: Client,
    buffers: HashMap<u32, Vec<u8>>,
    textures: HashMap<u32, Arc<Texture>>,
    /// Client arrays of the next draw (the trace's arrays event that precedes it).
    arrays: Vec<ArrayData<'static>>,
    array_bytes: Vec<Vec<u8>>,
    frame: Frame,
    sequence: u32,
    normal_matrix: Option<(DMat4, DMat3)>,
    /// A shader program is in use: draws go through shaders capture cannot follow.
    programmable: bool,
    /// Counts changes to the frame (draws, clears), so that a frame is presented once.
    revision: u64,
    /// The framebuffer object draws go to (0: the window's or OSMesa's buffer).
    framebuffer: u32,
}

impl Default for Context {
    fn default() -> Self {
        Context {
            errors: ErrorFlag::default(),
            matrices: Matrices::default(),
            imm: Immediate::default(),
            open: Vec::new(),
            lists: DisplayLists::default(),
            nesting: 0,
            s: State::default(),
            attrib_stack: Vec::new(),
            client: Client { unpack: Unpack::default(), ..Client::default() },
            buffers: HashMap::new(),
            textures: HashMap::new(),
            arrays: Vec::new(),
            array_bytes: Vec::new(),
            frame: Frame { depth_range: (0.0, 1.0), ..Frame::default() },
            sequence: 0,
            normal_matrix: None,
            programmable: false,
            revision: 0,
            framebuffer: 0,
        }
    }
}

fn vec4(v: DVec4) -> Vec4 {
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
        self.array_bytes = arrays.iter().map(|a| a.bytes.to_vec()).collect();
        self.arrays = arrays.iter().map(|a| ArrayData { bytes: &[], ..a.clone() }).collect();
    }

    /// The frame drawn since the last one was taken; the context starts a new one.
    pub fn take_frame(&mut self) -> Frame {
        let next = Frame {
            width: self.frame.width,
            height: self.frame.height,
            clear_color: self.frame.clear_color,
            depth_range: self.s.depth_range,
            ..Frame::default()
        };
        self.sequence = 0;
        std::mem::replace(&mut self.frame, next)
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
        !self.programmable && self.lists.compiling().is_none() && self.framebuffer == 0
    }

    /// Whether a display list is being compiled.
    pub fn compiling(&self) -> bool {
        self.lists.compiling().is_some()
    }

    /// The frame so far.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Follows one call. Errors go to the context's error flag, as GL would raise them.
    pub fn call(&mut self, op: Op, ty: u32, a: &[Value]) {
        if let Some((_, execute)) = self.lists.compiling() {
            if op.compiled() && !matches!(op, Op::NewList | Op::EndList) {
                for item in self.compile_items(op, ty, a) {
                    self.lists.compile(item);
                }
                if !execute {
                    self.arrays.clear();
                    return;
                }
            }
        }
        let r = self.execute(op, ty, a);
        self.errors.record(r);
    }

    fn compile_items(&mut self, op: Op, ty: u32, a: &[Value]) -> Vec<Item> {
        if matches!(
            op,
            Op::DrawArrays | Op::DrawElements | Op::DrawRangeElements | Op::MultiDrawArrays | Op::MultiDrawElements
        ) {
            // Client data is copied at compile time: keep the vertices the draw would fetch.
            let runs = self.fetch_draw(op, a).unwrap_or_default();
            return runs.into_iter().map(|(mode, verts)| Item::Draw(mode, verts)).collect();
        }
        vec![Item::Call(op, ty, a.iter().map(keep).collect())]
    }

    fn run_list(&mut self, list: u32) -> GlResult {
        if self.nesting >= MAX_NESTING {
            return Ok(()); // GL ignores calls nested deeper
        }
        let Some(items) = self.lists.get(list) else { return Ok(()) };
        self.nesting += 1;
        for item in items.iter() {
            match item {
                Item::Call(op, ty, kept) => {
                    let a: Vec<Value> = kept.iter().map(unkeep).collect();
                    let r = self.execute(*op, *ty, &a);
                    self.errors.record(r);
                }
                Item::Draw(mode, verts) => self.draw_fetched(*mode, verts),
            }
        }
        self.nesting -= 1;
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
            GL_DEPTH_TEST => s.depth_test = on,
            GL_TEXTURE_2D => s.texture_2d = on,
            GL_FOG => s.fog_enabled = on,
            GL_BLEND => s.blend = on,
            GL_ALPHA_TEST => s.alpha_test = on,
            GL_TEXTURE_GEN_S => s.texgen[0].enabled = on,
            GL_TEXTURE_GEN_T => s.texgen[1].enabled = on,
            c if (GL_CLIP_PLANE0..GL_CLIP_PLANE0 + 6).contains(&c) => {
                s.clip_planes[(c - GL_CLIP_PLANE0) as usize].0 = on
            }
            _ => {}
        }
    }

    fn client_array(&mut self, cap: u32) -> Option<&mut ArrayPointer> {
        let c = &mut self.client;
        Some(match cap {
            GL_VERTEX_ARRAY => &mut c.vertex,
            GL_NORMAL_ARRAY => &mut c.normal,
            GL_COLOR_ARRAY => &mut c.color,
            GL_TEXTURE_COORD_ARRAY => &mut c.texcoord[c.active_texcoord],
            _ => return None,
        })
    }

    fn set_pointer(&mut self, cap: u32, size: i32, ty: u32, stride: i32, a: &Value) {
        let buffer = self.client.array_buffer;
        let offset = match a {
            Value::Offset(o) => *o,
            _ => 0,
        };
        if let Some(p) = self.client_array(cap) {
            *p = ArrayPointer { enabled: p.enabled, size, ty, stride, offset, buffer };
        }
    }

    fn execute(&mut self, op: Op, ty: u32, a: &[Value]) -> GlResult {
        // Commands allowed between glBegin and glEnd (GL 2.1 section 2.6.3).
        let inside_ok = matches!(
            op,
            Op::Attr(_) | Op::Material | Op::End | Op::CallList | Op::CallLists | Op::ArrayElement | Op::GetError
        );
        if !inside_ok {
            self.imm.outside()?;
        }
        match op {
            Op::Attr(form) => self.attribute(form, a)?,
            Op::Begin => self.imm.begin(args::uint(a, 0))?,
            Op::End => {
                let batch = self.imm.end()?;
                let verts = std::mem::take(&mut self.open);
                self.draw(batch.mode, &verts);
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
                self.draw(GL_POLYGON, &verts);
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
                let (face, mode) = (args::uint(a, 0), args::uint(a, 1));
                if !matches!(face, GL_FRONT | GL_BACK | GL_FRONT_AND_BACK)
                    || !matches!(mode, GL_EMISSION | GL_AMBIENT | GL_DIFFUSE | GL_SPECULAR | GL_AMBIENT_AND_DIFFUSE)
                {
                    return Err(GlError::InvalidEnum);
                }
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
            Op::CullFace => match args::uint(a, 0) {
                f @ (GL_FRONT | GL_BACK | GL_FRONT_AND_BACK) => self.s.cull_face = f,
                _ => return Err(GlError::InvalidEnum),
            },
            Op::ClearColor => {
                self.s.clear_color =
                    Vec4::from_array(std::array::from_fn(|i| args::float(a, i) as f32)).clamp(Vec4::ZERO, Vec4::ONE)
            }
            Op::Clear => {
                self.revision += 1;
                if args::uint(a, 0) & GL_DEPTH_BUFFER_BIT != 0 {
                    self.frame.depth_cleared = true;
                }
                if args::uint(a, 0) & GL_COLOR_BUFFER_BIT != 0 {
                    // What was drawn before is covered: the frame starts again.
                    self.frame.unsupported_draws = 0;
                    self.frame.triangles.clear();
                    self.frame.surfaces.clear();
                    self.frame.lightings.clear();
                    self.frame.projection = None;
                    self.frame.viewport = None;
                    self.frame.cameras.clear();
                    self.frame.clear_color = self.s.clear_color;
                    self.frame.cleared = true;
                }
            }
            Op::NewList => self.lists.new_list(args::uint(a, 0), args::uint(a, 1))?,
            Op::EndList => self.lists.end_list()?,
            Op::CallList => self.run_list(args::uint(a, 0))?,
            Op::CallLists => {
                let names = self.lists.call_lists_names(args::int(a, 0) as i32, args::uint(a, 1), args::bytes(a, 2))?;
                for n in names {
                    self.run_list(n)?;
                }
            }
            Op::ListBase => self.lists.list_base(args::uint(a, 0)),
            Op::GenLists => {
                self.lists.gen_lists(args::int(a, 0) as i32)?;
            }
            Op::DeleteLists => self.lists.delete_lists(args::uint(a, 0), args::int(a, 1) as i32)?,
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
                for (mode, verts) in self.fetch_draw(op, a)? {
                    self.draw_fetched(mode, &verts);
                }
            }
            Op::ArrayElement => {}
            Op::BindBuffer => match args::uint(a, 0) {
                GL_ARRAY_BUFFER => self.client.array_buffer = args::uint(a, 1),
                GL_ELEMENT_ARRAY_BUFFER => self.client.element_buffer = args::uint(a, 1),
                _ => {}
            },
            Op::BufferData => {
                if let Some(name) = self.bound_buffer(args::uint(a, 0)) {
                    let size = args::int(a, 1).max(0) as usize;
                    let mut data = args::bytes(a, 2).to_vec();
                    data.resize(size.min(1 << 31), 0);
                    self.buffers.insert(name, data);
                }
            }
            Op::BufferSubData => {
                if let Some(name) = self.bound_buffer(args::uint(a, 0)) {
                    let offset = args::int(a, 1).max(0) as usize;
                    let data = args::bytes(a, 3);
                    let buf = self.buffers.entry(name).or_default();
                    if let Some(dst) = buf.get_mut(offset..offset + data.len()) {
                        dst.copy_from_slice(data);
                    }
                }
            }
            Op::DeleteBuffers => {
                for name in args::array(args::bytes(a, 1), GL_UNSIGNED_INT, args::int(a, 0).max(0) as usize) {
                    self.buffers.remove(&(name as u32));
                }
            }
            Op::BindTexture => {
                if args::uint(a, 0) == GL_TEXTURE_2D {
                    self.s.bound_texture = args::uint(a, 1);
                }
            }
            Op::DeleteTextures => {
                for name in args::array(args::bytes(a, 1), GL_UNSIGNED_INT, args::int(a, 0).max(0) as usize) {
                    let name = name as u32;
                    self.textures.remove(&name);
                    if self.s.bound_texture == name {
                        self.s.bound_texture = 0;
                    }
                }
            }
            Op::TexImage2D => self.tex_image(a, false)?,
            Op::TexSubImage2D => self.tex_image(a, true)?,
            Op::TexParameter => {
                if args::uint(a, 0) == GL_TEXTURE_2D {
                    let v = self.floats(a, 2, ty, 1).first().copied().unwrap_or(0.0) as u32;
                    let t = self.texture_mut();
                    match args::uint(a, 1) {
                        GL_TEXTURE_MIN_FILTER => t.min_filter = v,
                        GL_TEXTURE_MAG_FILTER => t.mag_filter = v,
                        GL_TEXTURE_WRAP_S => t.wrap_s = v,
                        GL_TEXTURE_WRAP_T => t.wrap_t = v,
                        _ => {}
                    }
                }
            }
            Op::TexEnv => match args::uint(a, 1) {
                GL_TEXTURE_ENV_MODE => {
                    self.s.env_mode = self.floats(a, 2, ty, 1).first().copied().unwrap_or(0.0) as u32
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
                    GL_FOG_MODE => f.mode = first as u32,
                    GL_FOG_DENSITY => f.density = first as f32,
                    GL_FOG_START => f.start = first as f32,
                    GL_FOG_END => f.end = first as f32,
                    GL_FOG_COLOR => f.color = color,
                    _ => {}
                }
            }
            Op::BlendFunc => self.s.blend_func = (args::uint(a, 0), args::uint(a, 1)),
            Op::AlphaFunc => self.s.alpha_func = (args::uint(a, 0), args::float(a, 1).clamp(0.0, 1.0) as f32),
            Op::DepthFunc => self.s.depth_func = args::uint(a, 0),
            Op::DepthMask => self.s.depth_mask = args::int(a, 0) != 0,
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
                if let Ok(p) = <[f64; 4]>::try_from(self.floats(a, 1, args::GL_DOUBLE, 4)) {
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
                if matches!(args::uint(a, 0), 0x8D40 | 0x8CA9) {
                    self.framebuffer = args::uint(a, 1);
                }
            }
            Op::VertexAttribPointer => {}
        }
        Ok(())
    }

    fn bound_buffer(&self, target: u32) -> Option<u32> {
        match target {
            GL_ARRAY_BUFFER => Some(self.client.array_buffer),
            GL_ELEMENT_ARRAY_BUFFER => Some(self.client.element_buffer),
            _ => None,
        }
        .filter(|n| *n != 0)
    }

    fn texture_mut(&mut self) -> &mut Texture {
        let t = self.textures.entry(self.s.bound_texture).or_default();
        Arc::make_mut(t)
    }

    fn tex_image(&mut self, a: &[Value], sub: bool) -> GlResult {
        if args::uint(a, 0) != GL_TEXTURE_2D {
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
            let t = self.texture_mut();
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
        let texels = texture::decode(w, h, format, ty, &unpack, data)
            .map(|t| t.into_iter().map(|c| texture::to_base(c, base)).collect())
            .unwrap_or_else(|| vec![Vec4::ONE; w * h]);
        let t = self.texture_mut();
        if level == 0 {
            t.base_format = base;
        }
        if t.levels.len() <= level {
            t.levels.resize(level + 1, Level::default());
        }
        t.levels[level] = Level { width: w, height: h, texels };
        Ok(())
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
                0x1603 => {} // GL_COLOR_INDEXES
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

    fn attribute(&mut self, f: AttrForm, a: &[Value]) -> GlResult {
        let (first, unit) = match f.attr {
            Attr::MultiTexCoord => {
                let unit = args::uint(a, 0).wrapping_sub(GL_TEXTURE0) as usize;
                if unit >= TEXCOORD_UNITS {
                    return Err(GlError::InvalidEnum);
                }
                (1, unit)
            }
            _ => (0, 0),
        };
        let raw: Vec<f64> = if f.vector {
            args::array(args::bytes(a, first), f.ty, f.n)
        } else {
            (first..first + f.n).map(|i| args::float(a, i)).collect()
        };
        let get = |k: usize, default: f64| raw.get(k).copied().unwrap_or(default);
        let norm = |k: usize, default: f64| raw.get(k).map_or(default, |x| args::normalize(*x, f.ty));
        match f.attr {
            Attr::Vertex => {
                let p = DVec4::new(
                    get(0, 0.0),
                    get(1, 0.0),
                    if f.n > 2 { get(2, 0.0) } else { 0.0 },
                    if f.n > 3 { get(3, 1.0) } else { 1.0 },
                );
                if self.imm.inside() {
                    let out = self.vertex_stage(p);
                    self.open.push(out);
                    self.imm.vertex(p);
                }
            }
            Attr::Normal => self.imm.normal(DVec3::new(norm(0, 0.0), norm(1, 0.0), norm(2, 1.0))),
            Attr::Color => {
                let alpha = if f.n > 3 { norm(3, 1.0) } else { 1.0 };
                self.imm.color(DVec4::new(norm(0, 0.0), norm(1, 0.0), norm(2, 0.0), alpha));
            }
            Attr::TexCoord | Attr::MultiTexCoord => {
                let t = DVec4::new(
                    get(0, 0.0),
                    if f.n > 1 { get(1, 0.0) } else { 0.0 },
                    if f.n > 2 { get(2, 0.0) } else { 0.0 },
                    if f.n > 3 { get(3, 1.0) } else { 1.0 },
                );
                self.imm.tex_coord(unit, t)?;
            }
            Attr::SecondaryColor => {}
            Attr::EdgeFlag => self.imm.edge_flag(get(0, 1.0) != 0.0),
        }
        Ok(())
    }

    /// The inverse transpose of the modelview's upper 3x3, cached per modelview.
    fn normal_matrix(&mut self, mv: &DMat4) -> DMat3 {
        if let Some((m, n)) = &self.normal_matrix {
            if m == mv {
                return *n;
            }
        }
        let n = DMat3::from_mat4(*mv).inverse().transpose();
        self.normal_matrix = Some((*mv, n));
        n
    }

    /// The lighting state of the moment, as a frame keeps it.
    fn lighting_state(&self) -> Lighting {
        let s = &self.s;
        Lighting {
            lights: s.lights.iter().filter(|l| l.enabled).copied().collect(),
            model: s.model,
            materials: s.materials,
            color_material: s.color_material.then_some((s.color_material_face, s.color_material_mode)),
        }
    }

    /// The fixed-function vertex stage: eye position, lighting of both faces, texture
    /// coordinates (texgen, texture matrix).
    fn vertex_stage(&mut self, object: DVec4) -> Out {
        let mv = *self.matrices.modelview.top();
        let eye = mv * object;
        let cur = self.imm.current;
        let s = &self.s;
        let mut normal = DVec3::Z;
        let (colors, secondary) = if s.lighting {
            let nm = self.normal_matrix(&mv);
            let s = &self.s;
            let mut n = nm * cur.normal;
            if s.normalize {
                n = n.normalize_or_zero();
            } else if s.rescale_normal {
                let len = DMat3::from_mat4(mv).inverse().row(2).length();
                if len > 0.0 {
                    n /= len;
                }
            }
            normal = n;
            let mats = self.lighting_state().materials(cur.color);
            let s = &self.s;
            let p = eye.truncate() / if eye.w != 0.0 { eye.w } else { 1.0 };
            let (f0, f1) = light_vertex(p, n, &mats[0], &s.lights, &s.model);
            let (b0, b1) = if s.model.two_side { light_vertex(p, -n, &mats[1], &s.lights, &s.model) } else { (f0, f1) };
            ([f0, b0], [f1, b1])
        } else {
            let c = cur.color.clamp(DVec4::ZERO, DVec4::ONE);
            ([c, c], [DVec4::ZERO; 2])
        };
        let s = &self.s;
        let mut tex = cur.texcoords[0];
        for (k, g) in s.texgen.iter().enumerate() {
            if g.enabled {
                tex[k] = match g.mode {
                    GL_OBJECT_LINEAR => g.object_plane.dot(object),
                    GL_EYE_LINEAR => g.eye_plane.dot(eye),
                    GL_SPHERE_MAP => {
                        let nm = DMat3::from_mat4(mv).inverse().transpose();
                        let n = (nm * cur.normal).normalize_or_zero();
                        let u = (eye.truncate() / if eye.w != 0.0 { eye.w } else { 1.0 }).normalize_or_zero();
                        let r = u - 2.0 * n.dot(u) * n;
                        let m = 2.0 * (r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0)).sqrt();
                        if m == 0.0 {
                            0.5
                        } else {
                            r[k] / m + 0.5
                        }
                    }
                    _ => tex[k],
                };
            }
        }
        let tex = *self.matrices.texture[0].top() * tex;
        Out { eye, colors, secondary, tex, normal, base: cur.color }
    }

    /// The vertices an array draw fetches, one list per primitive run.
    fn fetch_draw(&mut self, op: Op, a: &[Value]) -> GlResult<Vec<(u32, Vec<Fetched>)>> {
        let mode = args::uint(a, 0);
        if mode > GL_POLYGON {
            return Err(GlError::InvalidEnum);
        }
        let runs: Vec<Vec<u64>> = match op {
            Op::DrawArrays => {
                let (first, count) = (args::int(a, 1), args::int(a, 2));
                if first < 0 || count < 0 {
                    return Err(GlError::InvalidValue);
                }
                vec![(first as u64..(first + count) as u64).collect()]
            }
            Op::MultiDrawArrays => {
                let n = args::int(a, 3).max(0) as usize;
                let firsts = args::array(args::bytes(a, 1), GL_INT, n);
                let counts = args::array(args::bytes(a, 2), GL_INT, n);
                firsts.iter().zip(&counts).map(|(f, c)| (*f as u64..(*f + c.max(0.0)) as u64).collect()).collect()
            }
            Op::DrawElements | Op::DrawRangeElements => {
                let (count, ty, idx) = if op == Op::DrawElements { (1, 2, 3) } else { (3, 4, 5) };
                let count = args::int(a, count);
                if count < 0 {
                    return Err(GlError::InvalidValue);
                }
                let ty = args::uint(a, ty);
                if !matches!(ty, GL_UNSIGNED_BYTE | GL_UNSIGNED_SHORT | GL_UNSIGNED_INT) {
                    return Err(GlError::InvalidEnum);
                }
                vec![self.indices(a.get(idx).unwrap_or(&Value::Null), ty, count as usize)]
            }
            Op::MultiDrawElements => {
                // The per-draw index pointers are not recorded as memory: not captured yet.
                Vec::new()
            }
            _ => Vec::new(),
        };
        let sources = self.sources();
        let out = runs
            .into_iter()
            .map(|run| {
                let verts = run
                    .iter()
                    .map(|&i| Fetched {
                        position: sources[0].as_ref().and_then(|s| s.fetch(i, false)),
                        normal: sources[1].as_ref().and_then(|s| s.fetch(i, true)).map(|n| n.truncate()),
                        color: sources[2].as_ref().and_then(|s| s.fetch(i, true)),
                        tex: sources[3].as_ref().and_then(|s| s.fetch(i, false)),
                    })
                    .collect();
                (mode, verts)
            })
            .collect();
        Ok(out)
    }

    fn indices(&self, v: &Value, ty: u32, count: usize) -> Vec<u64> {
        let (bytes, start): (&[u8], usize) = match v {
            Value::Offset(o) | Value::Opaque(o) if self.client.element_buffer != 0 => {
                (self.buffers.get(&self.client.element_buffer).map_or(&[][..], |b| &b[..]), *o as usize)
            }
            Value::Blob(b) => (b, 0),
            _ => (&[], 0),
        };
        let size = args::type_size(ty).unwrap_or(4);
        let bytes = bytes.get(start..).unwrap_or(&[]);
        (0..count)
            .map_while(|i| args::element(bytes, ty, i))
            .map(|x| x as u64)
            .take(count)
            .take_while(|_| size > 0)
            .collect()
    }

    /// Where each array (vertex, normal, color, texcoord 0) of the next draw comes from.
    fn sources(&self) -> [Option<Source<'_>>; 4] {
        let kinds = [
            (glray_core::trace::array_kind::VERTEX, &self.client.vertex),
            (glray_core::trace::array_kind::NORMAL, &self.client.normal),
            (glray_core::trace::array_kind::COLOR, &self.client.color),
            (glray_core::trace::array_kind::TEXCOORD, &self.client.texcoord[0]),
        ];
        kinds.map(|(kind, p)| {
            // Client memory recorded with the draw.
            if let Some((i, d)) =
                self.arrays.iter().enumerate().find(|(_, d)| d.kind == kind && (kind != 3 || d.index == 0))
            {
                let elem = args::type_size(d.gl_type)? * d.size.max(0) as usize;
                let stride = if d.stride > 0 { d.stride as usize } else { elem };
                return Some(Source {
                    size: d.size.max(0) as usize,
                    ty: d.gl_type,
                    stride,
                    first: d.first,
                    bytes: &self.array_bytes[i],
                });
            }
            // A buffer object.
            if p.enabled && p.buffer != 0 {
                let buf = self.buffers.get(&p.buffer)?;
                let elem = args::type_size(p.ty)? * p.size.max(0) as usize;
                let stride = if p.stride > 0 { p.stride as usize } else { elem };
                return Some(Source {
                    size: p.size.max(0) as usize,
                    ty: p.ty,
                    stride,
                    first: 0,
                    bytes: buf.get(p.offset as usize..).unwrap_or(&[]),
                });
            }
            None
        })
    }

    /// Runs fetched vertices through the vertex stage as one draw.
    fn draw_fetched(&mut self, mode: u32, verts: &[Fetched]) {
        let saved = self.imm.current;
        let mut outs = Vec::with_capacity(verts.len());
        for v in verts {
            if let Some(n) = v.normal {
                self.imm.current.normal = n;
            }
            if let Some(c) = v.color {
                self.imm.current.color = c;
            }
            if let Some(t) = v.tex {
                self.imm.current.texcoords[0] = t;
            }
            if let Some(p) = v.position {
                outs.push(self.vertex_stage(p));
            }
        }
        // GL leaves the current values of enabled arrays undefined after a draw; Mesa keeps
        // the last one.
        if verts.iter().all(|v| v.color.is_none()) {
            self.imm.current = saved;
        }
        self.arrays.clear();
        self.draw(mode, &outs);
    }

    fn surface(&mut self) -> u32 {
        let s = &self.s;
        let texturing = if s.texture_2d {
            self.textures.get(&s.bound_texture).filter(|t| t.complete()).map(|t| Texturing {
                texture: t.clone(),
                env_mode: s.env_mode,
                env_color: s.env_color,
            })
        } else {
            None
        };
        let surface = Surface {
            texturing,
            fog: s.fog_enabled.then_some(s.fog),
            depth_test: s.depth_test,
            depth_func: s.depth_func,
            depth_mask: s.depth_mask,
            blend: s.blend.then_some(s.blend_func),
            alpha_test: s.alpha_test.then_some(s.alpha_func),
        };
        let same = |a: &Surface, b: &Surface| {
            a.fog == b.fog
                && a.depth_test == b.depth_test
                && a.depth_func == b.depth_func
                && a.depth_mask == b.depth_mask
                && a.blend == b.blend
                && a.alpha_test == b.alpha_test
                && match (&a.texturing, &b.texturing) {
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

    /// Assembles one draw's vertices into the frame's triangles.
    fn draw(&mut self, mode: u32, verts: &[Out]) {
        self.revision += 1;
        if self.programmable {
            self.frame.unsupported_draws += 1;
            return;
        }
        let Ok(asm) = assemble(mode, verts.len()) else { return };
        if verts.is_empty() || (asm.triangles.is_empty() && asm.lines.is_empty() && asm.points.is_empty()) {
            return;
        }
        let projection = *self.matrices.projection.top();
        let viewport = self.s.viewport;
        if self.frame.projection.is_none() {
            self.frame.projection = Some(projection);
            self.frame.viewport = Some(viewport);
            self.frame.depth_range = self.s.depth_range;
        }
        let view = View { projection, viewport };
        let camera = match self.frame.cameras.iter().rposition(|c| *c == view) {
            Some(i) => i as u32,
            None => {
                self.frame.cameras.push(view);
                (self.frame.cameras.len() - 1) as u32
            }
        };
        let surface = self.surface();
        let lighting = if self.s.lighting {
            let l = self.lighting_state();
            if self.frame.lightings.last() != Some(&l) {
                self.frame.lightings.push(l);
            }
            (self.frame.lightings.len() - 1) as u32
        } else {
            NO_LIGHTING
        };
        let sequence = self.sequence;
        self.sequence += 1;
        let clip: Vec<DVec4> = verts.iter().map(|v| projection * v.eye).collect();
        let flat = self.s.flat;
        let color = |v: &Out, face: usize| vec4(v.colors[face]);
        let secondary = |v: &Out, face: usize| v.secondary[face].truncate().as_vec3();
        let tex = |v: &Out| {
            let q = if v.tex.w != 0.0 { v.tex.w } else { 1.0 };
            Vec2::new((v.tex.x / q) as f32, (v.tex.y / q) as f32)
        };
        let eye3 = |v: &Out| (v.eye.truncate() / if v.eye.w != 0.0 { v.eye.w } else { 1.0 }).as_vec3();
        let mut tris = Vec::new();
        let mut lines: Vec<([u32; 2], u32)> = asm.lines.clone();
        let mut points: Vec<u32> = asm.points.clone();
        let polygon_of = |mode: u32, triangle: usize| match mode {
            GL_QUADS | GL_QUAD_STRIP => triangle / 2,
            GL_POLYGON => 0,
            _ => triangle,
        };
        // Edges two triangles of one polygon share: the diagonals of the split.
        let mut diagonals = std::collections::HashSet::new();
        if self.s.polygon_mode.contains(&GL_LINE) && matches!(mode, GL_QUADS | GL_QUAD_STRIP | GL_POLYGON) {
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
            let [a, b, c] = t.map(|i| clip[i as usize]);
            // The window-space winding, from clip coordinates (exact even for triangles that
            // cross the near plane, which clipping keeps on the same plane).
            let det = DMat3::from_cols(DVec3::new(a.x, a.y, a.w), DVec3::new(b.x, b.y, b.w), DVec3::new(c.x, c.y, c.w))
                .determinant();
            if det == 0.0 {
                continue;
            }
            let front = (det > 0.0) == self.s.front_ccw;
            if self.s.cull && (self.s.cull_face == GL_FRONT_AND_BACK || (self.s.cull_face == GL_FRONT) == front) {
                continue;
            }
            let face = if front { 0 } else { 1 };
            match self.s.polygon_mode[face] {
                GL_LINE => {
                    // The edges of the polygon the program drew: a quad or polygon split into
                    // triangles keeps its diagonals hidden (GL's edge flags for the split).
                    let polygon = polygon_of(mode, index);
                    for (x, y) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                        if !diagonals.contains(&(polygon, x.min(y), x.max(y))) {
                            lines.push(([x, y], provoking));
                        }
                    }
                    continue;
                }
                GL_POINT => {
                    points.extend(t);
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
        let inverse = projection.inverse();
        let (hw, hh) = (viewport.width.max(1) as f64 / 2.0, viewport.height.max(1) as f64 / 2.0);
        // A quad around window-space offsets of clip positions, back in eye space.
        let quad = |corners: [(DVec4, DVec2); 4]| -> Option<[Vec3; 4]> {
            let mut out = [Vec3::ZERO; 4];
            for (o, (c, off)) in out.iter_mut().zip(corners) {
                if c.w <= 0.0 {
                    return None;
                }
                let moved = DVec4::new(c.x + off.x / hw * c.w, c.y + off.y / hh * c.w, c.z, c.w);
                let e = inverse * moved;
                *o = (e.truncate() / e.w).as_vec3();
            }
            Some(out)
        };
        let line_half = self.s.line_width / 2.0;
        for &([i, j], provoking) in &lines {
            let (ca, cb) = (clip[i as usize], clip[j as usize]);
            if ca.w <= 0.0 || cb.w <= 0.0 {
                continue;
            }
            let d = DVec2::new((cb.x / cb.w - ca.x / ca.w) * hw, (cb.y / cb.w - ca.y / ca.w) * hh);
            let perp = DVec2::new(-d.y, d.x).normalize_or_zero() * line_half;
            let Some(q) = quad([(ca, -perp), (ca, perp), (cb, perp), (cb, -perp)]) else { continue };
            let (va, vb, pv) = (&verts[i as usize], &verts[j as usize], &verts[provoking as usize]);
            let (c0, c1) = if flat { (color(pv, 0), color(pv, 0)) } else { (color(va, 0), color(vb, 0)) };
            let (t0, t1) = (tex(va), tex(vb));
            for tri in [[0, 1, 2], [0, 2, 3]] {
                let pick = |k: usize| if k < 2 { (c0, t0) } else { (c1, t1) };
                tris.push(Triangle {
                    positions: tri.map(|k| q[k]),
                    colors: tri.map(|k| pick(k).0),
                    secondary: [Vec3::ZERO; 3],
                    texcoords: tri.map(|k| pick(k).1),
                    surface,
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
        let point_half = self.s.point_size / 2.0;
        for &i in &points {
            let c = clip[i as usize];
            let h = point_half;
            let corners = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(x, y)| (c, DVec2::new(x, y)));
            let Some(q) = quad(corners) else { continue };
            let v = &verts[i as usize];
            for tri in [[0, 1, 2], [0, 2, 3]] {
                tris.push(Triangle {
                    positions: tri.map(|k| q[k]),
                    colors: [color(v, 0); 3],
                    secondary: [Vec3::ZERO; 3],
                    texcoords: [tex(v); 3],
                    surface,
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::op_for;

    /// Calls a command by name with scalar arguments (floats as F64, the rest as Int).
    fn call(c: &mut Context, name: &str, args: &[Value]) {
        let (op, ty) = op_for(name).unwrap_or_else(|| panic!("{name} is not followed"));
        c.call(op, ty, args);
    }

    fn i(v: i64) -> Value<'static> {
        Value::Int(v)
    }

    fn f(v: f64) -> Value<'static> {
        Value::F64(v)
    }

    fn context() -> Context {
        let mut c = Context::default();
        c.set_drawable(100, 100);
        call(&mut c, "glMatrixMode", &[i(0x1701)]);
        call(&mut c, "glOrtho", &[f(-1.0), f(1.0), f(-1.0), f(1.0), f(-1.0), f(1.0)]);
        call(&mut c, "glMatrixMode", &[i(0x1700)]);
        c
    }

    fn triangle(c: &mut Context, ccw: bool) {
        call(c, "glBegin", &[i(4)]);
        let pts = if ccw { [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] } else { [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)] };
        for (x, y) in pts {
            call(c, "glVertex2f", &[f(x), f(y)]);
        }
        call(c, "glEnd", &[]);
    }

    #[test]
    fn commands_inside_begin_end_raise_invalid_operation() {
        let mut c = context();
        call(&mut c, "glBegin", &[i(4)]);
        call(&mut c, "glMatrixMode", &[i(0x1700)]);
        call(&mut c, "glColor3f", &[f(1.0), f(0.0), f(0.0)]); // allowed
        call(&mut c, "glEnd", &[]);
        assert_eq!(c.errors.take(), 0x0502);
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
    fn attribute_stack_overflows_and_restores_by_mask() {
        let mut c = context();
        call(&mut c, "glPopAttrib", &[]);
        assert_eq!(c.errors.take(), 0x0504);
        call(&mut c, "glPushAttrib", &[i(GL_ENABLE_BIT as i64)]);
        call(&mut c, "glEnable", &[i(GL_CULL_FACE as i64)]);
        call(&mut c, "glCullFace", &[i(GL_FRONT as i64)]);
        call(&mut c, "glPopAttrib", &[]);
        assert!(!c.s.cull, "GL_ENABLE_BIT restores the enable");
        assert_eq!(c.s.cull_face, GL_FRONT, "but not the face, which GL_POLYGON_BIT saves");
        for _ in 0..MAX_ATTRIB_DEPTH {
            call(&mut c, "glPushAttrib", &[i(0xFFFFF)]);
        }
        assert_eq!(c.errors.take(), 0);
        call(&mut c, "glPushAttrib", &[i(0xFFFFF)]);
        assert_eq!(c.errors.take(), 0x0503);
    }

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
    fn lists_compile_execute_and_nest() {
        let mut c = context();
        call(&mut c, "glNewList", &[i(1), i(0x1300)]); // GL_COMPILE
        triangle(&mut c, true);
        call(&mut c, "glEndList", &[]);
        assert_eq!(c.frame().triangles.len(), 0, "GL_COMPILE draws nothing");
        call(&mut c, "glNewList", &[i(2), i(0x1301)]); // COMPILE_AND_EXECUTE, calling list 1
        call(&mut c, "glTranslatef", &[f(0.5), f(0.0), f(0.0)]);
        call(&mut c, "glCallList", &[i(1)]);
        call(&mut c, "glEndList", &[]);
        assert_eq!(c.frame().triangles.len(), 1);
        call(&mut c, "glLoadIdentity", &[]);
        call(&mut c, "glListBase", &[i(1)]);
        call(&mut c, "glCallLists", &[i(2), i(0x1401), Value::Blob(&[0, 1])]);
        let t = &c.frame().triangles;
        assert_eq!(t.len(), 3, "lists 1 and 2 through glListBase");
        assert_eq!(t[1].positions[0].x, 0.0);
        assert_eq!(t[2].positions[0].x, 0.5, "list 2's translate, then list 1 nested");
        call(&mut c, "glNewList", &[i(3), i(0x1300)]);
        call(&mut c, "glNewList", &[i(4), i(0x1300)]);
        assert_eq!(c.errors.take(), 0x0502, "glNewList inside glNewList");
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
    fn arrays_from_buffers_and_client_memory() {
        let mut c = context();
        let floats: Vec<u8> = [0f32, 0.0, 1.0, 0.0, 0.0, 1.0].iter().flat_map(|v| v.to_ne_bytes()).collect();
        // A buffer object.
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(7)]);
        call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(24), Value::Blob(&floats), i(0x88E4)]);
        call(&mut c, "glVertexPointer", &[i(2), i(0x1406), i(0), Value::Offset(0)]);
        call(&mut c, "glEnableClientState", &[i(GL_VERTEX_ARRAY as i64)]);
        call(&mut c, "glDrawArrays", &[i(4), i(0), i(3)]);
        assert_eq!(c.frame().triangles.len(), 1);
        // Client memory, as the trace's arrays event gives it, with client indices.
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(0)]);
        c.set_arrays(&[ArrayData {
            kind: 0,
            index: 0,
            size: 2,
            gl_type: 0x1406,
            stride: 0,
            normalized: false,
            first: 0,
            bytes: &floats,
        }]);
        call(&mut c, "glDrawElements", &[i(4), i(3), i(0x1401), Value::Blob(&[2, 1, 0])]);
        let t = &c.frame().triangles;
        assert_eq!(t.len(), 2);
        assert_eq!(t[1].positions[0], Vec3::new(0.0, 1.0, 0.0), "index 2 first");
        call(&mut c, "glDrawArrays", &[i(4), i(-1), i(3)]);
        assert_eq!(c.errors.take(), 0x0501);
    }

    #[test]
    fn lighting_uses_color_material_and_two_sides() {
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

    #[test]
    fn a_color_clear_starts_the_frame_again() {
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
