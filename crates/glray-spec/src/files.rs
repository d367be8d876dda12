//! Reading gl-spec/'s own files: C types, what is exported, what glray does with each command
//! (classes.txt), how much memory a pointer argument reads (sizes.txt) and the commands capture
//! follows (capture.txt).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

use crate::fail;
use crate::model::{Attr, AttrForm, CaptureOp, Class, Command, Ends, Flags, ListRule, OpKind};

/// Every gl-spec/ file the model reads.
pub const FILES: &[&str] =
    &["types.txt", "exports.txt", "classes.txt", "osmesa.txt", "glx-extras.txt", "sizes.txt", "capture.txt"];

/// Lines of a gl-spec file without comments and blanks.
pub fn data_lines(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| fail(&format!("reading {}: {e}", path.display())));
    text.lines().map(|l| l.split('#').next().unwrap().trim().to_string()).filter(|l| !l.is_empty()).collect()
}

/// gl-spec/types.txt: C type -> Rust FFI type.
pub fn read_types(path: &Path) -> HashMap<String, String> {
    let mut map = HashMap::new();
    for line in data_lines(path) {
        let mut words: Vec<&str> = line.split_whitespace().collect();
        let rust = words.pop().unwrap();
        let rust = match rust {
            "ptr" => "*mut c_void",
            "ulong" => "c_ulong",
            other => other,
        };
        map.insert(words.join(" "), rust.to_string());
    }
    map
}

/// gl-spec/sizes.txt: COMPSIZE argument list -> rule name.
pub fn read_sizes(path: &Path) -> HashMap<String, String> {
    let mut map = HashMap::new();
    for line in data_lines(path) {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.len() != 2 {
            fail(&format!("gl-spec/sizes.txt: expected `ARGS RULE`: {line}"));
        }
        let args = if words[0] == "-" { String::new() } else { words[0].to_string() };
        map.insert(args, words[1].to_string());
    }
    map
}

/// Expands `{a,b}` alternatives; `*` is kept for glob matching.
pub fn expand(pattern: &str) -> Vec<String> {
    let Some(open) = pattern.find('{') else { return vec![pattern.to_string()] };
    let close = open + pattern[open..].find('}').unwrap_or_else(|| fail(&format!("unclosed {{ in {pattern}")));
    let (pre, alts, post) = (&pattern[..open], &pattern[open + 1..close], &pattern[close + 1..]);
    alts.split(',').flat_map(|alt| expand(&format!("{pre}{alt}{post}"))).collect()
}

pub fn glob(pattern: &[u8], name: &[u8]) -> bool {
    match (pattern.first(), name.first()) {
        (None, None) => true,
        (Some(b'*'), _) => glob(&pattern[1..], name) || (!name.is_empty() && glob(pattern, &name[1..])),
        (Some(p), Some(n)) if p == n => glob(&pattern[1..], &name[1..]),
        _ => false,
    }
}

/// The exported commands a pattern matches, in name order.
fn matching<'a>(pattern: &str, names: impl Iterator<Item = &'a String> + Clone) -> Vec<&'a String> {
    let mut out: Vec<&String> = Vec::new();
    for alt in expand(pattern) {
        out.extend(names.clone().filter(|n| glob(alt.as_bytes(), n.as_bytes())));
    }
    out.sort();
    out.dedup();
    out
}

/// A flag word of classes.txt.
fn flag(flags: &mut Flags, word: &str, line: &str) {
    let number =
        |v: &str| v.parse::<usize>().unwrap_or_else(|_| fail(&format!("gl-spec/classes.txt: `{word}`: {line}")));
    match word.split_once('=') {
        None if word == "handler" => flags.handler = true,
        None if word == "inside" => flags.inside = true,
        None if word == "taken" => flags.taken = true,
        None if word == "copies-texture" => flags.copies_texture = true,
        Some(("ends", v)) => {
            flags.ends = Some(Ends::parse(v).unwrap_or_else(|| {
                fail(&format!("gl-spec/classes.txt: ends= takes swap, finish, flush, readpixels or raster: {line}"))
            }))
        }
        Some(("shares", v)) => flags.shares = Some(number(v)),
        Some(("binds", v)) => flags.binds = Some(number(v)),
        _ => fail(&format!(
            "gl-spec/classes.txt: unexpected `{word}` (handler, inside, taken, copies-texture, ends=, shares=, binds=): {line}"
        )),
    }
}

/// gl-spec/classes.txt: each command's class, list rule and flags. Lines are matched top to
/// bottom, the first match wins; a command no line matches is `pass`; a pattern that matches no
/// exported command stops the build.
pub fn classify(path: &Path, commands: &mut BTreeMap<String, Command>) {
    let mut decided: HashSet<String> = HashSet::new();
    for line in data_lines(path) {
        let words: Vec<&str> = line.split_whitespace().collect();
        // The pattern may contain spaces only inside braces; everything before the class word is it.
        let class_at = words.iter().position(|w| Class::parse(w).is_some()).unwrap_or_else(|| {
            let names: Vec<&str> = Class::ALL.iter().map(|(n, _)| *n).collect();
            fail(&format!("gl-spec/classes.txt: no class ({}) in: {line}", names.join(", ")))
        });
        let pattern = words[..class_at].join("");
        let class = Class::parse(words[class_at]).unwrap();
        let list = words.get(class_at + 1).copied().unwrap_or("-");
        let list = ListRule::parse(list)
            .unwrap_or_else(|| fail(&format!("gl-spec/classes.txt: list rule must be compile, exec or -: {line}")));
        let mut flags = Flags::default();
        for w in words.iter().skip(class_at + 2) {
            flag(&mut flags, w, &line);
        }
        let names = matching(&pattern, commands.keys());
        if names.is_empty() {
            fail(&format!("gl-spec/classes.txt: `{pattern}` matches no exported command"));
        }
        for name in names.into_iter().cloned().collect::<Vec<_>>() {
            if decided.insert(name.clone()) {
                let cmd = commands.get_mut(&name).unwrap();
                (cmd.class, cmd.list, cmd.flags) = (class, list, flags);
            }
        }
    }
}

