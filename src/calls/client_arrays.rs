//! Client vertex arrays while recording: which are enabled and where they point (tracked from
//! the calls, since glArrayElement inside glBegin/glEnd forbids asking GL), and, at each draw,
//! the range of elements the draw reads, whose memory goes into the trace before the call.

use glray_gl::{
    GL_ARRAY_BUFFER_BINDING, GL_CLIENT_ACTIVE_TEXTURE, GL_ELEMENT_ARRAY_BUFFER, GL_ELEMENT_ARRAY_BUFFER_BINDING,
    GL_FLOAT, GL_MAX_TEXTURE_COORDS, GL_MAX_VERTEX_ATTRIBS, GL_TEXTURE0, GL_UNSIGNED_BYTE,
};
use std::ffi::c_void;

use glray_core::gltypes::{array_element_bytes, value_bytes};
use glray_core::trace::{array_kind, ArrayData};

use super::bound_buffer;
use crate::abi::commands::cmd;
use crate::abi::real;

const MAX_UNITS: usize = 32;

#[derive(Debug, Clone, Copy)]
struct Array {
    enabled: bool,
    size: i32,
    ty: u32,
    stride: i32,
    normalized: bool,
    ptr: u64,
    /// The buffer object the pointer was set with (0: client memory).
    buffer: i32,
}

impl Array {
    const fn new(size: i32, ty: u32) -> Array {
        Array { enabled: false, size, ty, stride: 0, normalized: false, ptr: 0, buffer: 0 }
    }

    /// Enabled, and read from the program's memory rather than a buffer object.
    fn reads_client(&self) -> bool {
        self.enabled && self.buffer == 0 && self.ptr != 0
    }

    fn element_bytes(&self) -> u64 {
        array_element_bytes(self.size, self.ty)
    }
}

/// The client-array state of one recorded thread.
#[derive(Debug, Clone)]
pub struct ClientArrays {
    fixed: [Array; 8],
    texcoords: [Array; MAX_UNITS],
    attribs: [Array; MAX_UNITS],
    client_active: usize,
    /// Whether any enabled array reads client memory: asked before every geometry call
    /// (glBegin and glEnd among them), set by `track`, the only way the arrays change.
    client: bool,
}

impl Default for ClientArrays {
    fn default() -> Self {
        let fixed = [
            Array::new(4, GL_FLOAT),         // vertex
            Array::new(3, GL_FLOAT),         // normal
            Array::new(4, GL_FLOAT),         // color
            Array::new(4, GL_FLOAT),         // (texcoords are per unit)
            Array::new(3, GL_FLOAT),         // secondary color
            Array::new(1, GL_FLOAT),         // fog coordinate
            Array::new(1, GL_UNSIGNED_BYTE), // edge flag
            Array::new(1, GL_FLOAT),         // color index
        ];
        ClientArrays {
            fixed,
            texcoords: [Array::new(4, GL_FLOAT); MAX_UNITS],
            attribs: [Array::new(4, GL_FLOAT); MAX_UNITS],
            client_active: 0,
            client: false,
        }
    }
}

/// Array memory one draw reads, where the program keeps it (read while the draw is recorded;
/// at 10M triangles a copy was 120 MB of fresh pages per draw).
pub struct Captured<'m> {
    kind: u8,
    index: u32,
    array: Array,
    first: u64,
    bytes: &'m [u8],
}

impl Captured<'_> {
    pub fn as_data(&self) -> ArrayData<'_> {
        ArrayData {
            kind: self.kind,
            index: self.index,
            size: self.array.size,
            gl_type: self.array.ty,
            stride: self.array.stride,
            normalized: self.array.normalized,
            first: self.first,
            bytes: self.bytes,
        }
    }
}

fn kind_of_cap(cap: u64) -> Option<usize> {
    Some(match cap {
        0x8074 => array_kind::VERTEX,
        0x8075 => array_kind::NORMAL,
        0x8076 => array_kind::COLOR,
        0x8078 => array_kind::TEXCOORD,
        0x845E => array_kind::SECONDARY_COLOR,
        0x8457 => array_kind::FOG_COORD,
        0x8079 => array_kind::EDGE_FLAG,
        0x8077 => array_kind::INDEX,
        _ => return None,
    } as usize)
}

impl ClientArrays {
    fn slot(&mut self, kind: usize) -> &mut Array {
        if kind == array_kind::TEXCOORD as usize {
            &mut self.texcoords[self.client_active]
        } else {
            &mut self.fixed[kind]
        }
    }

    fn set(&mut self, kind: usize, size: i32, ty: u32, stride: i32, ptr: u64) {
        let buffer = bound_buffer(GL_ARRAY_BUFFER_BINDING);
        let a = self.slot(kind);
        (a.size, a.ty, a.stride, a.ptr, a.buffer) = (size, ty, stride, ptr, buffer);
    }

