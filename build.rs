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
    for f in ["types.txt", "exports.txt", "classes.txt", "osmesa.txt", "glx-extras.txt"] {
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

    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let cmds: Vec<&Command> = commands.values().collect();
    write(&out.join("commands.rs"), &gen_commands(&cmds));
    write(&out.join("real.rs"), &gen_real(&cmds));
    write(&out.join("exports.rs"), &gen_exports(&cmds));

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
    params: Vec<(String, String)>,
    class: String,
    list: String,
    handler: bool,
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

type Proto = (String, Vec<(String, String)>);

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
    let block_applies = |req: roxmltree::Node| req.attribute("api").map_or(true, |a| a == api);
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
            params.push((pname, rust_type(&ty_c, types, &name)));
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
                params.push((a[split + 1..].to_string(), rust_type(&a[..=split], types, name)));
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
    let params: Vec<String> = c.params.iter().map(|(n, t)| format!("{}: {t}", ident(n))).collect();
    let args: Vec<String> = c.params.iter().map(|(n, _)| ident(n)).collect();
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
    let mut s = String::new();
    for c in cmds {
        let (params, args, ret) = signature(c);
        let types: Vec<&str> = c.params.iter().map(|(_, t)| t.as_str()).collect();
        writeln!(
            s,
            "#[inline(always)]\npub unsafe fn {name}({params}){ret} {{\n    \
             let addr__ = dispatch::{disp}(cmd::{name});\n    \
             if addr__.is_null() {{ return core::mem::zeroed(); }}\n    \
             let real__: unsafe extern \"C\" fn({types}){ret} = core::mem::transmute(addr__);\n    \
             real__({args})\n}}",
            name = c.name,
            disp = c.lib.dispatch(),
            types = types.join(", "),
        )
        .unwrap();
    }
    s
}

fn gen_exports(cmds: &[&Command]) -> String {
    let mut s = String::new();
    for c in cmds {
        let (params, args, ret) = signature(c);
        let body = if c.handler {
            format!("crate::ffi_guard::guard(c\"{0}\", || crate::handlers::{0}({args}))", c.name)
        } else {
            format!("crate::real::{}({args})", c.name)
        };
        writeln!(s, "#[no_mangle]\npub unsafe extern \"C\" fn {}({params}){ret} {{\n    {body}\n}}", c.name).unwrap();
    }
    writeln!(s, "/// The address of each export, in COMMANDS order: what GetProcAddress hands out.").unwrap();
    writeln!(s, "pub static EXPORTS: [FnAddr; COUNT] = [").unwrap();
    for c in cmds {
        writeln!(s, "    FnAddr({} as *const c_void),", c.name).unwrap();
    }
    writeln!(s, "];").unwrap();
    s
}
