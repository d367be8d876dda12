//! The stream of calls: every GL, GLX, EGL and OSMesa call the exports hand over, after the
//! real call returns, with the client memory it read; the memory of client vertex arrays at
//! each draw that reads them; drawable sizes at MakeCurrent; frame ends at swaps (and, for
//! OSMesa contexts, which have no swap, at glFinish). Its two sinks: the trace file
//! (`crate::record`, when recording) and the live feed (`crate::feed`, capture and ray tracing,
//! when ray tracing). One stream serves both, so that the trace and the ray tracer see exactly
//! the same calls and client memory, under one lock per call.
//!
//! Calls are serialised by that lock and encoded (`out`); the encoded bytes go to the file at
//! each frame end, every few MiB, and at exit.

mod client_arrays;
mod encoding;
pub mod given;
pub mod sizes;

use glray_gl::{
    EGL_HEIGHT, EGL_WIDTH, GLX_HEIGHT, GLX_WIDTH, GL_ARRAY_BUFFER_BINDING, GL_BUFFER_SIZE,
    GL_ELEMENT_ARRAY_BUFFER_BINDING, GL_MAP_WRITE_BIT, GL_READ_ONLY,
};
use std::collections::{HashMap, HashSet};
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, OnceLock};

use encoding::Encoding;

use crate::abi::commands::{cmd, Class, COMMANDS};
use crate::abi::real;
use crate::feed;
use crate::record::TraceFile;

pub use client_arrays::ClientArrays;

/// The generated `generated::NAME(rec, args..., ret)` of every command.
pub mod generated {
    #![allow(non_snake_case, clippy::all)]
    use super::{sizes, Recorder};
    use std::ffi::{c_ulong, c_void};
    include!(concat!(env!("OUT_DIR"), "/record.rs"));
}

static ACTIVE: AtomicBool = AtomicBool::new(false);
/// Whether calls go to a trace file (not only to capture).
static TO_FILE: AtomicBool = AtomicBool::new(false);
/// The stream: its encoder and its sinks.
static RECORDER: Mutex<Option<Recorder>> = Mutex::new(None);
/// Set in a child process right after fork: its recorder still holds the parent's file.
static FORKED: AtomicBool = AtomicBool::new(false);

/// Whether calls are being recorded: one relaxed load on every call.
#[inline(always)]
pub fn active() -> bool {
    ACTIVE.load(Ordering::Relaxed)
}

/// Starts the stream with its sinks: the trace `file` (created at the first call) and/or the
/// live feed `live` (each call is handed to `crate::feed` as soon as it is encoded). The
/// live feed's state is kept under the stream's lock: one lock per call, not two.
pub fn start(file: Option<TraceFile>, live: Option<crate::feed::Live>) {
    TO_FILE.store(file.is_some(), Ordering::Relaxed);
    *RECORDER.lock().unwrap_or_else(|e| e.into_inner()) = Some(Recorder::new(file, live));
    ACTIVE.store(true, Ordering::Relaxed);
    // SAFETY: registering plain extern "C" functions with atexit and pthread_atfork.
    unsafe {
        libc::atexit(finish_at_exit);
        libc::pthread_atfork(None, None, Some(forked_child));
    }
}

extern "C" fn forked_child() {
    FORKED.store(true, Ordering::Relaxed);
}

/// In a child after fork: with `%p` in the path the child records into a trace of its own
/// (opened at its first call); otherwise it stops recording, since the parent's file and
/// buffer are not its to write.
fn after_fork() {
    // A lock held by a parent thread at fork time is never released in the child.
    let Ok(mut guard) = RECORDER.try_lock() else {
        ACTIVE.store(false, Ordering::Relaxed);
        return;
    };
    // The child keeps ray tracing what it draws (from the state the parent had).
    let mut live = guard.as_mut().and_then(|r| r.e.take_live());
    if let Some(live) = live.as_mut() {
        live.forked();
    }
    let child_file = guard.as_ref().and_then(|r| r.file.as_ref()).and_then(TraceFile::for_child);
    if child_file.is_some() {
        *guard = Some(Recorder::new(child_file, live));
    } else if live.is_some() {
        // Without the parent's trace file.
        *guard = Some(Recorder::new(None, live));
    } else {
        *guard = None;
        ACTIVE.store(false, Ordering::Relaxed);
        glray_core::warn!(
            "process {} (forked) is not recorded: put %p in GLRAY_RECORD to record children",
            std::process::id()
        );
    }
}