    /// Follows the calls that change client-array state.
    pub fn track(&mut self, c: usize, a: &[u64]) {
        let i = |k: usize| a[k] as i64 as i32;
        let u = |k: usize| a[k] as u32;
        match c {
            cmd::glVertexPointer => self.set(0, i(0), u(1), i(2), a[3]),
            cmd::glVertexPointerEXT => self.set(0, i(0), u(1), i(2), a[4]),
            cmd::glNormalPointer => self.set(1, 3, u(0), i(1), a[2]),
            cmd::glNormalPointerEXT => self.set(1, 3, u(0), i(1), a[3]),
            cmd::glColorPointer => self.set(2, i(0), u(1), i(2), a[3]),
            cmd::glColorPointerEXT => self.set(2, i(0), u(1), i(2), a[4]),
            cmd::glTexCoordPointer => self.set(3, i(0), u(1), i(2), a[3]),
            cmd::glTexCoordPointerEXT => self.set(3, i(0), u(1), i(2), a[4]),
            cmd::glSecondaryColorPointer | cmd::glSecondaryColorPointerEXT => self.set(4, i(0), u(1), i(2), a[3]),
            cmd::glFogCoordPointer | cmd::glFogCoordPointerEXT => self.set(5, 1, u(0), i(1), a[2]),
            cmd::glEdgeFlagPointer => self.set(6, 1, GL_UNSIGNED_BYTE, i(0), a[1]),
            cmd::glEdgeFlagPointerEXT => self.set(6, 1, GL_UNSIGNED_BYTE, i(0), a[2]),
            cmd::glIndexPointer => self.set(7, 1, u(0), i(1), a[2]),
            cmd::glIndexPointerEXT => self.set(7, 1, u(0), i(1), a[3]),
            cmd::glVertexAttribPointer | cmd::glVertexAttribPointerARB => {
                if let Some(slot) = self.attribs.get_mut(a[0] as usize) {
                    let buffer = bound_buffer(GL_ARRAY_BUFFER_BINDING);
                    (slot.size, slot.ty, slot.normalized, slot.stride, slot.ptr, slot.buffer) =
                        (i(1), u(2), a[3] != 0, i(4), a[5], buffer);
                }
            }
            cmd::glEnableClientState | cmd::glDisableClientState => {
                if let Some(k) = kind_of_cap(a[0]) {
                    self.slot(k).enabled = c == cmd::glEnableClientState;
                }
            }
            cmd::glEnableVertexAttribArray
            | cmd::glEnableVertexAttribArrayARB
            | cmd::glDisableVertexAttribArray
            | cmd::glDisableVertexAttribArrayARB => {
                let on = c == cmd::glEnableVertexAttribArray || c == cmd::glEnableVertexAttribArrayARB;
                if let Some(slot) = self.attribs.get_mut(a[0] as usize) {
                    slot.enabled = on;
                }
            }
            cmd::glClientActiveTexture | cmd::glClientActiveTextureARB => {
                self.client_active = (a[0].wrapping_sub(GL_TEXTURE0 as u64) as usize).min(MAX_UNITS - 1);
            }
            // Calls that set many arrays at once: read the state back from GL.
            cmd::glInterleavedArrays | cmd::glPopClientAttrib | cmd::glBindVertexArray => self.sync_from_gl(),
            _ => return,
        }
        self.client = self.fixed.iter().chain(&self.texcoords).chain(&self.attribs).any(Array::reads_client);
    }

    /// Whether any enabled array reads client memory (so a draw needs capturing).
    pub fn any_client(&self) -> bool {
        self.client
    }

    /// The memory of every enabled client array for elements `lo..=hi`.
    ///
    /// # Safety
    /// Only while the draw that reads these elements is being made: `'m` must not outlive it.
    pub unsafe fn capture<'m>(&self, (lo, hi): (u64, u64)) -> Vec<Captured<'m>> {
        let mut out = Vec::new();
        let mut add = |kind: u8, index: u32, a: &Array| {
            if !a.reads_client() {
                return;
            }
            let elem = a.element_bytes();
            let stride = if a.stride > 0 { a.stride as u64 } else { elem };
            let len = (hi - lo).saturating_mul(stride).saturating_add(elem);
            if len > 1 << 30 {
                glray_core::warn!("recording: a draw reads {len} bytes of one array; not recorded");
                return;
            }
            let start = a.ptr.wrapping_add(lo.wrapping_mul(stride));
            // SAFETY: the draw being recorded reads exactly these elements of this array, and
            // the program keeps them as they are until it returns (the caller's promise).
            let bytes = unsafe { std::slice::from_raw_parts(start as usize as *const u8, len as usize) };
            out.push(Captured { kind, index, array: *a, first: lo, bytes });
        };
        for (k, a) in self.fixed.iter().enumerate() {
            if k != array_kind::TEXCOORD as usize {
                add(k as u8, 0, a);
            }
        }
        for (u, a) in self.texcoords.iter().enumerate() {
            add(array_kind::TEXCOORD, u as u32, a);
        }
        for (i, a) in self.attribs.iter().enumerate() {
            add(array_kind::ATTRIB, i as u32, a);
        }
        out
    }

