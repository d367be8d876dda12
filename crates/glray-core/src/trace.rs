//! glray's trace format (docs/trace-format.md): what the recorder writes and the replayer reads.
//!
//! A header (magic, version, flags), then events: command names defined at their first use,
//! calls with self-describing arguments (each value carries a type byte, so a trace can be read, dumped and
//! fuzzed without knowing any signature), frame ends, client-array memory captured at draw time,
//! and drawable sizes. The reader never trusts a length: every count and blob is checked against
//! the bytes left, and every error names its byte offset and call number.

use std::fmt;
use std::io::{self, Write};

pub const MAGIC: &[u8; 8] = b"GLRAYTRC";
pub const VERSION: u32 = 1;

/// Event tags.
pub mod tag {
    pub const CALL: u8 = 0x01;
    pub const FRAME: u8 = 0x02;
    pub const ARRAYS: u8 = 0x03;
    pub const DRAWABLE: u8 = 0x04;
    pub const END: u8 = 0x05;
    pub const NAME: u8 = 0x06;
}

/// Argument type bytes.
pub mod ty {
    pub const INT: u8 = 0x01;
    pub const UINT: u8 = 0x02;
    pub const F32: u8 = 0x03;
    pub const F64: u8 = 0x04;
    pub const NULL: u8 = 0x10;
    pub const OPAQUE: u8 = 0x11;
    pub const BLOB: u8 = 0x12;
    pub const STRING: u8 = 0x13;
    pub const OFFSET: u8 = 0x14;
    pub const STRINGS: u8 = 0x15;
    pub const NONE: u8 = 0x00;
}

/// A value as recorded.
#[derive(Debug, Clone, PartialEq)]
pub enum Value<'a> {
    Int(i64),
    UInt(u64),
    F32(f32),
    F64(f64),
    /// A null pointer.
    Null,
    /// A pointer whose memory was not recorded (an output, a handle): its value only.
    Opaque(u64),
    /// The memory a pointer argument pointed to.
    Blob(&'a [u8]),
    /// A NUL-terminated string, without its NUL.
    Str(&'a [u8]),
    /// An offset into the buffer object bound at the time (a pointer argument that is not memory).
    Offset(u64),
    /// An array of strings (glShaderSource).
    Strings(Vec<&'a [u8]>),
}

impl Value<'_> {
    /// An integer value (or a handle, recorded as an opaque pointer) as i64; 0 for others.
    pub fn as_int(&self) -> i64 {
        match self {
            Value::Int(x) => *x,
            Value::UInt(x) | Value::Opaque(x) | Value::Offset(x) => *x as i64,
            _ => 0,
        }
    }
}

/// One client vertex array's memory, captured when a draw read it.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayData<'a> {
    /// Which array (see `array_kind`).
    pub kind: u8,
    /// Texture unit or generic attribute index.
    pub index: u32,
    pub size: i32,
    pub gl_type: u32,
    pub stride: i32,
    pub normalized: bool,
    /// Index of the first element the memory holds.
    pub first: u64,
    pub bytes: &'a [u8],
}

/// Kinds of client arrays.
pub mod array_kind {
    pub const VERTEX: u8 = 0;
    pub const NORMAL: u8 = 1;
    pub const COLOR: u8 = 2;
    pub const TEXCOORD: u8 = 3;
    pub const SECONDARY_COLOR: u8 = 4;
    pub const FOG_COORD: u8 = 5;
    pub const EDGE_FLAG: u8 = 6;
    pub const INDEX: u8 = 7;
    pub const ATTRIB: u8 = 8;
    pub const LAST: u8 = ATTRIB;
}

/// A call's arguments, inline up to four (glVertex3fv's one, glColor4f's four): capture reads
/// every call a program makes, and a vector allocated and freed for each was a fifth of what
/// reading one cost.
pub type Args<'a> = smallvec::SmallVec<[Value<'a>; 4]>;

