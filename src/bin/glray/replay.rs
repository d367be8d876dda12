//! `glray replay TRACE --renderer osmesa`: plays a recorded trace into Mesa's OSMesa and writes
//! each frame as a PNG.
//!
//! GL calls are decoded by generated code (replay.rs in OUT_DIR) and called through OSMesa's own
//! functions. GLX, EGL and OSMesa calls are not replayed as such: contexts the program created
//! become OSMesa contexts, each drawable an RGBA buffer of the recorded size, MakeCurrent binds
//! them, and a frame end writes the drawable's buffer. Object names (textures, lists, buffers)
//! are not remapped: Mesa hands them out in the same order on replay.

use glray_gl::{GL_ARRAY_BUFFER_BINDING, GL_CLIENT_ACTIVE_TEXTURE, GL_RGB, GL_RGBA, GL_TEXTURE0, GL_UNSIGNED_BYTE};
use std::collections::{HashMap, HashSet};
use std::ffi::{c_char, c_void, CString};
use std::path::{Path, PathBuf};

use glray_core::image::Image;
use glray_core::reallib::{self, OSMesaApi, RealKind, RealLib};
use glray_core::trace::{array_kind, ArrayData, Event, Reader, Value};

use crate::commands::{cmd, lookup, Lib, COMMANDS, COUNT};

mod element;
use element::Immediate;

mod generated {
    #![allow(non_snake_case, clippy::all)]
    use super::{arity, FromValue, Replayer, Value};
    use crate::commands::{cmd, COUNT};
    use std::ffi::c_void;
    include!(concat!(env!("OUT_DIR"), "/replay.rs"));
}

/// The most memory one output argument of a replayed call may need.
const MAX_OUTPUT: usize = 1 << 30;

pub fn arity(want: usize, got: usize) -> String {
    format!("{got} arguments recorded, the command takes {want}")
}

/// A recorded value as an argument of a Rust FFI type.
pub trait FromValue: Sized {
    fn from_value(v: &Value, index: usize) -> Result<Self, String>;
}

macro_rules! int_from_value {
    ($($t:ty),*) => {$(
        impl FromValue for $t {
            fn from_value(v: &Value, i: usize) -> Result<$t, String> {
                match v {
                    Value::Int(x) => Ok(*x as $t),
                    Value::UInt(x) => Ok(*x as $t),
                    other => Err(format!("argument {i}: expected an integer, found {other:?}")),
                }
            }
        }
    )*};
}
int_from_value!(i8, i16, i32, i64, isize, u8, u16, u32, u64);

impl FromValue for f32 {
    fn from_value(v: &Value, i: usize) -> Result<f32, String> {
        match v {
            Value::F32(x) => Ok(*x),
            Value::F64(x) => Ok(*x as f32),
            other => Err(format!("argument {i}: expected a float, found {other:?}")),
        }
    }
}

impl FromValue for f64 {
    fn from_value(v: &Value, i: usize) -> Result<f64, String> {
        match v {
            Value::F64(x) => Ok(*x),
            Value::F32(x) => Ok(*x as f64),
            other => Err(format!("argument {i}: expected a float, found {other:?}")),
        }
    }
}

/// Which frames to write: every one, or a list like `0,3,5-7`.
#[derive(Debug, Clone, Default)]
pub struct FrameSet(Option<Vec<(u64, u64)>>);

impl FrameSet {
    pub fn parse(list: &str) -> Result<FrameSet, String> {
        let mut ranges = Vec::new();
        for part in list.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let bad = || format!("--frames: {part:?} is not a frame number or a range like 3-7");
            let (a, b) = part.split_once('-').unwrap_or((part, part));
            let (a, b): (u64, u64) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
            if a > b {
                return Err(bad());
            }
            ranges.push((a, b));
        }
        Ok(FrameSet(Some(ranges)))
    }

    pub fn contains(&self, n: u64) -> bool {
        self.0.as_ref().is_none_or(|r| r.iter().any(|(a, b)| (*a..=*b).contains(&n)))
    }

    /// The last frame asked for (None: every frame): a replay has nothing to do past it.
    pub fn last(&self) -> Option<u64> {
        self.0.as_ref().map(|r| r.iter().map(|(_, b)| *b).max().unwrap_or(0))
    }
}

