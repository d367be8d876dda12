//! real.rs: `real::NAME(args)`, a typed call of the real implementation through dispatch.

use std::fmt::Write as _;

use super::signature;
use crate::model::Spec;

pub fn generate(spec: &Spec) -> String {
    // Two functions per command: the inlined fast path, which only calls when the function
    // pointer is already known (so the compiler can make it a tail call with no frame), and a
    // cold one that resolves it (and reads the thread's context kind when a process mixes them).
    let mut s = String::new();
    let mut slow = String::new();
    for c in spec.sorted() {
        let (params, args, ret) = signature(c);
        let types: Vec<&str> = c.params.iter().map(|p| p.rust.as_str()).collect();
        let fn_type = format!("unsafe extern \"C\" fn({}){ret}", types.join(", "));
        writeln!(
            s,
            "#[inline(always)]\npub unsafe fn {name}({params}){ret} {{\n    \
             let addr__ = dispatch::{disp}_cached(cmd::{name});\n    \
             if !addr__.is_null() {{\n        \
             let real__: {fn_type} = core::mem::transmute(addr__);\n        \
             return real__({args});\n    }}\n    \
             slow::{name}({args})\n}}",
            name = c.name,
            disp = c.lib.dispatch(),
        )
        .unwrap();
        writeln!(
            slow,
            "#[cold]\n#[inline(never)]\npub unsafe fn {name}({params}){ret} {{\n    \
             let addr__ = dispatch::{disp}(cmd::{name});\n    \
             if addr__.is_null() {{ return core::mem::zeroed(); }}\n    \
             let real__: {fn_type} = core::mem::transmute(addr__);\n    \
             real__({args})\n}}",
            name = c.name,
            disp = c.lib.dispatch(),
        )
        .unwrap();
    }
    writeln!(s, "mod slow {{\n    use super::*;\n{slow}}}").unwrap();
    s
}
