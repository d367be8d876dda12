//! Putting a ray-traced frame into the real framebuffer of the current context (window, FBO
//! or OSMesa buffer), colour and depth, leaving the program's GL state as it was. Two ways:
//! - `pixels`: glDrawPixels, for compatibility contexts (every GL 1.x program);
//! - `shader`: a full-screen triangle textured by a small GLSL program, for core profiles, which
//!   have no glDrawPixels.
//!
//! Which one a context takes is decided here, per frame, from what the context says it is
//! (`GLRAY_PRESENT` can force one).

mod pixels;
mod shader;

use std::collections::HashSet;
use std::sync::Mutex;

use glray_render::Rendered;

use crate::abi::profile::{self, Kind};

/// A way of presenting, as set by `GLRAY_PRESENT`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Way {
    Auto,
    Pixels,
    Shader,
}

impl Way {
    /// The setting's value (already validated by the config).
    pub fn from_setting(value: &str) -> Way {
        match value {
            "pixels" => Way::Pixels,
            "shader" => Way::Shader,
            _ => Way::Auto,
        }
    }
}

/// The way `way` comes to in a context of `kind`, and what to tell the user about it once; None
/// when this context cannot be presented into.
fn choose(way: Way, kind: Kind) -> (Option<Way>, Option<&'static str>) {
    if kind.es {
        return (None, Some("OpenGL ES contexts are not presented into (glray captures desktop GL)"));
    }
    let shader_ok = (kind.major, kind.minor) >= (3, 1);
    match way {
        Way::Auto if kind.core => (Some(Way::Shader), None),
        Way::Auto => (Some(Way::Pixels), None),
        Way::Pixels if kind.core => {
            (Some(Way::Shader), Some("present = pixels: a core profile has no glDrawPixels; presenting with a shader"))
        }
        Way::Pixels => (Some(Way::Pixels), None),
        Way::Shader if shader_ok => (Some(Way::Shader), None),
        Way::Shader => {
            (Some(Way::Pixels), Some("present = shader needs GL 3.1 or later; presenting with glDrawPixels"))
        }
    }
}

/// Messages already given (each once per process).
static TOLD: Mutex<Option<HashSet<String>>> = Mutex::new(None);

fn tell_once(message: impl Into<String>) {
    let message = message.into();
    let mut told = TOLD.lock().unwrap_or_else(|e| e.into_inner());
    let told = told.get_or_insert_with(HashSet::new);
    if !told.contains(&message) {
        glray_core::warn!("{message}");
        told.insert(message);
    }
}

/// Draws `r` over the whole drawable of the current context, the way `way` comes to there.
/// Returns whether the frame was put in place.
///
/// # Safety
/// A GL context must be current on this thread.
pub unsafe fn draw(r: &Rendered, way: Way) -> bool {
    let Some(kind) = profile::current() else {
        tell_once("the current context gives no GL_VERSION; frames are not presented");
        return false;
    };
    let (chosen, message) = choose(way, kind);
    if let Some(message) = message {
        tell_once(message);
    }
    match chosen {
        Some(Way::Shader) => match shader::draw(r, kind) {
            Ok(()) => true,
            Err(e) if !kind.core => {
                tell_once(format!("presenting with a shader failed ({e}); presenting with glDrawPixels"));
                pixels::draw(r);
                true
            }
            Err(e) => {
                tell_once(format!("presenting with a shader failed ({e}); frames are not presented"));
                false
            }
        },
        Some(_) => {
            pixels::draw(r);
            true
        }
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_profiles_are_presented_with_a_shader_and_the_rest_with_pixels() {
        assert_eq!(choose(Way::Auto, Kind::desktop(4, 5, true)), (Some(Way::Shader), None));
        assert_eq!(choose(Way::Auto, Kind::desktop(4, 5, false)), (Some(Way::Pixels), None));
        assert_eq!(choose(Way::Auto, Kind::desktop(2, 1, false)), (Some(Way::Pixels), None));
        assert_eq!(choose(Way::Shader, Kind::desktop(4, 5, false)), (Some(Way::Shader), None));
        // Forcing what the context cannot do falls back, and says so.
        let (way, message) = choose(Way::Pixels, Kind::desktop(3, 3, true));
        assert_eq!(way, Some(Way::Shader));
        assert!(message.unwrap().contains("core profile"));
        let (way, message) = choose(Way::Shader, Kind::desktop(2, 1, false));
        assert_eq!(way, Some(Way::Pixels));
        assert!(message.unwrap().contains("3.1"));
        let es = Kind { major: 3, minor: 2, es: true, core: false };
        assert_eq!(choose(Way::Auto, es).0, None);
    }
}