struct Drawable {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

/// Counts of what a replay did.
#[derive(Debug, Default)]
pub struct Summary {
    pub calls: u64,
    pub frames_written: u64,
    pub readpixels_written: u64,
    pub missing: Vec<String>,
}

pub struct Replayer {
    osmesa: RealLib,
    api: OSMesaApi,
    /// Resolved OSMesa functions per command (null: not looked up yet).
    funcs: Vec<*mut c_void>,
    missing: HashSet<usize>,
    contexts: HashMap<u64, *mut c_void>,
    drawables: HashMap<u64, Drawable>,
    /// Per recorded thread: (recorded context, drawable id) bound by its last MakeCurrent.
    bound: HashMap<u32, (u64, u64)>,
    /// Per recorded thread: the context of a MakeCurrent whose DRAWABLE event comes next.
    pending: HashMap<u32, u64>,
    /// What OSMesa has current now: (OSMesa context, drawable id).
    current: Option<(*mut c_void, u64)>,
    thread: u32,
    /// Memory for the arguments of the call being replayed.
    strings: Vec<CString>,
    /// Copies of string-list arguments, NUL-terminated, and the pointer arrays to them.
    byte_lists: Vec<Vec<u8>>,
    pointer_lists: Vec<Vec<*const c_char>>,
    outputs: Vec<Vec<u8>>,
    /// Where the outputs of queries go (glGet*): nothing reads them, so all calls share it.
    scratch: Vec<u8>,
    /// Client arrays set from ARRAYS events, kept alive until replaced.
    arrays: HashMap<(u8, u32), Vec<u8>>,
    /// Per recorded thread inside glBegin/glEnd: the arrays of its next glArrayElement, which
    /// is given as immediate-mode calls (`element`).
    in_begin: HashMap<u32, Vec<element::Array>>,
    out: PathBuf,
    frames: FrameSet,
    readpixels: bool,
    /// Width and height of the glReadPixels being replayed (sizes its output).
    pending_read: Option<(i64, i64)>,
    summary: Summary,
}

impl Replayer {
    pub fn new(out: &Path, frames: FrameSet, readpixels: bool, osmesa_path: Option<&str>) -> Result<Replayer, String> {
        let osmesa = reallib::open(RealKind::OSMesa, osmesa_path, None)?;
        let api = OSMesaApi::load(&osmesa)?;
        std::fs::create_dir_all(out).map_err(|e| format!("--out {}: {e}", out.display()))?;
        Ok(Replayer {
            osmesa,
            api,
            funcs: vec![std::ptr::null_mut(); COUNT],
            missing: HashSet::new(),
            contexts: HashMap::new(),
            drawables: HashMap::new(),
            bound: HashMap::new(),
            pending: HashMap::new(),
            current: None,
            thread: 0,
            strings: Vec::new(),
            byte_lists: Vec::new(),
            pointer_lists: Vec::new(),
            outputs: Vec::new(),
            scratch: vec![0; 1 << 20],
            arrays: HashMap::new(),
            in_begin: HashMap::new(),
            out: out.to_path_buf(),
            frames,
            readpixels,
            pending_read: None,
            summary: Summary::default(),
        })
    }

    /// The OSMesa function of GL command `c`.
    pub fn gl(&mut self, c: usize) -> Result<*mut c_void, String> {
        if self.funcs[c].is_null() {
            let name = COMMANDS[c].name;
            let mut p = self.osmesa.sym(name);
            if p.is_null() {
                // SAFETY: a NUL-terminated name.
                p = unsafe { (self.api.get_proc)(name.as_ptr()) };
            }
            self.funcs[c] = if p.is_null() { std::ptr::dangling_mut::<c_void>() } else { p };
        }
        if self.funcs[c] == std::ptr::dangling_mut::<c_void>() {
            return Err("not implemented by OSMesa".into());
        }
        Ok(self.funcs[c])
    }

