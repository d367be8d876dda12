//! exports.rs: one `#[no_mangle] extern "C" fn NAME` per command, calling the real function or,
//! for the commands classes.txt marks `handler`, glray's handler under the panic guard; their
//! cold recording path; and the table of their addresses that GetProcAddress hands out.

use std::collections::HashMap;
use std::fmt::Write as _;

use super::{bits, ident, pointee, signature};
use crate::model::{Class, Command, Spec};

pub fn generate(spec: &Spec) -> String {
    let mut s = String::new();
    let mut recorded = String::new();
    let mut typed_names = Vec::new();
    let cmds = spec.sorted();
    for c in &cmds {
        let (params, args, ret) = signature(c);
        let call = if c.flags.handler {
            format!("crate::abi::ffi_guard::guard(c\"{0}\", || crate::abi::handlers::{0}({args}))", c.name)
        } else {
            format!("crate::abi::real::{}({args})", c.name)
        };
        let sep = if args.is_empty() { "" } else { ", " };
        // The export is the hot path: a flag test, then the real call (a tail call). Recording
        // lives in a cold function of its own, so that its frame and spills stay out of it.
        writeln!(
            s,
            "#[no_mangle]\npub unsafe extern \"C\" fn {name}({params}){ret} {{\n    \
             if crate::calls::active() {{\n        return recorded::{name}({args});\n    }}\n    \
             {call}\n}}",
            name = c.name,
        )
        .unwrap();
        // Only the outermost call of a thread is recorded (a real implementation calling its
        // own exported functions reaches glray's exports again). Commands that touch client
        // state may need to look at memory before the real call (a buffer about to be unmapped).
        // Geometry the ray tracer takes is not rasterized by the real GL (that is the speed-up):
        // before_real says so, and the real call is skipped.
        let in_begin = (c.class == Class::Vertex && c.name.starts_with("glVertex")) || c.refused_inside_begin();
        let before = if c.class.hooked() {
            let b: Vec<String> = c.params.iter().map(|p| bits(&p.rust, &ident(&p.name))).collect();
            format!(
                "let skip__ = outer__ && crate::calls::before_real(crate::abi::commands::cmd::{}, &[{}]);\n    ",
                c.name,
                b.join(", ")
            )
        } else if in_begin {
            // Inside a glBegin the real GL did not get: its vertices, and the commands GL
            // refuses between glBegin and glEnd (INVALID_OPERATION, nothing done, 0 returned),
            // which the real GL, outside any glBegin, would carry out (glGenLists would hand
            // out a name). Capture raises the error glGetError reports.
            "let skip__ = outer__ && crate::feed::in_skipped_begin();\n    ".to_string()
        } else {
            String::new()
        };
        let call = if before.is_empty() {
            call.clone()
        } else if c.class == Class::Geometry || in_begin {
            format!("if skip__ {{ Default::default() }} else {{ {call} }}")
        } else {
            format!("{{ let _ = skip__; {call} }}")
        };
        // Attribute commands go to capture typed when they can (`record::given`), else recorded.
        let given = given_call(c, &spec.types);
        if given.is_some() {
            typed_names.push(c.name.as_str());
        }
        let typed = given.map_or(String::new(), |g| format!("!{g} && "));
        writeln!(
            recorded,
            "#[cold]\n#[inline(never)]\n#[allow(clippy::unnecessary_cast)]\npub unsafe fn {name}({params}){ret} {{\n    \
             let outer__ = crate::calls::enter();\n    \
             {before}\
             let ret__ = {call};\n    \
             if outer__ {{\n        \
             if {typed}crate::calls::wants(crate::abi::commands::cmd::{name}) {{\n            \
             crate::calls::with(|rec__| crate::calls::generated::{name}(rec__, {args}{sep}ret__));\n        \
             }}\n        \
             crate::calls::leave();\n    \
             }}\n    \
             ret__\n}}",
            name = c.name,
        )
        .unwrap();
    }
    writeln!(s, "/// The commands whose exports hand them to capture typed (`record::given`).").unwrap();
    let typed: Vec<String> = typed_names.iter().map(|n| format!("crate::abi::commands::cmd::{n}")).collect();
    writeln!(s, "pub static TYPED: [usize; {}] = [{}];", typed.len(), typed.join(", ")).unwrap();
    writeln!(
        s,
        "/// The exports' slow path, taken while recording.\nmod recorded {{\n    use std::ffi::{{c_ulong, c_void}};\n{recorded}}}"
    )
    .unwrap();
    writeln!(s, "/// The address of each export, in COMMANDS order: what GetProcAddress hands out.").unwrap();
    writeln!(s, "pub static EXPORTS: [FnAddr; COUNT] = [").unwrap();
    for c in &cmds {
        writeln!(s, "    FnAddr({} as *const c_void),", c.name).unwrap();
    }
    writeln!(s, "];").unwrap();
    s
}

/// The commands capture takes typed (`record::given`): the per-vertex attributes of the vertex
/// stage (position, normal, colour, texture coordinates). The rest of class `vertex` (edge
/// flags, fog coordinates, secondary colours, materials...) is recorded.
const GIVEN_PREFIXES: &[&str] = &["glVertex", "glNormal", "glColor", "glTexCoord", "glMultiTexCoord"];

/// The call that hands attribute command `c` to capture typed: its components as numbers, or
/// its pointer to them as the type it points to, and a glMultiTexCoord's target; None for other
/// commands.
fn given_call(c: &Command, types: &HashMap<String, String>) -> Option<String> {
    if c.class != Class::Vertex || !GIVEN_PREFIXES.iter().any(|p| c.name.starts_with(p)) {
        return None;
    }
    let (target, parts) = match c.params.split_first() {
        Some((t, rest)) if t.name == "target" => (format!("{} as u32", ident(&t.name)), rest),
        _ => ("0".to_string(), &c.params[..]),
    };
    let name = &c.name;
    match parts {
        [p] if p.rust.contains('*') => {
            let ty = types.get(&pointee(&p.c))?;
            Some(format!(
                "crate::calls::given::given_ptr::<{ty}>(crate::abi::commands::cmd::{name}, {target}, {} as *const {ty})",
                ident(&p.name)
            ))
        }
        _ if parts.iter().all(|p| !p.rust.contains('*')) => {
            let raw: Vec<String> = parts.iter().map(|p| format!("{} as f64", ident(&p.name))).collect();
            Some(format!(
                "crate::calls::given::given(crate::abi::commands::cmd::{name}, {target}, &[{}])",
                raw.join(", ")
            ))
        }
        _ => None,
    }
}
