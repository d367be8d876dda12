//! The model every generator reads: the exported commands (prototype, library, and what glray
//! does with each, from gl-spec/classes.txt), the registry's enum values, and the ops capture
//! follows (gl-spec/capture.txt).

use std::collections::{BTreeMap, HashMap};

use crate::fail;

/// Which API, and so which real library, a command belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lib {
    Gl,
    Glx,
    Egl,
    OSMesa,
}

impl Lib {
    pub fn parse(s: &str) -> Lib {
        match s {
            "gl" => Lib::Gl,
            "glx" => Lib::Glx,
            "egl" => Lib::Egl,
            "osmesa" => Lib::OSMesa,
            _ => fail(&format!("gl-spec/exports.txt: unknown api `{s}` (gl, glx, egl, osmesa)")),
        }
    }

    pub fn rust(self) -> &'static str {
        match self {
            Lib::Gl => "Lib::Gl",
            Lib::Glx => "Lib::Glx",
            Lib::Egl => "Lib::Egl",
            Lib::OSMesa => "Lib::OSMesa",
        }
    }

    /// The dispatch function that finds the real implementation: GL commands follow the
    /// thread's current context (glvnd or OSMesa); the others have one home.
    pub fn dispatch(self) -> &'static str {
        match self {
            Lib::Gl => "gl",
            Lib::Glx | Lib::Egl => "glvnd",
            Lib::OSMesa => "osmesa",
        }
    }
}

/// A command's class in gl-spec/classes.txt (see that file for what each means).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    Pass,
    State,
    Vertex,
    Geometry,
    Dlist,
    Client,
    Query,
    Context,
    Frame,
    Lookup,
}

impl Class {
    pub const ALL: [(&'static str, Class); 10] = [
        ("pass", Class::Pass),
        ("state", Class::State),
        ("vertex", Class::Vertex),
        ("geometry", Class::Geometry),
        ("dlist", Class::Dlist),
        ("client", Class::Client),
        ("query", Class::Query),
        ("context", Class::Context),
        ("frame", Class::Frame),
        ("lookup", Class::Lookup),
    ];

    pub fn parse(s: &str) -> Option<Class> {
        Class::ALL.iter().find(|(n, _)| *n == s).map(|(_, c)| *c)
    }

    /// The variant's name in the generated `Class` enum.
    pub fn rust(self) -> &'static str {
        match self {
            Class::Pass => "Pass",
            Class::State => "State",
            Class::Vertex => "Vertex",
            Class::Geometry => "Geometry",
            Class::Dlist => "Dlist",
            Class::Client => "Client",
            Class::Query => "Query",
            Class::Context => "Context",
            Class::Frame => "Frame",
            Class::Lookup => "Lookup",
        }
    }

    /// Classes whose calls the recorder sees before and after the real call (client arrays,
    /// contexts, frames, and geometry that reads them).
    pub fn hooked(self) -> bool {
        matches!(self, Class::Geometry | Class::Client | Class::Context | Class::Frame)
    }
}

/// Whether a GL command is compiled into an open display list (Mesa's dlist.c rules).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ListRule {
    Compile,
    Exec,
    /// Not a GL command (GLX, EGL, OSMesa), or a GL command classes.txt does not list.
    NotGl,
}

impl ListRule {
    pub fn parse(s: &str) -> Option<ListRule> {
        Some(match s {
            "compile" => ListRule::Compile,
            "exec" => ListRule::Exec,
            "-" => ListRule::NotGl,
            _ => return None,
        })
    }

    pub fn rust(self) -> &'static str {
        match self {
            ListRule::Compile => "Compile",
            ListRule::Exec => "Exec",
            ListRule::NotGl => "NotGl",
        }
    }
}

/// Where a command ends a frame, or draws over it (gl-spec/classes.txt `ends=`): the frame so
/// far is ray traced and put in place first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ends {
    /// It does not.
    No,
    Swap,
    Finish,
    Flush,
    ReadPixels,
    /// Draws over the frame or reads it (glBitmap, glDrawPixels, a copy into a texture).
    Raster,
}

impl Ends {
    pub fn parse(s: &str) -> Option<Ends> {
        Some(match s {
            "swap" => Ends::Swap,
            "finish" => Ends::Finish,
            "flush" => Ends::Flush,
            "readpixels" => Ends::ReadPixels,
            "raster" => Ends::Raster,
            _ => return None,
        })
    }

    pub fn rust(self) -> &'static str {
        match self {
            Ends::No => "No",
            Ends::Swap => "Swap",
            Ends::Finish => "Finish",
            Ends::Flush => "Flush",
            Ends::ReadPixels => "ReadPixels",
            Ends::Raster => "Raster",
        }
    }
}

/// What gl-spec/classes.txt says of a command beside its class and list rule.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Flags {
    /// The export calls glray's handler in src/abi/handlers/.
    pub handler: bool,
    /// Allowed between glBegin and glEnd although not a vertex attribute (GL 2.1, 2.6.3).
    pub inside: bool,
    /// Geometry glray takes from the real GL when it ray traces the frame.
    pub taken: bool,
    pub ends: Option<Ends>,
    /// Creates a context that shares objects with the context in this argument.
    pub shares: Option<usize>,
    /// Makes the context in this argument current on the calling thread.
    pub binds: Option<usize>,
    /// Copies the framebuffer into a 2D texture (read back into capture afterwards).
    pub copies_texture: bool,
}

