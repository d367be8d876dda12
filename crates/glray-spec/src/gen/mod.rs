//! One generator per generated file (Mesa's glapi/gen), each a function of the model to text:
//!
//! | generator | file | included by |
//! |---|---|---|
//! | `commands` | commands.rs: the sorted command table and `cmd::NAME` | libglray's `abi::commands` |
//! | `real` | real.rs: `real::NAME(args)`, a typed call of the real function | `abi::real` |
//! | `exports` | exports.rs: the `extern "C"` functions and their address table | `abi::exports` |
//! | `record` | record.rs: `generated::NAME(rec, ...)`, writing a call to a trace | `record` |
//! | `replay` | replay.rs: each GL command called from recorded values | `glray replay` |
//! | `params` | params.rs: parameter type codes (reading apitrace's traces) | `glray replay` |
//! | `enums` | enums.rs: every GL, GLX, EGL and OSMesa enum value | glray-gl |
//! | `ops` | ops.rs: capture's `Op`, attribute forms, list and glBegin rules, context calls | glray-capture |

pub mod commands;
pub mod enums;
pub mod exports;
pub mod ops;
pub mod params;
pub mod real;
pub mod record;
pub mod replay;

use crate::model::Command;

/// Parameter names that are Rust keywords get a trailing underscore.
pub fn ident(name: &str) -> String {
    const KEYWORDS: &[&str] = &[
        "type", "ref", "in", "fn", "match", "mod", "move", "impl", "loop", "box", "self", "use", "where", "struct",
        "enum", "trait", "let", "mut", "const", "static", "priv", "final", "override", "async", "await", "dyn",
        "abstract", "become", "do", "macro", "typeof", "unsized", "virtual", "yield", "try",
    ];
    if KEYWORDS.contains(&name) {
        format!("{name}_")
    } else {
        name.to_string()
    }
}

/// A command's Rust parameter list, argument list and return clause.
pub fn signature(c: &Command) -> (String, String, String) {
    let params: Vec<String> = c.params.iter().map(|p| format!("{}: {}", ident(&p.name), p.rust)).collect();
    let args: Vec<String> = c.params.iter().map(|p| ident(&p.name)).collect();
    let ret = if c.ret == "()" { String::new() } else { format!(" -> {}", c.ret) };
    (params.join(", "), args.join(", "), ret)
}

/// The C base type a pointer parameter points to ("const GLfloat *" -> "GLfloat").
pub fn pointee(c_decl: &str) -> String {
    c_decl
        .replace('*', " ")
        .split_whitespace()
        .filter(|w| *w != "const" && *w != "struct")
        .collect::<Vec<_>>()
        .join(" ")
}

/// A value as the 64 bits the recorder's hooks take.
pub fn bits(rust: &str, v: &str) -> String {
    match rust {
        "f32" | "f64" => format!("{v}.to_bits() as u64"),
        "()" => "0u64".into(),
        r if r.contains('*') => format!("{v} as usize as u64"),
        "i8" | "i16" | "i32" | "i64" | "isize" => format!("{v} as i64 as u64"),
        _ => format!("{v} as u64"),
    }
}
