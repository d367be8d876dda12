//! record.rs: `generated::NAME(rec, args..., ret)` writes one call to the trace: scalars by
//! type, pointer arguments as the memory they read (sized from the registry's `len` and
//! gl-spec/sizes.txt). Commands whose class touches client arrays, contexts or frames also call
//! the recorder's hooks before and after, with their arguments as bits.

use std::collections::HashMap;
use std::fmt::Write as _;

use super::{bits, ident, pointee};
use crate::model::{Command, Param, Spec};

pub fn generate(spec: &Spec) -> String {
    let mut s = String::new();
    for c in spec.sorted() {
        let mut params: Vec<String> = c.params.iter().map(|p| format!("{}: {}", ident(&p.name), p.rust)).collect();
        params.push(format!("ret__: {}", c.ret));
        let hooked = c.class.hooked();
        writeln!(s, "#[allow(unused_variables, unused_parens, clippy::unnecessary_cast)]").unwrap();
        writeln!(s, "pub unsafe fn {}(rec: &mut Recorder, {}) {{", c.name, params.join(", ")).unwrap();
        if hooked {
            let b: Vec<String> = c.params.iter().map(|p| bits(&p.rust, &ident(&p.name))).collect();
            writeln!(s, "    let bits__: [u64; {}] = [{}];", b.len(), b.join(", ")).unwrap();
            writeln!(s, "    rec.before(crate::abi::commands::cmd::{}, &bits__);", c.name).unwrap();
        }
        writeln!(s, "    rec.begin(crate::abi::commands::cmd::{}, {});", c.name, c.params.len()).unwrap();
        for p in &c.params {
            let code = if p.rust.contains('*') {
                record_pointer(c, p, &spec.types, &spec.sizes)
            } else {
                record_scalar(&p.rust, &ident(&p.name))
            };
            writeln!(s, "    {code}").unwrap();
        }
        match c.ret.as_str() {
            "()" => writeln!(s, "    rec.e.no_return();").unwrap(),
            r if r.contains('*') => writeln!(s, "    rec.e.opaque(ret__ as usize as u64);").unwrap(),
            r => writeln!(s, "    {}", record_scalar(r, "ret__")).unwrap(),
        }
        if hooked {
            writeln!(s, "    rec.after(crate::abi::commands::cmd::{}, &bits__, {});", c.name, bits(&c.ret, "ret__"))
                .unwrap();
        }
        writeln!(s, "}}").unwrap();
    }
    s
}

/// Size in bytes of one element of a Rust FFI type.
fn rust_size(rust: &str) -> usize {
    match rust {
        "()" | "u8" | "i8" => 1,
        "u16" | "i16" => 2,
        "u32" | "i32" | "f32" => 4,
        _ => 8,
    }
}

fn is_char(base: &str) -> bool {
    matches!(base, "GLchar" | "GLcharARB" | "char")
}

/// `x as i64` for an integer parameter, or None if `name` is not an integer parameter of `c`.
fn int_param(c: &Command, name: &str) -> Option<String> {
    c.params
        .iter()
        .find(|p| p.name == name && !p.rust.contains('*') && !p.rust.starts_with('f'))
        .map(|p| format!("({} as i64)", ident(&p.name)))
}

/// Code that records pointer parameter `p` of command `c`.
fn record_pointer(c: &Command, p: &Param, types: &HashMap<String, String>, sizes: &HashMap<String, String>) -> String {
    let v = ident(&p.name);
    let base = pointee(&p.c);
    let elem = if base == "void" { 1 } else { types.get(&base).map_or(1, |r| rust_size(r)) };
    let stars = p.c.matches('*').count();
    let unknown = format!("rec.unknown_pointer(crate::abi::commands::cmd::{}, {v});", c.name);
    if !p.c.contains("const") {
        return format!("rec.output_pointer({v});");
    }
    if stars >= 2 && base == "void" && p.name == "indices" {
        // glMultiDrawElements: one index array per draw, of `count[i]` indices of `type`.
        let counts = c.params.iter().find(|q| q.name == "count" && q.rust.contains('*'));
        if let (Some(counts), Some(ty), Some(n)) = (counts, int_param(c, "type"), int_param(c, "drawcount")) {
            return format!("rec.index_arrays({v}, {}, {ty}, {n});", ident(&counts.name));
        }
        return unknown;
    }
    if stars >= 2 {
        // Arrays of strings (glShaderSource): `len` is the count, `length` the optional lengths.
        if is_char(&base) {
            if let Some(count) = p.len.as_deref().and_then(|l| int_param(c, l)) {
                let lengths = c.params.iter().find(|q| q.name == "length" && q.rust.contains('*'));
                let lengths = lengths.map_or("core::ptr::null_mut()".to_string(), |q| ident(&q.name));
                return format!("rec.strings({v}, {count}, {lengths});");
            }
        }
        return unknown;
    }
    let Some(len) = p.len.as_deref() else {
        return if is_char(&base) { format!("rec.c_string({v});") } else { unknown };
    };
    if let Some(inner) = len.strip_prefix("COMPSIZE(").and_then(|l| l.strip_suffix(')')) {
        let Some(rule) = sizes.get(inner) else { return unknown };
        let names: Vec<&str> = if inner.is_empty() { vec![] } else { inner.split(',').collect() };
        return match rule.as_str() {
            "c_string" => format!("rec.c_string({v});"),
            _ if inner.is_empty() && is_char(&base) => format!("rec.c_string({v});"),
            "string_with_length" => match int_param(c, names[1]) {
                Some(n) => format!("rec.string_with_length({v}, {n});"),
                None => unknown,
            },
            r if r.starts_with("array_pointer") => format!("rec.array_pointer({v});"),
            r => {
                let args: Option<Vec<String>> = names.iter().map(|n| int_param(c, n)).collect();
                match args {
                    Some(args) => {
                        format!("{{ let m = sizes::{r}(rec, &[{}]); rec.memory({v}, m, {elem}); }}", args.join(", "))
                    }
                    None => unknown,
                }
            }
        };
    }
    // A number, a parameter, or a product of them.
    let terms: Option<Vec<String>> = len
        .split('*')
        .map(|t| {
            let t = t.trim();
            if t.chars().all(|ch| ch.is_ascii_digit()) && !t.is_empty() {
                Some(format!("({t} as i64)"))
            } else {
                int_param(c, t)
            }
        })
        .collect();
    match terms {
        Some(t) => format!("rec.memory({v}, sizes::product(&[{}]), {elem});", t.join(", ")),
        None => unknown,
    }
}

fn record_scalar(rust: &str, v: &str) -> String {
    match rust {
        "f32" => format!("rec.e.f32({v});"),
        "f64" => format!("rec.e.f64({v});"),
        "i8" | "i16" | "i32" | "i64" | "isize" => format!("rec.e.int({v} as i64);"),
        _ => format!("rec.e.uint({v} as u64);"),
    }
}
