//! An OSMesa program, as headless ParaView and VisIt builds are: GL comes from libOSMesa itself
//! (no libGL), the image lands in the program's own buffer. Buffer objects come from
//! OSMesaGetProcAddress.
//!
//!     osmesa_scene OUT.png [FRAMES [PARTS]]     PARTS: lists,immediate,arrays,buffers,textures or all

#[path = "common/gl.rs"]
mod gl;
#[path = "common/osmesa.rs"]
mod osmesa;
#[path = "common/scene.rs"]
mod scene;

const W: i32 = 320;
const H: i32 = 240;

fn main() {
    let (out, frames, parts) = scene::args_with_parts();
    unsafe {
        let ctx = osmesa::OSMesa::new(W, H).unwrap_or_else(|e| {
            eprintln!("osmesa_scene: {e}");
            std::process::exit(1)
        });
        let buffers = scene::BufferFns::load(|n| osmesa::OSMesaGetProcAddress(n.as_ptr().cast()))
            .map(|b| &*Box::leak(Box::new(b)));
        let s = scene::Scene::with_parts(buffers, parts);
        // SCENE_STILL: every frame the same (the first), as an idle program redraws.
        let still = std::env::var_os("SCENE_STILL").is_some();
        for frame in 0..frames {
            s.draw(W, H, if still { 0 } else { frame });
            gl::glFinish();
        }
        let err = gl::glGetError();
        scene::write_png(&out, W as u32, H as u32, &ctx.rgb()).expect("write PNG");
        println!("osmesa_scene: {frames} frames, glGetError {err:#x}, wrote {out}");
    }
}
