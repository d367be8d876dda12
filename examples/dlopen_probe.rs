//! A program that loads GL itself, as plugin hosts and Python bindings do: dlopen of each GL
//! library name, then dlsym of one of its functions. Prints which file each function comes from.
//!
//!     dlopen_probe

use std::ffi::{c_void, CStr};

fn main() {
    let probes: [(&CStr, &CStr); 6] = [
        (c"libGL.so.1", c"glBegin"),
        (c"libGL.so", c"glXSwapBuffers"),
        (c"libOpenGL.so.0", c"glDrawRangeElements"),
        (c"libGLX.so.0", c"glXGetProcAddressARB"),
        (c"libEGL.so.1", c"eglSwapBuffers"),
        (c"libOSMesa.so.8", c"OSMesaMakeCurrent"),
    ];
    for (lib, sym) in probes {
        unsafe {
            let h = libc::dlopen(lib.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL);
            if h.is_null() {
                println!("{}: dlopen failed", lib.to_string_lossy());
                continue;
            }
            let p = libc::dlsym(h, sym.as_ptr());
            let mut info: libc::Dl_info = std::mem::zeroed();
            let file = if !p.is_null() && libc::dladdr(p as *const c_void, &mut info) != 0 {
                CStr::from_ptr(info.dli_fname).to_string_lossy().into_owned()
            } else {
                "(not found)".into()
            };
            println!("{} {} {}", lib.to_string_lossy(), sym.to_string_lossy(), file);
        }
    }
}
