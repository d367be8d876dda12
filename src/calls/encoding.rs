//! Where the recorder's events go. With a trace file (`Encoding::Bytes`) they are encoded in the
//! trace format, and capture (when ray tracing too) reads them back from those bytes, so that
//! the file and the ray tracer see exactly the same calls. Without one (`Encoding::Events`, what
//! `glray run` does by default) each event goes to capture as it is made: encoding every call
//! only to decode it again was ~40% of what following a glVertex cost.
//!
//! Both take the same calls in the same order (the generated recorders in `generated` call
//! `int`, `uint`, `f32`, ... on either), and `Events` hands capture the same `Event`s a
//! `Reader` would make of the bytes.

use std::io::{self, Write};

use glray_core::trace::{ArrayData, Encoder, Event, Value};

use crate::feed::Live;

// One per process (the recorder's): the events' state inline saves a load on every call.
#[allow(clippy::large_enum_variant)]
pub enum Encoding {
    /// Encoded; capture (the live ray tracer's state, when ray tracing) reads them back.
    Bytes(Encoder, Option<Live>),
    Events(Events),
}

impl Encoding {
    /// `Events` when the events go to capture (`live`) alone, else `Bytes`.
    pub fn new(to_file: bool, live: Option<Live>) -> Encoding {
        match live {
            Some(live) if !to_file => Encoding::Events(Events::new(Sink::CAPTURE, Some(live))),
            live => Encoding::Bytes(Encoder::new(), live),
        }
    }

    /// The live ray tracer's state, when ray tracing.
    pub fn live(&mut self) -> Option<&mut Live> {
        match self {
            Encoding::Bytes(_, live) => live.as_mut(),
            Encoding::Events(d) => d.live.as_mut(),
        }
    }

    /// Takes the live ray tracer's state away (for a new recorder: a forked child's).
    pub fn take_live(&mut self) -> Option<Live> {
        match self {
            Encoding::Bytes(_, live) => live.take(),
            Encoding::Events(d) => d.live.take(),
        }
    }

    /// Encoded bytes not flushed yet (none for `Events`).
    pub fn bytes(&self) -> &[u8] {
        match self {
            Encoding::Bytes(e, _) => e.bytes(),
            Encoding::Events(_) => &[],
        }
    }

    pub fn len(&self) -> usize {
        self.bytes().len()
    }

    pub fn clear(&mut self) {
        if let Encoding::Bytes(e, _) = self {
            e.clear()
        }
    }

    pub fn flush_to(&mut self, w: &mut dyn Write) -> io::Result<()> {
        match self {
            Encoding::Bytes(e, _) => e.flush_to(w),
            Encoding::Events(_) => Ok(()),
        }
    }

    pub fn end(&mut self) {
        if let Encoding::Bytes(e, _) = self {
            e.end()
        }
    }

    /// Names the next command number.
    pub fn name(&mut self, name: &[u8]) {
        match self {
            Encoding::Bytes(e, _) => e.name(name),
            Encoding::Events(d) => d.name(name),
        }
    }

    pub fn begin_call(&mut self, cmd: usize, thread: u32, nargs: u8) {
        match self {
            Encoding::Bytes(e, _) => e.begin_call(cmd, thread, nargs),
            Encoding::Events(d) => d.begin_call(cmd, thread, nargs),
        }
    }

    #[inline(always)]
    pub fn int(&mut self, v: i64) {
        match self {
            Encoding::Bytes(e, _) => e.int(v),
            Encoding::Events(d) => d.value(Value::Int(v)),
        }
    }

    #[inline(always)]
    pub fn uint(&mut self, v: u64) {
        match self {
            Encoding::Bytes(e, _) => e.uint(v),
            Encoding::Events(d) => d.value(Value::UInt(v)),
        }
    }

    #[inline(always)]
    pub fn f32(&mut self, v: f32) {
        match self {
            Encoding::Bytes(e, _) => e.f32(v),
            Encoding::Events(d) => d.value(Value::F32(v)),
        }
    }

