//! Attribute commands (glVertex3f, glNormal3fv, glColor4ub, glMultiTexCoord2f, ...) handed to
//! capture typed while no trace file is written: the hot path of immediate-mode programs, which
//! make millions of them a frame. The recorded way makes a call into values (`Value`), hands
//! them through the events to capture, which looks up the command's op and decodes the values
//! again: ~850 instructions a glNormal3fv, most of an immediate-mode frame's capture. Here the
//! export passes its components as numbers, and capture's form of the command (found once per
//! command, from its name as capture parses it) says what they are.
//!
//! They are not handed over one by one: each thread keeps the ones it made in a batch of its
//! own, and capture follows the batch, in order, under one turn of the recorder's lock, before
//! anything else of that thread's reaches capture (`drain`, called by every turn of the lock:
//! a recorded call, a frame's end, glGetError), when the batch is full, and when the thread
//! ends. The lock and the following's set-up were ~40% of a typed call's cost taken per call.
//!
//! A call that cannot go this way (a trace file is written, a null pointer, a thread ending)
//! is recorded as any other: these return false.

use std::cell::RefCell;
use std::sync::atomic::Ordering;
use std::sync::OnceLock;

use glray_capture::ops::{op_for, AttrForm, Op};

use super::{forked_check, Recorder, RECORDER, TO_FILE};
use crate::abi::commands::COMMANDS;

/// Capture's form of command `cmd`, when it is an attribute command.
#[inline]
fn form(cmd: usize) -> Option<AttrForm> {
    static FORMS: OnceLock<Vec<Option<AttrForm>>> = OnceLock::new();
    let forms = FORMS.get_or_init(|| {
        COMMANDS
            .iter()
            .map(|c| match op_for(c.name.to_str().unwrap_or("")) {
                Some((Op::Attr(form), _)) => Some(form),
                _ => None,
            })
            .collect()
    });
    forms.get(cmd).copied().flatten()
}

/// One attribute command made and not followed yet.
#[derive(Clone, Copy)]
pub struct TypedCall {
    pub form: AttrForm,
    /// A glMultiTexCoord's unit (0 for the others).
    pub target: u32,
    /// The real GL did not get the call (a glVertex inside a glBegin capture took).
    pub unseen: bool,
    /// Its components as the program passed them (the first `form.n`, at most 4).
    pub raw: [f64; 4],
}

impl TypedCall {
    pub fn components(&self) -> &[f64] {
        &self.raw[..self.form.n.min(4)]
    }
}

/// How many calls a thread keeps before capture follows them: 20 KB a thread.
const BATCH: usize = 256;

/// A thread's calls not followed yet.
struct Batch {
    len: usize,
    calls: [Option<TypedCall>; BATCH],
}

impl Drop for Batch {
    /// A thread ending: capture follows what it left (the current values it gave belong to
    /// its context, which another thread may make current).
    fn drop(&mut self) {
        if self.len > 0 {
            locked(|rec| follow(rec, self));
        }
    }
}

thread_local! {
    static PENDING: RefCell<Batch> = const { RefCell::new(Batch { len: 0, calls: [None; BATCH] }) };
}

/// An attribute command given its components one by one (glVertex3f): `raw`, as the program
/// passed them; `target` a glMultiTexCoord's unit (0 for the others). True when it is
/// capture's to follow.
#[inline]
pub fn given(cmd: usize, target: u32, raw: &[f64]) -> bool {
    if TO_FILE.load(Ordering::Relaxed) {
        return false;
    }
    let Some(form) = form(cmd) else { return false };
    let mut r = [0.0; 4];
    let n = raw.len().min(4);
    r[..n].copy_from_slice(&raw[..n]);
    keep(form, target, r)
}

