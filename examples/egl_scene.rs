//! An EGL program: Mesa's surfaceless platform (no display server), a pbuffer, a GL 1.x
//! compatibility context, and the same scene; buffer objects come from eglGetProcAddress.
//!
//!     egl_scene OUT.png [FRAMES]

#[path = "common/egl.rs"]
mod egl;
#[path = "common/gl.rs"]
mod gl;
#[path = "common/scene.rs"]
mod scene;

#[link(name = "GL")]
extern "C" {}

const W: i32 = 320;
const H: i32 = 240;

fn main() {
    let (out, frames) = scene::args();
    unsafe {
        let ctx = egl::Egl::new(W, H).unwrap_or_else(|e| {
            eprintln!("egl_scene: {e}");
            std::process::exit(1)
        });
        let buffers =
            scene::BufferFns::load(|n| egl::eglGetProcAddress(n.as_ptr().cast())).map(|b| &*Box::leak(Box::new(b)));
        let s = scene::Scene::new(buffers);
        let last = scene::draw_frames(&s, W, H, frames, || ctx.swap());
        let err = gl::glGetError();
        let (major, minor) = ctx.version;
        drop(ctx);
        scene::write_png(&out, W as u32, H as u32, &last).expect("write PNG");
        println!("egl_scene: EGL {major}.{minor}, {frames} frames, glGetError {err:#x}, wrote {out}");
    }
}
