//! Client arrays and buffer objects: the pointer state, where a draw's vertices come from
//! (client memory recorded with the draw, or a buffer object), and array draws resolved to
//! vertices for the vertex stage.

use glam::DVec4;
use glray_core::hash::content_hash;
use glray_core::threads::{collect_pieces, fill_pieces, piece_of, Filler};
use glray_core::trace::{array_kind, Value};
use glray_gl::{
    GL_ARRAY_BUFFER, GL_COLOR_ARRAY, GL_ELEMENT_ARRAY_BUFFER, GL_FLOAT, GL_INT, GL_NORMAL_ARRAY, GL_POLYGON,
    GL_TEXTURE_COORD_ARRAY, GL_TRIANGLES, GL_UNSIGNED_BYTE, GL_UNSIGNED_INT, GL_UNSIGNED_SHORT, GL_VERTEX_ARRAY,
};

use crate::args;
use crate::client_draws::KEEP_FROM_ELEMENTS;
use crate::context::{Context, Fetched};
use crate::error::{GlError, GlResult};
use crate::immediate::TEXCOORD_UNITS;
use crate::mesh_builder::Compiled;
use crate::ops::Op;
use crate::primitive::QuadSplit;
use crate::texture::Unpack;

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
}
