//! glGetError: the real GL's error, or, when it has none, the error GL would have raised for a
//! call the real GL never saw (geometry glray ray traces instead of passing it on: a bad
//! glDrawArrays mode, a glBegin inside glBegin) or saw out of place (a call inside a glBegin
//! the real GL never got reaches it outside one and raises nothing there).

use crate::abi::real;

pub unsafe fn glGetError() -> u32 {
    let real = real::glGetError();
    let ours = crate::calls::take_unseen_error();
    if real != 0 {
        real
    } else {
        ours
    }
}
