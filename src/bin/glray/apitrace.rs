//! Reading apitrace's trace files (docs/trace-format.md, "apitrace's traces"): the file is `at`
//! then chunks of a little-endian u32 length and a raw snappy block; the stream is apitrace's
//! binary format (its docs/FORMAT.markdown, versions up to 6). Each call is converted into a
//! call of glray's trace format, in the order calls returned, so that `glray replay` plays it
//! like one of its own:
//! - arrays of values become the memory of the parameter's element type (from the Khronos
//!   registry, via build.rs's parameter codes); apitrace's "fake" pointer calls already carry
//!   client vertex arrays as blobs, so no ARRAYS events are needed;
//! - apitrace does not record drawable sizes: the first glViewport a thread issues after a
//!   MakeCurrent gives it (apitrace itself emits such a viewport call);
//! - glXSwapBuffers/eglSwapBuffers end frames;
//! - apitrace's `memcpy` pseudo-calls (what a program wrote into a mapped buffer) become a
//!   glBufferSubData of that range after the buffer's glUnmapBuffer, as glray records them.

use std::collections::HashMap;

use glray_core::trace::Encoder;

use crate::commands::{cmd, lookup, COUNT};

mod params {
    use crate::commands::COUNT;
    include!(concat!(env!("OUT_DIR"), "/params.rs"));
}

/// Whether `data` looks like an apitrace file.
pub fn is_apitrace(data: &[u8]) -> bool {
    data.starts_with(b"at")
}

/// Decompresses the snappy container; errors name the byte offset in the file.
fn decompress(data: &[u8]) -> Result<Vec<u8>, String> {
    const MAX_CHUNK: usize = 64 << 20;
    let mut out = Vec::new();
    let mut pos = 2;
    let mut dec = snap::raw::Decoder::new();
    while pos < data.len() {
        let len_bytes = data.get(pos..pos + 4).ok_or_else(|| format!("byte {pos}: truncated chunk length"))?;
        let len = u32::from_le_bytes(len_bytes.try_into().unwrap()) as usize;
        let chunk = data
            .get(pos + 4..pos + 4 + len)
            .ok_or_else(|| format!("byte {pos}: chunk of {len} bytes, {} left", data.len() - pos - 4))?;
        let size = snap::raw::decompress_len(chunk).map_err(|e| format!("byte {pos}: {e}"))?;
        if size > MAX_CHUNK {
            return Err(format!("byte {pos}: a chunk claims {size} bytes uncompressed"));
        }
        let start = out.len();
        out.resize(start + size, 0);
        dec.decompress(chunk, &mut out[start..]).map_err(|e| format!("byte {pos}: {e}"))?;
        pos += 4 + len;
    }
    Ok(out)
}

/// An apitrace value.
#[derive(Debug, Clone)]
enum V {
    Null,
    Int(i64),
    UInt(u64),
    F32(f32),
    F64(f64),
    Str(Vec<u8>),
    Blob(Vec<u8>),
    Array(Vec<V>),
    Opaque(u64),
    Other,
}

impl V {
    fn int(&self) -> i64 {
        match self {
            V::Int(x) => *x,
            V::UInt(x) => *x as i64,
            V::F32(x) => *x as i64,
            V::F64(x) => *x as i64,
            V::Opaque(x) => *x as i64,
            _ => 0,
        }
    }

    fn float(&self) -> f64 {
        match self {
            V::F32(x) => *x as f64,
            V::F64(x) => *x,
            other => other.int() as f64,
        }
    }
}

struct Call {
    thread: u32,
    sig: usize,
    args: Vec<V>,
    ret: Option<V>,
}

/// The stream parser: apitrace's signatures are defined at first use and referred to by id.
struct Parser<'a> {
    data: &'a [u8],
    pos: usize,
    version: u64,
    functions: HashMap<u64, (String, usize)>,
    enums: HashMap<u64, ()>,
    bitmasks: HashMap<u64, ()>,
    structs: HashMap<u64, usize>,
    frames: HashMap<u64, ()>,
}

impl<'a> Parser<'a> {
    fn err(&self, what: &str) -> String {
        format!("apitrace stream byte {}: {what}", self.pos)
    }

    fn byte(&mut self) -> Result<u8, String> {
        let b = *self.data.get(self.pos).ok_or_else(|| self.err("truncated"))?;
        self.pos += 1;
        Ok(b)
    }

