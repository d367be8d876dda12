//! Which GL commands capture follows, by name: each recorded command name maps once to an `Op`
//! (a trace names a command at its first call), so that a call costs a table look-up, not a
//! string comparison. The per-vertex attribute commands (glVertex3f, glColor4ubv,
//! glMultiTexCoord2fARB, ...: about 200 names) are parsed from their name's suffix, the way the
//! GL spec builds those names, instead of being listed.

use crate::args::GL_UNSIGNED_SHORT;
use crate::args::{GL_BYTE, GL_DOUBLE, GL_FLOAT, GL_INT, GL_SHORT, GL_UNSIGNED_BYTE, GL_UNSIGNED_INT};

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

macro_rules! ops {
    ($($op:ident = $($name:literal)|+;)*) => {
        /// The commands capture follows, other than vertex attributes.
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum Op {
            Attr(AttrForm),
            $($op,)*
        }

        /// The op of a command name and the GL type its pointer parameters point to (from the
        /// name's f/d/i/s suffix: glLightfv's are floats, glLoadMatrixd's doubles); None for
        /// commands capture does not follow.
        pub fn op_for(name: &str) -> Option<(Op, u32)> {
            if let Some(form) = attr_form(name) {
                return Some((Op::Attr(form), form.ty));
            }
            let op = match name {
                $($($name)|+ => Op::$op,)*
                _ => return None,
            };
            Some((op, param_type(name)))
        }
    };
}

