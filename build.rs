//! Generates libglray.so's exported API from the Khronos XML registry and gl-spec/.
//!
//! Inputs (all data, nothing pasted):
//! - the Khronos registry (`khronos_api`: gl.xml, glx.xml, egl.xml) for names and prototypes;
//! - gl-spec/exports.txt: which features and extensions of each API are exported;
//! - gl-spec/osmesa.txt: OSMesa's prototypes (OSMesa is not in a Khronos registry);
//! - gl-spec/types.txt: C type -> Rust FFI type;
//! - gl-spec/classes.txt: what glray does with each command (class, display-list rule, handler).
//!
//! Outputs in OUT_DIR, included by src/generated.rs:
//! - commands.rs: the sorted command table (names, library, class, list rule) and `cmd::NAME`
//!   indices;
//! - real.rs: `real::NAME(args)`, a typed call of the real implementation through dispatch;
//! - exports.rs: one `#[no_mangle] extern "C"` function per command, calling either
//!   `real::NAME` or `crate::handlers::NAME`, and the table of their addresses that the
//!   GetProcAddress handlers hand out.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn main() {
    let spec = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("gl-spec");
    for f in ["types.txt", "exports.txt", "classes.txt", "osmesa.txt", "glx-extras.txt", "sizes.txt"] {
        println!("cargo:rerun-if-changed={}", spec.join(f).display());
    }
    println!("cargo:rerun-if-changed=build.rs");

    let types = read_types(&spec.join("types.txt"));
    let mut commands: BTreeMap<String, Command> = BTreeMap::new();
    for line in data_lines(&spec.join("exports.txt")) {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 4 {
            fail(&format!("gl-spec/exports.txt: expected `api registry features extensions`: {line}"));
        }
        let lib = Lib::parse(f[0]);
        // `gl.xml@gles2` reads the features and extensions of API gles2 from gl.xml.
        let (file, api) = f[1].split_once('@').unwrap_or((f[1], f[0]));
        let found = match file {
            "gl.xml" => registry_commands(khronos_api::GL_XML, api, f[2], &f[3..], &types),
            "glx.xml" => registry_commands(khronos_api::GLX_XML, api, f[2], &f[3..], &types),
            "egl.xml" => registry_commands(khronos_api::EGL_XML, api, f[2], &f[3..], &types),
            other => prototype_file(&spec.join(other), &types),
        };
        for (name, (ret, params)) in found {
            commands.entry(name.clone()).or_insert(Command {
                name,
                lib,
                ret,
                params,
                class: "pass".into(),
                list: "-".into(),
                handler: false,
            });
        }
    }
    classify(&spec.join("classes.txt"), &mut commands);

    let sizes = read_sizes(&spec.join("sizes.txt"));

    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let cmds: Vec<&Command> = commands.values().collect();
    write(&out.join("commands.rs"), &gen_commands(&cmds));
    write(&out.join("real.rs"), &gen_real(&cmds));
    write(&out.join("exports.rs"), &gen_exports(&cmds, &types));
    write(&out.join("record.rs"), &gen_record(&cmds, &types, &sizes));
    write(&out.join("replay.rs"), &gen_replay(&cmds));
    write(&out.join("params.rs"), &gen_params(&cmds, &types));

    // The glvnd layout that every loader accepts (see docs/design.md): SONAME libGL.so.1, and
    // glvnd's libGLX and libOpenGL as dependencies so that dlsym(handle, name) on our handle
    // falls through to them for anything we do not define. `-l:` needs no -dev packages.
    println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libGL.so.1");
    println!("cargo:rustc-cdylib-link-arg=-Wl,--no-as-needed");
    println!("cargo:rustc-cdylib-link-arg=-l:libGLX.so.0");
    println!("cargo:rustc-cdylib-link-arg=-l:libOpenGL.so.0");
    println!("cargo:rustc-cdylib-link-arg=-Wl,--as-needed");
    // Our own calls to our own exports bind inside the library, never to a host's symbol of the
    // same name (apitrace's lesson: hosts with globals named like GL functions).
    println!("cargo:rustc-cdylib-link-arg=-Wl,-Bsymbolic-functions");
}