extern "C" fn finish_at_exit() {
    let _ = std::panic::catch_unwind(finish);
}

/// Writes the end marker and flushes; recording stops.
pub fn finish() {
    ACTIVE.store(false, Ordering::Relaxed);
    if let Some(rec) = RECORDER.lock().unwrap_or_else(|e| e.into_inner()).as_mut() {
        if rec.file.as_ref().is_some_and(TraceFile::is_open) {
            rec.e.end();
            rec.flush();
        }
    }
}

thread_local! {
    static THREAD: std::cell::Cell<u32> = const { std::cell::Cell::new(u32::MAX) };
    static INSIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether a call of `cmd` is to be recorded: always into a trace file; for capture alone,
/// only the commands capture follows and those the recorder itself needs (draws, client
/// arrays, contexts, frame ends). Queries and the rest then cost no lock and no encoding.
#[inline]
pub fn wants(cmd: usize) -> bool {
    static CAPTURE_WANTS: OnceLock<Vec<bool>> = OnceLock::new();
    if TO_FILE.load(Ordering::Relaxed) {
        return true;
    }
    let wants = CAPTURE_WANTS.get_or_init(|| {
        COMMANDS
            .iter()
            .map(|c| {
                let name = c.name.to_str().unwrap_or("");
                glray_capture::ops::op_for(name).is_some()
                    || matches!(c.class, Class::Geometry | Class::Client | Class::Context | Class::Frame)
            })
            .collect()
    });
    wants.get(cmd).copied().unwrap_or(true)
}

/// This thread's number in the recording (None before its first recorded call).
pub fn thread_number() -> Option<u32> {
    Some(THREAD.with(|t| t.get())).filter(|t| *t != u32::MAX)
}

/// Marks this thread as inside a recorded call; false if it already was (the call is nested:
/// a real implementation calling an exported function, and is not recorded).
pub fn enter() -> bool {
    INSIDE.with(|i| !i.replace(true))
}

/// Ends the outermost recorded call of this thread.
pub fn leave() {
    INSIDE.with(|i| i.set(false));
}

/// Runs `f` with the recorder, under the lock and a panic guard: an I/O error or a panic stops
/// recording (with a message) but never the program.
pub fn with(f: impl FnOnce(&mut Recorder)) {
    if !forked_check() {
        return;
    }
    let mut guard = RECORDER.lock().unwrap_or_else(|e| e.into_inner());
    let Some(rec) = guard.as_mut() else { return };
    given::drain(rec);
    rec.thread = rec.calling_thread();
    let ok = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if let Some(file) = rec.file.as_mut().filter(|f| !f.is_open()) {
            file.open()?;
        }
        f(rec);
        rec.e.discard_call();
        if rec.e.live().is_some() {
            rec.feed_capture();
        }
        if rec.e.len() > (8 << 20) {
            rec.flush();
        }
        rec.error.take().map_or(Ok(()), Err)
    }));
    let err = match ok {
        Ok(Ok(())) => return,
        Ok(Err(e)) => e,
        Err(_) => "internal error while recording".to_string(),
    };
    glray_core::error!("recording stopped: {err}");
    ACTIVE.store(false, Ordering::Relaxed);
    *guard = None;
}

/// In a child just forked, makes the recorder the child's (`after_fork`); false if the child
/// records nothing.
#[inline]
fn forked_check() -> bool {
    // A load, not a swap: a locked instruction on every call cost as much as the recorder's
    // lock. Only a child just forked (one thread) ever finds it set.
    if FORKED.load(Ordering::Relaxed) {
        FORKED.store(false, Ordering::Relaxed);
        after_fork();
        return active();
    }
    true
}

/// Runs `f` with the live ray tracer's state, under the recorder's lock; None when nothing is
/// ray traced. Not to be called from inside `with` (the lock is not re-entrant): it serves
/// the frame triggers and glGetError, which run outside a call's recording.
pub fn with_live<R>(f: impl FnOnce(&mut crate::feed::Live) -> R) -> Option<R> {
    if !forked_check() {
        return None;
    }
    let mut guard = RECORDER.lock().unwrap_or_else(|e| e.into_inner());
    let rec = guard.as_mut()?;
    given::drain(rec);
    rec.e.live().map(f)
}