    /// A pointer argument GL reads.
    pub fn input_pointer(&mut self, v: &Value) -> Result<*mut c_void, String> {
        Ok(match v {
            Value::Null | Value::Opaque(_) => std::ptr::null_mut(),
            Value::Offset(o) => *o as usize as *mut c_void,
            Value::Blob(b) => b.as_ptr() as *mut c_void,
            Value::Str(s) => {
                let c = CString::new(s.to_vec()).map_err(|_| "a string argument contains a NUL byte")?;
                let p = c.as_ptr() as *mut c_void;
                self.strings.push(c);
                p
            }
            Value::Strings(list) => {
                // Shader sources (NUL-terminated, unless lengths are given) or index arrays
                // (glMultiDrawElements, binary): each copied with a NUL after it.
                let mut ptrs = Vec::with_capacity(list.len());
                for s in list {
                    let mut bytes = Vec::with_capacity(s.len() + 1);
                    bytes.extend_from_slice(s);
                    bytes.push(0);
                    ptrs.push(bytes.as_ptr() as *const c_char);
                    self.byte_lists.push(bytes);
                }
                let p = ptrs.as_ptr() as *mut c_void;
                self.pointer_lists.push(ptrs);
                p
            }
            other => return Err(format!("expected a pointer, found {other:?}")),
        })
    }

    /// A pointer argument GL writes through: scratch memory large enough for the call.
    pub fn output_pointer(&mut self, c: usize, v: &Value) -> Result<*mut c_void, String> {
        if matches!(v, Value::Null) {
            return Ok(std::ptr::null_mut());
        }
        if let Value::Offset(o) = v {
            return Ok(*o as usize as *mut c_void);
        }
        if !matches!(c, cmd::glReadPixels | cmd::glReadnPixels | cmd::glReadnPixelsARB) {
            return Ok(self.scratch.as_mut_ptr().cast());
        }
        // Pixels read back (kept for --readpixels): at most 16 bytes a pixel (RGBA float), plus
        // row padding.
        let mut buf = vec![0u8; self.read_pixels_size()?];
        let p = buf.as_mut_ptr() as *mut c_void;
        self.outputs.push(buf);
        Ok(p)
    }

    fn read_pixels_size(&self) -> Result<usize, String> {
        let (w, h) = self.pending_read.ok_or("glReadPixels without its size")?;
        let size = (w.max(0) as usize).saturating_mul(h.max(0) as usize).saturating_mul(16).saturating_add(65536);
        if size > MAX_OUTPUT {
            return Err(format!("glReadPixels of {w}x{h} pixels needs more than 1 GiB"));
        }
        Ok(size)
    }
}

/// Which argument of a context-creating command is the context to share with.
fn share_argument(c: usize) -> Option<Option<usize>> {
    Some(match c {
        cmd::glXCreateContext | cmd::glXCreateContextAttribsARB | cmd::eglCreateContext => Some(2),
        cmd::glXCreateNewContext | cmd::glXCreateContextWithConfigSGIX => Some(3),
        cmd::OSMesaCreateContext | cmd::OSMesaCreateContextAttribs => Some(1),
        cmd::OSMesaCreateContextExt => Some(4),
        _ => return None,
    })
}

/// Which argument of a MakeCurrent is the context (the drawable is the next one, but for
/// OSMesa, whose buffer is).
pub(crate) fn context_argument(c: usize) -> Option<usize> {
    Some(match c {
        cmd::glXMakeCurrent => 2,
        cmd::glXMakeContextCurrent | cmd::glXMakeCurrentReadSGI | cmd::eglMakeCurrent => 3,
        cmd::OSMesaMakeCurrent => 0,
        _ => return None,
    })
}

fn handle(v: Option<&Value>) -> u64 {
    v.map_or(0, |v| v.as_int() as u64)
}

impl Replayer {
    /// Replays the whole trace; an error names the byte offset and call number.
    pub fn run(&mut self, data: &[u8]) -> Result<&Summary, String> {
        let mut reader = Reader::new(data).map_err(|e| e.to_string())?;
        // The trace's command numbers, as this glray's (filled as the trace names them).
        let mut map: Vec<Option<usize>> = Vec::new();
        let mut last_offset;
        loop {
            last_offset = reader.offset();
            let Some(event) = reader.next_event().map_err(|e| e.to_string())? else { break };
            let at = |e: String| format!("byte {last_offset} (call {}): {e}", reader.calls().saturating_sub(1));
            match event {
                Event::Call { cmd: c, thread, args, ret } => {
                    let Some(ours) = map[c] else {
                        return Err(at(format!(
                            "the trace calls {}, which this glray does not know",
                            String::from_utf8_lossy(reader.name(c))
                        )));
                    };
                    self.thread = thread;
                    self.summary.calls += 1;
                    self.call(ours, &args, ret.as_ref())
                        .map_err(|e| at(format!("{}: {e}", COMMANDS[ours].name.to_string_lossy())))?;
                }
                Event::Drawable { thread, id, width, height } => {
                    self.thread = thread;
                    self.drawable(thread, id, width, height).map_err(at)?;
                }
                Event::Arrays { thread, arrays } => {
                    self.thread = thread;
                    self.set_arrays(&arrays).map_err(at)?;
                }
                Event::Frame { number } => {
                    self.frame(number).map_err(at)?;
                    // Past the last frame asked for, nothing more is written (glReadPixels
                    // images are, at any frame).
                    if !self.readpixels && self.frames.last().is_some_and(|last| number >= last) {
                        break;
                    }
                }
                Event::Name { number } => {
                    debug_assert_eq!(number, map.len());
                    map.push(lookup(reader.name(number)));
                }
                Event::End => break,
            }
        }
        let mut missing: Vec<String> =
            self.missing.iter().map(|c| COMMANDS[*c].name.to_string_lossy().into_owned()).collect();
        missing.sort();
        self.summary.missing = missing;
        Ok(&self.summary)
    }

