//! Feeding recorded events (from a trace file, or from the live library's in-memory recorder)
//! into GL contexts, and handing out each frame when it ends.
//!
//! Calls go to the context current on their thread, as GL routes them: context creation and
//! MakeCurrent calls (GLX, EGL, OSMesa) are followed for that, and for share groups (a context
//! created with another to share with gets the same display lists, textures and buffers). A
//! thread that never made a context current (a trace cut from a longer run) has a context of
//! its own.

use glray_core::trace::{Event, Value};

use crate::fixed::Context;
use crate::ops::{context_call, op_for, AttrForm, ContextCall, Op};
use glray_scene::frame::Frame;

/// Every call looks its thread's context up (four maps, twice per call): a 10M-vertex display
/// list is 60M calls, and SipHash on these small integer keys was a fifth of compiling it.
type HashMap<K, V> = rustc_hash::FxHashMap<K, V>;

/// What a command means to capture: a GL command it follows, or a context call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Gl(Op, u32),
    Context(ContextCall),
}

fn kind_of(name: &str) -> Option<Kind> {
    match context_call(name) {
        Some(c) => Some(Kind::Context(c)),
        None => op_for(name).map(|(op, ty)| Kind::Gl(op, ty)),
    }
}

/// What the live library knows of a call that a trace does not say.
#[derive(Debug, Clone, Copy)]
pub struct LiveCall {
    /// The real GL did not get the call: its errors are glGetError's to report.
    pub unseen: bool,
    /// The context is a core profile (capture follows none of its calls).
    pub core_profile: bool,
}

impl LiveCall {
    fn give(self, ctx: &mut Context) {
        ctx.unseen = self.unseen;
        ctx.core_profile = self.core_profile;
    }
}

#[derive(Default)]
pub struct Capture {
    /// What each command number the trace has named means.
    kinds: Vec<Option<Kind>>,
    /// Each context's place in `slots`, by key (contexts are never dropped: a program makes a
    /// few).
    contexts: HashMap<u64, usize>,
    slots: Vec<Context>,
    /// The context current on each thread.
    current: HashMap<u32, u64>,
    /// Each context's share group (a context alone is a group of its own).
    groups: HashMap<u64, u64>,
    /// Which context holds each group's shared objects now.
    holders: HashMap<u64, u64>,
    /// The thread of the last call: the one whose frame a frame event ends.
    last_thread: u32,
    /// The last thread `context` resolved, and its context's place in `slots`: calls come in
    /// long runs from one thread, and the lookups that resolve one were most of following a
    /// glVertex (the last of them, by key, still a twentieth). Forgotten when a context is
    /// created or made current.
    resolved: Option<(u32, usize)>,
}

/// The key of a thread's context when it never made one current.
fn thread_key(thread: u32) -> u64 {
    u64::MAX - thread as u64
}