/// Called before the real call of commands that touch client state, with their arguments as
/// bits: memory a program wrote through a mapped buffer must be read before glUnmapBuffer
/// invalidates the mapping. True when the real call is to be skipped (geometry the ray
/// tracer takes instead of the rasterizer).
pub fn before_real(cmd: usize, args: &[u64]) -> bool {
    if matches!(cmd, cmd::glUnmapBuffer | cmd::glUnmapBufferARB) {
        with(|rec| rec.capture_mapping(args[0] as u32));
    }
    let skip = match feed::before(cmd) {
        feed::Before::Decided(skip) => skip,
        feed::Before::Fire(firing) => {
            let Some(thread) = thread_number() else { return false };
            with_live(|live| feed::fire(live, cmd, thread, firing)).unwrap_or(false)
        }
    };
    feed::skipped(skip);
    skip
}

/// The first error the calling thread's context raised that the real GL could not (0: none).
pub fn take_unseen_error() -> u32 {
    let Some(thread) = thread_number() else { return 0 };
    with_live(|live| feed::take_unseen_error(live, thread)).unwrap_or(0)
}

/// A buffer mapped for writing: where, and which part of the buffer.
struct Mapping {
    ptr: u64,
    offset: i64,
    length: i64,
}

/// What the recorder knows per recorded thread.
#[derive(Default)]
struct ThreadState {
    /// Buffers mapped for writing, by target.
    mappings: HashMap<u32, Mapping>,
    /// What a glUnmapBuffer about to return found in its mapping: (target, offset, bytes).
    unmapped: Option<(u32, i64, Vec<u8>)>,
    arrays: ClientArrays,
    /// The drawable bound by the last MakeCurrent, and its size.
    drawable: (u64, u32, u32),
    /// Whether the current context is an OSMesa one (its frames end at glFinish).
    osmesa: bool,
    /// Arguments of the last GLX/EGL MakeCurrent, to re-query the size at swaps.
    surface: Option<(SurfaceApi, u64, u64)>,
}

#[derive(Clone, Copy)]
enum SurfaceApi {
    Glx,
    Egl,
}

pub struct Recorder {
    /// Where events go: trace bytes, or straight to capture when no file is written.
    pub e: Encoding,
    /// The trace file, if recording to one.
    file: Option<TraceFile>,
    /// How much of `e` capture has been given.
    fed: usize,
    /// How many commands capture knows the names of.
    fed_names: usize,
    thread: u32,
    next_thread: u32,
    /// By thread number (threads are numbered from 0 as they first call): found on every
    /// call, where a hash map's lookup was ~150 instructions.
    threads: Vec<ThreadState>,
    warned: HashSet<usize>,
    frame: u64,
    error: Option<String>,
    /// Each command's number in this trace (u32::MAX: not named yet), and how many are named.
    numbers: Vec<u32>,
    named: u32,
}

impl Recorder {
    fn new(file: Option<TraceFile>, live: Option<crate::feed::Live>) -> Recorder {
        Recorder {
            e: Encoding::new(file.is_some(), live),
            file,
            fed: 0,
            fed_names: 0,
            thread: 0,
            next_thread: 0,
            threads: Vec::new(),
            warned: HashSet::new(),
            frame: 0,
            error: None,
            numbers: vec![u32::MAX; crate::abi::commands::COUNT],
            named: 0,
        }
    }

    fn flush(&mut self) {
        if self.e.live().is_some() {
            // Capture must see every event before the buffer is emptied.
            self.feed_capture();
        }
        match self.file.as_mut() {
            Some(file) => {
                let e = &mut self.e;
                if let Err(err) = file.write(|f| e.flush_to(f)) {
                    self.error = Some(err);
                }
            }
            None => self.e.clear(),
        }
        self.fed = 0;
    }

    /// Hands the events recorded since the last call to capture.
    fn feed_capture(&mut self) {
        let (fed, named) = (self.fed, self.fed_names);
        if let Encoding::Bytes(e, Some(live)) = &mut self.e {
            let bytes = &e.bytes()[fed..];
            if !bytes.is_empty() {
                self.fed_names = crate::feed::feed(live, bytes, named);
            }
        }
        if self.file.is_none() {
            self.e.clear();
            self.fed = 0;
        } else {
            self.fed = self.e.len();
        }
    }

    fn state(&mut self) -> &mut ThreadState {
        let t = self.thread as usize;
        if t >= self.threads.len() {
            self.threads.resize_with(t + 1, ThreadState::default);
        }
        &mut self.threads[t]
    }

