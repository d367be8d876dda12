//! enums.rs: every enum value of the GL, GLX and EGL registries and OSMesa's, as constants
//! (`pub const GL_LESS: u32 = 0x0201;`): glray names GL's numbers, never writes them.

use std::fmt::Write as _;

use crate::model::Spec;

pub fn generate(spec: &Spec) -> String {
    let mut s = String::new();
    let mut seen = std::collections::HashSet::new();
    for e in &spec.enums {
        if seen.insert(e.name.as_str()) {
            writeln!(s, "pub const {}: {} = {};", e.name, e.rust, e.value).unwrap();
        }
    }
    s
}
