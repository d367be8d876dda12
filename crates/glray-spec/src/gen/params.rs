//! params.rs: each command's parameter and return type codes, to turn another tracer's values
//! (apitrace writes pointer arguments as arrays of values) into glray's.

use std::collections::HashMap;
use std::fmt::Write as _;

use super::pointee;
use crate::model::Spec;

/// One character per parameter, then `|` and one for the return type:
///   i u f d   signed, unsigned, float, double scalar
///   B b S W I U L F D   pointer to i8, u8 (also void, chars), i16, u16, i32, u32, 64-bit, f32, f64
///   P         pointer to pointers (string arrays)
///   O         pointer the command writes through
///   h         opaque handle (GLXContext, EGLDisplay, GLsync...): its value
///   -         (return) nothing; p (return) a pointer
fn param_code(rust: &str, c_decl: &str, types: &HashMap<String, String>) -> char {
    if !rust.contains('*') {
        return match rust {
            "f32" => 'f',
            "f64" => 'd',
            "i8" | "i16" | "i32" | "i64" | "isize" => 'i',
            "()" => '-',
            _ => 'u',
        };
    }
    if !c_decl.contains('*') {
        return 'h';
    }
    if !c_decl.contains("const") {
        return 'O';
    }
    if c_decl.matches('*').count() >= 2 {
        return 'P';
    }
    let base = pointee(c_decl);
    match types.get(&base).map(String::as_str).unwrap_or("u8") {
        "i8" => 'B',
        "i16" => 'S',
        "u16" => 'W',
        "i32" => 'I',
        "u32" => 'U',
        "f32" => 'F',
        "f64" => 'D',
        "i64" | "u64" | "isize" | "c_ulong" | "*mut c_void" => 'L',
        _ => 'b',
    }
}

pub fn generate(spec: &Spec) -> String {
    let mut s = String::from(
        "/// Parameter and return type codes of every command (glray-spec's gen/params.rs).\npub static PARAMS: [&str; COUNT] = [\n",
    );
    for c in spec.sorted() {
        let args: String = c.params.iter().map(|p| param_code(&p.rust, &p.c, &spec.types)).collect();
        let ret = if c.ret.contains('*') { 'p' } else { param_code(&c.ret, "", &spec.types) };
        writeln!(s, "    \"{args}|{ret}\",").unwrap();
    }
    s.push_str("];\n");
    s
}