    /// The calling thread's number, given at its first recorded call.
    fn calling_thread(&mut self) -> u32 {
        THREAD.with(|t| {
            if t.get() == u32::MAX {
                t.set(self.next_thread);
                self.next_thread += 1;
            }
            t.get()
        })
    }

    /// Starts the record of a call; a command's first call also names it in the trace.
    pub fn begin(&mut self, cmd: usize, nargs: usize) {
        let mut number = self.numbers[cmd];
        if number == u32::MAX {
            number = self.named;
            self.named += 1;
            self.numbers[cmd] = number;
            self.e.name(COMMANDS[cmd].name.to_bytes());
        }
        self.e.begin_call(number as usize, self.thread, nargs as u8);
    }

    /// A pointer the call writes through, or one whose memory is not recorded: its value.
    pub fn output_pointer(&mut self, p: *mut c_void) {
        if p.is_null() {
            self.e.null()
        } else {
            self.e.opaque(p as usize as u64)
        }
    }

    /// A pointer whose size glray cannot tell (reported once per command).
    pub fn unknown_pointer(&mut self, cmd: usize, p: *mut c_void) {
        // GLX, EGL and OSMesa arguments are not replayed (contexts and surfaces are remade), so
        // only GL commands are worth a warning.
        if !p.is_null() && COMMANDS[cmd].lib == crate::abi::commands::Lib::Gl && self.warned.insert(cmd) {
            glray_core::warn!(
                "recording {}: the size of a pointer argument is unknown; its memory is not recorded",
                COMMANDS[cmd].name.to_string_lossy()
            );
        }
        self.output_pointer(p)
    }

    /// The memory a pointer argument reads, sized by a rule.
    pub fn memory(&mut self, p: *mut c_void, mem: sizes::Mem, elem: usize) {
        const LIMIT: usize = 1 << 30;
        if p.is_null() {
            return self.e.null();
        }
        let bytes = match mem {
            sizes::Mem::Offset => return self.e.offset(p as usize as u64),
            sizes::Mem::Elements(n) => n.saturating_mul(elem),
            sizes::Mem::Bytes(n) => n,
        };
        if bytes > LIMIT {
            glray_core::warn!("recording: a {bytes}-byte argument is over the 1 GiB limit; only its address is kept");
            return self.e.opaque(p as usize as u64);
        }
        // SAFETY: the program passed `p` to GL for GL to read `bytes` bytes (the registry's rule).
        let data = unsafe { std::slice::from_raw_parts(p as *const u8, bytes) };
        // SAFETY: the program's memory stays as it is until its GL call returns, after this
        // record of it ends.
        unsafe { self.e.blob(data) };
    }

    pub fn c_string(&mut self, p: *mut c_void) {
        if p.is_null() {
            return self.e.null();
        }
        // SAFETY: GL takes this argument as a NUL-terminated string.
        let s = unsafe { CStr::from_ptr(p as *const libc::c_char) };
        // SAFETY: as in `memory`.
        unsafe { self.e.string(s.to_bytes()) };
    }

    pub fn string_with_length(&mut self, p: *mut c_void, len: i64) {
        if p.is_null() || len < 0 {
            return self.c_string(p);
        }
        // SAFETY: GL reads `len` bytes of this string.
        let s = unsafe { std::slice::from_raw_parts(p as *const u8, len as usize) };
        // SAFETY: as in `memory`.
        unsafe { self.e.string(s) };
    }

    /// An array of `count` strings, each NUL-terminated or of the length in `lengths`.
    pub fn strings(&mut self, p: *mut c_void, count: i64, lengths: *mut c_void) {
        if p.is_null() || count < 0 {
            return self.e.null();
        }
        let ptrs = p as *const *const libc::c_char;
        let lens = lengths as *const i32;
        let mut list = Vec::with_capacity(count as usize);
        for i in 0..count as usize {
            // SAFETY: GL reads `count` string pointers and, if given, `count` lengths.
            unsafe {
                let s = *ptrs.add(i);
                let len = if lens.is_null() { -1 } else { *lens.add(i) };
                list.push(if s.is_null() {
                    &[][..]
                } else if len < 0 {
                    CStr::from_ptr(s).to_bytes()
                } else {
                    std::slice::from_raw_parts(s as *const u8, len as usize)
                });
            }
        }
        // SAFETY: as in `memory` (the strings are the program's).
        unsafe { self.e.strings(&list) };
    }

