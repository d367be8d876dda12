//! Display lists the real GL does not run. A glCallList whose geometry the ray tracer takes is
//! not passed on to the real GL (it would rasterize the list), so what else the list does to the
//! GL state never reaches it. A list that moves the modelview outside a push and pop
//! (xscreensaver's molecule scales and centres its model in one) leaves the real matrices behind
//! capture's, and a program that reads them back (glGetFloatv(GL_MODELVIEW_MATRIX) to face its
//! labels to the viewer, gluProject) or places a raster position with them gets the old ones.
//! After such a call, the matrix stacks the list changed are put into the real GL.

use glray_capture::events::Capture;
use glray_capture::matrix::Seen;

use crate::real;

/// Before capture follows call number `c` (the recorder's numbering) of `thread`, which the
/// real GL did not get when `unseen`: the matrix state to compare with afterwards, for a list
/// call.
#[inline]
pub fn before(capture: &mut Capture, c: usize, thread: u32, unseen: bool) -> Option<Seen> {
    if !unseen || !capture.calls_lists(c) {
        return None;
    }
    Some(capture.context(thread).matrices.seen())
}

/// After capture followed the list call `before` came from: the real GL gets every stack whose
/// top or depth the list changed, and the list's matrix mode.
pub fn after(capture: &mut Capture, thread: u32, before: Option<Seen>) {
    let Some(before) = before else { return };
    let now = capture.context(thread).matrices.seen();
    if now == before {
        return;
    }
    // SAFETY: the live layer follows a call on the thread that made it, whose context is
    // current; glLoadMatrixd reads the 16 doubles of a local array.
    unsafe {
        for (&(mode, top, depth), &(_, old_top, old_depth)) in now.stacks.iter().zip(&before.stacks) {
            if (top, depth) == (old_top, old_depth) {
                continue;
            }
            real::glMatrixMode(mode);
            for _ in old_depth..depth {
                real::glPushMatrix();
            }
            for _ in depth..old_depth {
                real::glPopMatrix();
            }
            let mut m = top.to_cols_array();
            real::glLoadMatrixd(m.as_mut_ptr().cast());
        }
        real::glMatrixMode(now.mode);
    }
}