    #[inline(always)]
    pub fn f64(&mut self, v: f64) {
        match self {
            Encoding::Bytes(e, _) => e.f64(v),
            Encoding::Events(d) => d.value(Value::F64(v)),
        }
    }

    pub fn null(&mut self) {
        match self {
            Encoding::Bytes(e, _) => e.null(),
            Encoding::Events(d) => d.value(Value::Null),
        }
    }

    pub fn opaque(&mut self, v: u64) {
        match self {
            Encoding::Bytes(e, _) => e.opaque(v),
            Encoding::Events(d) => d.value(Value::Opaque(v)),
        }
    }

    pub fn offset(&mut self, v: u64) {
        match self {
            Encoding::Bytes(e, _) => e.offset(v),
            Encoding::Events(d) => d.value(Value::Offset(v)),
        }
    }

    /// Memory a pointer argument read.
    ///
    /// # Safety
    /// `b` is read when the call ends (its return value, or `no_return`): it must stay valid
    /// and unchanged until then. The recorder's turn (`record::with`) ends every call it
    /// begins, or forgets it (`discard_call`).
    #[inline(always)]
    pub unsafe fn blob(&mut self, b: &[u8]) {
        match self {
            Encoding::Bytes(e, _) => e.blob(b),
            // SAFETY: the caller keeps `b` until the call ends, when `Events` lets it go.
            Encoding::Events(d) => d.value(Value::Blob(unsafe { until_the_call_ends(b) })),
        }
    }

    /// A string argument.
    ///
    /// # Safety
    /// As for `blob`.
    pub unsafe fn string(&mut self, b: &[u8]) {
        match self {
            Encoding::Bytes(e, _) => e.string(b),
            // SAFETY: as for `blob`.
            Encoding::Events(d) => d.value(Value::Str(unsafe { until_the_call_ends(b) })),
        }
    }

    /// An array of strings.
    ///
    /// # Safety
    /// As for `blob`, for each string (not `list` itself, which is copied).
    pub unsafe fn strings(&mut self, list: &[&[u8]]) {
        match self {
            Encoding::Bytes(e, _) => e.strings(list),
            // SAFETY: as for `blob`.
            Encoding::Events(d) => {
                d.value(Value::Strings(list.iter().map(|s| unsafe { until_the_call_ends(s) }).collect()))
            }
        }
    }

    /// Ends a call with no return value.
    #[inline(always)]
    pub fn no_return(&mut self) {
        match self {
            Encoding::Bytes(e, _) => e.no_return(),
            Encoding::Events(d) => d.end(false),
        }
    }

    pub fn frame(&mut self, number: u64) {
        match self {
            Encoding::Bytes(e, _) => e.frame(number),
            Encoding::Events(d) => d.event(&Event::Frame { number }),
        }
    }

    pub fn drawable(&mut self, thread: u32, id: u64, width: u32, height: u32) {
        match self {
            Encoding::Bytes(e, _) => e.drawable(thread, id, width, height),
            Encoding::Events(d) => d.event(&Event::Drawable { thread, id, width, height }),
        }
    }

    pub fn arrays(&mut self, thread: u32, arrays: &[ArrayData]) {
        match self {
            Encoding::Bytes(e, _) => e.arrays(thread, arrays),
            Encoding::Events(d) => d.event(&Event::Arrays { thread, arrays: arrays.to_vec() }),
        }
    }

    /// Forgets a call begun and never ended (none is, but its values must not outlive the
    /// recorder's turn).
    pub fn discard_call(&mut self) {
        if let Encoding::Events(d) = self {
            d.call = None;
            d.values.clear();
        }
    }
}

/// Memory the program (or the recorder) holds, as long as the call being recorded: `Events`
/// hands capture the call's values where they are (copied, they were a tenth of following a
/// glVertex3fv), and lets them go when the call ends.
///
/// # Safety
/// `b` must stay valid until the call ends (see `Encoding::blob`).
unsafe fn until_the_call_ends(b: &[u8]) -> &'static [u8] {
    // SAFETY: the caller's promise; `Events` never keeps a value past the call.
    unsafe { std::slice::from_raw_parts(b.as_ptr(), b.len()) }
}

