//! A GLX program of the kind glxgears is: an X window, glXChooseVisual/glXCreateContext,
//! fixed-function drawing, glXSwapBuffers. Buffer objects are fetched with glXGetProcAddressARB.
//! Writes the last frame (read back before its swap) to OUT.png.
//!
//!     glx_scene OUT.png [FRAMES]      (needs DISPLAY)

#[path = "common/gl.rs"]
mod gl;
#[path = "common/scene.rs"]
mod scene;

use glray_gl::{GLX_DEPTH_SIZE, GLX_DOUBLEBUFFER, GLX_RED_SIZE, GLX_RGBA};
use std::ffi::c_void;
use x11::{glx, xlib};

const W: i32 = 320;
const H: i32 = 240;

fn main() {
    let (out, frames) = scene::args();
    unsafe {
        let dpy = xlib::XOpenDisplay(std::ptr::null());
        if dpy.is_null() {
            eprintln!("glx_scene: cannot open display (is DISPLAY set?)");
            std::process::exit(1);
        }
        let screen = xlib::XDefaultScreen(dpy);
        let mut attrs = [GLX_RGBA, GLX_DOUBLEBUFFER, GLX_DEPTH_SIZE, 16, GLX_RED_SIZE, 8, 0];
        let vi = glx::glXChooseVisual(dpy, screen, attrs.as_mut_ptr());
        if vi.is_null() {
            eprintln!("glx_scene: no RGBA double-buffered visual");
            std::process::exit(1);
        }
        let root = xlib::XRootWindow(dpy, screen);
        let mut swa: xlib::XSetWindowAttributes = std::mem::zeroed();
        swa.colormap = xlib::XCreateColormap(dpy, root, (*vi).visual, xlib::AllocNone);
        swa.event_mask = xlib::ExposureMask;
        let win = xlib::XCreateWindow(
            dpy,
            root,
            0,
            0,
            W as u32,
            H as u32,
            0,
            (*vi).depth,
            xlib::InputOutput as u32,
            (*vi).visual,
            xlib::CWColormap | xlib::CWEventMask,
            &mut swa,
        );
        xlib::XMapWindow(dpy, win);
        let ctx = glx::glXCreateContext(dpy, vi, std::ptr::null_mut(), xlib::True);
        if glx::glXMakeCurrent(dpy, win, ctx) == 0 {
            eprintln!("glx_scene: glXMakeCurrent failed");
            std::process::exit(1);
        }
        let get = |name: &std::ffi::CStr| -> *const c_void {
            match glx::glXGetProcAddressARB(name.as_ptr().cast()) {
                Some(f) => f as *const c_void,
                None => std::ptr::null(),
            }
        };
        let buffers = scene::BufferFns::load(get).map(|b| &*Box::leak(Box::new(b)));
        let s = scene::Scene::new(buffers);
        let last = scene::draw_frames(&s, W, H, frames, || glx::glXSwapBuffers(dpy, win));
        let err = gl::glGetError();
        glx::glXMakeCurrent(dpy, 0, std::ptr::null_mut());
        glx::glXDestroyContext(dpy, ctx);
        xlib::XDestroyWindow(dpy, win);
        xlib::XCloseDisplay(dpy);
        scene::write_png(&out, W as u32, H as u32, &last).expect("write PNG");
        println!("glx_scene: {frames} frames, glGetError {err:#x}, wrote {out}");
    }
}
