//! replay.rs: for every GL command, a function that turns recorded values into arguments and
//! calls the replay target's function; `REPLAY[cmd]` finds it.

use std::fmt::Write as _;

use crate::model::{Lib, Spec};

pub fn generate(spec: &Spec) -> String {
    let cmds = spec.sorted();
    let mut s = String::new();
    writeln!(s, "pub type ReplayFn = unsafe fn(&mut Replayer, &[Value]) -> Result<(), String>;").unwrap();
    for c in cmds.iter().filter(|c| c.lib == Lib::Gl) {
        writeln!(s, "#[allow(unused_variables, clippy::useless_transmute)]").unwrap();
        writeln!(s, "unsafe fn {}(r: &mut Replayer, a: &[Value]) -> Result<(), String> {{", c.name).unwrap();
        writeln!(s, "    if a.len() != {} {{ return Err(arity({}, a.len())); }}", c.params.len(), c.params.len())
            .unwrap();
        writeln!(s, "    let f__ = r.gl(cmd::{})?;", c.name).unwrap();
        let mut names = Vec::new();
        for (i, p) in c.params.iter().enumerate() {
            let v = format!("a{i}");
            let conv = if p.rust.contains('*') {
                if p.c.contains("const") {
                    format!("r.input_pointer(&a[{i}])?")
                } else {
                    format!("r.output_pointer(cmd::{}, &a[{i}])?", c.name)
                }
            } else {
                format!("<{} as FromValue>::from_value(&a[{i}], {i})?", p.rust)
            };
            writeln!(s, "    let {v}: {} = {conv};", p.rust).unwrap();
            names.push(v);
        }
        let types: Vec<&str> = c.params.iter().map(|p| p.rust.as_str()).collect();
        let ret = if c.ret == "()" { String::new() } else { format!(" -> {}", c.ret) };
        writeln!(s, "    let real__: unsafe extern \"C\" fn({}){ret} = core::mem::transmute(f__);", types.join(", "))
            .unwrap();
        writeln!(s, "    real__({});\n    Ok(())\n}}", names.join(", ")).unwrap();
    }
    writeln!(s, "pub static REPLAY: [Option<ReplayFn>; COUNT] = [").unwrap();
    for c in &cmds {
        if c.lib == Lib::Gl {
            writeln!(s, "    Some({} as ReplayFn),", c.name).unwrap();
        } else {
            writeln!(s, "    None,").unwrap();
        }
    }
    writeln!(s, "];").unwrap();
    s
}