    /// glMultiDrawElements' per-draw index pointers: with an element buffer bound they are
    /// offsets into it, recorded as they are (a blob of pointer-sized offsets); otherwise the
    /// indices each points to, `counts[i]` of `ty`, as a list.
    pub fn index_arrays(&mut self, p: *mut c_void, counts: *mut c_void, ty: i64, drawcount: i64) {
        if p.is_null() || counts.is_null() || drawcount < 0 {
            return self.e.null();
        }
        let n = drawcount as usize;
        let ptrs = p as *const *const u8;
        if bound_buffer(GL_ELEMENT_ARRAY_BUFFER_BINDING) != 0 {
            // SAFETY: GL reads `drawcount` pointers.
            let raw = unsafe { std::slice::from_raw_parts(ptrs as *const u8, n * std::mem::size_of::<usize>()) };
            // SAFETY: as in `memory`.
            return unsafe { self.e.blob(raw) };
        }
        let size = glray_core::gltypes::array_element_bytes(1, ty as u32) as usize;
        let counts = counts as *const i32;
        let mut list: Vec<&[u8]> = Vec::with_capacity(n);
        for i in 0..n {
            // SAFETY: GL reads `drawcount` counts and pointers, and `counts[i]` indices from each.
            unsafe {
                let (q, count) = (*ptrs.add(i), (*counts.add(i)).max(0) as usize);
                list.push(if q.is_null() || size == 0 { &[][..] } else { std::slice::from_raw_parts(q, count * size) });
            }
        }
        // SAFETY: as in `memory` (the indices are the program's).
        unsafe { self.e.strings(&list) };
    }

    /// A vertex array pointer: an offset when a buffer object is bound, else the address (the
    /// memory is captured when a draw reads it).
    pub fn array_pointer(&mut self, p: *mut c_void) {
        if bound_buffer(GL_ARRAY_BUFFER_BINDING) != 0 {
            self.e.offset(p as usize as u64)
        } else {
            self.output_pointer(p)
        }
    }

    /// Called before a hooked command is recorded (draws: capture client arrays first).
    pub fn before(&mut self, cmd: usize, args: &[u64]) {
        if !self.state().arrays.any_client() {
            return;
        }
        if let Some(range) = client_arrays::draw_range(cmd, args) {
            let thread = self.thread;
            // SAFETY: the draw is being recorded: its arrays are valid and unchanged until
            // it returns, and `captured` goes before that, after the arrays event.
            let captured = unsafe { self.state().arrays.capture(range) };
            if !captured.is_empty() {
                let list: Vec<_> = captured.iter().map(|c| c.as_data()).collect();
                self.e.arrays(thread, &list);
            }
        }
    }

    /// Before glUnmapBuffer: copies what the program wrote into the mapping.
    fn capture_mapping(&mut self, target: u32) {
        let st = self.state();
        if let Some(m) = st.mappings.remove(&target) {
            // SAFETY: the mapping is valid until the glUnmapBuffer that is about to run.
            let bytes = unsafe { std::slice::from_raw_parts(m.ptr as usize as *const u8, m.length.max(0) as usize) };
            st.unmapped = Some((target, m.offset, bytes.to_vec()));
        }
    }