    fn call(&mut self, c: usize, args: &[Value], ret: Option<&Value>) -> Result<(), String> {
        if COMMANDS[c].lib != Lib::Gl {
            return self.context_call(c, args, ret);
        }
        if !self.make_thread_current()? {
            // No context on this thread when the program called: GL ignored it then too.
            return Ok(());
        }
        match c {
            cmd::glBegin => {
                self.in_begin.insert(self.thread, Vec::new());
            }
            cmd::glEnd => {
                self.in_begin.remove(&self.thread);
            }
            cmd::glArrayElement => {
                if let Some(arrays) = self.in_begin.get_mut(&self.thread).map(std::mem::take) {
                    if !arrays.is_empty() {
                        let k = args.first().map_or(0, |v| v.as_int().max(0) as u64);
                        return self.immediate(&element::calls(&arrays, k));
                    }
                }
            }
            _ => {}
        }
        if matches!(c, cmd::glReadPixels | cmd::glReadnPixels | cmd::glReadnPixelsARB) && args.len() >= 4 {
            self.pending_read = Some((args[2].as_int(), args[3].as_int()));
        }
        let Some(f) = generated::REPLAY[c] else { return Ok(()) };
        // SAFETY: the generated function converts each recorded value to the command's
        // argument type and calls OSMesa's implementation of it.
        let result = unsafe { f(self, args) };
        let result = match result {
            Err(e) if e == "not implemented by OSMesa" => {
                self.missing.insert(c);
                Ok(())
            }
            other => other,
        };
        if result.is_ok() && self.readpixels && c == cmd::glReadPixels {
            self.write_read_pixels(args)?;
        }
        self.strings.clear();
        self.byte_lists.clear();
        self.pointer_lists.clear();
        self.outputs.clear();
        self.pending_read = None;
        result
    }

    /// GLX, EGL and OSMesa calls: contexts become OSMesa contexts; the rest has no effect here.
    fn context_call(&mut self, c: usize, args: &[Value], ret: Option<&Value>) -> Result<(), String> {
        if let Some(share) = share_argument(c) {
            let recorded = handle(ret);
            if recorded == 0 {
                return Ok(()); // the program's own creation failed
            }
            let share =
                share.and_then(|i| self.contexts.get(&handle(args.get(i))).copied()).unwrap_or(std::ptr::null_mut());
            // The depth and stencil the program asked OSMesa for (depth precision decides
            // z-fighting pixels); Mesa's defaults for OSMesaCreateContext; GLX and EGL visuals
            // on llvmpipe have 24 and 8.
            let (depth, stencil) = match c {
                cmd::OSMesaCreateContextExt => (handle(args.get(1)) as i32, handle(args.get(2)) as i32),
                cmd::OSMesaCreateContext => (16, 8),
                _ => (24, 8),
            };
            // SAFETY: OSMesaCreateContextExt with an RGBA format and a shared context or null.
            let ctx = unsafe { (self.api.create_ext)(GL_RGBA, depth.clamp(0, 32), stencil.clamp(0, 8), 0, share) };
            if ctx.is_null() {
                return Err("OSMesa could not create a context".into());
            }
            self.contexts.insert(recorded, ctx);
        } else if let Some(i) = context_argument(c) {
            if handle(ret) != 0 {
                self.pending.insert(self.thread, handle(args.get(i)));
            }
        } else if c == cmd::eglReleaseThread {
            self.bound.remove(&self.thread);
        } else if matches!(c, cmd::glXDestroyContext | cmd::eglDestroyContext | cmd::OSMesaDestroyContext) {
            let i = if c == cmd::OSMesaDestroyContext { 0 } else { 1 };
            if let Some(ctx) = self.contexts.remove(&handle(args.get(i))) {
                if self.current.is_some_and(|(cur, _)| cur == ctx) {
                    // SAFETY: unbinding OSMesa's current context.
                    unsafe { (self.api.make_current)(std::ptr::null_mut(), std::ptr::null_mut(), 0, 0, 0) };
                    self.current = None;
                }
                // SAFETY: a context this replay created and no longer uses.
                unsafe { (self.api.destroy)(ctx) };
            }
        }
        Ok(())
    }

