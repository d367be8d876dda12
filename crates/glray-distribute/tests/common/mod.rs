//! What the tests of ranks in threads share: GL calls made into a capture context, a lit
//! scene's context, a preset's options.

use glray_capture::fixed::Context;
use glray_core::trace::Value::{self, Int, F64};
use glray_render::{Effects, Options};

pub fn call(c: &mut Context, name: &str, args: &[Value<'static>]) {
    let (op, ty) = glray_capture::ops::op_for(name).unwrap_or_else(|| panic!("{name}"));
    c.call(op, ty, args);
}

/// A capture context drawing into a `w` x `h` window through glFrustum(`frustum`), lit by
/// light 0 with colour material and the depth test on.
pub fn lit_context(w: u32, h: u32, frustum: [f64; 6]) -> Context {
    let mut c = Context::default();
    c.set_drawable(w, h);
    call(&mut c, "glMatrixMode", &[Int(0x1701)]);
    call(&mut c, "glFrustum", &frustum.map(F64));
    call(&mut c, "glMatrixMode", &[Int(0x1700)]);
    for cap in [0x0B50, 0x4000, 0x0B57, 0x0B71] {
        // lighting, light 0, colour material, depth test
        call(&mut c, "glEnable", &[Int(cap)]);
    }
    c
}

/// A preset's options, as a user gets them (AO denoised where the preset has AO).
pub fn options(preset: &str) -> Options {
    Options { effects: Effects::preset(preset).unwrap(), ..Options::default() }
}
