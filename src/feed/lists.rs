//! Display lists the real GL does not run. A glCallList whose geometry the ray tracer takes is
//! not passed on to the real GL (it would rasterize the list), so what else the list does to the
//! GL state never reaches it. A list that moves the modelview outside a push and pop
//! (xscreensaver's molecule scales and centres its model in one) leaves the real matrices behind
//! capture's, and a program that reads them back (glGetFloatv(GL_MODELVIEW_MATRIX) to face its
//! labels to the viewer, gluProject) or places a raster position with them gets the old ones.
//! After such a call, the matrix stacks the list changed are put into the real GL, and so is the
//! rest of the state it changed that the real GL answers queries and draws with
//! (`list_effects::StateSeen`: enables, face, shading, depth, blending, current colour, lights
//! and materials...).

use glray_capture::events::Capture;
use glray_capture::fixed::list_effects::StateSeen;
use glray_capture::fixed::matrices::Seen;
use glray_gl::{
    GL_AMBIENT, GL_BACK, GL_CONSTANT_ATTENUATION, GL_DIFFUSE, GL_EMISSION, GL_FRONT, GL_LIGHT0, GL_LIGHT_MODEL_AMBIENT,
    GL_LIGHT_MODEL_COLOR_CONTROL, GL_LIGHT_MODEL_LOCAL_VIEWER, GL_LIGHT_MODEL_TWO_SIDE, GL_LINEAR_ATTENUATION,
    GL_MATRIX_MODE, GL_MODELVIEW, GL_MODELVIEW_MATRIX, GL_POSITION, GL_QUADRATIC_ATTENUATION,
    GL_SEPARATE_SPECULAR_COLOR, GL_SHININESS, GL_SINGLE_COLOR, GL_SPECULAR, GL_SPOT_CUTOFF, GL_SPOT_DIRECTION,
    GL_SPOT_EXPONENT, GL_TEXTURE_2D,
};
use glray_scene::lighting::{Light, LightModel, Material};

use crate::abi::real;

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
        const FACES: [u32; 2] = [GL_FRONT, GL_BACK]; // GL_FRONT, GL_BACK
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
            real::glBindTexture(GL_TEXTURE_2D, now.bound_texture); // GL_TEXTURE_2D
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
    put_lighting(was, now);
}

/// Puts into the real GL the lights, materials, light model and colour-material mode that
/// differ between `was` and `now`.
fn put_lighting(was: &StateSeen, now: &StateSeen) {
    let four = |v: glam::DVec4| v.as_vec4().to_array();
    // SAFETY: as in `after`; each pointer is to a local array of the length the call reads.
    unsafe {
        let set = |light: u32, pname: u32, mut v: [f32; 4]| real::glLightfv(light, pname, v.as_mut_ptr().cast());
        let mut moved = Vec::new();
        for (k, (light, was_light)) in now.lights.iter().zip(&was.lights).enumerate() {
            let name = GL_LIGHT0 + k as u32;
            if light == was_light {
                continue;
            }
            set(name, GL_AMBIENT, four(light.ambient));
            set(name, GL_DIFFUSE, four(light.diffuse));
            set(name, GL_SPECULAR, four(light.specular));
            real::glLightf(name, GL_SPOT_EXPONENT, light.spot_exponent as f32);
            real::glLightf(name, GL_SPOT_CUTOFF, light.spot_cutoff as f32);
            real::glLightf(name, GL_CONSTANT_ATTENUATION, light.constant_attenuation as f32);
            real::glLightf(name, GL_LINEAR_ATTENUATION, light.linear_attenuation as f32);
            real::glLightf(name, GL_QUADRATIC_ATTENUATION, light.quadratic_attenuation as f32);
            if (light.position, light.spot_direction) != (was_light.position, was_light.spot_direction) {
                moved.push((name, light));
            }
        }
        if !moved.is_empty() {
            put_in_eye_space(&moved);
        }
        for (face, (m, was_m)) in [GL_FRONT, GL_BACK].into_iter().zip(now.materials.iter().zip(&was.materials)) {
            if m != was_m {
                put_material(face, m);
            }
        }
        if now.light_model != was.light_model {
            put_light_model(&was.light_model, &now.light_model);
        }
        if now.color_material != was.color_material {
            real::glColorMaterial(now.color_material.0, now.color_material.1);
        }
    }
}

/// The positions and spot directions of `lights`, which capture holds in eye coordinates: GL
/// takes them through the modelview matrix, so they are given with the identity there, and the
/// program's matrix and matrix mode put back (not pushed: a full stack would overflow).
unsafe fn put_in_eye_space(lights: &[(u32, &Light)]) {
    let mode = real::get_int(GL_MATRIX_MODE) as u32;
    let mut modelview = [0.0f64; 16];
    // SAFETY: as in `put_lighting`: GL writes 16 doubles; the others read 4 floats or 16 doubles.
    unsafe {
        real::glGetDoublev(GL_MODELVIEW_MATRIX, modelview.as_mut_ptr().cast());
        real::glMatrixMode(GL_MODELVIEW);
        real::glLoadIdentity();
        for (name, light) in lights {
            let mut position = light.position.as_vec4().to_array();
            real::glLightfv(*name, GL_POSITION, position.as_mut_ptr().cast());
            let mut direction = light.spot_direction.as_vec3().extend(0.0).to_array();
            real::glLightfv(*name, GL_SPOT_DIRECTION, direction.as_mut_ptr().cast());
        }
        real::glLoadMatrixd(modelview.as_mut_ptr().cast());
        real::glMatrixMode(mode);
    }
}

/// Material `m` of `face` (GL_FRONT or GL_BACK) into the real GL.
unsafe fn put_material(face: u32, m: &Material) {
    // SAFETY: as in `put_lighting`.
    unsafe {
        for (pname, v) in
            [(GL_AMBIENT, m.ambient), (GL_DIFFUSE, m.diffuse), (GL_SPECULAR, m.specular), (GL_EMISSION, m.emission)]
        {
            let mut v = v.as_vec4().to_array();
            real::glMaterialfv(face, pname, v.as_mut_ptr().cast());
        }
        real::glMaterialf(face, GL_SHININESS, m.shininess as f32);
    }
}

/// The parts of the light model that differ into the real GL (only those: GL 1.1 has no
/// colour control, and asking for it would leave an error for the program's glGetError).
unsafe fn put_light_model(was: &LightModel, now: &LightModel) {
    // SAFETY: as in `put_lighting`.
    unsafe {
        if now.ambient != was.ambient {
            let mut ambient = now.ambient.as_vec4().to_array();
            real::glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient.as_mut_ptr().cast());
        }
        if now.local_viewer != was.local_viewer {
            real::glLightModeli(GL_LIGHT_MODEL_LOCAL_VIEWER, i32::from(now.local_viewer));
        }
        if now.two_side != was.two_side {
            real::glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, i32::from(now.two_side));
        }
        if now.separate_specular != was.separate_specular {
            let control = if now.separate_specular { GL_SEPARATE_SPECULAR_COLOR } else { GL_SINGLE_COLOR };
            real::glLightModeli(GL_LIGHT_MODEL_COLOR_CONTROL, control as i32);
        }
    }
}