    /// A DRAWABLE event: the thread's last MakeCurrent bound its context to this drawable.
    fn drawable(&mut self, thread: u32, id: u64, width: u32, height: u32) -> Result<(), String> {
        let ctx = self.pending.remove(&thread).or_else(|| self.bound.get(&thread).map(|b| b.0));
        match ctx {
            Some(ctx) if ctx != 0 && id != 0 => {
                if width == 0 || height == 0 || width > 16384 || height > 16384 {
                    return Err(format!("drawable of {width}x{height} pixels"));
                }
                let d = self.drawables.entry(id).or_insert(Drawable { width: 0, height: 0, pixels: Vec::new() });
                if (d.width, d.height) != (width, height) {
                    *d = Drawable { width, height, pixels: vec![0; width as usize * height as usize * 4] };
                    // The buffer moved: OSMesa must be told again.
                    if self.current.is_some_and(|(_, cur)| cur == id) {
                        self.current = None;
                    }
                }
                self.bound.insert(thread, (ctx, id));
            }
            _ => {
                self.bound.remove(&thread);
            }
        }
        Ok(())
    }

    /// Makes the calling thread's context and drawable OSMesa's current ones; false if the
    /// thread has none.
    fn make_thread_current(&mut self) -> Result<bool, String> {
        let Some(&(ctx, id)) = self.bound.get(&self.thread) else { return Ok(false) };
        let Some(&osctx) = self.contexts.get(&ctx) else { return Ok(false) };
        if self.current == Some((osctx, id)) {
            return Ok(true);
        }
        let d = self.drawables.get_mut(&id).ok_or("a drawable without a size")?;
        // SAFETY: the buffer holds width*height RGBA pixels and lives in `drawables` until it is
        // resized, when `current` is cleared and this runs again.
        let ok = unsafe {
            (self.api.make_current)(
                osctx,
                d.pixels.as_mut_ptr().cast(),
                GL_UNSIGNED_BYTE,
                d.width as i32,
                d.height as i32,
            )
        };
        if ok == 0 {
            return Err(format!("OSMesaMakeCurrent failed for a {}x{} drawable", d.width, d.height));
        }
        self.current = Some((osctx, id));
        Ok(true)
    }

