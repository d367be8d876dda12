//! Client arrays and buffer objects: the pointer state, where a draw's vertices come from
//! (client memory recorded with the draw, or a buffer object), and array draws resolved to
//! vertices for the vertex stage.

use glam::DVec4;
use glray_core::hash::content_hash;
use glray_core::threads::{collect_pieces, copy_of, fill_pieces, piece_of, Filler};
use glray_core::trace::{array_kind, Value};
use glray_gl::{
    GL_ARRAY_BUFFER, GL_COLOR_ARRAY, GL_ELEMENT_ARRAY_BUFFER, GL_FLOAT, GL_INT, GL_NORMAL_ARRAY, GL_POLYGON,
    GL_TEXTURE0, GL_TEXTURE_COORD_ARRAY, GL_TRIANGLES, GL_UNPACK_ALIGNMENT, GL_UNPACK_ROW_LENGTH,
    GL_UNPACK_SKIP_PIXELS, GL_UNPACK_SKIP_ROWS, GL_UNSIGNED_BYTE, GL_UNSIGNED_INT, GL_UNSIGNED_SHORT, GL_VERTEX_ARRAY,
};
use std::sync::Arc;

use crate::args;
use crate::error::{GlError, GlResult};
use crate::fixed::immediate::TEXCOORD_UNITS;
use crate::fixed::lists::fetched_mesh;
use crate::fixed::mesh_builder::Compiled;
use crate::fixed::{Context, Fetched};
use crate::ops::Op;
use crate::primitive::QuadSplit;
use crate::texture::Unpack;

/// Client draws reading fewer elements than this stay the frame's own triangles: they are cheap
/// to make again, and that path follows Mesa's clipping rule for quads (`QuadSplit`).
pub(crate) const KEEP_FROM_ELEMENTS: i64 = 4096;

/// An array draw of buffer objects: its arguments and pointer state, and the buffers it reads.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct BufferDraw {
    words: Vec<i64>,
    buffers: [Option<u32>; 5],
}

impl BufferDraw {
    /// A key of words alone, for meshes of client memory that no draw's arguments describe
    /// (`immediate_meshes`).
    pub(crate) fn of_words(words: Vec<i64>) -> BufferDraw {
        BufferDraw { words, buffers: [None; 5] }
    }
}

/// One array's pointer state, for arrays in buffer objects (client memory arrives with the
/// draw, in the trace's arrays event).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ArrayPointer {
    pub(crate) enabled: bool,
    pub(crate) size: i32,
    pub(crate) ty: u32,
    pub(crate) stride: i32,
    pub(crate) offset: u64,
    pub(crate) buffer: u32,
}

/// An array a draw reads: its memory and layout, from element `first` on.
pub(crate) struct Source<'a> {
    pub(crate) size: usize,
    pub(crate) ty: u32,
    pub(crate) stride: usize,
    pub(crate) first: u64,
    pub(crate) bytes: &'a [u8],
}

