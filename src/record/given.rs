//! Attribute commands (glVertex3f, glNormal3fv, glColor4ub, glMultiTexCoord2f, ...) handed to
//! capture typed while no trace file is written: the hot path of immediate-mode programs, which
//! make millions of them a frame. The recorded way makes a call into values (`Value`), hands
//! them through the events to capture, which looks up the command's op and decodes the values
//! again: ~850 instructions a glNormal3fv, most of an immediate-mode frame's capture. Here the
//! export passes its components as numbers, and capture's form of the command (found once per
//! command, from its name as capture parses it) says what they are.
//!
//! A call that cannot go this way (a trace file is written, a display list is being compiled, a
//! null pointer) is recorded as any other: these return false.

use std::sync::atomic::Ordering;
use std::sync::OnceLock;

use glray_capture::ops::{op_for, AttrForm, Op};

use super::{forked_check, RECORDER, TO_FILE};
use crate::commands::COMMANDS;

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

/// An attribute command given its components one by one (glVertex3f): `raw`, as the program
/// passed them; `target` a glMultiTexCoord's unit (0 for the others). True when capture took it.
#[inline]
pub fn given(cmd: usize, target: u32, raw: &[f64]) -> bool {
    if TO_FILE.load(Ordering::Relaxed) {
        return false;
    }
    let Some(form) = form(cmd) else { return false };
    hand(form, target, raw)
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
    let n = form.n.min(4);
    let mut raw = [0.0; 4];
    for (k, slot) in raw[..n].iter_mut().enumerate() {
        // SAFETY: the caller's promise; GL reads the components unaligned as well.
        *slot = unsafe { p.add(k).read_unaligned() }.into();
    }
    hand(form, target, &raw[..n])
}

/// Hands the command to capture under the recorder's lock, as the calling thread's.
fn hand(form: AttrForm, target: u32, raw: &[f64]) -> bool {
    if !forked_check() {
        return true;
    }
    let mut guard = RECORDER.lock().unwrap_or_else(|e| e.into_inner());
    let Some(rec) = guard.as_mut() else { return true };
    let thread = rec.calling_thread();
    rec.thread = thread;
    match rec.e.live() {
        Some(live) => crate::raytrace::follow_given(live, thread, form, target, raw),
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commands::{cmd, lookup};

    #[test]
    fn every_command_an_export_hands_over_typed_has_a_form_in_capture() {
        // Else its calls would silently go the recorded way (build.rs picks the commands by
        // name; capture parses the forms from the names).
        assert!(crate::exports::TYPED.len() >= 150, "{} commands", crate::exports::TYPED.len());
        for &c in &crate::exports::TYPED {
            assert!(form(c).is_some(), "{:?} has no attribute form", COMMANDS[c].name);
        }
        let named = |name: &str| form(lookup(name.as_bytes()).unwrap());
        let f = named("glColor4ubv").unwrap();
        assert!(f.vector && f.n == 4 && f.ty == glray_capture::args::GL_UNSIGNED_BYTE);
        assert!(named("glMultiTexCoord2fARB").is_some_and(|f| f.n == 2 && !f.vector));
        assert_eq!(form(cmd::glMaterialfv), None);
        assert!(!crate::exports::TYPED.contains(&cmd::glEdgeFlag), "edge flags are recorded");
    }
}