    /// An ARRAYS event: points each client array at the recorded memory, with the recorded
    /// layout, as the program's arrays were when it drew.
    fn set_arrays(&mut self, arrays: &[ArrayData]) -> Result<(), String> {
        if !self.make_thread_current()? {
            return Ok(());
        }
        if let Some(next) = self.in_begin.get_mut(&self.thread) {
            // A glArrayElement's: no gl*Pointer between glBegin and glEnd.
            *next = arrays.iter().map(element::Array::of).collect();
            return Ok(());
        }
        type Ptr = unsafe extern "C" fn(i32, u32, i32, *const c_void);
        type Ptr3 = unsafe extern "C" fn(u32, i32, *const c_void);
        type Ptr2 = unsafe extern "C" fn(i32, *const c_void);
        type Attrib = unsafe extern "C" fn(u32, i32, u32, u8, i32, *const c_void);
        type GetI = unsafe extern "C" fn(u32, *mut i32);
        type BindBuffer = unsafe extern "C" fn(u32, u32);
        type Active = unsafe extern "C" fn(u32);
        // SAFETY: OSMesa's own functions with their GL signatures.
        unsafe {
            let get_i: GetI = std::mem::transmute(self.gl(cmd::glGetIntegerv)?);
            let bind: BindBuffer = std::mem::transmute(self.gl(cmd::glBindBuffer)?);
            let mut array_buffer = 0i32;
            get_i(GL_ARRAY_BUFFER_BINDING, &mut array_buffer); // GL_ARRAY_BUFFER_BINDING
            if array_buffer != 0 {
                bind(0x8892, 0); // client memory: no buffer bound while pointing
            }
            for a in arrays {
                let elem_stride = if a.stride > 0 { a.stride as u64 } else { 0 };
                let bytes = a.bytes.to_vec();
                // The memory starts at element `first`: point GL before it, so that element
                // indices land in it. Only elements first.. are read.
                let stride_for_offset = if elem_stride > 0 { elem_stride } else { element_bytes(a) };
                let ptr =
                    bytes.as_ptr().wrapping_sub((a.first.wrapping_mul(stride_for_offset)) as usize) as *const c_void;
                let key = (a.kind, a.index);
                match a.kind {
                    array_kind::VERTEX => std::mem::transmute::<*mut c_void, Ptr>(self.gl(cmd::glVertexPointer)?)(
                        a.size, a.gl_type, a.stride, ptr,
                    ),
                    array_kind::NORMAL => std::mem::transmute::<*mut c_void, Ptr3>(self.gl(cmd::glNormalPointer)?)(
                        a.gl_type, a.stride, ptr,
                    ),
                    array_kind::COLOR => std::mem::transmute::<*mut c_void, Ptr>(self.gl(cmd::glColorPointer)?)(
                        a.size, a.gl_type, a.stride, ptr,
                    ),
                    array_kind::SECONDARY_COLOR => std::mem::transmute::<*mut c_void, Ptr>(
                        self.gl(cmd::glSecondaryColorPointer)?,
                    )(a.size, a.gl_type, a.stride, ptr),
                    array_kind::FOG_COORD => {
                        std::mem::transmute::<*mut c_void, Ptr3>(self.gl(cmd::glFogCoordPointer)?)(
                            a.gl_type, a.stride, ptr,
                        )
                    }
                    array_kind::EDGE_FLAG => {
                        std::mem::transmute::<*mut c_void, Ptr2>(self.gl(cmd::glEdgeFlagPointer)?)(a.stride, ptr)
                    }
                    array_kind::INDEX => std::mem::transmute::<*mut c_void, Ptr3>(self.gl(cmd::glIndexPointer)?)(
                        a.gl_type, a.stride, ptr,
                    ),
                    array_kind::TEXCOORD => {
                        let active: Active = std::mem::transmute(self.gl(cmd::glClientActiveTexture)?);
                        let mut previous = 0i32;
                        get_i(GL_CLIENT_ACTIVE_TEXTURE, &mut previous); // GL_CLIENT_ACTIVE_TEXTURE
                        active(GL_TEXTURE0 + a.index);
                        std::mem::transmute::<*mut c_void, Ptr>(self.gl(cmd::glTexCoordPointer)?)(
                            a.size, a.gl_type, a.stride, ptr,
                        );
                        active(previous as u32);
                    }
                    array_kind::ATTRIB => std::mem::transmute::<*mut c_void, Attrib>(
                        self.gl(cmd::glVertexAttribPointer)?,
                    )(
                        a.index, a.size, a.gl_type, a.normalized as u8, a.stride, ptr
                    ),
                    _ => {}
                }
                self.arrays.insert(key, bytes);
            }
            if array_buffer != 0 {
                bind(0x8892, array_buffer as u32);
            }
        }
        Ok(())
    }

