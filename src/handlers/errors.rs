//! glGetError: the real GL's error, or, when it has none, the error GL would have raised inside
//! a glBegin/glEnd the real GL never saw (captured geometry is not passed on, so a program's
//! misplaced call inside glBegin reaches the real GL outside one and raises nothing there).

use crate::real;

pub unsafe fn glGetError() -> u32 {
    let real = real::glGetError();
    let ours = crate::raytrace::take_begin_error();
    if real != 0 {
        real
    } else {
        ours
    }
}