#[derive(Clone, Copy, PartialEq)]
enum Lib {
    Gl,
    Glx,
    Egl,
    OSMesa,
}

impl Lib {
    fn parse(s: &str) -> Lib {
        match s {
            "gl" => Lib::Gl,
            "glx" => Lib::Glx,
            "egl" => Lib::Egl,
            "osmesa" => Lib::OSMesa,
            _ => fail(&format!("gl-spec/exports.txt: unknown api `{s}` (gl, glx, egl, osmesa)")),
        }
    }
    fn rust(self) -> &'static str {
        match self {
            Lib::Gl => "Lib::Gl",
            Lib::Glx => "Lib::Glx",
            Lib::Egl => "Lib::Egl",
            Lib::OSMesa => "Lib::OSMesa",
        }
    }
    /// The dispatch function that finds the real implementation: GL commands follow the
    /// thread's current context (glvnd or OSMesa); the others have one home.
    fn dispatch(self) -> &'static str {
        match self {
            Lib::Gl => "gl",
            Lib::Glx | Lib::Egl => "glvnd",
            Lib::OSMesa => "osmesa",
        }
    }
}

struct Command {
    name: String,
    lib: Lib,
    ret: String,
    params: Vec<Param>,
    class: String,
    list: String,
    handler: bool,
}

/// One parameter: its name, Rust FFI type, C declaration (without the name) and the registry's
/// `len` (how many elements a pointer parameter points to), if any.
#[derive(Clone)]
struct Param {
    name: String,
    rust: String,
    c: String,
    len: Option<String>,
}

fn fail(msg: &str) -> ! {
    panic!("glray build: {msg}");
}

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap_or_else(|e| fail(&format!("writing {}: {e}", path.display())));
}

/// Lines of a gl-spec file without comments and blanks.
fn data_lines(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| fail(&format!("reading {}: {e}", path.display())));
    text.lines().map(|l| l.split('#').next().unwrap().trim().to_string()).filter(|l| !l.is_empty()).collect()
}