/// The GL type name (for capture's `ty`) of a C type, or None for one capture does not read.
fn gl_type(c: &str) -> Option<&'static str> {
    let base: Vec<&str> =
        c.split(|ch: char| ch.is_whitespace() || ch == '*').filter(|w| !w.is_empty() && *w != "const").collect();
    Some(match base.join(" ").as_str() {
        "GLbyte" => "GL_BYTE",
        "GLubyte" | "GLboolean" => "GL_UNSIGNED_BYTE",
        "GLshort" => "GL_SHORT",
        "GLushort" => "GL_UNSIGNED_SHORT",
        "GLint" | "GLsizei" => "GL_INT",
        "GLuint" | "GLenum" | "GLbitfield" => "GL_UNSIGNED_INT",
        "GLfloat" | "GLclampf" => "GL_FLOAT",
        "GLdouble" | "GLclampd" => "GL_DOUBLE",
        _ => return None,
    })
}

/// The type of the values a command carries: its first pointer parameter's pointee (glLightfv:
/// floats), else its last scalar parameter's (glLighti: an int); GL_FLOAT when neither says.
fn carried_type(c: &Command) -> &'static str {
    let pointer = c.params.iter().find(|p| p.c.contains('*')).and_then(|p| gl_type(&p.c));
    pointer
        .or_else(|| c.params.iter().rev().find(|p| !p.c.contains('*')).and_then(|p| gl_type(&p.c)))
        .unwrap_or("GL_FLOAT")
}

/// An attribute command's form, from its prototype: a glMultiTexCoord's leading `target`
/// aside, either one pointer to `len` components (the `v` form) or the components themselves.
fn attr_form(attr: Attr, c: &Command) -> AttrForm {
    let params = match c.params.split_first() {
        Some((t, rest)) if t.name == "target" => rest,
        _ => &c.params[..],
    };
    let form = match params {
        [p] if p.c.contains('*') => p
            .len
            .as_deref()
            .and_then(|l| l.parse::<usize>().ok())
            .zip(gl_type(&p.c))
            .map(|(n, ty)| AttrForm { attr, n, ty, vector: true }),
        [first, ..] if params.iter().all(|p| !p.c.contains('*') && p.c == first.c) => {
            gl_type(&first.c).map(|ty| AttrForm { attr, n: params.len(), ty, vector: false })
        }
        _ => None,
    };
    form.unwrap_or_else(|| fail(&format!("gl-spec/capture.txt: {} is not an attribute command of one type", c.name)))
}

/// gl-spec/capture.txt: `OP PATTERN` lines name capture's ops and their commands; `attr ATTR
/// PATTERN` lines its per-vertex attribute commands, whose forms come from their prototypes.
/// Every command named must be exported and have a list rule in classes.txt (capture compiles
/// a command into a display list by it).
pub fn read_ops(path: &Path, commands: &BTreeMap<String, Command>) -> Vec<CaptureOp> {
    let mut out: Vec<CaptureOp> = Vec::new();
    let mut seen = HashSet::new();
    let mut concern = None;
    for line in data_lines(path) {
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            // `[lighting]` -> `Lighting`.
            let mut c = name.chars();
            concern = Some(c.next().map(|f| f.to_ascii_uppercase().to_string() + c.as_str()).unwrap_or_default());
            continue;
        }
        let Some(concern) = concern.clone() else {
            fail(&format!("gl-spec/capture.txt: a line before any [concern]: {line}"))
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        let (attr, op, pattern) = match words.as_slice() {
            ["attr", a, rest @ ..] if !rest.is_empty() => (
                Some(
                    Attr::parse(a)
                        .unwrap_or_else(|| fail(&format!("gl-spec/capture.txt: unknown attribute `{a}`: {line}"))),
                ),
                None,
                rest.join(""),
            ),
            [op, rest @ ..] if !rest.is_empty() && op.chars().next().is_some_and(|c| c.is_ascii_uppercase()) => {
                (None, Some(op.to_string()), rest.join(""))
            }
            _ => fail(&format!("gl-spec/capture.txt: expected `Op PATTERN` or `attr ATTR PATTERN`: {line}")),
        };
        let names = matching(&pattern, commands.keys());
        if names.is_empty() {
            fail(&format!("gl-spec/capture.txt: `{pattern}` matches no exported command"));
        }
        for name in names {
            let c = &commands[name];
            if c.list == ListRule::NotGl {
                fail(&format!("gl-spec/capture.txt: {name} has no list rule (compile or exec) in classes.txt"));
            }
            if !seen.insert(name.clone()) {
                fail(&format!("gl-spec/capture.txt: {name} is named twice"));
            }
            let kind = match (&attr, &op) {
                (Some(a), _) => OpKind::Attr(attr_form(*a, c)),
                (None, Some(op)) => OpKind::Op(op.clone()),
                _ => unreachable!(),
            };
            let ty = match &kind {
                OpKind::Attr(f) => f.ty,
                OpKind::Op(_) => carried_type(c),
            };
            out.push(CaptureOp { command: name.clone(), kind, ty, concern: concern.clone() });
        }
    }
    out
}
