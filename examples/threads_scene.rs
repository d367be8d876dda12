//! Several threads, each with its own context, drawing the scene at once; thread N writes
//! OUT_PREFIX-N.png. KIND `osmesa` or `egl` gives every thread that kind of context; `mixed`
//! alternates them, so that OSMesa and glvnd contexts are current at the same time in one
//! process. Each image must equal the one drawn with the same kind of context alone: glray keeps
//! each thread's current context apart. (Without glray, a mixed process cannot work: all its gl*
//! calls bind to whichever library the program linked first.)
//!
//!     threads_scene OUT_PREFIX THREADS osmesa|egl|mixed

#[path = "common/egl.rs"]
mod egl;
#[path = "common/gl.rs"]
mod gl;
#[path = "common/osmesa.rs"]
mod osmesa;
#[path = "common/scene.rs"]
mod scene;

const W: i32 = 160;
const H: i32 = 120;

unsafe fn draw_frames(s: &scene::Scene, swap: impl Fn()) {
    for frame in 0..20 {
        s.draw(W, H, frame % 3);
        gl::glFinish();
        swap();
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = || -> ! {
        eprintln!("usage: threads_scene OUT_PREFIX THREADS osmesa|egl|mixed");
        std::process::exit(2)
    };
    let (Some(prefix), Some(Ok(threads)), Some(kind)) =
        (args.first().cloned(), args.get(1).map(|t| t.parse::<u32>()), args.get(2).cloned())
    else {
        usage()
    };
    if !["osmesa", "egl", "mixed"].contains(&kind.as_str()) {
        usage()
    }
    let handles: Vec<_> = (0..threads)
        .map(|t| {
            let out = format!("{prefix}-{t}.png");
            let egl = kind == "egl" || (kind == "mixed" && t % 2 == 1);
            std::thread::spawn(move || unsafe {
                let rgb = if egl {
                    let mut ctx = egl::Egl::new(W, H).expect("EGL context");
                    // Other threads still use the process's one EGL display.
                    ctx.terminate_on_drop = false;
                    let s = scene::Scene::new(None);
                    draw_frames(&s, || {});
                    let rgb = scene::read_rgb(W, H);
                    ctx.swap();
                    rgb
                } else {
                    let ctx = osmesa::OSMesa::new(W, H).expect("OSMesa context");
                    let s = scene::Scene::new(None);
                    draw_frames(&s, || {});
                    ctx.rgb()
                };
                scene::write_png(&out, W as u32, H as u32, &rgb).expect("write PNG");
            })
        })
        .collect();
    for h in handles {
        h.join().expect("a drawing thread failed");
    }
    println!("threads_scene: {threads} {kind} threads done");
}