/// An attribute command given a pointer to its components (glNormal3fv).
///
/// # Safety
/// `p` is null or points to as many components of `T` as the command reads (GL's rule for the
/// program's pointer).
#[inline]
pub unsafe fn given_ptr<T: Copy + Into<f64>>(cmd: usize, target: u32, p: *const T) -> bool {
    if TO_FILE.load(Ordering::Relaxed) || p.is_null() {
        return false;
    }
    let Some(form) = form(cmd) else { return false };
    let mut raw = [0.0; 4];
    for (k, slot) in raw[..form.n.min(4)].iter_mut().enumerate() {
        // SAFETY: the caller's promise; GL reads the components unaligned as well.
        *slot = unsafe { p.add(k).read_unaligned() }.into();
    }
    keep(form, target, raw)
}

/// Adds a call to this thread's batch; capture follows the batch when it is full.
#[inline]
fn keep(form: AttrForm, target: u32, raw: [f64; 4]) -> bool {
    let unseen = crate::feed::in_skipped_begin();
    let full = PENDING.try_with(|p| {
        let Ok(mut b) = p.try_borrow_mut() else { return None };
        let at = b.len;
        b.calls[at] = Some(TypedCall { form, target, unseen, raw });
        b.len += 1;
        Some(b.len == BATCH)
    });
    match full {
        Ok(Some(full)) => {
            if full {
                flush();
            }
            true
        }
        // The thread is ending (its batch is gone): the recorded way.
        _ => false,
    }
}

/// Capture follows the calling thread's batch, under the recorder's lock (`rec`): before
/// anything else of the thread's reaches capture.
#[inline]
pub(super) fn drain(rec: &mut Recorder) {
    let _ = PENDING.try_with(|p| {
        if let Ok(mut b) = p.try_borrow_mut() {
            if b.len > 0 {
                follow(rec, &mut b);
            }
        }
    });
}

/// Capture follows the calling thread's batch now: before the thread binds another context,
/// so that its calls are followed in the context, and the profile, they were made in (the
/// binding changes what `profile::core` says before capture follows the MakeCurrent).
pub fn flush() {
    let pending = PENDING.try_with(|p| p.try_borrow().is_ok_and(|b| b.len > 0));
    if pending == Ok(true) {
        locked(drain);
    }
}

/// Runs `f` with the recorder under its lock, when there is one.
fn locked(f: impl FnOnce(&mut Recorder)) {
    if forked_check() {
        if let Some(rec) = RECORDER.lock().unwrap_or_else(|e| e.into_inner()).as_mut() {
            f(rec);
        }
    }
}

/// `drain` for batch `b`.
fn follow(rec: &mut Recorder, b: &mut Batch) {
    let thread = rec.calling_thread();
    rec.thread = thread;
    let calls = b.calls[..b.len].iter().flatten().map(|g| (g.form, g.target, g.components(), g.unseen));
    if let Some(live) = rec.e.live() {
        crate::feed::follow_given(live, thread, calls);
    }
    b.len = 0;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::abi::commands::{cmd, lookup};
    use glray_gl::GL_UNSIGNED_BYTE;

    #[test]
    fn every_command_an_export_hands_over_typed_has_a_form_in_capture() {
        // Else its calls would silently go the recorded way (build.rs picks the commands by
        // name; capture parses the forms from the names).
        assert!(crate::abi::exports::TYPED.len() >= 150, "{} commands", crate::abi::exports::TYPED.len());
        for &c in &crate::abi::exports::TYPED {
            assert!(form(c).is_some(), "{:?} has no attribute form", COMMANDS[c].name);
        }
        let named = |name: &str| form(lookup(name.as_bytes()).unwrap());
        let f = named("glColor4ubv").unwrap();
        assert!(f.vector && f.n == 4 && f.ty == GL_UNSIGNED_BYTE);
        assert!(named("glMultiTexCoord2fARB").is_some_and(|f| f.n == 2 && !f.vector));
        assert_eq!(form(cmd::glMaterialfv), None);
        assert!(!crate::abi::exports::TYPED.contains(&cmd::glEdgeFlag), "edge flags are recorded");
    }
}