#[derive(Debug, Clone, PartialEq)]
pub enum Event<'a> {
    Call {
        cmd: usize,
        thread: u32,
        args: Args<'a>,
        ret: Option<Value<'a>>,
    },
    Frame {
        number: u64,
    },
    Arrays {
        thread: u32,
        arrays: Vec<ArrayData<'a>>,
    },
    Drawable {
        thread: u32,
        id: u64,
        width: u32,
        height: u32,
    },
    /// Command number `number` is named `Reader::names[number]` from here on.
    Name {
        number: usize,
    },
    End,
}

// ---------------------------------------------------------------------------------------------
// Writing

/// Encodes events into a byte buffer; `flush_to` hands them to a writer.
pub struct Encoder {
    buf: Vec<u8>,
}

impl Default for Encoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Encoder {
    pub fn new() -> Encoder {
        Encoder { buf: Vec::with_capacity(1 << 16) }
    }

    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }

    pub fn len(&self) -> usize {
        self.buf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    pub fn flush_to(&mut self, w: &mut dyn Write) -> io::Result<()> {
        w.write_all(&self.buf)?;
        self.buf.clear();
        Ok(())
    }

    /// Drops the events not flushed yet.
    pub fn clear(&mut self) {
        self.buf.clear();
    }

    pub fn header(&mut self) {
        self.buf.extend_from_slice(MAGIC);
        self.buf.extend_from_slice(&VERSION.to_le_bytes());
        self.buf.extend_from_slice(&0u32.to_le_bytes());
    }

    /// Defines the next command number (0, 1, 2, ... in order) as `name`.
    pub fn name(&mut self, name: &[u8]) {
        self.buf.push(tag::NAME);
        self.bytes_with_len(name);
    }

    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.buf.push((v as u8) | 0x80);
            v >>= 7;
        }
        self.buf.push(v as u8);
    }

    fn zigzag(&mut self, v: i64) {
        self.varint(((v << 1) ^ (v >> 63)) as u64);
    }

    fn bytes_with_len(&mut self, b: &[u8]) {
        self.varint(b.len() as u64);
        self.buf.extend_from_slice(b);
    }

    /// Starts a call of command `cmd` (a number defined by an earlier `name`) with `nargs`
    /// arguments.
    pub fn begin_call(&mut self, cmd: usize, thread: u32, nargs: u8) {
        self.buf.push(tag::CALL);
        self.varint(cmd as u64);
        self.varint(thread as u64);
        self.buf.push(nargs);
    }

    pub fn int(&mut self, v: i64) {
        self.buf.push(ty::INT);
        self.zigzag(v);
    }

    pub fn uint(&mut self, v: u64) {
        self.buf.push(ty::UINT);
        self.varint(v);
    }

    pub fn f32(&mut self, v: f32) {
        self.buf.push(ty::F32);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub fn f64(&mut self, v: f64) {
        self.buf.push(ty::F64);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub fn null(&mut self) {
        self.buf.push(ty::NULL);
    }

    pub fn opaque(&mut self, v: u64) {
        self.buf.push(ty::OPAQUE);
        self.varint(v);
    }

    pub fn offset(&mut self, v: u64) {
        self.buf.push(ty::OFFSET);
        self.varint(v);
    }

    pub fn blob(&mut self, b: &[u8]) {
        self.buf.push(ty::BLOB);
        self.bytes_with_len(b);
    }

    pub fn string(&mut self, b: &[u8]) {
        self.buf.push(ty::STRING);
        self.bytes_with_len(b);
    }

    pub fn strings(&mut self, list: &[&[u8]]) {
        self.buf.push(ty::STRINGS);
        self.varint(list.len() as u64);
        for s in list {
            self.bytes_with_len(s);
        }
    }

    /// Ends a call: no return value.
    pub fn no_return(&mut self) {
        self.buf.push(ty::NONE);
    }

    pub fn frame(&mut self, number: u64) {
        self.buf.push(tag::FRAME);
        self.varint(number);
    }

    pub fn drawable(&mut self, thread: u32, id: u64, width: u32, height: u32) {
        self.buf.push(tag::DRAWABLE);
        self.varint(thread as u64);
        self.varint(id);
        self.varint(width as u64);
        self.varint(height as u64);
    }

    pub fn arrays(&mut self, thread: u32, arrays: &[ArrayData]) {
        self.buf.push(tag::ARRAYS);
        self.varint(thread as u64);
        self.varint(arrays.len() as u64);
        for a in arrays {
            self.buf.push(a.kind);
            self.varint(a.index as u64);
            self.zigzag(a.size as i64);
            self.varint(a.gl_type as u64);
            self.zigzag(a.stride as i64);
            self.buf.push(a.normalized as u8);
            self.varint(a.first);
            self.bytes_with_len(a.bytes);
        }
    }

    pub fn end(&mut self) {
        self.buf.push(tag::END);
    }
}

// ---------------------------------------------------------------------------------------------
// Reading

/// A malformed trace: where and what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TraceError {
    pub offset: usize,
    /// The number of the call being read (0-based), if any call had started.
    pub call: Option<u64>,
    pub message: String,
}

