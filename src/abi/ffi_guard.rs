//! No panic crosses `extern "C"`: handlers run under `guard`, which turns a panic into a logged
//! error and a zero result (what the real GL returns for a call it ignores).

use std::ffi::CStr;
use std::panic::{catch_unwind, AssertUnwindSafe};

pub fn guard<R>(name: &CStr, f: impl FnOnce() -> R) -> R {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            glray_core::error!("internal error in {}: {what}; the call returned 0", name.to_string_lossy());
            // SAFETY: every exported command returns (), an integer, a float or a raw pointer,
            // for all of which all-zero bits are a valid value.
            unsafe { std::mem::zeroed() }
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_panic_becomes_zero() {
        let (r, said): (u32, _) = glray_core::log::captured(|| super::guard(c"glTest", || panic!("boom")));
        assert_eq!(r, 0);
        assert_eq!(said, "glray: error: internal error in glTest: boom; the call returned 0\n");
        let (p, _): (*mut u8, _) = glray_core::log::captured(|| super::guard(c"glTest", || panic!("boom")));
        assert!(p.is_null());
        assert_eq!(super::guard(c"glTest", || 7u8), 7);
    }
}