    fn uint(&mut self) -> Result<u64, String> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = self.byte()?;
            v |= ((b & 0x7f) as u64) << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(self.err("integer longer than 64 bits"))
    }

    fn count(&mut self, what: &str) -> Result<usize, String> {
        let n = self.uint()?;
        if n > (self.data.len() - self.pos) as u64 {
            return Err(self.err(&format!("impossible count of {what}: {n}")));
        }
        Ok(n as usize)
    }

    fn bytes(&mut self, n: usize) -> Result<&'a [u8], String> {
        let s = self.data.get(self.pos..self.pos + n).ok_or_else(|| self.err("truncated"))?;
        self.pos += n;
        Ok(s)
    }

    fn string(&mut self) -> Result<Vec<u8>, String> {
        let n = self.count("string bytes")?;
        Ok(self.bytes(n)?.to_vec())
    }

    fn sint(&mut self) -> Result<i64, String> {
        match self.byte()? {
            3 => Ok(-(self.uint()? as i64)),
            4 => Ok(self.uint()? as i64),
            t => Err(self.err(&format!("expected an integer, found type {t}"))),
        }
    }

    fn value(&mut self, depth: u32) -> Result<V, String> {
        if depth > 64 {
            return Err(self.err("values nested too deep"));
        }
        Ok(match self.byte()? {
            0x00 => V::Null,
            0x01 => V::UInt(0),
            0x02 => V::UInt(1),
            0x03 => V::Int(-(self.uint()? as i64)),
            0x04 => V::UInt(self.uint()?),
            0x05 => V::F32(f32::from_le_bytes(self.bytes(4)?.try_into().unwrap())),
            0x06 => V::F64(f64::from_le_bytes(self.bytes(8)?.try_into().unwrap())),
            0x07 => V::Str(self.string()?),
            0x08 => V::Blob(self.string()?),
            0x09 => {
                let id = self.uint()?;
                if self.version >= 3 && !self.enums.contains_key(&id) {
                    let n = self.count("enum values")?;
                    for _ in 0..n {
                        self.string()?;
                        self.sint()?;
                    }
                    self.enums.insert(id, ());
                } else if self.version < 3 && !self.enums.contains_key(&id) {
                    self.string()?;
                    self.value(depth + 1)?;
                    self.enums.insert(id, ());
                }
                if self.version >= 3 {
                    V::Int(self.sint()?)
                } else {
                    V::Other
                }
            }
            0x0a => {
                let id = self.uint()?;
                if !self.bitmasks.contains_key(&id) {
                    let n = self.count("bitmask flags")?;
                    for _ in 0..n {
                        self.string()?;
                        self.uint()?;
                    }
                    self.bitmasks.insert(id, ());
                }
                V::UInt(self.uint()?)
            }
            0x0b => {
                let n = self.count("array values")?;
                let mut values = Vec::with_capacity(n);
                for _ in 0..n {
                    values.push(self.value(depth + 1)?);
                }
                V::Array(values)
            }
            0x0c => {
                let id = self.uint()?;
                let members = match self.structs.get(&id) {
                    Some(m) => *m,
                    None => {
                        self.string()?;
                        let n = self.count("struct members")?;
                        for _ in 0..n {
                            self.string()?;
                        }
                        self.structs.insert(id, n);
                        n
                    }
                };
                for _ in 0..members {
                    self.value(depth + 1)?;
                }
                V::Other
            }
            0x0d => V::Opaque(self.uint()?),
            0x0e => {
                self.value(depth + 1)?;
                self.value(depth + 1)?
            }
            0x0f => {
                let n = self.count("wide characters")?;
                for _ in 0..n {
                    self.uint()?;
                }
                V::Other
            }
            t => return Err(self.err(&format!("unknown value type {t}"))),
        })
    }

    /// Call details up to the terminator: arguments, return value, flags, backtrace.
    fn details(&mut self, call: &mut Call) -> Result<(), String> {
        loop {
            match self.byte()? {
                0x00 => return Ok(()),
                0x01 => {
                    let i = self.count("argument number")?;
                    let v = self.value(0)?;
                    if call.args.len() <= i {
                        call.args.resize(i + 1, V::Null);
                    }
                    call.args[i] = v;
                }
                0x02 => call.ret = Some(self.value(0)?),
                0x03 => call.thread = self.uint()? as u32,
                0x04 => {
                    let n = self.count("backtrace frames")?;
                    for _ in 0..n {
                        let id = self.uint()?;
                        if !self.frames.contains_key(&id) {
                            loop {
                                match self.byte()? {
                                    0 => break,
                                    1..=3 => {
                                        self.string()?;
                                    }
                                    4 | 5 => {
                                        self.uint()?;
                                    }
                                    d => return Err(self.err(&format!("unknown backtrace detail {d}"))),
                                }
                            }
                            self.frames.insert(id, ());
                        }
                    }
                }
                0x05 => {
                    self.uint()?;
                }
                d => return Err(self.err(&format!("unknown call detail {d}"))),
            }
        }
    }
}