fn read_types(path: &Path) -> HashMap<String, String> {
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

/// A C declaration ("const GLfloat *v", "GLXContext ctx") as a Rust FFI type.
fn rust_type(c_decl: &str, types: &HashMap<String, String>, context: &str) -> String {
    if c_decl.contains('*') {
        // Every pointer is passed as a raw pointer: const-ness and pointee do not change the ABI.
        return "*mut c_void".into();
    }
    let base: Vec<&str> = c_decl.split_whitespace().filter(|w| *w != "const" && *w != "struct").collect();
    let base = base.join(" ");
    types
        .get(&base)
        .cloned()
        .unwrap_or_else(|| fail(&format!("gl-spec/types.txt has no entry for `{base}` ({context})")))
}

/// The C type text of a <proto> or <param> element: everything before its <name>.
fn decl_text(node: roxmltree::Node) -> (String, String) {
    let mut ty = String::new();
    let mut name = String::new();
    for child in node.children() {
        if child.has_tag_name("name") {
            name = child.text().unwrap_or("").to_string();
            break;
        }
        if let Some(t) = child.text() {
            ty.push_str(t);
            ty.push(' ');
        }
    }
    (ty.split_whitespace().collect::<Vec<_>>().join(" "), name)
}

fn version_in(range: &str, number: &str) -> bool {
    let parse = |s: &str| -> (u32, u32) {
        let mut it = s.split('.').map(|x| x.parse::<u32>().unwrap_or(0));
        (it.next().unwrap_or(0), it.next().unwrap_or(0))
    };
    let (lo, hi) = range.split_once('-').unwrap_or((range, range));
    let v = parse(number);
    parse(lo) <= v && v <= parse(hi)
}

type Proto = (String, Vec<Param>);

fn registry_commands(
    xml: &[u8],
    api: &str,
    range: &str,
    extensions: &[&str],
    types: &HashMap<String, String>,
) -> BTreeMap<String, Proto> {
    let text = std::str::from_utf8(xml).expect("registry is UTF-8");
    let doc = roxmltree::Document::parse(text).unwrap_or_else(|e| fail(&format!("{api}.xml: {e}")));
    let root = doc.root_element();

    let mut protos: HashMap<&str, roxmltree::Node> = HashMap::new();
    for cmds in root.children().filter(|n| n.has_tag_name("commands")) {
        for c in cmds.children().filter(|n| n.has_tag_name("command")) {
            if let Some(p) = c.children().find(|n| n.has_tag_name("proto")) {
                let (_, name) = decl_text(p);
                // A leaked &str keeps the map simple; the build script is short-lived.
                protos.insert(Box::leak(name.into_boxed_str()), c);
            }
        }
    }

    let mut wanted: Vec<String> = Vec::new();
    let block_applies = |req: roxmltree::Node| req.attribute("api").is_none_or(|a| a == api);
    for f in root.children().filter(|n| n.has_tag_name("feature")) {
        if f.attribute("api") != Some(api) || !version_in(range, f.attribute("number").unwrap_or("")) {
            continue;
        }
        for req in f.children().filter(|n| n.has_tag_name("require") && block_applies(*n)) {
            for c in req.children().filter(|n| n.has_tag_name("command")) {
                wanted.push(c.attribute("name").unwrap().to_string());
            }
        }
    }
    let all = extensions == ["all"];
    let listed: HashSet<&str> = extensions.iter().copied().collect();
    let mut seen_ext = HashSet::new();
    for exts in root.children().filter(|n| n.has_tag_name("extensions")) {
        for x in exts.children().filter(|n| n.has_tag_name("extension")) {
            let name = x.attribute("name").unwrap_or("");
            let supported = x.attribute("supported").unwrap_or("").split('|').any(|s| s == api);
            if !(supported && (all || listed.contains(name))) {
                continue;
            }
            seen_ext.insert(name.to_string());
            for req in x.children().filter(|n| n.has_tag_name("require") && block_applies(*n)) {
                for c in req.children().filter(|n| n.has_tag_name("command")) {
                    wanted.push(c.attribute("name").unwrap().to_string());
                }
            }
        }
    }
    if !all {
        for x in &listed {
            if *x != "-" && !seen_ext.contains(*x) {
                fail(&format!("gl-spec/exports.txt: {api}.xml has no extension {x} for {api}"));
            }
        }
    }

    let mut out = BTreeMap::new();
    for name in wanted {
        let node =
            protos.get(name.as_str()).unwrap_or_else(|| fail(&format!("{api}.xml requires unknown command {name}")));
        let proto = node.children().find(|n| n.has_tag_name("proto")).unwrap();
        let (ret_c, _) = decl_text(proto);
        let ret = rust_type(&ret_c, types, &name);
        let mut params = Vec::new();
        for p in node.children().filter(|n| n.has_tag_name("param")) {
            let (ty_c, pname) = decl_text(p);
            let rust = rust_type(&ty_c, types, &name);
            params.push(Param { name: pname, rust, c: ty_c, len: p.attribute("len").map(str::to_string) });
        }
        out.insert(name, (ret, params));
    }
    out
}

/// A file of C prototypes, one per line: `RET NAME(TYPE NAME, ...);`
fn prototype_file(path: &Path, types: &HashMap<String, String>) -> BTreeMap<String, Proto> {
    let mut out = BTreeMap::new();
    for line in data_lines(path) {
        let bad_line = |line: &str| -> String { format!("{}: not a prototype: {line}", path.display()) };
        macro_rules! bad {
            () => {
                || fail(&bad_line(&line))
            };
        }
        let (head, rest) = line.split_once('(').unwrap_or_else(bad!());
        let args = rest.trim_end_matches(';').trim_end().strip_suffix(')').unwrap_or_else(bad!());
        let head = head.trim();
        let split = head.rfind(|c: char| c.is_whitespace() || c == '*').unwrap_or_else(bad!());
        let (ret_c, name) = (&head[..=split], head[split + 1..].trim());
        let ret = rust_type(ret_c.trim(), types, name);
        let mut params = Vec::new();
        if args.trim() != "void" {
            for a in args.split(',') {
                let a = a.trim();
                let split = a.rfind(|c: char| c.is_whitespace() || c == '*').unwrap_or_else(bad!());
                let c = a[..=split].trim().to_string();
                params.push(Param { name: a[split + 1..].to_string(), rust: rust_type(&c, types, name), c, len: None });
            }
        }
        out.insert(name.to_string(), (ret, params));
    }
    out
}

/// Expands `{a,b}` alternatives; `*` is kept for glob matching.
fn expand(pattern: &str) -> Vec<String> {
    let Some(open) = pattern.find('{') else { return vec![pattern.to_string()] };
    let close = open + pattern[open..].find('}').unwrap_or_else(|| fail(&format!("unclosed {{ in {pattern}")));
    let (pre, alts, post) = (&pattern[..open], &pattern[open + 1..close], &pattern[close + 1..]);
    alts.split(',').flat_map(|alt| expand(&format!("{pre}{alt}{post}"))).collect()
}

fn glob(pattern: &[u8], name: &[u8]) -> bool {
    match (pattern.first(), name.first()) {
        (None, None) => true,
        (Some(b'*'), _) => glob(&pattern[1..], name) || (!name.is_empty() && glob(pattern, &name[1..])),
        (Some(p), Some(n)) if p == n => glob(&pattern[1..], &name[1..]),
        _ => false,
    }
}

fn classify(path: &Path, commands: &mut BTreeMap<String, Command>) {
    const CLASSES: &[&str] =
        &["pass", "state", "vertex", "geometry", "dlist", "client", "query", "context", "frame", "lookup"];
    let mut decided: HashSet<String> = HashSet::new();
    for line in data_lines(path) {
        let words: Vec<&str> = line.split_whitespace().collect();
        // The pattern may contain spaces only inside braces; everything before the class word is it.
        let class_at = words
            .iter()
            .position(|w| CLASSES.contains(w))
            .unwrap_or_else(|| fail(&format!("gl-spec/classes.txt: no class ({}) in: {line}", CLASSES.join(", "))));
        let pattern = words[..class_at].join("");
        let class = words[class_at];
        let list = words.get(class_at + 1).copied().unwrap_or("-");
        if !["compile", "exec", "-"].contains(&list) {
            fail(&format!("gl-spec/classes.txt: list rule must be compile, exec or -: {line}"));
        }
        let handler = match words.get(class_at + 2) {
            None => false,
            Some(&"handler") => true,
            Some(w) => fail(&format!("gl-spec/classes.txt: unexpected `{w}`: {line}")),
        };
        let mut matched = false;
        for alt in expand(&pattern) {
            for (name, cmd) in commands.iter_mut() {
                if glob(alt.as_bytes(), name.as_bytes()) {
                    matched = true;
                    if decided.insert(name.clone()) {
                        cmd.class = class.into();
                        cmd.list = list.into();
                        cmd.handler = handler;
                    }
                }
            }
        }
        if !matched {
            fail(&format!("gl-spec/classes.txt: `{pattern}` matches no exported command"));
        }
    }
}

/// Parameter names that are Rust keywords get a trailing underscore.
fn ident(name: &str) -> String {
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

fn signature(c: &Command) -> (String, String, String) {
    let params: Vec<String> = c.params.iter().map(|p| format!("{}: {}", ident(&p.name), p.rust)).collect();
    let args: Vec<String> = c.params.iter().map(|p| ident(&p.name)).collect();
    let ret = if c.ret == "()" { String::new() } else { format!(" -> {}", c.ret) };
    (params.join(", "), args.join(", "), ret)
}

fn gen_commands(cmds: &[&Command]) -> String {
    let mut s = String::new();
    writeln!(s, "/// Number of exported commands.\npub const COUNT: usize = {};", cmds.len()).unwrap();
    writeln!(s, "/// Every exported command, sorted by name (binary-searchable), with its rules.").unwrap();
    writeln!(s, "pub static COMMANDS: [CommandInfo; COUNT] = [").unwrap();
    for c in cmds {
        writeln!(
            s,
            "    CommandInfo {{ name: c\"{}\", lib: {}, class: Class::{}, list: ListRule::{}, handled: {} }},",
            c.name,
            c.lib.rust(),
            capitalize(&c.class),
            match c.list.as_str() {
                "compile" => "Compile",
                "exec" => "Exec",
                _ => "NotGl",
            },
            c.handler
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

fn capitalize(s: &str) -> String {
    let mut c = s.chars();
    c.next().map(|f| f.to_uppercase().collect::<String>() + c.as_str()).unwrap_or_default()
}

fn gen_real(cmds: &[&Command]) -> String {
    // Two functions per command: the inlined fast path, which only calls when the function
    // pointer is already known (so the compiler can make it a tail call with no frame), and a
    // cold one that resolves it (and reads the thread's context kind when a process mixes them).
    let mut s = String::new();
    let mut slow = String::new();
    for c in cmds {
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

/// Whether GL refuses command `c` between glBegin and glEnd (OpenGL 2.1, section 2.6.3: only
/// vertex attributes, generic ones included, glMaterial, glEvalCoord and glEvalPoint,
/// glArrayElement, glCallList(s) and glEdgeFlag are allowed there), among the GL commands
/// whose export calls the real one directly (handlers, glGetError among them, decide for
/// themselves).
fn refused_inside_begin(c: &Command) -> bool {
    // Generic attributes too (glVertexAttrib4f, glVertexAttribI4i...), not their pointers.
    let generic = c
        .name
        .strip_prefix("glVertexAttrib")
        .is_some_and(|rest| rest.trim_start_matches(['I', 'L', 'P']).starts_with(|ch: char| ch.is_ascii_digit()));
    let allowed = generic || ["glMaterial", "glEvalCoord", "glEvalPoint"].iter().any(|p| c.name.starts_with(p));
    ["state", "dlist", "client", "query", "pass"].contains(&c.class.as_str()) && c.list != "-" && !c.handler && !allowed
}

fn gen_exports(cmds: &[&Command], types: &HashMap<String, String>) -> String {
    let mut s = String::new();
    let mut recorded = String::new();
    let mut typed_names = Vec::new();
    for c in cmds {
        let (params, args, ret) = signature(c);
        let call = if c.handler {
            format!("crate::ffi_guard::guard(c\"{0}\", || crate::handlers::{0}({args}))", c.name)
        } else {
            format!("crate::real::{}({args})", c.name)
        };
        let sep = if args.is_empty() { "" } else { ", " };
        // The export is the hot path: a flag test, then the real call (a tail call). Recording
        // lives in a cold function of its own, so that its frame and spills stay out of it.
        writeln!(
            s,
            "#[no_mangle]\npub unsafe extern \"C\" fn {name}({params}){ret} {{\n    \
             if crate::record::active() {{\n        return recorded::{name}({args});\n    }}\n    \
             {call}\n}}",
            name = c.name,
        )
        .unwrap();
        // Only the outermost call of a thread is recorded (a real implementation calling its
        // own exported functions reaches glray's exports again). Commands that touch client
        // state may need to look at memory before the real call (a buffer about to be unmapped).
        // Geometry the ray tracer takes is not rasterized by the real GL (that is the speed-up):
        // before_real says so, and the real call is skipped.
        let in_begin = (c.class == "vertex" && c.name.starts_with("glVertex")) || refused_inside_begin(c);
        let before = if ["geometry", "client", "context", "frame"].contains(&c.class.as_str()) {
            let b: Vec<String> = c.params.iter().map(|p| bits(&p.rust, &ident(&p.name))).collect();
            format!(
                "let skip__ = outer__ && crate::record::before_real(crate::commands::cmd::{}, &[{}]);\n    ",
                c.name,
                b.join(", ")
            )
        } else if in_begin {
            // Inside a glBegin the real GL did not get: its vertices, and the commands GL
            // refuses between glBegin and glEnd (INVALID_OPERATION, nothing done, 0 returned),
            // which the real GL, outside any glBegin, would carry out (glGenLists would hand
            // out a name). Capture raises the error glGetError reports.
            "let skip__ = outer__ && crate::raytrace::in_skipped_begin();\n    ".to_string()
        } else {
            String::new()
        };
        let call = if before.is_empty() {
            call.clone()
        } else if c.class == "geometry" || in_begin {
            format!("if skip__ {{ Default::default() }} else {{ {call} }}")
        } else {
            format!("{{ let _ = skip__; {call} }}")
        };
        // Attribute commands go to capture typed when they can (`record::given`), else recorded.
        let given = given_call(c, types);
        if given.is_some() {
            typed_names.push(c.name.as_str());
        }
        let typed = given.map_or(String::new(), |g| format!("!{g} && "));
        writeln!(
            recorded,
            "#[cold]\n#[inline(never)]\n#[allow(clippy::unnecessary_cast)]\npub unsafe fn {name}({params}){ret} {{\n    \
             let outer__ = crate::record::enter();\n    \
             {before}\
             let ret__ = {call};\n    \
             if outer__ {{\n        \
             if {typed}crate::record::wants(crate::commands::cmd::{name}) {{\n            \
             crate::record::with(|rec__| crate::record::generated::{name}(rec__, {args}{sep}ret__));\n        \
             }}\n        \
             crate::record::leave();\n    \
             }}\n    \
             ret__\n}}",
            name = c.name,
        )
        .unwrap();
    }
    writeln!(s, "/// The commands whose exports hand them to capture typed (`record::given`).").unwrap();
    let typed: Vec<String> = typed_names.iter().map(|n| format!("crate::commands::cmd::{n}")).collect();
    writeln!(s, "pub static TYPED: [usize; {}] = [{}];", typed.len(), typed.join(", ")).unwrap();
    writeln!(s, "/// The exports' slow path, taken while recording.\nmod recorded {{\n    use std::ffi::{{c_ulong, c_void}};\n{recorded}}}").unwrap();
    writeln!(s, "/// The address of each export, in COMMANDS order: what GetProcAddress hands out.").unwrap();
    writeln!(s, "pub static EXPORTS: [FnAddr; COUNT] = [").unwrap();
    for c in cmds {
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
    if c.class != "vertex" || !GIVEN_PREFIXES.iter().any(|p| c.name.starts_with(p)) {
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
                "crate::record::given::given_ptr::<{ty}>(crate::commands::cmd::{name}, {target}, {} as *const {ty})",
                ident(&p.name)
            ))
        }
        _ if parts.iter().all(|p| !p.rust.contains('*')) => {
            let raw: Vec<String> = parts.iter().map(|p| format!("{} as f64", ident(&p.name))).collect();
            Some(format!("crate::record::given::given(crate::commands::cmd::{name}, {target}, &[{}])", raw.join(", ")))
        }
        _ => None,
    }
}

/// gl-spec/sizes.txt: COMPSIZE argument list -> rule name.
fn read_sizes(path: &Path) -> HashMap<String, String> {
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

/// The C base type a pointer parameter points to ("const GLfloat *" -> "GLfloat").
fn pointee(c_decl: &str) -> String {
    c_decl
        .replace('*', " ")
        .split_whitespace()
        .filter(|w| *w != "const" && *w != "struct")
        .collect::<Vec<_>>()
        .join(" ")
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
    let unknown = format!("rec.unknown_pointer(crate::commands::cmd::{}, {v});", c.name);
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

fn bits(rust: &str, v: &str) -> String {
    match rust {
        "f32" | "f64" => format!("{v}.to_bits() as u64"),
        "()" => "0u64".into(),
        r if r.contains('*') => format!("{v} as usize as u64"),
        "i8" | "i16" | "i32" | "i64" | "isize" => format!("{v} as i64 as u64"),
        _ => format!("{v} as u64"),
    }
}

/// record.rs: `generated::NAME(rec, args..., ret)` writes one call to the trace. Commands whose
/// class touches client arrays, contexts or frames also call the recorder's hooks before and
/// after, with their arguments as bits.
fn gen_record(cmds: &[&Command], types: &HashMap<String, String>, sizes: &HashMap<String, String>) -> String {
    let mut s = String::new();
    for c in cmds {
        let mut params: Vec<String> = c.params.iter().map(|p| format!("{}: {}", ident(&p.name), p.rust)).collect();
        params.push(format!("ret__: {}", c.ret));
        let hooked = ["geometry", "client", "context", "frame"].contains(&c.class.as_str());
        writeln!(s, "#[allow(unused_variables, unused_parens, clippy::unnecessary_cast)]").unwrap();
        writeln!(s, "pub unsafe fn {}(rec: &mut Recorder, {}) {{", c.name, params.join(", ")).unwrap();
        if hooked {
            let b: Vec<String> = c.params.iter().map(|p| bits(&p.rust, &ident(&p.name))).collect();
            writeln!(s, "    let bits__: [u64; {}] = [{}];", b.len(), b.join(", ")).unwrap();
            writeln!(s, "    rec.before(crate::commands::cmd::{}, &bits__);", c.name).unwrap();
        }
        writeln!(s, "    rec.begin(crate::commands::cmd::{}, {});", c.name, c.params.len()).unwrap();
        for p in &c.params {
            let code = if p.rust.contains('*') {
                record_pointer(c, p, types, sizes)
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
            writeln!(s, "    rec.after(crate::commands::cmd::{}, &bits__, {});", c.name, bits(&c.ret, "ret__"))
                .unwrap();
        }
        writeln!(s, "}}").unwrap();
    }
    s
}

/// replay.rs: for every GL command, a function that turns recorded values into arguments and
/// calls the replay target's function; `REPLAY[cmd]` finds it.
fn gen_replay(cmds: &[&Command]) -> String {
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
    for c in cmds {
        if c.lib == Lib::Gl {
            writeln!(s, "    Some({} as ReplayFn),", c.name).unwrap();
        } else {
            writeln!(s, "    None,").unwrap();
        }
    }
    writeln!(s, "];").unwrap();
    s
}

/// One character per parameter, then `|` and one for the return type: how to turn another
/// tracer's values (apitrace writes pointer arguments as arrays of values) into glray's.
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

fn gen_params(cmds: &[&Command], types: &HashMap<String, String>) -> String {
    let mut s = String::from("/// Parameter and return type codes of every command (see build.rs, param_code).\npub static PARAMS: [&str; COUNT] = [\n");
    for c in cmds {
        let args: String = c.params.iter().map(|p| param_code(&p.rust, &p.c, types)).collect();
        let ret = if c.ret.contains('*') { 'p' } else { param_code(&c.ret, "", types) };
        writeln!(s, "    \"{args}|{ret}\",").unwrap();
    }
    s.push_str("];\n");
    s
}
