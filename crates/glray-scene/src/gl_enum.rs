//! `gl_enum!`: a typed enum for a set of GL values (a depth function, a blend factor, a texture
//! filter), with the conversions from and to GL's numbers (named by glray-gl, never written
//! here). The scene holds these, not raw numbers: a value GL would refuse never reaches it, and
//! its byte encoding does not depend on GL's numbering.

macro_rules! gl_enum {
    ($(#[$meta:meta])* pub enum $name:ident { $($(#[$vmeta:meta])* $variant:ident = $gl:ident),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
        pub enum $name {
            $($(#[$vmeta])* $variant),+
        }

        impl $name {
            /// The value for GL's number; None for a number GL does not accept here.
            pub fn from_gl(value: u32) -> Option<$name> {
                match value {
                    $(glray_gl::$gl => Some($name::$variant),)+
                    _ => None,
                }
            }

            /// GL's number for it.
            pub fn gl(self) -> u32 {
                match self {
                    $($name::$variant => glray_gl::$gl,)+
                }
            }
        }
    };
}

pub(crate) use gl_enum;