/// What a conversion found.
#[derive(Debug, Default)]
pub struct Conversion {
    pub calls: u64,
    /// Commands this glray does not know (skipped), with their call counts.
    pub unknown: Vec<(String, u64)>,
}

/// Converts an apitrace file into a glray trace in memory.
pub fn convert(file: &[u8]) -> Result<(Vec<u8>, Conversion), String> {
    let data = decompress(file)?;
    let mut p = Parser {
        data: &data,
        pos: 0,
        version: 0,
        functions: HashMap::new(),
        enums: HashMap::new(),
        bitmasks: HashMap::new(),
        structs: HashMap::new(),
        frames: HashMap::new(),
    };
    p.version = p.uint()?;
    if p.version > 6 {
        return Err(format!("apitrace trace version {} is not supported (glray reads versions up to 6)", p.version));
    }
    if p.version >= 6 {
        p.uint()?; // semantic version
        loop {
            let name = p.string()?;
            if name.is_empty() {
                break;
            }
            p.string()?;
        }
    }
    // Calls complete at their leave event, in that order.
    let mut pending: HashMap<u64, Call> = HashMap::new();
    let mut done: Vec<Call> = Vec::new();
    let mut next_call = 0u64;
    while p.pos < data.len() {
        match p.byte()? {
            0x00 => {
                let thread = if p.version >= 4 { p.uint()? as u32 } else { 0 };
                let id = p.uint()?;
                if !p.functions.contains_key(&id) {
                    let name = String::from_utf8_lossy(&p.string()?).into_owned();
                    let n = p.count("argument names")?;
                    for _ in 0..n {
                        p.string()?;
                    }
                    let ours = lookup(name.as_bytes()).unwrap_or(COUNT);
                    p.functions.insert(id, (name, ours));
                }
                let mut call = Call { thread, sig: id as usize, args: Vec::new(), ret: None };
                p.details(&mut call)?;
                pending.insert(next_call, call);
                next_call += 1;
            }
            0x01 => {
                let no = p.uint()?;
                let mut call = pending.remove(&no).ok_or_else(|| p.err(&format!("leave of unknown call {no}")))?;
                p.details(&mut call)?;
                done.push(call);
            }
            e => return Err(p.err(&format!("unknown event {e}"))),
        }
    }
    // Calls the program was still in when it stopped.
    let mut rest: Vec<(u64, Call)> = pending.into_iter().collect();
    rest.sort_by_key(|(n, _)| *n);
    done.extend(rest.into_iter().map(|(_, c)| c));
    encode(&p.functions, &done)
}

