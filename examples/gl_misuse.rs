//! Calls GL the wrong way and prints what happens, one line per call, so that a run under glray
//! can be compared line for line with a run without it: calls without a current context, bad
//! enums and values, calls inside glBegin/glEnd that are not allowed there, matrix stack
//! overflow and underflow, a failed MakeCurrent, unknown GetProcAddress names; then, once a
//! frame has been shown (under glray: ray traced, after which the real GL no longer gets the
//! geometry), draws that are wrong in every way glGetError reports.
//!
//!     gl_misuse

#[path = "common/egl.rs"]
mod egl;
#[path = "common/gl.rs"]
mod gl;
#[path = "common/osmesa.rs"]
mod osmesa;

use egl::{eglGetError, eglGetProcAddress, eglMakeCurrent};
use gl::*;
use glray_gl::{
    GL_COLOR_BUFFER_BIT, GL_COMPILE, GL_DEPTH_BUFFER_BIT, GL_FLOAT, GL_MODELVIEW, GL_TRIANGLES, GL_UNSIGNED_BYTE,
    GL_VERSION, GL_VIEWPORT,
};
use osmesa::{OSMesaGetCurrentContext, OSMesaGetProcAddress, OSMesaMakeCurrent};
use std::ffi::CStr;

fn main() {
    unsafe {
        // No context at all: glvnd ignores GL calls and glGetError answers 0.
        glVertex3f(1.0, 2.0, 3.0);
        glEnable(0xFFFF);
        println!("no context: glGetError = {:#x}", glGetError());
        println!("no context: glGetString(GL_VERSION) is null = {}", glGetString(GL_VERSION).is_null());
        let mut vp = [-7i32; 4];
        glGetIntegerv(GL_VIEWPORT, vp.as_mut_ptr());
        println!("no context: glGetIntegerv(GL_VIEWPORT) = {vp:?}");
        println!(
            "eglMakeCurrent(EGL_NO_DISPLAY, ...) = {}",
            eglMakeCurrent(std::ptr::null_mut(), std::ptr::null_mut(), std::ptr::null_mut(), std::ptr::null_mut())
        );
        println!("eglGetError = {:#x}", eglGetError());
        println!(
            "eglGetProcAddress(\"notAFunction\") is null = {}",
            eglGetProcAddress(c"notAFunction".as_ptr().cast()).is_null()
        );
        println!(
            "eglGetProcAddress(\"glBegin\") is null = {}",
            eglGetProcAddress(c"glBegin".as_ptr().cast()).is_null()
        );

        // A failed MakeCurrent (zero size) leaves no context current.
        let mut ctx = osmesa::OSMesa::new(64, 64).expect("OSMesa context");
        OSMesaMakeCurrent(std::ptr::null_mut(), std::ptr::null_mut(), 0, 0, 0);
        let (ctx, buffer) = (ctx.ctx, &mut ctx.buffer);
        println!(
            "OSMesaMakeCurrent(0x0) = {}",
            OSMesaMakeCurrent(ctx, buffer.as_mut_ptr().cast(), GL_UNSIGNED_BYTE, 0, 0)
        );
        println!(
            "OSMesaMakeCurrent(bad type) = {}",
            OSMesaMakeCurrent(ctx, buffer.as_mut_ptr().cast(), 0x1234, 64, 64)
        );
        println!("current context is null = {}", OSMesaGetCurrentContext().is_null());
        println!(
            "OSMesaMakeCurrent(64x64) = {}",
            OSMesaMakeCurrent(ctx, buffer.as_mut_ptr().cast(), GL_UNSIGNED_BYTE, 64, 64)
        );
        let version = CStr::from_ptr(glGetString(GL_VERSION).cast()).to_string_lossy().into_owned();
        println!("GL_VERSION = {version}");

        let check = |what: &str| println!("{what}: glGetError = {:#x}", glGetError());
        glEnable(0xFFFF);
        check("glEnable(0xFFFF)");
        glViewport(0, 0, -1, -1);
        check("glViewport(-1, -1)");
        glMatrixMode(0x1234);
        check("glMatrixMode(0x1234)");
        glBegin(GL_TRIANGLES);
        let list = glGenLists(1);
        glEnd();
        println!("glGenLists inside glBegin = {list}");
        check("glGenLists inside glBegin/glEnd");
        glEnd();
        check("glEnd without glBegin");
        glMatrixMode(GL_MODELVIEW);
        for _ in 0..40 {
            glPushMatrix();
        }
        check("40 x glPushMatrix");
        for _ in 0..41 {
            glPopMatrix();
        }
        check("41 x glPopMatrix");
        glEndList();
        check("glEndList with no list open");
        glNewList(0, GL_COMPILE);
        check("glNewList(0)");
        glDeleteLists(1, -1);
        check("glDeleteLists(1, -1)");
        glReadPixels(0, 0, 1, 1, 0xDEAD, GL_UNSIGNED_BYTE, buffer.as_mut_ptr().cast());
        check("glReadPixels(bad format)");
        // Frames that end at glFinish, as OSMesa programs' do: glray ray traces them and takes
        // the geometry from the real GL from then on, so what follows reaches glray only.
        for _ in 0..2 {
            glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
            glBegin(GL_TRIANGLES);
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] {
                glVertex3f(x, y, 0.0);
            }
            glEnd();
            glFinish();
        }
        glDrawArrays(0x20, 0, 3);
        check("glDrawArrays(bad mode)");
        glDrawArrays(GL_TRIANGLES, 0, -1);
        check("glDrawArrays(count -1)");
        let indices = [0u32, 1, 2];
        glDrawElements(GL_TRIANGLES, 3, GL_FLOAT, indices.as_ptr().cast());
        check("glDrawElements(GL_FLOAT indices)");
        glBegin(0x20);
        check("glBegin(bad mode)");
        // (glGetError itself is not allowed inside glBegin/glEnd: checked after the glEnd.)
        glBegin(GL_TRIANGLES);
        glBegin(GL_TRIANGLES);
        glEnd();
        check("glBegin inside glBegin");
        glEnd();
        check("glEnd again");
        println!(
            "OSMesaGetProcAddress(\"glNotAFunction\") is null = {}",
            OSMesaGetProcAddress(c"glNotAFunction".as_ptr().cast()).is_null()
        );
        println!(
            "OSMesaGetProcAddress(\"glBindBuffer\") is null = {}",
            OSMesaGetProcAddress(c"glBindBuffer".as_ptr().cast()).is_null()
        );
        println!("done");
    }
}