    /// Reads the whole client-array state back from the real GL (after calls that change many
    /// arrays at once). Never called inside glBegin/glEnd: those calls are not allowed there.
    fn sync_from_gl(&mut self) {
        // (enable cap, size, type, stride, pointer, buffer binding) queries per fixed array;
        // 0 = not applicable.
        const Q: [(u32, u32, u32, u32, u32, u32); 8] = [
            (0x8074, 0x807A, 0x807B, 0x807C, 0x808E, 0x8896),
            (0x8075, 0, 0x807E, 0x807F, 0x808F, 0x8897),
            (0x8076, 0x8081, 0x8082, 0x8083, 0x8090, 0x8898),
            (0x8078, 0x8088, 0x8089, 0x808A, 0x8092, 0x889A),
            (0x845E, 0x845A, 0x845B, 0x845C, 0x845D, 0x889C),
            (0x8457, 0, 0x8454, 0x8455, 0x8456, 0x889D),
            (0x8079, 0, 0, 0x808C, 0x8093, 0x889B),
            (0x8077, 0, 0x8085, 0x8086, 0x8091, 0x8899),
        ];
        // SAFETY: state queries with out-parameters of the right sizes.
        unsafe {
            let geti = real::get_int;
            let getp = |pname: u32| {
                let mut p: *mut c_void = std::ptr::null_mut();
                real::glGetPointerv(pname, (&mut p as *mut *mut c_void).cast());
                p as usize as u64
            };
            // A core profile has only generic attributes: asking for the fixed arrays there
            // would leave GL_INVALID_ENUM for the program's glGetError.
            let fixed = !crate::abi::profile::core();
            for (k, q) in Q.iter().enumerate().filter(|_| fixed) {
                if k == array_kind::TEXCOORD as usize {
                    continue;
                }
                let a = &mut self.fixed[k];
                a.enabled = real::glIsEnabled(q.0) != 0;
                if q.1 != 0 {
                    a.size = geti(q.1);
                }
                if q.2 != 0 {
                    a.ty = geti(q.2) as u32;
                }
                a.stride = geti(q.3);
                a.ptr = getp(q.4);
                a.buffer = geti(q.5);
            }
            let q = Q[array_kind::TEXCOORD as usize];
            let active = if fixed { geti(GL_CLIENT_ACTIVE_TEXTURE) } else { GL_TEXTURE0 as i32 }; // GL_CLIENT_ACTIVE_TEXTURE
            let units = if fixed { (geti(GL_MAX_TEXTURE_COORDS) as usize).clamp(1, MAX_UNITS) } else { 0 }; // GL_MAX_TEXTURE_COORDS
            for u in 0..units {
                real::glClientActiveTexture(GL_TEXTURE0 + u as u32);
                let a = &mut self.texcoords[u];
                a.enabled = real::glIsEnabled(q.0) != 0;
                (a.size, a.ty, a.stride, a.ptr, a.buffer) =
                    (geti(q.1), geti(q.2) as u32, geti(q.3), getp(q.4), geti(q.5));
            }
            if fixed {
                real::glClientActiveTexture(active as u32);
            }
            self.client_active = (active as u32).wrapping_sub(GL_TEXTURE0) as usize % MAX_UNITS;
            let attribs = (geti(GL_MAX_VERTEX_ATTRIBS) as usize).min(MAX_UNITS); // GL_MAX_VERTEX_ATTRIBS
            for i in 0..attribs {
                let attr = |pname: u32| {
                    let mut v = 0i32;
                    real::glGetVertexAttribiv(i as u32, pname, (&mut v as *mut i32).cast());
                    v
                };
                let mut p: *mut c_void = std::ptr::null_mut();
                real::glGetVertexAttribPointerv(i as u32, 0x8645, (&mut p as *mut *mut c_void).cast());
                let a = &mut self.attribs[i];
                a.enabled = attr(0x8622) != 0;
                (a.size, a.stride, a.ty, a.normalized, a.buffer) =
                    (attr(0x8623), attr(0x8624), attr(0x8625) as u32, attr(0x886A) != 0, attr(0x889F));
                a.ptr = p as usize as u64;
            }
        }
    }
}

