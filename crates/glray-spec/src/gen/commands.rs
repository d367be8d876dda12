//! commands.rs: the table of every exported command, sorted by name (binary search for
//! GetProcAddress), with what glray does with it, and `cmd::NAME`, each command's index.

use std::fmt::Write as _;

use crate::model::{Ends, Spec};

pub fn generate(spec: &Spec) -> String {
    let cmds = spec.sorted();
    let mut s = String::new();
    writeln!(s, "/// Number of exported commands.\npub const COUNT: usize = {};", cmds.len()).unwrap();
    writeln!(s, "/// Every exported command, sorted by name (binary-searchable), with its rules.").unwrap();
    writeln!(s, "pub static COMMANDS: [CommandInfo; COUNT] = [").unwrap();
    for c in &cmds {
        writeln!(
            s,
            "    CommandInfo {{ name: c\"{}\", lib: {}, class: Class::{}, list: ListRule::{}, handled: {}, taken: {}, \
             ends: Ends::{} }},",
            c.name,
            c.lib.rust(),
            c.class.rust(),
            c.list.rust(),
            c.flags.handler,
            c.flags.taken,
            c.flags.ends.unwrap_or(Ends::No).rust(),
        )
        .unwrap();
    }
    writeln!(s, "];\n\n/// Index of each command in COMMANDS.\n#[allow(non_upper_case_globals)]\npub mod cmd {{")
        .unwrap();
    for (i, c) in cmds.iter().enumerate() {
        writeln!(s, "    pub const {}: usize = {i};", c.name).unwrap();
    }
    writeln!(s, "}}").unwrap();
    s
}
