//! What the context current on each thread is (GL version, ES or desktop, core or compatibility
//! profile), asked once when it is made current. Capture and recording follow fixed-function GL,
//! which core profiles do not have; presenting a frame needs a way the context supports.

use glray_gl::{GL_CONTEXT_CORE_PROFILE_BIT, GL_CONTEXT_PROFILE_MASK, GL_EXTENSIONS, GL_NUM_EXTENSIONS, GL_VERSION};
use std::cell::Cell;
use std::ffi::CStr;

use crate::abi::real::{self, get_int};

/// What a context is: its version, ES or desktop, core or compatibility.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kind {
    pub major: u32,
    pub minor: u32,
    pub es: bool,
    /// No fixed-function pipeline and no glDrawPixels: a core profile (3.2+), or a 3.1 context
    /// without GL_ARB_compatibility.
    pub core: bool,
}

#[cfg(test)]
impl Kind {
    /// A desktop GL context of this version and profile (for tests of what depends on it).
    pub fn desktop(major: u32, minor: u32, core: bool) -> Kind {
        Kind { major, minor, es: false, core }
    }
}

/// GL_VERSION's "major.minor" and whether it names OpenGL ES ("OpenGL ES 3.2 Mesa 22.3.6",
/// "4.5 (Core Profile) Mesa 22.3.6", "2.1 Mesa ...").
fn parse_version(version: &str) -> Option<(u32, u32, bool)> {
    let (es, rest) = match version.strip_prefix("OpenGL ES") {
        Some(rest) => (true, rest.trim_start_matches(|c: char| c != ' ').trim_start()),
        None => (false, version),
    };
    let number = rest.split_whitespace().next()?;
    let mut parts = number.split('.');
    let major = parts.next()?.parse().ok()?;
    let minor = parts.next()?.chars().take_while(char::is_ascii_digit).collect::<String>().parse().ok()?;
    Some((major, minor, es))
}

/// # Safety
/// A GL context must be current on this thread.
unsafe fn string(name: *mut std::ffi::c_void) -> Option<String> {
    (!name.is_null()).then(|| CStr::from_ptr(name as *const _).to_string_lossy().into_owned())
}

/// Asks the current context what it is (only queries valid in its version, so the program's
/// glGetError sees nothing of it).
///
/// # Safety
/// A GL context must be current on this thread.
unsafe fn query() -> Option<Kind> {
    let (major, minor, es) = parse_version(&string(real::glGetString(GL_VERSION))?)?;
    let core = if es {
        false
    } else if (major, minor) >= (3, 2) {
        get_int(GL_CONTEXT_PROFILE_MASK) as u32 & GL_CONTEXT_CORE_PROFILE_BIT != 0
    } else if (major, minor) == (3, 1) {
        let n = get_int(GL_NUM_EXTENSIONS).max(0) as u32;
        !(0..n).any(|i| string(real::glGetStringi(GL_EXTENSIONS, i)).as_deref() == Some("GL_ARB_compatibility"))
    } else {
        false
    };
    Some(Kind { major, minor, es, core })
}

thread_local! {
    /// This thread's current context, as asked at its MakeCurrent (outer None: not asked yet;
    /// inner None: no context, or one that gives no version).
    static CURRENT: Cell<Option<Option<Kind>>> = const { Cell::new(None) };
}

/// Called after this thread made a context current (or released it). Asked now rather than when
/// first needed: capture asks after every call, and a glGetString after a glBegin would be an
/// error the program sees.
pub fn made_current() {
    // SAFETY: on the thread that just bound the context; with none bound, glGetString returns NULL.
    let kind = unsafe { query() };
    CURRENT.with(|c| c.set(Some(kind)));
}

/// What this thread's current context is (asked now if it was not at its MakeCurrent).
pub fn current() -> Option<Kind> {
    CURRENT.with(|c| match c.get() {
        Some(kind) => kind,
        None => {
            // SAFETY: as in made_current; asked of whatever is current on this thread.
            let kind = unsafe { query() };
            c.set(Some(kind));
            kind
        }
    })
}

/// Whether this thread's current context is a core profile (no fixed-function GL).
pub fn core() -> bool {
    current().is_some_and(|k| k.core)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_are_read_as_mesa_and_vendors_write_them() {
        assert_eq!(parse_version("4.5 (Core Profile) Mesa 22.3.6"), Some((4, 5, false)));
        assert_eq!(parse_version("4.5 (Compatibility Profile) Mesa 22.3.6"), Some((4, 5, false)));
        assert_eq!(parse_version("2.1 Mesa 22.3.6"), Some((2, 1, false)));
        assert_eq!(parse_version("4.6.0 NVIDIA 535.104.05"), Some((4, 6, false)));
        assert_eq!(parse_version("3.1"), Some((3, 1, false)));
        assert_eq!(parse_version("OpenGL ES 3.2 Mesa 22.3.6"), Some((3, 2, true)));
        assert_eq!(parse_version("OpenGL ES-CM 1.1 Mesa 22.3.6"), Some((1, 1, true)));
        assert_eq!(parse_version(""), None);
        assert_eq!(parse_version("Mesa"), None);
    }
}