/// Reads `count` indices of `ty` from client memory `ptr` or, with an element buffer bound, from
/// that buffer at offset `ptr`; returns their smallest and largest value.
fn index_range(count: i64, ty: u32, ptr: u64, base_vertex: i64) -> Option<(u64, u64)> {
    if count <= 0 {
        return None;
    }
    let size = value_bytes(ty) as usize;
    let bytes = (count as usize).checked_mul(size)?;
    let buffer: Vec<u8>;
    let data: &[u8] = if bound_buffer(GL_ELEMENT_ARRAY_BUFFER_BINDING) != 0 {
        let mut v = vec![0u8; bytes];
        // SAFETY: reads `bytes` bytes of the bound element buffer into `v`.
        unsafe {
            real::glGetBufferSubData(GL_ELEMENT_ARRAY_BUFFER, ptr as isize, bytes as isize, v.as_mut_ptr().cast())
        };
        buffer = v;
        &buffer
    } else if ptr == 0 {
        return None;
    } else {
        // SAFETY: the draw reads `count` indices from this client memory; read where they are
        // (a copy of 10M triangles' indices was 120 MB of fresh pages per draw).
        unsafe { std::slice::from_raw_parts(ptr as usize as *const u8, bytes) }
    };
    let (lo, hi) = glray_core::indices::min_max(data, size)?;
    // Adding the base vertex keeps the order, so the range moves as a whole.
    let based = |v: u32| (v as i64 + base_vertex).max(0) as u64;
    Some((based(lo), based(hi)))
}

fn union(a: Option<(u64, u64)>, b: Option<(u64, u64)>) -> Option<(u64, u64)> {
    match (a, b) {
        (Some(x), Some(y)) => Some((x.0.min(y.0), x.1.max(y.1))),
        (x, None) => x,
        (None, y) => y,
    }
}

/// The elements a draw command reads from the arrays, inclusive; None for other commands.
pub fn draw_range(c: usize, a: &[u64]) -> Option<(u64, u64)> {
    let span = |first: u64, count: u64| {
        let (first, count) = (first as i64 as i32, count as i64 as i32);
        (first >= 0 && count > 0).then(|| (first as u64, first as u64 + count as u64 - 1))
    };
    match c {
        cmd::glDrawArrays
        | cmd::glDrawArraysEXT
        | cmd::glDrawArraysInstanced
        | cmd::glDrawArraysInstancedARB
        | cmd::glDrawArraysInstancedEXT => span(a[1], a[2]),
        cmd::glArrayElement | cmd::glArrayElementEXT => span(a[0], 1),
        cmd::glDrawElements
        | cmd::glDrawElementsInstanced
        | cmd::glDrawElementsInstancedARB
        | cmd::glDrawElementsInstancedEXT => index_range(a[1] as i64 as i32 as i64, a[2] as u32, a[3], 0),
        cmd::glDrawElementsBaseVertex => {
            index_range(a[1] as i64 as i32 as i64, a[2] as u32, a[3], a[4] as i64 as i32 as i64)
        }
        cmd::glDrawRangeElements | cmd::glDrawRangeElementsEXT => {
            index_range(a[3] as i64 as i32 as i64, a[4] as u32, a[5], 0)
        }
        cmd::glDrawRangeElementsBaseVertex => {
            index_range(a[3] as i64 as i32 as i64, a[4] as u32, a[5], a[6] as i64 as i32 as i64)
        }
        cmd::glMultiDrawArrays | cmd::glMultiDrawArraysEXT => {
            let n = a[3] as i64 as i32;
            let (firsts, counts) = (a[1] as usize as *const i32, a[2] as usize as *const i32);
            if n <= 0 || firsts.is_null() || counts.is_null() {
                return None;
            }
            // SAFETY: the draw reads `n` firsts and counts.
            (0..n as usize)
                .fold(None, |acc, i| unsafe { union(acc, span(*firsts.add(i) as u64, *counts.add(i) as u64)) })
        }
        cmd::glMultiDrawElements | cmd::glMultiDrawElementsEXT => {
            let n = a[4] as i64 as i32;
            let (counts, indices) = (a[1] as usize as *const i32, a[3] as usize as *const u64);
            if n <= 0 || counts.is_null() || indices.is_null() {
                return None;
            }
            // SAFETY: the draw reads `n` counts and index pointers.
            (0..n as usize).fold(None, |acc, i| unsafe {
                union(acc, index_range(*counts.add(i) as i64, a[2] as u32, *indices.add(i), 0))
            })
        }
        _ => None,
    }
}