/// The names of the commands a trace has named, by number.
pub type Names<'a> = dyn Fn(usize) -> &'a [u8] + 'a;

/// Where `Events` go: capture (`Sink::CAPTURE`), or a test's.
#[derive(Clone, Copy)]
pub struct Sink {
    /// A call: command number, thread, arguments, return value.
    pub call: fn(&mut Option<Live>, usize, u32, &[Value], Option<&Value>),
    /// Any other event, and a Name event's name.
    pub event: for<'a> fn(&mut Option<Live>, &Event, &Names<'a>),
}

impl Sink {
    pub const CAPTURE: Sink = Sink { call: crate::feed::follow_call, event: crate::feed::follow };
}

/// Events made as the recorder goes, each handed over whole as soon as it is made.
pub struct Events {
    to: Sink,
    /// The live ray tracer's state (None in tests).
    live: Option<Live>,
    /// The call being made: command number, thread, number of arguments.
    call: Option<(usize, u32, u8)>,
    /// Its values so far (the return value last). Memory values borrow what the recorder
    /// was given for the call only (`until_the_call_ends`): they are cleared when it ends. A
    /// vector kept from call to call, not `Args`: the small vector's checks of where its
    /// elements live were a tenth of following a glNormal3f.
    values: Vec<Value<'static>>,
    /// Commands named so far (a name defines the next number, as in a trace).
    named: usize,
}

/// A call's arguments and return value (its last value, if `returned`).
fn split<'v, 'a>(values: &'v [Value<'a>], returned: bool) -> (&'v [Value<'a>], Option<&'v Value<'a>>) {
    match values.split_last() {
        Some((ret, args)) if returned => (args, Some(ret)),
        _ => (values, None),
    }
}

impl Events {
    pub fn new(to: Sink, live: Option<Live>) -> Events {
        Events { to, live, call: None, values: Vec::with_capacity(16), named: 0 }
    }

    fn name(&mut self, name: &[u8]) {
        let number = self.named;
        self.named += 1;
        (self.to.event)(&mut self.live, &Event::Name { number }, &|_| name);
    }

    /// Hands over an event other than a call or a name.
    fn event(&mut self, event: &Event) {
        (self.to.event)(&mut self.live, event, &|_| &[]);
    }

    fn begin_call(&mut self, cmd: usize, thread: u32, nargs: u8) {
        self.call = Some((cmd, thread, nargs));
        self.values.clear();
    }

    /// The call's next value: an argument, or, after the last, its return value (which ends
    /// the call).
    // Always inlined: called, the value was written to the stack in parts and read back
    // whole, a store-forwarding stall on every argument (a tenth of a glNormal3f's time).
    #[inline(always)]
    fn value(&mut self, v: Value<'static>) {
        let Some((_, _, nargs)) = self.call else { return };
        self.values.push(v);
        if self.values.len() > nargs as usize {
            self.end(true);
        }
    }

