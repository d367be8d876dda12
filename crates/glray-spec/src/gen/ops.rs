//! ops.rs, for glray-capture: the `Op` enum of the commands capture follows and `op_for`, which
//! maps a command's name to its op and the GL type its values carry (from its prototype: a
//! per-vertex attribute command's form, glLightfv's floats); whether each op is compiled into
//! display lists and allowed between glBegin and glEnd (from classes.txt, so the recorder, the
//! exports and capture cannot disagree); and which calls create, bind or copy into contexts.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::fail;
use crate::model::{Command, ListRule, OpKind, Spec};

/// The one answer all of an op's commands give to `question` (they must agree).
fn agreed(op: &str, commands: &[&Command], question: &str, answer: impl Fn(&Command) -> bool) -> bool {
    let first = answer(commands[0]);
    if let Some(other) = commands.iter().find(|c| answer(c) != first) {
        fail(&format!(
            "gl-spec: capture's op {op} joins {} and {}, which differ in {question}",
            commands[0].name, other.name
        ));
    }
    first
}

pub fn generate(spec: &Spec) -> String {
    // The ops in the order capture.txt first names them, each with its commands.
    let mut order: Vec<&str> = Vec::new();
    let mut members: BTreeMap<&str, Vec<&Command>> = BTreeMap::new();
    for op in &spec.ops {
        if let OpKind::Op(name) = &op.kind {
            if !members.contains_key(name.as_str()) {
                order.push(name);
            }
            members.entry(name).or_default().push(&spec.commands[&op.command]);
        }
    }
    let mut s = String::new();
    writeln!(s, "/// The commands capture follows, other than vertex attributes (gl-spec/capture.txt).").unwrap();
    writeln!(s, "#[derive(Debug, Clone, Copy, PartialEq, Eq)]\npub enum Op {{\n    Attr(AttrForm),").unwrap();
    for op in &order {
        let names: Vec<&str> = members[op].iter().map(|c| c.name.as_str()).collect();
        writeln!(s, "    /// {}\n    {op},", names.join(", ")).unwrap();
    }
    writeln!(s, "}}\n").unwrap();

    writeln!(
        s,
        "/// The op of a command name and the GL type its values carry (glLightfv's are floats,\n\
         /// glLoadMatrixd's doubles); None for commands capture does not follow.\n\
         pub fn op_for(name: &str) -> Option<(Op, u32)> {{\n    Some(match name {{"
    )
    .unwrap();
    for op in &spec.ops {
        let value = match &op.kind {
            OpKind::Attr(f) => format!(
                "Op::Attr(AttrForm {{ attr: Attr::{}, n: {}, ty: glray_gl::{}, vector: {} }})",
                f.attr.rust(),
                f.n,
                f.ty,
                f.vector
            ),
            OpKind::Op(name) => format!("Op::{name}"),
        };
        writeln!(s, "        \"{}\" => ({value}, glray_gl::{}),", op.command, op.ty).unwrap();
    }
    writeln!(s, "        _ => return None,\n    }})\n}}\n").unwrap();

    // The parts of the context, in the order capture.txt names them, and each op's.
    let mut concerns: Vec<&str> = Vec::new();
    let mut of: BTreeMap<&str, &str> = BTreeMap::new();
    for op in &spec.ops {
        if !concerns.contains(&op.concern.as_str()) {
            concerns.push(&op.concern);
        }
        let name = match &op.kind {
            OpKind::Op(name) => name.as_str(),
            OpKind::Attr(_) => "Attr(_)",
        };
        if of.insert(name, &op.concern).is_some_and(|c| c != op.concern) {
            fail(&format!("gl-spec/capture.txt: op {name} is in two [concern]s"));
        }
    }
    writeln!(
        s,
        "/// The parts of a context, each with its state and the code that follows its ops\n\
         /// (gl-spec/capture.txt's `[concern]` sections).\n\
         #[derive(Debug, Clone, Copy, PartialEq, Eq)]\npub enum Concern {{\n    {},\n}}\n",
        concerns.join(",\n    ")
    )
    .unwrap();

    let mut exec = Vec::new();
    let mut inside = Vec::new();
    for op in &order {
        let cmds = &members[op];
        if !agreed(op, cmds, "their list rule", |c| c.list == ListRule::Compile) {
            exec.push(format!("Op::{op}"));
        }
        if agreed(op, cmds, "being allowed inside glBegin", Command::allowed_inside_begin) {
            inside.push(format!("Op::{op}"));
        }
    }
    // Every attribute command must be compiled and allowed inside glBegin, as `Op::Attr` is.
    for op in &spec.ops {
        if let OpKind::Attr(_) = op.kind {
            let c = &spec.commands[&op.command];
            if c.list != ListRule::Compile || !c.allowed_inside_begin() {
                fail(&format!("gl-spec: attribute command {} must be `vertex compile` in classes.txt", c.name));
            }
        }
    }
    inside.insert(0, "Op::Attr(_)".into());
    writeln!(
        s,
        "impl Op {{\n    /// Whether glNewList compiles the command into the list (classes.txt's `compile`; GL 2.1\n    \
         /// section 5.4: commands that return values, create or delete objects, or set client state\n    \
         /// run at once instead).\n    pub fn compiled(self) -> bool {{\n        !matches!(self, {})\n    }}\n\n    \
         /// Whether GL allows the command between glBegin and glEnd (GL 2.1 section 2.6.3).\n    \
         pub fn inside_begin(self) -> bool {{\n        matches!(self, {})\n    }}\n\n    \
         /// The part of the context that follows the op.\n    \
         pub fn concern(self) -> Concern {{\n        match self {{\n{}        }}\n    }}\n}}\n",
        exec.join(" | "),
        inside.join(" | "),
        of.iter().map(|(op, c)| format!("            Op::{op} => Concern::{c},\n")).collect::<String>()
    )
    .unwrap();

    writeln!(
        s,
        "/// A call that creates or binds a context, or copies the framebuffer into a texture\n\
         /// (classes.txt's `shares=`, `binds=`, `copies-texture`).\n\
         #[derive(Debug, Clone, Copy, PartialEq, Eq)]\npub enum ContextCall {{\n    \
         /// Creates a context; the argument at this index is the context to share with.\n    Create(usize),\n    \
         /// Makes the context at this argument index current on the calling thread.\n    MakeCurrent(usize),\n    \
         /// Copies the framebuffer into a 2D texture: what it took is the real GL's to say.\n    CopiesTexture,\n}}\n\n\
         pub fn context_call(name: &str) -> Option<ContextCall> {{\n    Some(match name {{"
    )
    .unwrap();
    for c in spec.sorted() {
        let call = match (c.flags.shares, c.flags.binds, c.flags.copies_texture) {
            (Some(i), _, _) => format!("ContextCall::Create({i})"),
            (_, Some(i), _) => format!("ContextCall::MakeCurrent({i})"),
            (_, _, true) => "ContextCall::CopiesTexture".to_string(),
            _ => continue,
        };
        writeln!(s, "        \"{}\" => {call},", c.name).unwrap();
    }
    writeln!(s, "        _ => return None,\n    }})\n}}").unwrap();
    s
}
