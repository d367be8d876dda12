//! Display lists the real GL does not run. A glCallList whose geometry the ray tracer takes is
//! not passed on to the real GL (it would rasterize the list), so what else the list does to the
//! GL state never reaches it. A list that moves the modelview outside a push and pop
//! (xscreensaver's molecule scales and centres its model in one) leaves the real matrices behind
//! capture's, and a program that reads them back (glGetFloatv(GL_MODELVIEW_MATRIX) to face its
//! labels to the viewer, gluProject) or places a raster position with them gets the old ones.
//! After such a call, the matrix stacks the list changed are put into the real GL, and so is the
//! rest of the state it changed that the real GL answers queries and draws with
//! (`list_effects::StateSeen`: enables, face, shading, depth, blending, current colour...).

use glray_capture::events::Capture;
use glray_capture::list_effects::StateSeen;
use glray_capture::matrix::Seen;

use crate::real;

/// Before capture follows call number `c` (the recorder's numbering) of `thread`, which the
/// real GL did not get when `unseen`: the matrix state to compare with afterwards, for a list
/// call.
#[inline]
pub fn before(capture: &mut Capture, c: usize, thread: u32, unseen: bool) -> Option<(Seen, StateSeen)> {
    if !unseen || !capture.calls_lists(c) {
        return None;
    }
    let context = capture.context(thread);
    Some((context.matrices.seen(), context.state_seen()))
}

/// After capture followed the list call `before` came from: the real GL gets every stack whose
/// top or depth the list changed, the list's matrix mode, and the rest of the state it changed.
pub fn after(capture: &mut Capture, thread: u32, before: Option<(Seen, StateSeen)>) {
    let Some((before, state_before)) = before else { return };
    let context = capture.context(thread);
    let state = context.state_seen();
    if state != state_before {
        put_state(&state_before, &state);
    }
    let now = context.matrices.seen();
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

/// Puts into the real GL each part of `now` that differs from `was`.
fn put_state(was: &StateSeen, now: &StateSeen) {
    // SAFETY: as in `after`: the calling thread's context is current; the calls take values.
    unsafe {
        for (&(cap, on), &(_, was_on)) in now.enables.iter().zip(&was.enables) {
            if on != was_on {
                if on {
                    real::glEnable(cap)
                } else {
                    real::glDisable(cap)
                }
            }
        }
        if now.front_face != was.front_face {
            real::glFrontFace(now.front_face);
        }
        if now.cull_face != was.cull_face {
            real::glCullFace(now.cull_face);
        }
        if now.shade_model != was.shade_model {
            real::glShadeModel(now.shade_model);
        }
        const FACES: [u32; 2] = [0x0404, 0x0405]; // GL_FRONT, GL_BACK
        for ((face, mode), was_mode) in FACES.iter().zip(now.polygon_mode).zip(was.polygon_mode) {
            if mode != was_mode {
                real::glPolygonMode(*face, mode);
            }
        }
        if now.depth_func != was.depth_func {
            real::glDepthFunc(now.depth_func);
        }
        if now.depth_mask != was.depth_mask {
            real::glDepthMask(u8::from(now.depth_mask));
        }
        if now.blend_func != was.blend_func {
            real::glBlendFunc(now.blend_func.0, now.blend_func.1);
        }
        if now.alpha_func != was.alpha_func {
            real::glAlphaFunc(now.alpha_func.0, now.alpha_func.1);
        }
        if now.line_width != was.line_width {
            real::glLineWidth(now.line_width as f32);
        }
        if now.point_size != was.point_size {
            real::glPointSize(now.point_size as f32);
        }
        if now.bound_texture != was.bound_texture {
            real::glBindTexture(0x0DE1, now.bound_texture); // GL_TEXTURE_2D
        }
        if now.color != was.color {
            let c = now.color;
            real::glColor4d(c.x, c.y, c.z, c.w);
        }
        if now.normal != was.normal {
            let n = now.normal;
            real::glNormal3d(n.x, n.y, n.z);
        }
    }
}