    /// Makes `calls` (a glArrayElement's, `element`) in OSMesa's current context.
    fn immediate(&mut self, calls: &[Immediate]) -> Result<(), String> {
        type V4 = unsafe extern "C" fn(f64, f64, f64, f64);
        type V3 = unsafe extern "C" fn(f64, f64, f64);
        type V1 = unsafe extern "C" fn(f64);
        type Flag = unsafe extern "C" fn(u8);
        type U4 = unsafe extern "C" fn(u32, f64, f64, f64, f64);
        for call in calls {
            // SAFETY: OSMesa's own functions with their GL signatures.
            unsafe {
                match *call {
                    Immediate::Color4d([r, g, b, a]) => {
                        std::mem::transmute::<*mut c_void, V4>(self.gl(cmd::glColor4d)?)(r, g, b, a)
                    }
                    Immediate::SecondaryColor3d([r, g, b]) => {
                        std::mem::transmute::<*mut c_void, V3>(self.gl(cmd::glSecondaryColor3d)?)(r, g, b)
                    }
                    Immediate::Normal3d([x, y, z]) => {
                        std::mem::transmute::<*mut c_void, V3>(self.gl(cmd::glNormal3d)?)(x, y, z)
                    }
                    Immediate::FogCoordd(f) => std::mem::transmute::<*mut c_void, V1>(self.gl(cmd::glFogCoordd)?)(f),
                    Immediate::EdgeFlag(e) => {
                        std::mem::transmute::<*mut c_void, Flag>(self.gl(cmd::glEdgeFlag)?)(u8::from(e))
                    }
                    Immediate::MultiTexCoord4d(unit, [s, t, r, q]) => std::mem::transmute::<*mut c_void, U4>(
                        self.gl(cmd::glMultiTexCoord4d)?,
                    )(
                        GL_TEXTURE0 + unit, s, t, r, q
                    ),
                    Immediate::VertexAttrib4d(i, [x, y, z, w]) => {
                        std::mem::transmute::<*mut c_void, U4>(self.gl(cmd::glVertexAttrib4d)?)(i, x, y, z, w)
                    }
                    Immediate::Vertex4d([x, y, z, w]) => {
                        std::mem::transmute::<*mut c_void, V4>(self.gl(cmd::glVertex4d)?)(x, y, z, w)
                    }
                }
            }
        }
        Ok(())
    }

    /// A FRAME event: the drawable of the thread that ended the frame, as a PNG.
    fn frame(&mut self, number: u64) -> Result<(), String> {
        if !self.frames.contains(number) || !self.make_thread_current()? {
            return Ok(());
        }
        // SAFETY: glFinish of the current OSMesa context: the buffer is complete after it.
        unsafe { std::mem::transmute::<*mut c_void, unsafe extern "C" fn()>(self.gl(cmd::glFinish)?)() };
        let (_, id) = self.current.ok_or("no current drawable")?;
        let d = &self.drawables[&id];
        let image = Image::from_bottom_up(d.width, d.height, &d.pixels, 4);
        image.write_png(&self.out.join(format!("frame-{number:04}.png")))?;
        self.summary.frames_written += 1;
        Ok(())
    }

    /// With --readpixels: what a glReadPixels of RGB/RGBA bytes returned, as a PNG.
    fn write_read_pixels(&mut self, args: &[Value]) -> Result<(), String> {
        let (w, h, format, ty) = (args[2].as_int(), args[3].as_int(), args[4].as_int() as u32, args[5].as_int() as u32);
        let bpp = match (format, ty) {
            (GL_RGB, GL_UNSIGNED_BYTE) => 3,
            (GL_RGBA, GL_UNSIGNED_BYTE) => 4,
            _ => return Ok(()),
        };
        let mut align = 4i32;
        // SAFETY: glGetIntegerv(GL_PACK_ALIGNMENT) writes one integer.
        unsafe {
            std::mem::transmute::<*mut c_void, unsafe extern "C" fn(u32, *mut i32)>(self.gl(cmd::glGetIntegerv)?)(
                0x0D05, &mut align,
            )
        };
        let Some(out) = self.outputs.last() else { return Ok(()) };
        let row = (w as usize * bpp).div_ceil(align.max(1) as usize) * align.max(1) as usize;
        let mut packed = Vec::with_capacity(w as usize * h as usize * bpp);
        for y in 0..h as usize {
            packed.extend_from_slice(&out[y * row..y * row + w as usize * bpp]);
        }
        let image = Image::from_bottom_up(w as u32, h as u32, &packed, bpp);
        let n = self.summary.readpixels_written;
        image.write_png(&self.out.join(format!("readpixels-{n:04}.png")))?;
        self.summary.readpixels_written += 1;
        Ok(())
    }
}

fn element_bytes(a: &ArrayData) -> u64 {
    if a.kind == array_kind::EDGE_FLAG {
        1
    } else {
        glray_core::gltypes::array_element_bytes(a.size, a.gl_type)
    }
}

impl Drop for Replayer {
    fn drop(&mut self) {
        // SAFETY: unbinding and destroying the contexts this replay created.
        unsafe {
            (self.api.make_current)(std::ptr::null_mut(), std::ptr::null_mut(), 0, 0, 0);
            for ctx in self.contexts.values() {
                (self.api.destroy)(*ctx);
            }
        }
    }
}