impl fmt::Display for TraceError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.call {
            Some(c) => write!(f, "byte {} (call {c}): {}", self.offset, self.message),
            None => write!(f, "byte {}: {}", self.offset, self.message),
        }
    }
}

impl std::error::Error for TraceError {}

/// Reads a whole trace held in memory.
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
    /// Offset of the event being read, for messages.
    event_start: usize,
    pub version: u32,
    /// How many commands earlier pieces named (see `events`); `names` continues from there.
    named_before: usize,
    names: Vec<&'a [u8]>,
    calls: u64,
    in_call: bool,
    ended: bool,
}

impl<'a> Reader<'a> {
    /// Checks the header.
    pub fn new(data: &'a [u8]) -> Result<Reader<'a>, TraceError> {
        let mut r = Reader {
            data,
            pos: 0,
            event_start: 0,
            version: 0,
            named_before: 0,
            names: Vec::new(),
            calls: 0,
            in_call: false,
            ended: false,
        };
        let magic = r.take(8, "the magic number")?;
        if magic != MAGIC {
            return Err(r.error_at(0, "not a glray trace (the file does not start with GLRAYTRC)".into()));
        }
        let v = r.take(4, "the version")?;
        r.version = u32::from_le_bytes(v.try_into().unwrap());
        if r.version != VERSION {
            return Err(r.error_at(
                8,
                format!("trace version {} is not supported (this glray reads version {VERSION})", r.version),
            ));
        }
        let _flags = r.take(4, "the flags")?;
        Ok(r)
    }

    /// Reads events without a header, for a stream of them cut into pieces (the live library
    /// hands each call's events over as it records them): `named` commands were named by
    /// earlier pieces (their names read as empty here).
    pub fn events(data: &'a [u8], named: usize) -> Reader<'a> {
        Reader {
            data,
            pos: 0,
            event_start: 0,
            version: VERSION,
            named_before: named,
            names: Vec::new(),
            calls: 0,
            in_call: false,
            ended: false,
        }
    }

    /// How many commands are named so far.
    pub fn named(&self) -> usize {
        self.named_before + self.names.len()
    }

    /// The name of command `number` (empty for one an earlier piece named, see `events`).
    pub fn name(&self, number: usize) -> &'a [u8] {
        number.checked_sub(self.named_before).and_then(|k| self.names.get(k)).copied().unwrap_or(&[])
    }

    /// The offset of the next event.
    pub fn offset(&self) -> usize {
        self.pos
    }

    /// How many calls have been read.
    pub fn calls(&self) -> u64 {
        self.calls
    }

    fn error_at(&self, offset: usize, message: String) -> TraceError {
        TraceError { offset, call: self.in_call.then(|| self.calls.saturating_sub(1)), message }
    }

    fn error(&self, message: String) -> TraceError {
        self.error_at(self.event_start, message)
    }

    // The readers below run for every field of every call capture follows (a display list's
    // compile is tens of millions of calls): inlined, with their errors made out of line.

    #[inline]
    fn take(&mut self, n: usize, what: &(impl fmt::Display + ?Sized)) -> Result<&'a [u8], TraceError> {
        let left = self.data.len() - self.pos;
        if n > left {
            return Err(self.truncated(what, n, left));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    #[cold]
    fn truncated(&self, what: &(impl fmt::Display + ?Sized), n: usize, left: usize) -> TraceError {
        self.error_at(self.pos, format!("truncated: {what} needs {n} bytes, {left} left"))
    }

    #[inline]
    fn byte(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<u8, TraceError> {
        Ok(self.take(1, what)?[0])
    }

    #[inline]
    fn varint(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<u64, TraceError> {
        // Most numbers in a trace (command numbers, threads, lengths) fit one byte.
        if let Some(&b) = self.data.get(self.pos).filter(|b| **b < 0x80) {
            self.pos += 1;
            return Ok(b as u64);
        }
        self.long_varint(what)
    }

    fn long_varint(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<u64, TraceError> {
        let start = self.pos;
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = self.byte(what)?;
            if shift == 63 && b > 1 {
                break;
            }
            v |= ((b & 0x7f) as u64) << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(self.error_at(start, format!("{what}: varint longer than 64 bits")))
    }

    #[inline]
    fn zigzag(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<i64, TraceError> {
        let v = self.varint(what)?;
        Ok((v >> 1) as i64 ^ -((v & 1) as i64))
    }

    /// A count of items of at least `min_item_bytes` each: never more than the bytes left allow,
    /// so a corrupt count cannot cause a huge allocation.
    #[inline]
    fn count(&mut self, min_item_bytes: usize, what: &(impl fmt::Display + ?Sized)) -> Result<usize, TraceError> {
        let start = self.pos;
        let n = self.varint(what)?;
        let left = (self.data.len() - self.pos) as u64;
        if n.saturating_mul(min_item_bytes as u64) > left {
            return Err(self.error_at(start, format!("impossible count of {what}: {n}, with {left} bytes left")));
        }
        Ok(n as usize)
    }

    #[inline]
    fn sized(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<&'a [u8], TraceError> {
        let n = self.count(1, what)?;
        self.take(n, what)
    }

    #[inline]
    fn u32_of(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<u32, TraceError> {
        let start = self.pos;
        let v = self.varint(what)?;
        u32::try_from(v).map_err(|_| self.error_at(start, format!("{what} {v} does not fit 32 bits")))
    }

    fn i32_of(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<i32, TraceError> {
        let start = self.pos;
        let v = self.zigzag(what)?;
        i32::try_from(v).map_err(|_| self.error_at(start, format!("{what} {v} does not fit 32 bits")))
    }

    fn value(&mut self, what: &(impl fmt::Display + ?Sized)) -> Result<Value<'a>, TraceError> {
        let at = self.pos;
        Ok(match self.byte(what)? {
            ty::INT => Value::Int(self.zigzag(what)?),
            ty::UINT => Value::UInt(self.varint(what)?),
            ty::F32 => Value::F32(f32::from_le_bytes(self.take(4, what)?.try_into().unwrap())),
            ty::F64 => Value::F64(f64::from_le_bytes(self.take(8, what)?.try_into().unwrap())),
            ty::NULL => Value::Null,
            ty::OPAQUE => Value::Opaque(self.varint(what)?),
            ty::OFFSET => Value::Offset(self.varint(what)?),
            ty::BLOB => Value::Blob(self.sized(what)?),
            ty::STRING => Value::Str(self.sized(what)?),
            ty::STRINGS => {
                let n = self.count(1, what)?;
                let mut list = Vec::with_capacity(n);
                for _ in 0..n {
                    list.push(self.sized(what)?);
                }
                Value::Strings(list)
            }
            other => return Err(self.error_at(at, format!("{what}: unknown value type {other:#04x}"))),
        })
    }

    /// The next event, or None at the end of the data. A trace cut short without an END event
    /// (the program died while recording) ends cleanly at the last complete event; one cut
    /// inside an event is an error naming the offset.
    pub fn next_event(&mut self) -> Result<Option<Event<'a>>, TraceError> {
        self.in_call = false;
        if self.ended || self.pos == self.data.len() {
            return Ok(None);
        }
        self.event_start = self.pos;
        let t = self.byte("an event")?;
        let event = match t {
            tag::CALL => {
                self.calls += 1;
                self.in_call = true;
                let at = self.pos;
                let cmd = self.varint("the command number")?;
                if cmd >= self.named() as u64 {
                    return Err(
                        self.error_at(at, format!("command number {cmd} was never named ({} are)", self.named()))
                    );
                }
                let cmd = cmd as usize;
                let thread = self.u32_of("the thread number")?;
                let nargs = self.byte("the argument count")?;
                let mut args = Args::with_capacity(nargs as usize);
                for i in 0..nargs {
                    args.push(self.value(&format_args!("argument {i}"))?);
                }
                let ret = if self.data.get(self.pos) == Some(&ty::NONE) {
                    self.pos += 1;
                    None
                } else {
                    Some(self.value("the return value")?)
                };
                Event::Call { cmd, thread, args, ret }
            }
            tag::FRAME => Event::Frame { number: self.varint("the frame number")? },
            tag::DRAWABLE => Event::Drawable {
                thread: self.u32_of("the thread number")?,
                id: self.varint("the drawable")?,
                width: self.u32_of("the width")?,
                height: self.u32_of("the height")?,
            },
            tag::ARRAYS => {
                let thread = self.u32_of("the thread number")?;
                let n = self.count(8, "arrays")?;
                let mut arrays = Vec::with_capacity(n);
                for _ in 0..n {
                    let at = self.pos;
                    let kind = self.byte("the array kind")?;
                    if kind > array_kind::LAST {
                        return Err(self.error_at(at, format!("unknown array kind {kind}")));
                    }
                    arrays.push(ArrayData {
                        kind,
                        index: self.u32_of("the array index")?,
                        size: self.i32_of("the array size")?,
                        gl_type: self.u32_of("the array type")?,
                        stride: self.i32_of("the array stride")?,
                        normalized: self.byte("the normalized flag")? != 0,
                        first: self.varint("the first element")?,
                        bytes: self.sized("the array memory")?,
                    });
                }
                Event::Arrays { thread, arrays }
            }
            tag::NAME => {
                let name = self.sized("a command name")?;
                if name.is_empty() || !name.iter().all(|c| c.is_ascii_alphanumeric() || *c == b'_') {
                    return Err(self.error(format!("bad command name {:?}", String::from_utf8_lossy(name))));
                }
                self.names.push(name);
                Event::Name { number: self.named() - 1 }
            }
            tag::END => {
                self.ended = true;
                Event::End
            }
            other => return Err(self.error(format!("unknown event type {other:#04x}"))),
        };
        Ok(Some(event))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<u8> {
        let mut e = Encoder::new();
        e.header();
        for n in [&b"glBegin"[..], b"glVertex3fv", b"glXSwapBuffers"] {
            e.name(n);
        }
        e.begin_call(0, 0, 1);
        e.uint(4);
        e.no_return();
        e.begin_call(1, 0, 1);
        e.blob(&[0, 0, 128, 63, 0, 0, 0, 64, 0, 0, 64, 64]);
        e.no_return();
        e.drawable(0, 77, 300, 200);
        e.arrays(
            0,
            &[ArrayData {
                kind: array_kind::VERTEX,
                index: 0,
                size: 3,
                gl_type: 0x1406,
                stride: 0,
                normalized: false,
                first: 2,
                bytes: &[1, 2, 3],
            }],
        );
        e.begin_call(2, 1, 2);
        e.opaque(0xdead_beef);
        e.uint(u64::MAX);
        e.int(-5);
        e.frame(0);
        e.end();
        e.bytes().to_vec()
    }

    #[test]
    fn pieces_of_a_stream_number_commands_after_the_earlier_pieces() {
        // Three commands were named by earlier pieces; this one calls the third and names a fourth.
        let mut e = Encoder::new();
        e.begin_call(2, 0, 0);
        e.no_return();
        e.name(b"glFinish");
        e.begin_call(3, 0, 0);
        e.no_return();
        let mut r = Reader::events(e.bytes(), 3);
        assert!(matches!(r.next_event().unwrap(), Some(Event::Call { cmd: 2, .. })));
        assert_eq!(r.next_event().unwrap(), Some(Event::Name { number: 3 }));
        assert!(matches!(r.next_event().unwrap(), Some(Event::Call { cmd: 3, .. })));
        assert_eq!(r.next_event().unwrap(), None);
        assert_eq!((r.named(), r.name(3), r.name(1), r.name(9)), (4, &b"glFinish"[..], &b""[..], &b""[..]));
        // A command no piece named is an error at its offset.
        let mut e = Encoder::new();
        e.begin_call(3, 0, 0);
        e.no_return();
        let err = Reader::events(e.bytes(), 3).next_event().unwrap_err();
        assert!(err.to_string().contains("command number 3 was never named (3 are)"), "{err}");
    }

    #[test]
    fn round_trip() {
        let data = sample();
        let mut r = Reader::new(&data).unwrap();
        let mut events = Vec::new();
        while let Some(e) = r.next_event().unwrap() {
            if !matches!(e, Event::Name { .. }) {
                events.push(e);
            }
        }
        assert_eq!(events.len(), 7);
        assert_eq!(events[0], Event::Call { cmd: 0, thread: 0, args: smallvec::smallvec![Value::UInt(4)], ret: None });
        assert_eq!(
            events[3],
            Event::Arrays {
                thread: 0,
                arrays: vec![ArrayData {
                    kind: 0,
                    index: 0,
                    size: 3,
                    gl_type: 0x1406,
                    stride: 0,
                    normalized: false,
                    first: 2,
                    bytes: &[1, 2, 3]
                }]
            }
        );
        assert_eq!(
            events[4],
            Event::Call {
                cmd: 2,
                thread: 1,
                args: smallvec::smallvec![Value::Opaque(0xdead_beef), Value::UInt(u64::MAX)],
                ret: Some(Value::Int(-5))
            }
        );
        assert_eq!(events[6], Event::End);
        assert_eq!(r.calls(), 3);
        assert_eq!((0..3).map(|n| r.name(n)).collect::<Vec<_>>(), [&b"glBegin"[..], b"glVertex3fv", b"glXSwapBuffers"]);
    }

    #[test]
    fn every_truncation_is_a_clean_error_or_a_clean_end() {
        let data = sample();
        for cut in 0..data.len() {
            let part = &data[..cut];
            match Reader::new(part) {
                Err(e) => assert!(e.message.contains("truncated") || e.message.contains("impossible"), "{cut}: {e}"),
                Ok(mut r) => loop {
                    match r.next_event() {
                        Ok(Some(_)) => {}
                        Ok(None) => break,
                        Err(e) => {
                            assert!(e.offset <= cut, "{cut}: {e}");
                            assert!(e.to_string().starts_with("byte "), "{e}");
                            break;
                        }
                    }
                },
            }
        }
    }

    #[test]
    fn bad_headers_are_named() {
        assert!(Reader::new(b"NOTATRACE.......").err().unwrap().message.contains("not a glray trace"));
        let mut data = sample();
        data[8] = 9;
        let e = Reader::new(&data).err().unwrap();
        assert!(e.message.contains("version 9") && e.offset == 8, "{e}");
    }

    #[test]
    fn impossible_sizes_do_not_allocate() {
        let mut e = Encoder::new();
        e.header();
        e.name(b"glTexImage2D");
        let mut data = e.bytes().to_vec();
        // A call whose blob claims 2^60 bytes.
        data.extend_from_slice(&[tag::CALL, 0, 0, 1, ty::BLOB]);
        data.extend_from_slice(&[0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x10]);
        let mut r = Reader::new(&data).unwrap();
        assert!(matches!(r.next_event().unwrap(), Some(Event::Name { number: 0 })));
        let err = r.next_event().unwrap_err();
        assert!(err.message.contains("impossible count") && err.call == Some(0), "{err}");
        // A command number beyond the table.
        let mut data = e.bytes().to_vec();
        data.extend_from_slice(&[tag::CALL, 5, 0, 0, ty::NONE]);
        let mut r = Reader::new(&data).unwrap();
        r.next_event().unwrap();
        let err = r.next_event().unwrap_err();
        assert!(err.message.contains("command number 5 was never named"), "{err}");
    }
}