ops! {
    Begin = "glBegin";
    End = "glEnd";
    MatrixMode = "glMatrixMode";
    LoadIdentity = "glLoadIdentity";
    LoadMatrix = "glLoadMatrixf" | "glLoadMatrixd";
    MultMatrix = "glMultMatrixf" | "glMultMatrixd";
    LoadTransposeMatrix = "glLoadTransposeMatrixf" | "glLoadTransposeMatrixd" | "glLoadTransposeMatrixfARB"
        | "glLoadTransposeMatrixdARB";
    MultTransposeMatrix = "glMultTransposeMatrixf" | "glMultTransposeMatrixd" | "glMultTransposeMatrixfARB"
        | "glMultTransposeMatrixdARB";
    Rotate = "glRotatef" | "glRotated";
    Translate = "glTranslatef" | "glTranslated";
    Scale = "glScalef" | "glScaled";
    Frustum = "glFrustum" | "glFrustumf";
    Ortho = "glOrtho" | "glOrthof";
    PushMatrix = "glPushMatrix";
    PopMatrix = "glPopMatrix";
    Viewport = "glViewport";
    DepthRange = "glDepthRange" | "glDepthRangef";
    ActiveTexture = "glActiveTexture" | "glActiveTextureARB";
    ClientActiveTexture = "glClientActiveTexture" | "glClientActiveTextureARB";
    Enable = "glEnable";
    Disable = "glDisable";
    EnableClientState = "glEnableClientState";
    DisableClientState = "glDisableClientState";
    Material = "glMaterialf" | "glMaterialfv" | "glMateriali" | "glMaterialiv";
    ColorMaterial = "glColorMaterial";
    Light = "glLightf" | "glLightfv" | "glLighti" | "glLightiv";
    LightModel = "glLightModelf" | "glLightModelfv" | "glLightModeli" | "glLightModeliv";
    ShadeModel = "glShadeModel";
    FrontFace = "glFrontFace";
    CullFace = "glCullFace";
    ClearColor = "glClearColor";
    ClearDepth = "glClearDepth" | "glClearDepthf";
    Clear = "glClear";
    Rect = "glRectf" | "glRectd" | "glRecti" | "glRects" | "glRectfv" | "glRectdv" | "glRectiv" | "glRectsv";
    NewList = "glNewList";
    EndList = "glEndList";
    CallList = "glCallList";
    CallLists = "glCallLists";
    ListBase = "glListBase";
    GenLists = "glGenLists";
    DeleteLists = "glDeleteLists";
    PushAttrib = "glPushAttrib";
    PopAttrib = "glPopAttrib";
    VertexPointer = "glVertexPointer" | "glVertexPointerEXT";
    NormalPointer = "glNormalPointer" | "glNormalPointerEXT";
    ColorPointer = "glColorPointer" | "glColorPointerEXT";
    TexCoordPointer = "glTexCoordPointer" | "glTexCoordPointerEXT";
    InterleavedArrays = "glInterleavedArrays";
    DrawArrays = "glDrawArrays" | "glDrawArraysEXT";
    DrawElements = "glDrawElements";
    DrawRangeElements = "glDrawRangeElements" | "glDrawRangeElementsEXT";
    MultiDrawArrays = "glMultiDrawArrays" | "glMultiDrawArraysEXT";
    MultiDrawElements = "glMultiDrawElements" | "glMultiDrawElementsEXT";
    ArrayElement = "glArrayElement" | "glArrayElementEXT";
    BindBuffer = "glBindBuffer" | "glBindBufferARB";
    BufferData = "glBufferData" | "glBufferDataARB";
    BufferSubData = "glBufferSubData" | "glBufferSubDataARB";
    DeleteBuffers = "glDeleteBuffers" | "glDeleteBuffersARB";
    BindTexture = "glBindTexture" | "glBindTextureEXT";
    DeleteTextures = "glDeleteTextures" | "glDeleteTexturesEXT";
    TexImage1D = "glTexImage1D";
    TexImage2D = "glTexImage2D";
    TexSubImage1D = "glTexSubImage1D";
    TexSubImage2D = "glTexSubImage2D";
    TexParameter = "glTexParameteri" | "glTexParameterf" | "glTexParameteriv" | "glTexParameterfv";
    TexEnv = "glTexEnvi" | "glTexEnvf" | "glTexEnviv" | "glTexEnvfv";
    TexGen = "glTexGeni" | "glTexGenf" | "glTexGend" | "glTexGeniv" | "glTexGenfv" | "glTexGendv";
    PixelStore = "glPixelStorei" | "glPixelStoref";
    Fog = "glFogf" | "glFogi" | "glFogfv" | "glFogiv";
    BlendFunc = "glBlendFunc";
    LogicOp = "glLogicOp";
    AlphaFunc = "glAlphaFunc";
    DepthFunc = "glDepthFunc";
    DepthMask = "glDepthMask";
    ColorMask = "glColorMask";
    Scissor = "glScissor";
    PolygonMode = "glPolygonMode";
    PolygonOffset = "glPolygonOffset" | "glPolygonOffsetEXT";
    LineWidth = "glLineWidth";
    PointSize = "glPointSize";
    ClipPlane = "glClipPlane";
    GetError = "glGetError";
    UseProgram = "glUseProgram" | "glUseProgramObjectARB";
    BindFramebuffer = "glBindFramebuffer" | "glBindFramebufferEXT";
    VertexAttribPointer = "glVertexAttribPointer" | "glVertexAttribPointerARB" | "glVertexAttribIPointer";
}

/// The parameter type a command name's suffix gives (GL_FLOAT when it gives none).
fn param_type(name: &str) -> u32 {
    let name = name.strip_suffix("ARB").or_else(|| name.strip_suffix("EXT")).unwrap_or(name);
    let name = name.strip_suffix('v').unwrap_or(name);
    match name.as_bytes().last() {
        Some(b'd') => GL_DOUBLE,
        Some(b'i') => GL_INT,
        Some(b's') => GL_SHORT,
        _ => GL_FLOAT,
    }
}