fn encode(functions: &HashMap<u64, (String, usize)>, calls: &[Call]) -> Result<(Vec<u8>, Conversion), String> {
    let mut e = Encoder::new();
    e.header();
    let mut numbers = vec![u32::MAX; COUNT];
    let mut named = 0u32;
    let mut unknown: HashMap<String, u64> = HashMap::new();
    let mut conversion = Conversion::default();
    let mut frame = 0u64;
    // Threads whose MakeCurrent waits for a size: (drawable).
    let mut waiting: HashMap<u32, u64> = HashMap::new();
    // Buffers mapped now: address -> (target, offset in the buffer, length).
    let mut mapped: HashMap<u64, (u64, i64, u64)> = HashMap::new();
    // Writes into them, per target, to be replayed after the unmap: (offset, bytes).
    let mut written: HashMap<u64, Vec<(i64, Vec<u8>)>> = HashMap::new();
    let mut number = |e: &mut Encoder, ours: usize| {
        if numbers[ours] == u32::MAX {
            numbers[ours] = named;
            named += 1;
            e.name(crate::commands::COMMANDS[ours].name.to_bytes());
        }
        numbers[ours] as usize
    };
    for call in calls {
        let (name, ours) = &functions[&(call.sig as u64)];
        let ours = *ours;
        let arg = |i: usize| call.args.get(i).map_or(0, V::int) as u64;
        if ours == COUNT && name == "memcpy" {
            let dest = arg(0);
            let hit = mapped.iter().find(|(ptr, (_, _, len))| dest >= **ptr && dest - **ptr < *len);
            if let (Some((ptr, (target, offset, _))), Some(V::Blob(bytes))) = (hit, call.args.get(1)) {
                written.entry(*target).or_default().push((offset + (dest - ptr) as i64, bytes.clone()));
            }
            continue;
        }
        if ours == COUNT {
            *unknown.entry(name.clone()).or_default() += 1;
            continue;
        }
        let codes = params::PARAMS[ours];
        let (arg_codes, ret_code) = codes.split_once('|').unwrap();
        let arg_codes: Vec<char> = arg_codes.chars().collect();
        // A size for the drawable a MakeCurrent bound: the thread's first viewport after it.
        if ours == cmd::glViewport {
            if let Some(drawable) = waiting.remove(&call.thread) {
                let arg = |i: usize| call.args.get(i).map_or(0, V::int);
                let (w, h) = ((arg(0) + arg(2)).clamp(1, 16384), (arg(1) + arg(3)).clamp(1, 16384));
                e.drawable(call.thread, drawable, w as u32, h as u32);
            }
        }
        let n = number(&mut e, ours);
        e.begin_call(n, call.thread, arg_codes.len() as u8);
        for (i, code) in arg_codes.iter().enumerate() {
            encode_value(&mut e, *code, call.args.get(i).unwrap_or(&V::Null));
        }
        match (ret_code, &call.ret) {
            ("-", _) => e.no_return(),
            (_, None) => e.uint(0),
            ("p", Some(v)) => e.opaque(v.int() as u64),
            (c, Some(v)) => encode_value(&mut e, c.chars().next().unwrap(), v),
        }
        conversion.calls += 1;
        let ret_true = call.ret.as_ref().is_some_and(|r| r.int() != 0);
        let ret = call.ret.as_ref().map_or(0, V::int) as u64;
        // A successful GLX/EGL MakeCurrent: its drawable gets the size of the next viewport.
        if let Some(ctx) = crate::replay::context_argument(ours).filter(|_| ret_true && ours != cmd::OSMesaMakeCurrent)
        {
            if arg(ctx) != 0 {
                waiting.insert(call.thread, arg(1));
            } else {
                e.drawable(call.thread, 0, 0, 0);
            }
        }
        match ours {
            cmd::glMapBuffer | cmd::glMapBufferARB if ret != 0 => {
                mapped.insert(ret, (arg(0), 0, u64::MAX));
            }
            cmd::glMapBufferRange if ret != 0 => {
                mapped.insert(ret, (arg(0), arg(1) as i64, arg(2)));
            }
            cmd::glUnmapBuffer | cmd::glUnmapBufferARB => {
                let target = arg(0);
                mapped.retain(|_, (t, _, _)| *t != target);
                for (offset, bytes) in written.remove(&target).unwrap_or_default() {
                    let n = number(&mut e, cmd::glBufferSubData);
                    e.begin_call(n, call.thread, 4);
                    e.uint(target);
                    e.int(offset);
                    e.int(bytes.len() as i64);
                    e.blob(&bytes);
                    e.no_return();
                }
            }
            cmd::glXSwapBuffers
            | cmd::eglSwapBuffers
            | cmd::eglSwapBuffersWithDamageKHR
            | cmd::eglSwapBuffersWithDamageEXT => {
                e.frame(frame);
                frame += 1;
            }
            _ => {}
        }
    }
    e.end();
    let mut unknown: Vec<(String, u64)> = unknown.into_iter().collect();
    unknown.sort();
    conversion.unknown = unknown;
    Ok((e.bytes().to_vec(), conversion))
}