    /// Called after a hooked command is recorded.
    pub fn after(&mut self, cmd: usize, args: &[u64], ret: u64) {
        self.state().arrays.track(cmd, args);
        match cmd {
            cmd::glMapBuffer | cmd::glMapBufferARB if ret != 0 && args[1] != u64::from(GL_READ_ONLY) => {
                let mut size = 0i32;
                // SAFETY: the size of the buffer bound to the target just mapped.
                unsafe { real::glGetBufferParameteriv(args[0] as u32, GL_BUFFER_SIZE, (&mut size as *mut i32).cast()) };
                self.state().mappings.insert(args[0] as u32, Mapping { ptr: ret, offset: 0, length: size as i64 });
            }
            cmd::glMapBufferRange if ret != 0 && args[3] & u64::from(GL_MAP_WRITE_BIT) != 0 => {
                let m = Mapping { ptr: ret, offset: args[1] as i64, length: args[2] as i64 };
                self.state().mappings.insert(args[0] as u32, m);
            }
            cmd::glUnmapBuffer | cmd::glUnmapBufferARB => {
                // The trace gets the data as a glBufferSubData after the unmap (a mapped buffer
                // takes no SubData), so that a replay ends with the same buffer contents.
                if let Some((target, offset, bytes)) = self.state().unmapped.take() {
                    self.begin(cmd::glBufferSubData, 4);
                    self.e.uint(target as u64);
                    self.e.int(offset);
                    self.e.int(bytes.len() as i64);
                    // SAFETY: `bytes` is dropped after the call ends, on the next line.
                    unsafe { self.e.blob(&bytes) };
                    self.e.no_return();
                }
            }
            cmd::glXMakeCurrent if ret != 0 => self.bound(SurfaceApi::Glx, args[0], args[1], args[2]),
            cmd::glXMakeContextCurrent | cmd::glXMakeCurrentReadSGI if ret != 0 => {
                self.bound(SurfaceApi::Glx, args[0], args[1], args[3])
            }
            cmd::eglMakeCurrent if ret != 0 => self.bound(SurfaceApi::Egl, args[0], args[1], args[3]),
            cmd::OSMesaMakeCurrent if ret != 0 => {
                let thread = self.thread;
                let st = self.state();
                st.osmesa = args[0] != 0;
                st.surface = None;
                st.drawable = (args[1], args[3] as u32, args[4] as u32);
                self.e.drawable(thread, args[1], args[3] as u32, args[4] as u32);
            }
            cmd::glXSwapBuffers
            | cmd::eglSwapBuffers
            | cmd::eglSwapBuffersWithDamageKHR
            | cmd::eglSwapBuffersWithDamageEXT => self.frame_end(true),
            cmd::glFinish if self.state().osmesa => self.frame_end(false),
            _ => {}
        }
    }

    fn bound(&mut self, kind: SurfaceApi, dpy: u64, drawable: u64, ctx: u64) {
        let thread = self.thread;
        let st = self.state();
        st.osmesa = false;
        if ctx == 0 {
            st.surface = None;
            st.drawable = (0, 0, 0);
            self.e.drawable(thread, 0, 0, 0);
            return;
        }
        st.surface = Some((kind, dpy, drawable));
        let (w, h) = surface_size(kind, dpy, drawable);
        self.state().drawable = (drawable, w, h);
        self.e.drawable(thread, drawable, w, h);
    }

    fn frame_end(&mut self, swapped: bool) {
        self.e.frame(self.frame);
        self.frame += 1;
        if swapped {
            // A window may have been resized: the next frame is drawn at the new size.
            let thread = self.thread;
            let st = self.state();
            if let Some((kind, dpy, drawable)) = st.surface {
                let (w, h) = surface_size(kind, dpy, drawable);
                if (drawable, w, h) != st.drawable {
                    st.drawable = (drawable, w, h);
                    self.e.drawable(thread, drawable, w, h);
                }
            }
        }
        self.flush();
    }
}

/// The buffer object bound to a binding point, from the real GL.
pub(crate) fn bound_buffer(binding: u32) -> i32 {
    real::get_int(binding)
}

fn surface_size(kind: SurfaceApi, dpy: u64, drawable: u64) -> (u32, u32) {
    let (mut w, mut h) = (0u32, 0u32);
    // SAFETY: size queries of the drawable just made current, with out-parameters of the
    // right type (unsigned int for GLX, EGLint for EGL).
    unsafe {
        match kind {
            SurfaceApi::Glx => {
                real::glXQueryDrawable(
                    dpy as usize as *mut c_void,
                    drawable as _,
                    GLX_WIDTH,
                    (&mut w as *mut u32).cast(),
                );
                real::glXQueryDrawable(
                    dpy as usize as *mut c_void,
                    drawable as _,
                    GLX_HEIGHT,
                    (&mut h as *mut u32).cast(),
                );
            }
            SurfaceApi::Egl => {
                let (mut ew, mut eh) = (0i32, 0i32);
                let surface = drawable as usize as *mut c_void;
                real::eglQuerySurface(dpy as usize as *mut c_void, surface, EGL_WIDTH, (&mut ew as *mut i32).cast());
                real::eglQuerySurface(dpy as usize as *mut c_void, surface, EGL_HEIGHT, (&mut eh as *mut i32).cast());
                (w, h) = (ew.max(0) as u32, eh.max(0) as u32);
            }
        }
    }
    (w, h)
}