    /// Ends the call (`returned`: its last value is its return value) and hands it over.
    fn end(&mut self, returned: bool) {
        let Some((cmd, thread, _)) = self.call.take() else { return };
        let (args, ret) = split(&self.values, returned);
        (self.to.call)(&mut self.live, cmd, thread, args, ret);
        self.values.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_core::trace::Reader;
    use std::cell::RefCell;

    thread_local! {
        static SEEN: RefCell<Vec<String>> = const { RefCell::new(Vec::new()) };
    }

    fn seen(text: String) {
        SEEN.with(|s| s.borrow_mut().push(text));
    }

    fn shown(event: &Event, name: &[u8]) -> String {
        match event {
            Event::Name { number } => format!("name {number} {}", String::from_utf8_lossy(name)),
            e => format!("{e:?}"),
        }
    }

    const TEST: Sink = Sink {
        call: |_, cmd, thread, args, ret| {
            let event = Event::Call { cmd, thread, args: args.iter().cloned().collect(), ret: ret.cloned() };
            seen(shown(&event, b""))
        },
        event: |_, event, name| {
            let n = match event {
                Event::Name { number } => name(*number),
                _ => b"",
            };
            seen(shown(event, n))
        },
    };

    /// Calls of every kind of value, with and without memory and return values, between
    /// the other events.
    fn record(out: &mut Encoding) {
        // SAFETY (the memory values below): everything they borrow outlives this function,
        // which ends every call it begins.
        let program = [1u8, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12];
        out.name(b"glNormal3f");
        out.begin_call(0, 0, 3);
        out.f32(0.5);
        out.f32(-1.0);
        out.f32(2.0);
        out.no_return();
        out.name(b"glVertex3fv");
        out.begin_call(1, 1, 1);
        unsafe { out.blob(&program) };
        out.no_return();
        out.drawable(1, 77, 640, 480);
        out.name(b"glGetString");
        out.begin_call(2, 0, 1);
        out.uint(0x1F00);
        out.opaque(0xDEAD);
        out.name(b"glShaderSource");
        out.begin_call(3, 0, 4);
        out.uint(5);
        out.int(-2);
        unsafe { out.strings(&[b"void main()", b"{}"]) };
        out.null();
        out.no_return();
        out.name(b"glBindAttribLocation");
        out.begin_call(4, 0, 6);
        out.f64(1.25);
        out.offset(64);
        unsafe { out.string(b"position") };
        unsafe { out.blob(&program[..4]) };
        out.uint(9);
        unsafe { out.blob(&[]) };
        out.int(-7);
        let arrays = [ArrayData {
            kind: 1,
            index: 0,
            size: 3,
            gl_type: 0x1406,
            stride: 12,
            normalized: false,
            first: 4,
            bytes: &program,
        }];
        out.arrays(0, &arrays);
        out.frame(3);
    }

    #[test]
    fn events_made_directly_are_the_events_read_back_from_the_trace_bytes() {
        SEEN.with(|s| s.borrow_mut().clear());
        let mut direct = Encoding::Events(Events::new(TEST, None));
        record(&mut direct);
        let direct: Vec<String> = SEEN.with(|s| s.borrow_mut().drain(..).collect());

        let mut bytes = Encoding::new(true, None);
        record(&mut bytes);
        let mut reader = Reader::events(bytes.bytes(), 0);
        let mut decoded = Vec::new();
        while let Some(event) = reader.next_event().unwrap() {
            let name = match event {
                Event::Name { number } => reader.name(number),
                _ => b"",
            };
            decoded.push(shown(&event, name));
        }
        assert_eq!(direct.len(), 13, "{direct:#?}");
        assert_eq!(direct, decoded);
        // The values themselves, not only that both ways agree.
        assert!(
            direct[1].contains("F32(0.5), F32(-1.0), F32(2.0)") && direct[1].contains("ret: None"),
            "{}",
            direct[1]
        );
        assert!(direct[6].contains("args: [UInt(7936)], ret: Some(Opaque(57005))"), "{}", direct[6]);
        assert!(
            direct[10].contains("Blob([1, 2, 3, 4])") && direct[10].contains("ret: Some(Int(-7))"),
            "{}",
            direct[10]
        );
    }

    #[test]
    fn a_call_never_ended_is_forgotten() {
        SEEN.with(|s| s.borrow_mut().clear());
        let mut out = Encoding::Events(Events::new(TEST, None));
        out.begin_call(0, 0, 2);
        out.uint(1);
        out.discard_call();
        out.uint(2);
        out.no_return();
        assert!(SEEN.with(|s| s.borrow().is_empty()));
        out.begin_call(0, 0, 1);
        out.uint(3);
        out.no_return();
        assert_eq!(SEEN.with(|s| s.borrow().clone()), ["Call { cmd: 0, thread: 0, args: [UInt(3)], ret: None }"]);
    }
}
