//! Which GL commands capture follows, by name: each recorded command name maps once to an `Op`
//! (a trace names a command at its first call), so that a call costs a table look-up, not a
//! string comparison. The table is generated at build time (glray-spec's `gen::ops`) from
//! gl-spec/capture.txt, classes.txt and the Khronos registry: the per-vertex attribute commands'
//! forms (glVertex3f, glColor4ubv, glMultiTexCoord2fARB, ...: about 200 names) are read off their
//! prototypes, and whether an op is compiled into display lists or allowed between glBegin and
//! glEnd is classes.txt's word, the same the exports and the recorder go by.

/// A per-vertex attribute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attr {
    Vertex,
    Normal,
    Color,
    SecondaryColor,
    /// glTexCoord: unit 0.
    TexCoord,
    /// glMultiTexCoord: the unit is the first argument.
    MultiTexCoord,
    EdgeFlag,
}

/// How an attribute command passes its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AttrForm {
    pub attr: Attr,
    /// Number of components.
    pub n: usize,
    /// GL type of the components.
    pub ty: u32,
    /// The `v` form: one pointer instead of n scalars.
    pub vector: bool,
}

include!(concat!(env!("OUT_DIR"), "/ops.rs"));

/// The form of an attribute command, by name (None for any other command).
pub fn attr_form(name: &str) -> Option<AttrForm> {
    match op_for(name)? {
        (Op::Attr(form), _) => Some(form),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_gl::{GL_BYTE, GL_DOUBLE, GL_FLOAT, GL_INT, GL_SHORT, GL_UNSIGNED_BYTE, GL_UNSIGNED_SHORT};

    #[test]
    fn attribute_forms_come_from_the_prototypes() {
        let f = |n| attr_form(n).map(|f| (f.attr, f.n, f.ty, f.vector));
        assert_eq!(f("glVertex3f"), Some((Attr::Vertex, 3, GL_FLOAT, false)));
        assert_eq!(f("glColor4ubv"), Some((Attr::Color, 4, GL_UNSIGNED_BYTE, true)));
        assert_eq!(f("glMultiTexCoord2dARB"), Some((Attr::MultiTexCoord, 2, GL_DOUBLE, false)));
        assert_eq!(f("glSecondaryColor3usEXT"), Some((Attr::SecondaryColor, 3, GL_UNSIGNED_SHORT, false)));
        assert_eq!(f("glEdgeFlagv"), Some((Attr::EdgeFlag, 1, GL_UNSIGNED_BYTE, true)));
        assert_eq!(f("glNormal3b"), Some((Attr::Normal, 3, GL_BYTE, false)));
        assert_eq!(f("glVertexPointer"), None);
        assert_eq!(f("glVertex3hNV"), None);
        assert_eq!(f("glColorMaterial"), None);
        assert_eq!(f("glColor4ubVertex2fSUN"), None);
        assert_eq!(op_for("glCallLists").map(|o| o.0), Some(Op::CallLists));
        assert_eq!(op_for("glLoadMatrixd"), Some((Op::LoadMatrix, GL_DOUBLE)));
        assert_eq!(op_for("glLightiv"), Some((Op::Light, GL_INT)));
        assert_eq!(op_for("glLoadTransposeMatrixfARB"), Some((Op::LoadTransposeMatrix, GL_FLOAT)));
        assert_eq!(op_for("glVertexAttrib3f"), None);
        assert!(!Op::GenLists.compiled() && Op::Rotate.compiled());
        assert!(Op::Material.inside_begin() && Op::End.inside_begin() && !Op::Rotate.inside_begin());
    }

    #[test]
    fn the_type_a_command_carries_is_its_name_suffixs() {
        // The ops that read values by the type their command carries (`Context::floats`): the
        // type from the prototype is the one GL's naming gives (f floats, d doubles, i ints, s
        // shorts).
        for family in ["Light", "LightModel", "Material", "TexParameter", "TexEnv", "TexGen", "Fog", "Rect"] {
            for suffix in ["f", "fv", "i", "iv", "d", "dv", "s", "sv"] {
                let name = format!("gl{family}{suffix}");
                let Some((_, ty)) = op_for(&name) else { continue };
                let want = match suffix.trim_end_matches('v') {
                    "d" => GL_DOUBLE,
                    "i" => GL_INT,
                    "s" => GL_SHORT,
                    _ => GL_FLOAT,
                };
                assert_eq!(ty, want, "{name}");
            }
        }
        for name in ["glLoadMatrixf", "glMultMatrixd", "glLoadTransposeMatrixdARB", "glMultTransposeMatrixf"] {
            let want = if name.ends_with('d') || name.ends_with("dARB") { GL_DOUBLE } else { GL_FLOAT };
            assert_eq!(op_for(name).unwrap().1, want, "{name}");
        }
    }

    #[test]
    fn context_calls_name_their_arguments() {
        assert_eq!(context_call("glXCreateContext"), Some(ContextCall::Create(2)));
        assert_eq!(context_call("glXCreateNewContext"), Some(ContextCall::Create(3)));
        assert_eq!(context_call("OSMesaCreateContextExt"), Some(ContextCall::Create(4)));
        assert_eq!(context_call("eglMakeCurrent"), Some(ContextCall::MakeCurrent(3)));
        assert_eq!(context_call("OSMesaMakeCurrent"), Some(ContextCall::MakeCurrent(0)));
        assert_eq!(context_call("glCopyTexSubImage2D"), Some(ContextCall::CopiesTexture));
        assert_eq!(context_call("glCopyTexImage1D"), None);
        assert_eq!(context_call("glBegin"), None);
    }
}