impl Capture {
    /// Follows one event; a frame end returns the frame just drawn (with its thread).
    /// `name` resolves a command number named by a Name event.
    pub fn event<'a>(&mut self, ev: &Event, name: impl Fn(usize) -> &'a [u8]) -> Option<(u32, Frame)> {
        match ev {
            Event::Name { number } => {
                let kind = std::str::from_utf8(name(*number)).ok().and_then(kind_of);
                if self.kinds.len() <= *number {
                    self.kinds.resize(*number + 1, None);
                }
                self.kinds[*number] = kind;
            }
            Event::Call { cmd, thread, args, ret } => self.call(*cmd, *thread, args, ret.as_ref(), None),
            Event::Arrays { thread, arrays } => self.context(*thread).set_arrays(arrays),
            Event::Drawable { thread, width, height, .. } => self.context(*thread).set_drawable(*width, *height),
            Event::Frame { .. } => {
                let thread = self.last_thread;
                return Some((thread, self.context(thread).take_frame()));
            }
            Event::End => {}
        }
        None
    }

    /// Whether call number `cmd` copies the framebuffer into a 2D texture, whose texels the
    /// caller reads back from the real GL (`Context::copied_texture`). Asked after every call.
    #[inline]
    pub fn copies_texture(&self, cmd: usize) -> bool {
        matches!(self.kinds.get(cmd), Some(Some(Kind::Context(ContextCall::CopiesTexture))))
    }

    /// Whether call number `cmd` runs display lists (glCallList, glCallLists), whose state
    /// changes the real GL misses when it is not given the call (see src/raytrace/lists.rs).
    #[inline]
    pub fn calls_lists(&self, cmd: usize) -> bool {
        matches!(self.kinds.get(cmd), Some(Some(Kind::Gl(Op::CallList | Op::CallLists, _))))
    }

    /// Follows one call; `live`, what the live library knows of it, is given to the context
    /// the call goes to (as it was before the call, for a MakeCurrent). A call made live is
    /// handed here without becoming an `Event`: moved into one and out again, its arguments
    /// were copied twice per call.
    pub fn call(&mut self, cmd: usize, thread: u32, args: &[Value], ret: Option<&Value>, live: Option<LiveCall>) {
        self.last_thread = thread;
        let kind = self.kinds.get(cmd).copied().flatten();
        if let Some(Kind::Gl(op, ty)) = kind {
            let ctx = self.context(thread);
            if let Some(l) = live {
                l.give(ctx);
            }
            ctx.returned = ret.map(Value::as_int);
            return ctx.call(op, ty, args);
        }
        if let Some(l) = live {
            l.give(self.context(thread));
        }
        match kind {
            Some(Kind::Context(ContextCall::Create(share))) => {
                self.resolved = None;
                let created = ret.map_or(0, Value::as_int) as u64;
                let share = args.get(share).map_or(0, Value::as_int) as u64;
                if created != 0 {
                    let group = if share != 0 { *self.groups.get(&share).unwrap_or(&share) } else { created };
                    self.groups.insert(created, group);
                }
            }
            Some(Kind::Context(ContextCall::MakeCurrent(at))) => {
                self.resolved = None;
                let ok = ret.is_none_or(|r| r.as_int() != 0);
                if ok {
                    match args.get(at).map_or(0, Value::as_int) as u64 {
                        0 => self.current.remove(&thread),
                        ctx => self.current.insert(thread, ctx),
                    };
                }
            }
            Some(Kind::Gl(..) | Kind::Context(ContextCall::CopiesTexture)) | None => {}
        }
    }

    /// Attribute commands of `thread`'s handed over typed, in the order they were made
    /// (`Context::take_given`): each its form, glMultiTexCoord's target, components, and
    /// whether the real GL did not get it. They all go to one context: the live layer hands a
    /// thread's calls over before anything that could change its context.
    pub fn given<'a>(
        &mut self,
        thread: u32,
        core_profile: bool,
        calls: impl IntoIterator<Item = (AttrForm, u32, &'a [f64], bool)>,
    ) {
        self.last_thread = thread;
        let ctx = self.context(thread);
        for (form, target, raw, unseen) in calls {
            LiveCall { unseen, core_profile }.give(ctx);
            ctx.take_given(form, target, raw);
        }
    }

    /// The context current on a thread, holding its share group's objects.
    pub fn context(&mut self, thread: u32) -> &mut Context {
        if let Some((_, slot)) = self.resolved.filter(|(t, _)| *t == thread) {
            return &mut self.slots[slot];
        }
        let key = self.current.get(&thread).copied().unwrap_or_else(|| thread_key(thread));
        let group = *self.groups.get(&key).unwrap_or(&key);
        let holder = self.holders.insert(group, key);
        let slot = self.slot(key);
        if let Some(h) = holder.filter(|h| *h != key) {
            let shared = self.contexts.get(&h).map(|&from| self.slots[from].take_shared()).unwrap_or_default();
            self.slots[slot].put_shared(shared);
        }
        self.resolved = Some((thread, slot));
        &mut self.slots[slot]
    }

    /// The place of context `key` in `slots`, made fresh the first time.
    fn slot(&mut self, key: u64) -> usize {
        let fresh = self.slots.len();
        let slot = *self.contexts.entry(key).or_insert(fresh);
        if slot == fresh {
            self.slots.push(Context::default());
        }
        slot
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tiny trace: `names` are named in order; calls are (command index, thread, args, ret).
    fn feed(c: &mut Capture, names: &[&str], calls: &[(usize, u32, Vec<Value<'static>>, Option<Value<'static>>)]) {
        let bytes: Vec<Vec<u8>> = names.iter().map(|n| n.as_bytes().to_vec()).collect();
        for number in 0..names.len() {
            c.event(&Event::Name { number }, |n| &bytes[n]);
        }
        for (cmd, thread, args, ret) in calls {
            c.event(
                &Event::Call { cmd: *cmd, thread: *thread, args: args.iter().cloned().collect(), ret: ret.clone() },
                |n| &bytes[n],
            );
        }
    }

    #[test]
    fn contexts_are_followed_per_make_current_and_share_groups_share_lists() {
        let names = ["glXCreateContext", "glXMakeCurrent", "glGenLists", "glMatrixMode", "glIsList"];
        let op = |v: i64| Value::Int(v);
        let mut c = Capture::default();
        feed(
            &mut c,
            &names,
            &[
                (0, 0, vec![op(1), op(2), op(0), op(1)], Some(Value::Opaque(0xA))), // A
                (0, 0, vec![op(1), op(2), op(0xA), op(1)], Some(Value::Opaque(0xB))), // B shares with A
                (0, 0, vec![op(1), op(2), op(0), op(1)], Some(Value::Opaque(0xC))), // C alone
                (1, 0, vec![op(1), op(5), Value::Opaque(0xA)], Some(op(1))),
                (2, 0, vec![op(3)], Some(op(1))), // lists 1-3 in A's group
                (3, 0, vec![op(0x1701)], None),   // A: projection mode
                (1, 0, vec![op(1), op(5), Value::Opaque(0xB)], Some(op(1))),
            ],
        );
        assert!(c.context(0).shared.lists.is_list(2), "B sees A's lists");
        assert_eq!(c.context(0).matrices.mode, crate::fixed::matrices::Mode::ModelView, "but has its own matrix mode");
        feed(&mut c, &names, &[(1, 0, vec![op(1), op(5), Value::Opaque(0xC)], Some(op(1)))]);
        assert!(!c.context(0).shared.lists.is_list(2), "C does not");
        feed(&mut c, &names, &[(1, 0, vec![op(1), op(5), Value::Opaque(0xA)], Some(op(1)))]);
        assert!(c.context(0).shared.lists.is_list(2));
        assert_eq!(c.context(0).matrices.mode, crate::fixed::matrices::Mode::Projection);
    }
}