impl<'a> Source<'a> {
    /// An array of `size` components of `ty` every `stride` bytes (0: tightly packed), whose
    /// `bytes` start at element `first`; None for a type glray does not read.
    fn new(size: i32, ty: u32, stride: i32, first: u64, bytes: &'a [u8]) -> Option<Source<'a>> {
        let size = size.max(0) as usize;
        let elem = args::type_size(ty)? * size;
        let stride = if stride > 0 { stride as usize } else { elem };
        Some(Source { size, ty, stride, first, bytes })
    }

    pub(crate) fn fetch(&self, i: u64, normalized: bool) -> Option<DVec4> {
        let at = usize::try_from(i.checked_sub(self.first)?).ok()?.checked_mul(self.stride)?;
        let b = self.bytes.get(at..)?;
        let n = self.size.min(4);
        let mut x = [0.0, 0.0, 0.0, 1.0];
        if args::elements(b, self.ty, &mut x[..n]) < n {
            return None;
        }
        if normalized {
            for c in &mut x[..n] {
                *c = args::normalize(*c, self.ty);
            }
        }
        Some(DVec4::from_array(x))
    }

    /// Elements `lo..=hi` as `fetch` gives them, each made into `T` as it is read (no array of
    /// doubles in between: at 10M triangles that was 160 MB per attribute, and most of an
    /// indexed draw's capture), in pieces on glray's threads; None when one is missing.
    fn fetch_range<T: Send>(
        &self,
        lo: u32,
        hi: u32,
        normalized: bool,
        make: impl Fn(DVec4) -> T + Sync,
    ) -> Option<Vec<T>> {
        let len = (hi - lo) as usize + 1;
        let made = collect_pieces(len, piece_of::<T>(), |first, piece| {
            let from = lo + first as u32;
            let till = from + piece.room() as u32;
            if self.ty == GL_FLOAT && self.size >= 1 {
                // Floats read as floats: the same values as through doubles, without the
                // type's dispatch per element (floats are never normalised).
                let n = self.size.min(4);
                for i in from..till {
                    let Some(b) = self.element(i, 4 * n) else { return };
                    let mut x = [0.0, 0.0, 0.0, 1.0];
                    for (c, v) in x.iter_mut().zip(b.chunks_exact(4)) {
                        *c = f32::from_ne_bytes([v[0], v[1], v[2], v[3]]) as f64;
                    }
                    piece.push(make(DVec4::from_array(x)));
                }
                return;
            }
            for i in from..till {
                let Some(v) = self.fetch(u64::from(i), normalized) else { return };
                piece.push(make(v));
            }
        });
        made.map(|(out, _)| out)
    }

    /// Elements `lo..=hi` as three floats each, as `fetch_range` gives them with `make` taking
    /// x, y and z. Arrays of three or four floats (positions, normals: most big draws) are
    /// read as floats straight into the vector, with no round trip through doubles (which
    /// gives the same floats back).
    fn vec3_range(&self, lo: u32, hi: u32, normalized: bool) -> Option<Vec<glam::Vec3>> {
        if self.ty != GL_FLOAT || self.size < 3 {
            return self.fetch_range(lo, hi, normalized, |v| v.truncate().as_vec3());
        }
        let made = collect_pieces((hi - lo) as usize + 1, piece_of::<glam::Vec3>(), |first, piece| {
            let from = lo + first as u32;
            for i in from..from + piece.room() as u32 {
                let Some(b) = self.element(i, 12) else { return };
                let f = |k: usize| f32::from_ne_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
                piece.push(glam::Vec3::new(f(0), f(4), f(8)));
            }
        });
        made.map(|(out, _)| out)
    }

    /// The `len` bytes of element `i`, if the array holds them.
    #[inline]
    fn element(&self, i: u32, len: usize) -> Option<&[u8]> {
        let at = usize::try_from(u64::from(i).checked_sub(self.first)?).ok()?.checked_mul(self.stride)?;
        self.bytes.get(at..at.checked_add(len)?)
    }
}

/// Client state: array pointers, buffer bindings, pixel unpacking.
#[derive(Debug, Clone, Default)]
pub(crate) struct Client {
    pub(crate) vertex: ArrayPointer,
    pub(crate) normal: ArrayPointer,
    pub(crate) color: ArrayPointer,
    pub(crate) texcoord: [ArrayPointer; TEXCOORD_UNITS],
    pub(crate) active_texcoord: usize,
    pub(crate) array_buffer: u32,
    pub(crate) element_buffer: u32,
    pub(crate) unpack: Unpack,
}

/// How an array draw's quads are cut: as Mesa cuts them, along the other diagonal when they come
/// through indices (`QuadSplit`).
pub(crate) fn quad_split(op: Op) -> QuadSplit {
    match op {
        Op::DrawElements | Op::DrawRangeElements | Op::MultiDrawElements => QuadSplit::Indexed,
        _ => QuadSplit::Direct,
    }
}

/// Where glDrawElements (and glDrawRangeElements, after its start and end) keeps its count,
/// index type and indices among its arguments.
fn index_args(op: Op) -> (usize, usize, usize) {
    if op == Op::DrawRangeElements {
        (3, 4, 5)
    } else {
        (1, 2, 3)
    }
}

/// The size of an index of GL type `ty`; None for a type that is not one.
fn index_size(ty: u32) -> Option<usize> {
    match ty {
        GL_UNSIGNED_BYTE => Some(1),
        GL_UNSIGNED_SHORT => Some(2),
        GL_UNSIGNED_INT => Some(4),
        _ => None,
    }
}

/// The index of `SIZE` bytes (1, 2 or 4) at the start of `b`, which holds it.
#[inline(always)]
fn index_at<const SIZE: usize>(b: &[u8]) -> u32 {
    match SIZE {
        1 => u32::from(b[0]),
        2 => u32::from(u16::from_ne_bytes([b[0], b[1]])),
        _ => u32::from_ne_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// The triangles a piece takes, read from the indices of `SIZE` bytes at the start of `bytes`
/// (which holds them all).
fn read_triangles<const SIZE: usize>(bytes: &[u8], triangles: &mut Filler<'_, [u32; 3]>) {
    for b in bytes.chunks_exact(3 * SIZE).take(triangles.room()) {
        triangles.push([index_at::<SIZE>(b), index_at::<SIZE>(&b[SIZE..]), index_at::<SIZE>(&b[2 * SIZE..])]);
    }
}

/// Element `i` of each array (vertex, normal, colour, texture coordinates).
fn fetch(sources: &[Option<Source<'_>>; 4], i: u64) -> Fetched {
    Fetched {
        position: sources[0].as_ref().and_then(|s| s.fetch(i, false)),
        normal: sources[1].as_ref().and_then(|s| s.fetch(i, true)).map(|n| n.truncate()),
        color: sources[2].as_ref().and_then(|s| s.fetch(i, true)),
        tex: sources[3].as_ref().and_then(|s| s.fetch(i, false)),
    }
}

impl Context {
    pub(crate) fn client_array(&mut self, cap: u32) -> Option<&mut ArrayPointer> {
        let c = &mut self.client;
        Some(match cap {
            GL_VERTEX_ARRAY => &mut c.vertex,
            GL_NORMAL_ARRAY => &mut c.normal,
            GL_COLOR_ARRAY => &mut c.color,
            GL_TEXTURE_COORD_ARRAY => &mut c.texcoord[c.active_texcoord],
            _ => return None,
        })
    }

    pub(crate) fn set_pointer(&mut self, cap: u32, size: i32, ty: u32, stride: i32, a: &Value) {
        let buffer = self.client.array_buffer;
        let offset = match a {
            Value::Offset(o) => *o,
            _ => 0,
        };
        if let Some(p) = self.client_array(cap) {
            *p = ArrayPointer { enabled: p.enabled, size, ty, stride, offset, buffer };
        }
    }

    pub(crate) fn bound_buffer(&self, target: u32) -> Option<u32> {
        match target {
            GL_ARRAY_BUFFER => Some(self.client.array_buffer),
            GL_ELEMENT_ARRAY_BUFFER => Some(self.client.element_buffer),
            _ => None,
        }
        .filter(|n| *n != 0)
    }

    /// The vertices an array draw fetches, one list per primitive run.
    pub(crate) fn fetch_draw(&mut self, op: Op, a: &[Value]) -> GlResult<Vec<(u32, Vec<Fetched>)>> {
        let mode = args::uint(a, 0);
        if mode > GL_POLYGON {
            return Err(GlError::InvalidEnum);
        }
        let runs: Vec<Vec<u32>> = match op {
            Op::DrawArrays => {
                let (first, count) = (args::int(a, 1), args::int(a, 2));
                if first < 0 || count < 0 {
                    return Err(GlError::InvalidValue);
                }
                vec![(first as u32..(first + count) as u32).collect()]
            }
            Op::MultiDrawArrays => {
                let n = args::int(a, 3).max(0) as usize;
                let firsts = args::array(args::bytes(a, 1), GL_INT, n);
                let counts = args::array(args::bytes(a, 2), GL_INT, n);
                firsts.iter().zip(&counts).map(|(f, c)| (*f as u32..(*f + c.max(0.0)) as u32).collect()).collect()
            }
            Op::DrawElements | Op::DrawRangeElements => {
                let (count, ty, idx) = index_args(op);
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
                let n = args::int(a, 4);
                let ty = args::uint(a, 2);
                if n < 0 {
                    return Err(GlError::InvalidValue);
                }
                if !matches!(ty, GL_UNSIGNED_BYTE | GL_UNSIGNED_SHORT | GL_UNSIGNED_INT) {
                    return Err(GlError::InvalidEnum);
                }
                let counts = args::array(args::bytes(a, 1), GL_INT, n as usize);
                if counts.iter().any(|c| *c < 0.0) {
                    return Err(GlError::InvalidValue);
                }
                match a.get(3) {
                    // Client memory: each draw's indices.
                    Some(Value::Strings(list)) => list
                        .iter()
                        .zip(&counts)
                        .map(|(bytes, count)| self.indices(&Value::Blob(bytes), ty, *count as usize))
                        .collect(),
                    // Offsets into the element buffer, as the pointers were.
                    Some(Value::Blob(raw)) if self.client.element_buffer != 0 => raw
                        .chunks_exact(std::mem::size_of::<usize>())
                        .zip(&counts)
                        .map(|(o, count)| {
                            let offset = usize::from_ne_bytes(o.try_into().expect("pointer-sized")) as u64;
                            self.indices(&Value::Offset(offset), ty, *count as usize)
                        })
                        .collect(),
                    _ => Vec::new(),
                }
            }
            _ => Vec::new(),
        };
        let sources = self.sources();
        let out =
            runs.into_iter().map(|run| (mode, run.iter().map(|&i| fetch(&sources, u64::from(i))).collect())).collect();
        Ok(out)
    }

    /// glArrayElement(i): element `i` of the enabled arrays.
    pub(crate) fn element(&self, i: u64) -> Fetched {
        fetch(&self.sources(), i)
    }

    /// What identifies an array draw that reads buffer objects only (vertex, normal, colour
    /// and texture arrays, and indices): the same draw of unchanged buffers makes the same
    /// mesh, kept with the buffers (`Shared::buffer_draws`) so that its BVH is kept too. None
    /// for a draw that reads client memory, or is invalid (the uncached path raises its error).
    pub(crate) fn buffer_draw_key(&self, op: Op, a: &[Value]) -> Option<BufferDraw> {
        if !self.arrays.is_empty() || args::uint(a, 0) > GL_POLYGON {
            return None;
        }
        let c = &self.client;
        let pointers = [&c.vertex, &c.normal, &c.color, &c.texcoord[0]];
        if !c.vertex.enabled || pointers.iter().any(|p| p.enabled && p.buffer == 0) {
            return None;
        }
        let mut words: Vec<i64> = vec![i64::from(op == Op::DrawArrays)];
        match op {
            Op::DrawArrays => words.extend([0, 1, 2].map(|i| args::int(a, i))),
            Op::DrawElements | Op::DrawRangeElements => {
                let (count, ty, idx) = index_args(op);
                if c.element_buffer == 0
                    || !matches!(args::uint(a, ty), GL_UNSIGNED_BYTE | GL_UNSIGNED_SHORT | GL_UNSIGNED_INT)
                {
                    return None;
                }
                let offset = match a.get(idx) {
                    Some(Value::Offset(o) | Value::Opaque(o)) => *o as i64,
                    Some(Value::Null) | None => 0,
                    _ => return None,
                };
                words.extend([args::int(a, 0), args::int(a, count), args::int(a, ty), offset]);
            }
            _ => return None,
        }
        if words[1..].iter().any(|w| *w < 0) {
            return None;
        }
        for p in pointers {
            words.extend([p.enabled as i64, p.size as i64, p.ty as i64, p.stride as i64, p.offset as i64]);
        }
        let buffers = [c.vertex.buffer, c.normal.buffer, c.color.buffer, c.texcoord[0].buffer, c.element_buffer];
        Some(BufferDraw { words, buffers: buffers.map(|b| if b == 0 { None } else { Some(b) }) })
    }

    /// What identifies a big array draw that reads client memory only (`client_draws`): its
    /// arguments, each array's layout, and a 128-bit hash of every byte it reads (the arrays'
    /// elements and its indices), so that a draw of the same bytes makes the same mesh. None
    /// for a draw of fewer than `KEEP_FROM_ELEMENTS` elements, one that reads a buffer object,
    /// and an invalid one (the uncached path raises its error).
    pub(crate) fn client_draw_key(&self, op: Op, a: &[Value]) -> Option<BufferDraw> {
        if self.arrays.is_empty() || args::uint(a, 0) > GL_POLYGON {
            return None;
        }
        let c = &self.client;
        let pointers = [&c.vertex, &c.normal, &c.color, &c.texcoord[0]];
        if pointers.iter().any(|p| p.enabled && p.buffer != 0) {
            return None;
        }
        let mut words = match op {
            Op::DrawArrays => {
                let (first, count) = (args::int(a, 1), args::int(a, 2));
                if first < 0 || count < KEEP_FROM_ELEMENTS {
                    return None;
                }
                vec![0, args::int(a, 0), first, count]
            }
            Op::DrawElements | Op::DrawRangeElements => {
                let (count, ty, idx) = index_args(op);
                let count = args::int(a, count);
                let size = match args::uint(a, ty) {
                    GL_UNSIGNED_BYTE => 1,
                    GL_UNSIGNED_SHORT => 2,
                    GL_UNSIGNED_INT => 4,
                    _ => return None,
                };
                // Client indices (with an element buffer bound they are an offset into it).
                let Some(Value::Blob(indices)) = a.get(idx) else { return None };
                if count < KEEP_FROM_ELEMENTS {
                    return None;
                }
                let bytes = usize::try_from(count).ok()?.checked_mul(size)?;
                let mut words = vec![1, args::int(a, 0), count, size as i64];
                words.extend(content_hash(indices.get(..bytes).unwrap_or(indices)));
                words
            }
            _ => return None,
        };
        for ((d, hash), bytes) in self.arrays.iter().zip(&self.array_hashes).zip(&self.array_bytes) {
            words.extend([
                i64::from(d.kind),
                i64::from(d.index),
                i64::from(d.size),
                i64::from(d.gl_type),
                i64::from(d.stride),
                i64::from(d.normalized),
                d.first as i64,
            ]);
            words.extend(hash.unwrap_or_else(|| content_hash(bytes)));
        }
        // Which arrays are enabled decides what the draw reads, beside the memory given.
        words.extend(pointers.map(|p| i64::from(p.enabled)));
        Some(BufferDraw { words, buffers: [None; 5] })
    }

    /// A buffer's contents changed (or it is gone): meshes made from it are stale.
    pub(crate) fn buffer_changed(&mut self, name: u32) {
        self.shared.buffer_draws.retain(|k, _| !k.buffers.contains(&Some(name)));
    }

    /// The first `count` indices of type `ty` (fewer if the memory ends), from client memory or,
    /// with an element buffer bound, from that buffer at offset `v`.
    pub(crate) fn indices(&self, v: &Value, ty: u32, count: usize) -> Vec<u32> {
        let bytes = self.index_bytes(v);
        // Read by type, not element by element: an indexed draw of 10M triangles has 30M.
        match index_size(ty) {
            Some(1) => bytes.chunks_exact(1).take(count).map(index_at::<1>).collect(),
            Some(2) => bytes.chunks_exact(2).take(count).map(index_at::<2>).collect(),
            Some(_) => bytes.chunks_exact(4).take(count).map(index_at::<4>).collect(),
            None => Vec::new(),
        }
    }

    /// The memory a draw's indices `v` are read from: client memory recorded with the draw, or
    /// the bound element buffer from the offset `v` gives.
    fn index_bytes<'a>(&'a self, v: &'a Value) -> &'a [u8] {
        let (bytes, start): (&[u8], usize) = match v {
            // With an element buffer bound the pointer is an offset into it; offset 0 is a
            // null pointer, recorded as such.
            Value::Offset(_) | Value::Opaque(_) | Value::Null if self.client.element_buffer != 0 => {
                let o = match v {
                    Value::Offset(o) | Value::Opaque(o) => *o as usize,
                    _ => 0,
                };
                (self.shared.buffers.get(&self.client.element_buffer).map_or(&[][..], |b| &b[..]), o)
            }
            Value::Blob(b) => (b, 0),
            _ => (&[], 0),
        };
        bytes.get(start..).unwrap_or(&[])
    }

    /// An indexed GL_TRIANGLES draw (glDrawElements, glDrawRangeElements) as an indexed mesh:
    /// each vertex the indices name fetched once, the triangles as index triples. The general
    /// path fetches a vertex per index, repeating every shared vertex (about six times in a
    /// closed surface): at 10M triangles, 30M vertices of f64 attributes (GBs of fresh pages,
    /// most of a 25-second first frame) where 5M are enough. None for other draws, indices
    /// spread far wider than their number, or a vertex the arrays cannot give: the general path
    /// takes those (errors included).
    pub(crate) fn indexed_triangles(&self, op: Op, a: &[Value]) -> Option<Compiled> {
        if !matches!(op, Op::DrawElements | Op::DrawRangeElements) {
            return None;
        }
        let (count, ty, idx) = index_args(op);
        let count = usize::try_from(args::int(a, count)).ok()?;
        if args::uint(a, 0) != GL_TRIANGLES || count < 3 {
            return None;
        }
        let size = index_size(args::uint(a, ty))?;
        let bytes = self.index_bytes(a.get(idx).unwrap_or(&Value::Null));
        let count = count.min(bytes.len() / size);
        if count == 0 {
            return None;
        }
        // The indices' range (every one of them, a trailing index that makes no whole triangle
        // included, as in the general path), then the triangles read straight from them, both
        // in pieces on glray's threads: at 10M triangles these are 120 MB in and out, on the
        // program's thread while the tracer's wait.
        let (lo, hi) = glray_core::indices::min_max(&bytes[..count * size], size)?;
        let (mut triangles, _) = collect_pieces(count / 3, piece_of::<[u32; 3]>(), |first, piece| {
            let from = &bytes[3 * size * first..];
            match size {
                1 => read_triangles::<1>(from, piece),
                2 => read_triangles::<2>(from, piece),
                _ => read_triangles::<4>(from, piece),
            }
        })?;
        let n = (hi as usize).checked_sub(lo as usize)? + 1;
        if n > 2 * count + 1024 {
            return None;
        }
        if lo != 0 {
            fill_pieces(&mut triangles, piece_of::<[u32; 3]>(), |_, piece| {
                for t in piece {
                    *t = t.map(|i| i - lo);
                }
            });
        }
        let sources = self.sources();
        let range = |k: usize, normalized: bool| -> Option<Option<Vec<glam::Vec4>>> {
            match &sources[k] {
                Some(s) => s.fetch_range(lo, hi, normalized, |v| v.as_vec4()).map(Some),
                None => Some(None),
            }
        };
        let position = sources[0].as_ref()?;
        // w is 1 unless the array gives it.
        let (positions, ws) = if position.size >= 4 {
            position.fetch_range(lo, hi, false, |p| (p.truncate().as_vec3(), p.w as f32))?.into_iter().unzip()
        } else {
            (position.vec3_range(lo, hi, false)?, Vec::new())
        };
        let normals = match &sources[1] {
            Some(s) => Some(s.vec3_range(lo, hi, true)?),
            None => None,
        };
        let colors = range(2, true)?;
        let texcoords = range(3, false)?;
        // What the last index leaves current, as the general path's last vertex does (a
        // trailing index that makes no whole triangle included), exactly as given.
        let last_at = &bytes[(count - 1) * size..];
        let last = u64::from(match size {
            1 => index_at::<1>(last_at),
            2 => index_at::<2>(last_at),
            _ => index_at::<4>(last_at),
        });
        let current = |k: usize, normalized: bool| sources[k].as_ref().and_then(|s| s.fetch(last, normalized));
        let end = (current(1, true).map(|n| n.truncate()), current(2, true), current(3, false));
        Some(Compiled::from_arrays(positions, ws, normals, colors, texcoords, triangles, end))
    }

    /// Where each array (vertex, normal, color, texcoord 0) of the next draw comes from.
    pub(crate) fn sources(&self) -> [Option<Source<'_>>; 4] {
        let kinds = [
            (array_kind::VERTEX, &self.client.vertex),
            (array_kind::NORMAL, &self.client.normal),
            (array_kind::COLOR, &self.client.color),
            (array_kind::TEXCOORD, &self.client.texcoord[0]),
        ];
        kinds.map(|(kind, p)| {
            // Client memory recorded with the draw.
            if let Some((i, d)) = self
                .arrays
                .iter()
                .enumerate()
                .find(|(_, d)| d.kind == kind && (kind != array_kind::TEXCOORD || d.index == 0))
            {
                return Source::new(d.size, d.gl_type, d.stride, d.first, &self.array_bytes[i]);
            }
            // A buffer object.
            if p.enabled && p.buffer != 0 {
                let buf = self.shared.buffers.get(&p.buffer)?;
                return Source::new(p.size, p.ty, p.stride, 0, buf.get(p.offset as usize..).unwrap_or(&[]));
            }
            None
        })
    }

    /// Runs fetched vertices through the vertex stage as one draw.
    pub(crate) fn draw_fetched(&mut self, mode: u32, verts: &[Fetched], quads: QuadSplit) {
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
        self.draw(mode, &outs, quads);
    }
}

/// How many buffer draws' meshes a share group keeps (a program that makes new draws every
/// frame must not grow it without end).
const MAX_BUFFER_DRAWS: usize = 256;

impl Context {
    /// Follows a client-array or buffer-object command, or an array draw (`Concern::Arrays`).
    pub(crate) fn array_command(&mut self, op: Op, a: &[Value]) -> GlResult {
        match op {
            Op::ClientActiveTexture => {
                let unit = args::uint(a, 0).wrapping_sub(GL_TEXTURE0) as usize;
                if unit >= TEXCOORD_UNITS {
                    return Err(GlError::InvalidEnum);
                }
                self.client.active_texcoord = unit;
            }
            Op::EnableClientState | Op::DisableClientState => {
                let on = op == Op::EnableClientState;
                match self.client_array(args::uint(a, 0)) {
                    Some(p) => p.enabled = on,
                    None => return Err(GlError::InvalidEnum),
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
                if self.programmable {
                    return self.program_draw(op, a);
                }
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
            _ => unreachable!("{op:?} is not an array command"),
        }
        Ok(())
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_gl::{GL_BYTE, GL_DOUBLE, GL_SHORT};

    #[test]
    fn a_big_blocks_hash_in_pieces_sees_every_byte() {
        // Big enough to be hashed in pieces on all cores; a byte changed in any piece, the last
        // included, changes the hash, and the same bytes elsewhere give the same one.
        let mut bytes: Vec<u8> = (0..(17usize << 20) + 3).map(|k| (k * 31 + k / 4093) as u8).collect();
        let hash = content_hash(&bytes);
        assert_eq!(content_hash(&bytes.clone()), hash);
        for at in [0, 5 << 20, bytes.len() - 1] {
            bytes[at] ^= 1;
            assert_ne!(content_hash(&bytes), hash, "byte {at} changed");
            bytes[at] ^= 1;
        }
        assert_ne!(content_hash(&bytes[..bytes.len() - 1]), hash, "one byte fewer");
    }

    #[test]
    fn a_range_of_elements_is_what_fetching_each_gives() {
        // Every type an array can have, 1 to 4 components, packed and with a stride, from a
        // first element on, normalised and not: `fetch_range` (floats read straight as floats)
        // against `fetch` element by element; and a range past the memory gives nothing.
        let memory: Vec<u8> = (0..400u32).map(|k| (k * 37 + 11) as u8).collect();
        for ty in [GL_BYTE, GL_UNSIGNED_BYTE, GL_SHORT, GL_UNSIGNED_SHORT, GL_INT, GL_UNSIGNED_INT, GL_FLOAT, GL_DOUBLE]
        {
            for size in 1..=4 {
                for stride in [0, 36] {
                    for normalized in [false, true] {
                        let s = Source::new(size, ty, stride, 2, &memory).expect("a type glray reads");
                        let whole = |p: DVec4| p.to_array().map(f64::to_bits);
                        let each: Option<Vec<_>> = (3..=7u64).map(|i| s.fetch(i, normalized).map(whole)).collect();
                        let each = each.expect("within the memory");
                        assert_eq!(
                            s.fetch_range(3, 7, normalized, whole),
                            Some(each),
                            "{ty:#x} x{size} stride {stride}"
                        );
                        assert_eq!(s.fetch_range(3, 500, normalized, whole), None, "past the memory");
                    }
                }
            }
        }
    }

    // Through the context, as a program calls them.
    use crate::fixed::tests::*;
    use glam::{DVec4, Vec3, Vec4};
    use glray_core::trace::{ArrayData, Value};

    use glray_scene::frame::TriangleId;

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
    fn big_client_draws_are_kept_by_the_bytes_they_read() {
        use crate::fixed::arrays::KEEP_FROM_ELEMENTS;
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
    fn array_elements_give_vertices_inside_glbegin_and_in_lists() {
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
    fn multi_draw_elements_draws_each_index_array() {
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
    #[test]
    fn draws_of_unchanged_buffers_keep_their_mesh() {
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
}