/// Writes one apitrace value as glray's value for a parameter of type `code`.
fn encode_value(e: &mut Encoder, code: char, v: &V) {
    match code {
        'i' => e.int(v.int()),
        'u' => e.uint(v.int() as u64),
        'f' => e.f32(v.float() as f32),
        'd' => e.f64(v.float()),
        'O' => match v {
            V::Null => e.null(),
            _ => e.opaque(1),
        },
        'h' => e.opaque(v.int() as u64),
        _ => match v {
            V::Null => e.null(),
            V::Str(s) => e.string(s),
            V::Blob(b) => e.blob(b),
            // A pointer apitrace did not follow: small values are offsets into a bound buffer
            // (vertex arrays and pixel data from buffer objects), large ones addresses.
            V::Opaque(x) | V::UInt(x) if *x < 1 << 32 => e.offset(*x),
            V::Opaque(x) | V::UInt(x) => e.opaque(*x),
            V::Array(values) if code == 'P' => {
                let strings: Vec<&[u8]> = values
                    .iter()
                    .map(|s| match s {
                        V::Str(s) | V::Blob(s) => s.as_slice(),
                        _ => &[][..],
                    })
                    .collect();
                e.strings(&strings);
            }
            V::Array(values) => {
                let mut bytes = Vec::new();
                for x in values {
                    match code {
                        'B' | 'b' => bytes.push(x.int() as u8),
                        'S' | 'W' => bytes.extend_from_slice(&(x.int() as u16).to_le_bytes()),
                        'I' | 'U' => bytes.extend_from_slice(&(x.int() as u32).to_le_bytes()),
                        'L' => bytes.extend_from_slice(&(x.int() as u64).to_le_bytes()),
                        'F' => bytes.extend_from_slice(&(x.float() as f32).to_le_bytes()),
                        'D' => bytes.extend_from_slice(&x.float().to_le_bytes()),
                        _ => {}
                    }
                }
                e.blob(&bytes);
            }
            _ => e.null(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small apitrace v6 stream: glViewport(0, 0, 4, 4) then glClearColor(...).
    fn stream() -> Vec<u8> {
        let mut s = vec![6, 6]; // version 6, semantic version 6
        s.extend_from_slice(&[12]);
        s.extend_from_slice(b"process.name");
        s.extend_from_slice(&[1, b'x', 0]); // value "x", end of properties
                                            // enter: thread 0, new signature 0 "glViewport" with 4 argument names
        s.extend_from_slice(&[0, 0, 0, 10]);
        s.extend_from_slice(b"glViewport");
        s.push(4);
        for n in [b"x", b"y", b"w", b"h"] {
            s.push(1);
            s.extend_from_slice(n);
        }
        for (i, v) in [0u8, 0, 4, 4].iter().enumerate() {
            s.extend_from_slice(&[1, i as u8, 4, *v]); // CALL_ARG i, UINT v
        }
        s.push(0); // end of enter details
        s.extend_from_slice(&[1, 0, 0]); // leave call 0, no details
                                         // glClearColor with float arguments, an enum and an array value thrown in
        s.extend_from_slice(&[0, 0, 1, 12]);
        s.extend_from_slice(b"glClearColor");
        s.push(4);
        for n in [b"r", b"g", b"b", b"a"] {
            s.push(1);
            s.extend_from_slice(n);
        }
        for i in 0..4u8 {
            s.extend_from_slice(&[1, i, 5]);
            s.extend_from_slice(&0.5f32.to_le_bytes());
        }
        s.extend_from_slice(&[5, 1, 0]); // CALL_FLAGS 1, end
        s.extend_from_slice(&[1, 1, 2, 9, 7, 1, 1, b'A', 4, 1, 4, 1, 0]); // leave 1: ret = enum(sig 7) 1
        s
    }

    fn container(stream: &[u8]) -> Vec<u8> {
        let block = snap::raw::Encoder::new().compress_vec(stream).unwrap();
        let mut f = b"at".to_vec();
        f.extend_from_slice(&(block.len() as u32).to_le_bytes());
        f.extend_from_slice(&block);
        f
    }

    #[test]
    fn a_stream_converts_into_glray_calls() {
        let (data, c) = convert(&container(&stream())).unwrap();
        assert_eq!(c.calls, 2);
        let mut r = glray_core::trace::Reader::new(&data).unwrap();
        let mut calls = Vec::new();
        while let Some(e) = r.next_event().unwrap() {
            if let glray_core::trace::Event::Call { cmd, args, .. } = e {
                calls.push((String::from_utf8_lossy(r.name(cmd)).into_owned(), args.len()));
            }
        }
        assert_eq!(calls, vec![("glViewport".to_string(), 4), ("glClearColor".to_string(), 4)]);
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let s = stream();
        for cut in 0..s.len() {
            // Calls cut short are still converted (the program died mid-call); a cut inside a
            // value is an error naming the stream offset.
            match convert(&container(&s[..cut])) {
                Ok(_) => {}
                Err(e) => assert!(e.contains("byte "), "{cut}: {e}"),
            }
        }
        let f = container(&s);
        for cut in 2..f.len() {
            if let Err(e) = convert(&f[..cut]) {
                assert!(e.contains("byte "), "{cut}: {e}");
            }
        }
        assert!(convert(b"at\xff\xff\xff\xff").unwrap_err().contains("byte 2"));
    }
}