/// One parameter: its name, Rust FFI type, C declaration (without the name) and the registry's
/// `len` (how many elements a pointer parameter points to), if any.
#[derive(Debug, Clone)]
pub struct Param {
    pub name: String,
    pub rust: String,
    pub c: String,
    pub len: Option<String>,
}

/// An exported command.
#[derive(Debug, Clone)]
pub struct Command {
    pub name: String,
    pub lib: Lib,
    pub ret: String,
    pub params: Vec<Param>,
    pub class: Class,
    pub list: ListRule,
    pub flags: Flags,
}

impl Command {
    /// Whether GL allows the command between glBegin and glEnd (OpenGL 2.1, section 2.6.3:
    /// vertex attributes, generic ones included, glMaterial, glEvalCoord and glEvalPoint,
    /// glArrayElement, glCallList(s), glEdgeFlag, and glEnd), or glray answers it there itself
    /// (classes.txt's `inside`).
    pub fn allowed_inside_begin(&self) -> bool {
        // Generic attributes too (glVertexAttrib4f, glVertexAttribI4i...), not their pointers.
        let generic = self
            .name
            .strip_prefix("glVertexAttrib")
            .is_some_and(|rest| rest.trim_start_matches(['I', 'L', 'P']).starts_with(|ch: char| ch.is_ascii_digit()));
        self.class == Class::Vertex || self.flags.inside || generic
    }

    /// Whether the export refuses the command inside a glBegin the real GL did not get: the GL
    /// commands GL refuses there, whose export calls the real one directly (handlers decide for
    /// themselves).
    pub fn refused_inside_begin(&self) -> bool {
        matches!(self.class, Class::State | Class::Dlist | Class::Client | Class::Query | Class::Pass)
            && self.list != ListRule::NotGl
            && !self.flags.handler
            && !self.allowed_inside_begin()
    }
}

/// One enum value of a registry.
#[derive(Debug, Clone)]
pub struct EnumValue {
    pub name: String,
    /// The Rust type of the constant (`u32`, `u64`, `i32`).
    pub rust: &'static str,
    pub value: String,
}

/// A per-vertex attribute, as capture's `Attr` names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attr {
    Vertex,
    Normal,
    Color,
    SecondaryColor,
    TexCoord,
    MultiTexCoord,
    EdgeFlag,
}

impl Attr {
    pub const ALL: [(&'static str, Attr); 7] = [
        ("Vertex", Attr::Vertex),
        ("Normal", Attr::Normal),
        ("Color", Attr::Color),
        ("SecondaryColor", Attr::SecondaryColor),
        ("TexCoord", Attr::TexCoord),
        ("MultiTexCoord", Attr::MultiTexCoord),
        ("EdgeFlag", Attr::EdgeFlag),
    ];

    pub fn parse(s: &str) -> Option<Attr> {
        Attr::ALL.iter().find(|(n, _)| *n == s).map(|(_, a)| *a)
    }

    pub fn rust(self) -> &'static str {
        Attr::ALL.iter().find(|(_, a)| *a == self).map(|(n, _)| *n).unwrap()
    }
}

/// How an attribute command passes its values (capture's `AttrForm`), read off its prototype.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AttrForm {
    pub attr: Attr,
    pub n: usize,
    /// The GL type name of the components (`GL_FLOAT`, ...).
    pub ty: &'static str,
    pub vector: bool,
}

/// What one command means to capture (gl-spec/capture.txt).
#[derive(Debug, Clone)]
pub enum OpKind {
    /// An op of capture's `Op` enum.
    Op(String),
    /// A per-vertex attribute command.
    Attr(AttrForm),
}

/// A command capture follows, with the GL type its pointer (or scalar) parameters carry and
/// the part of the context that follows it (capture.txt's `[concern]`, as a `Concern` variant).
#[derive(Debug, Clone)]
pub struct CaptureOp {
    pub command: String,
    pub kind: OpKind,
    pub ty: &'static str,
    pub concern: String,
}

/// Everything the generators read.
pub struct Spec {
    pub commands: BTreeMap<String, Command>,
    /// gl-spec/types.txt: C type -> Rust FFI type.
    pub types: HashMap<String, String>,
    /// gl-spec/sizes.txt: COMPSIZE argument list -> rule name.
    pub sizes: HashMap<String, String>,
    /// GL, GLX and EGL enum values, and OSMesa's.
    pub enums: Vec<EnumValue>,
    /// Capture's ops, in gl-spec/capture.txt's order (the `Op` variants in the order they are
    /// first named).
    pub ops: Vec<CaptureOp>,
}

impl Spec {
    /// The commands, sorted by name.
    pub fn sorted(&self) -> Vec<&Command> {
        self.commands.values().collect()
    }
}
