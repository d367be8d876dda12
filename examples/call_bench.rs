//! The cost of a GL call: times the calls that dominate real programs (glGetIntegerv and
//! glGetBooleanv are over half of ParaView's calls; glVertex3f, glNormal3f and glColor3f run
//! millions of times a second in immediate-mode programs) in an OSMesa context. Run it as is for
//! Mesa directly and under glray (`glray run -- call_bench`): scripts/bench-calls does both and
//! prints the ratios.
//!
//!     call_bench [MILLION_CALLS]

#[path = "common/gl.rs"]
mod gl;
#[path = "common/osmesa.rs"]
mod osmesa;

use gl::*;
use glray_gl::{GL_COMPILE, GL_DEPTH_TEST, GL_POINTS, GL_VIEWPORT};
use std::time::Instant;

extern "C" {
    fn glGetBooleanv(pname: u32, data: *mut u8);
}

const GL_DEPTH_TEST_ENUM: u32 = GL_DEPTH_TEST;

fn time(name: &str, n: u64, mut f: impl FnMut(u64)) {
    // Best of 5 runs: the machine is shared and noisy; the minimum is the call's cost.
    let best = (0..5)
        .map(|_| {
            let t = Instant::now();
            f(n);
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min);
    println!("{name:<28} {:8.2} ns/call", best * 1e9 / n as f64);
}

fn main() {
    let millions: u64 = std::env::args().nth(1).map(|m| m.parse().expect("a number")).unwrap_or(5);
    let n = millions * 1_000_000;
    unsafe {
        let _ctx = osmesa::OSMesa::new(64, 64).expect("OSMesa context");
        let mut vp = [0i32; 4];
        time("glGetIntegerv(VIEWPORT)", n, |n| {
            for _ in 0..n {
                glGetIntegerv(GL_VIEWPORT, vp.as_mut_ptr());
            }
        });
        let mut b = 0u8;
        time("glGetBooleanv(DEPTH_TEST)", n, |n| {
            for _ in 0..n {
                glGetBooleanv(GL_DEPTH_TEST_ENUM, &mut b);
            }
        });
        time("glNormal3f", n, |n| {
            for i in 0..n {
                glNormal3f(i as f32, 0.0, 1.0);
            }
        });
        time("glColor3f", n, |n| {
            for i in 0..n {
                glColor3f(i as f32, 0.5, 1.0);
            }
        });
        // Vertices compiled into a display list: Mesa stores them, nothing is rasterized, so
        // the call itself is what is measured. The list is rebuilt per run.
        let list = glGenLists(1);
        time("glVertex3f (in glNewList)", n, |n| {
            glNewList(list, GL_COMPILE);
            glBegin(GL_POINTS);
            for i in 0..n {
                glVertex3f(i as f32, 0.0, 0.0);
            }
            glEnd();
            glEndList();
        });
        std::hint::black_box((vp, b));
    }
}