/// Parses glVertex2f, glColor4ubv, glMultiTexCoord3dARB, glEdgeFlagv, ...
pub fn attr_form(name: &str) -> Option<AttrForm> {
    let name = name.strip_prefix("gl")?;
    let name = name.strip_suffix("ARB").or_else(|| name.strip_suffix("EXT")).unwrap_or(name);
    let (attr, rest) = [
        ("Vertex", Attr::Vertex),
        ("Normal", Attr::Normal),
        ("SecondaryColor", Attr::SecondaryColor),
        ("Color", Attr::Color),
        ("MultiTexCoord", Attr::MultiTexCoord),
        ("TexCoord", Attr::TexCoord),
        ("EdgeFlag", Attr::EdgeFlag),
    ]
    .iter()
    .find_map(|(prefix, attr)| name.strip_prefix(prefix).map(|rest| (*attr, rest)))?;
    if attr == Attr::EdgeFlag {
        return match rest {
            "" => Some(AttrForm { attr, n: 1, ty: GL_UNSIGNED_BYTE, vector: false }),
            "v" => Some(AttrForm { attr, n: 1, ty: GL_UNSIGNED_BYTE, vector: true }),
            _ => None,
        };
    }
    let n = rest.chars().next()?.to_digit(10)? as usize;
    if !(1..=4).contains(&n) {
        return None;
    }
    let rest = &rest[1..];
    let (ty, rest) = [
        ("ub", GL_UNSIGNED_BYTE),
        ("us", GL_UNSIGNED_SHORT),
        ("ui", GL_UNSIGNED_INT),
        ("b", GL_BYTE),
        ("s", GL_SHORT),
        ("i", GL_INT),
        ("f", GL_FLOAT),
        ("d", GL_DOUBLE),
    ]
    .iter()
    .find_map(|(suffix, ty)| rest.strip_prefix(suffix).map(|rest| (*ty, rest)))?;
    let vector = match rest {
        "" => false,
        "v" => true,
        _ => return None,
    };
    Some(AttrForm { attr, n, ty, vector })
}

impl Op {
    /// Whether glNewList compiles the command into the list (GL 2.1 section 5.4: commands that
    /// return values, create or delete objects, or set client state run at once instead).
    pub fn compiled(self) -> bool {
        !matches!(
            self,
            Op::NewList
                | Op::EndList
                | Op::GenLists
                | Op::DeleteLists
                | Op::EnableClientState
                | Op::DisableClientState
                | Op::ClientActiveTexture
                | Op::VertexPointer
                | Op::NormalPointer
                | Op::ColorPointer
                | Op::TexCoordPointer
                | Op::InterleavedArrays
                | Op::BindBuffer
                | Op::BufferData
                | Op::BufferSubData
                | Op::DeleteBuffers
                | Op::DeleteTextures
                | Op::PixelStore
                | Op::GetError
                | Op::VertexAttribPointer
                | Op::BindFramebuffer
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attribute_names_parse_from_their_suffix() {
        let f = |n| attr_form(n).map(|f| (f.attr, f.n, f.ty, f.vector));
        assert_eq!(f("glVertex3f"), Some((Attr::Vertex, 3, GL_FLOAT, false)));
        assert_eq!(f("glColor4ubv"), Some((Attr::Color, 4, GL_UNSIGNED_BYTE, true)));
        assert_eq!(f("glMultiTexCoord2dARB"), Some((Attr::MultiTexCoord, 2, GL_DOUBLE, false)));
        assert_eq!(f("glSecondaryColor3usEXT"), Some((Attr::SecondaryColor, 3, GL_UNSIGNED_SHORT, false)));
        assert_eq!(f("glEdgeFlagv"), Some((Attr::EdgeFlag, 1, GL_UNSIGNED_BYTE, true)));
        assert_eq!(f("glVertexPointer"), None);
        assert_eq!(f("glVertex3hNV"), None);
        assert_eq!(f("glColorMaterial"), None);
        assert_eq!(f("glVertex5f"), None);
        assert_eq!(op_for("glCallLists").map(|o| o.0), Some(Op::CallLists));
        assert_eq!(op_for("glLoadMatrixd"), Some((Op::LoadMatrix, GL_DOUBLE)));
        assert_eq!(op_for("glLightiv"), Some((Op::Light, GL_INT)));
        assert_eq!(op_for("glLoadTransposeMatrixfARB"), Some((Op::LoadTransposeMatrix, GL_FLOAT)));
        assert_eq!(op_for("glVertexAttrib3f"), None);
        assert!(!Op::GenLists.compiled() && Op::Rotate.compiled());
    }
}
