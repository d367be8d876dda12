//! Reading the Khronos XML registry (the commands of a range of features and of extensions, and
//! enum values) and files of C prototypes (gl-spec/osmesa.txt, glx-extras.txt).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

use crate::fail;
use crate::files::data_lines;
use crate::model::{EnumValue, Param};

/// A command's Rust return type and parameters.
pub type Proto = (String, Vec<Param>);

/// A C declaration ("const GLfloat *v", "GLXContext ctx") as a Rust FFI type.
pub fn rust_type(c_decl: &str, types: &HashMap<String, String>, context: &str) -> String {
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

fn parse(xml: &[u8], what: &str) -> roxmltree::Document<'static> {
    // The registry texts are 'static (khronos_api's include_bytes).
    let text: &'static str =
        Box::leak(std::str::from_utf8(xml).expect("registry is UTF-8").to_string().into_boxed_str());
    roxmltree::Document::parse(text).unwrap_or_else(|e| fail(&format!("{what}: {e}")))
}

/// The commands of `api`'s features in version `range` and of its `extensions` ("all": every
/// extension the registry marks as supported by `api`).
pub fn commands(
    xml: &[u8],
    api: &str,
    range: &str,
    extensions: &[&str],
    types: &HashMap<String, String>,
) -> BTreeMap<String, Proto> {
    let doc = parse(xml, &format!("{api}.xml"));
    let root = doc.root_element();

    let mut protos: HashMap<String, roxmltree::Node> = HashMap::new();
    for cmds in root.children().filter(|n| n.has_tag_name("commands")) {
        for c in cmds.children().filter(|n| n.has_tag_name("command")) {
            if let Some(p) = c.children().find(|n| n.has_tag_name("proto")) {
                let (_, name) = decl_text(p);
                protos.insert(name, c);
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

/// The enum values a registry defines for `api` (the first value of a name wins, unless a later
/// one is the one for `api`: gl.xml gives GL_ACTIVE_PROGRAM_EXT one value for GL, another for
/// GLES), each as the Rust type `rust` unless its value needs a wider one. Values that are not
/// numbers (EGL's casts of pointers) are left out.
pub fn enums(xml: &[u8], api: &str, rust: &'static str) -> Vec<EnumValue> {
    let doc = parse(xml, &format!("{api}.xml"));
    let mut out: Vec<EnumValue> = Vec::new();
    let mut at: HashMap<String, usize> = HashMap::new();
    for e in doc.descendants().filter(|n| n.has_tag_name("enum")) {
        let (Some(name), Some(value)) = (e.attribute("name"), e.attribute("value")) else { continue };
        // EGL writes its negative values as casts: EGL_CAST(EGLint,-1). Casts to handles
        // (EGL_NO_CONTEXT) are pointers, not numbers.
        let value = match value.strip_prefix("EGL_CAST(EGLint,").and_then(|v| v.strip_suffix(')')) {
            Some(v) => v,
            None => value,
        };
        let number = if let Some(hex) = value.strip_prefix("0x") {
            u64::from_str_radix(hex, 16).ok().map(|v| v as i128)
        } else {
            value.parse::<i128>().ok()
        };
        let Some(number) = number else { continue };
        let ty = if e.attribute("type") == Some("ull") || number > u32::MAX as i128 {
            "u64"
        } else if number < 0 {
            "i32"
        } else if rust == "i32" && number > i32::MAX as i128 {
            "u32"
        } else {
            rust
        };
        let value = EnumValue { name: name.to_string(), rust: ty, value: value.to_string() };
        match at.get(name) {
            Some(&i) if e.attribute("api") == Some(api) => out[i] = value,
            Some(_) => {}
            None => {
                at.insert(name.to_string(), out.len());
                out.push(value);
            }
        }
    }
    out
}

/// A file of C prototypes, one per line: `RET NAME(TYPE NAME, ...);` (lines `#define NAME VALUE`
/// are enum values: `prototype_file_enums`).
pub fn prototype_file(path: &Path, types: &HashMap<String, String>) -> BTreeMap<String, Proto> {
    let mut out = BTreeMap::new();
    for line in data_lines(path).into_iter().filter(|l| !l.starts_with("define ")) {
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

/// The `define NAME VALUE` lines of a prototype file (OSMesa's formats and parameters).
pub fn prototype_file_enums(path: &Path) -> Vec<EnumValue> {
    data_lines(path)
        .iter()
        .filter_map(|l| l.strip_prefix("define "))
        .map(|d| {
            let words: Vec<&str> = d.split_whitespace().collect();
            if words.len() != 2 {
                fail(&format!("{}: expected `define NAME VALUE`: {d}", path.display()));
            }
            EnumValue { name: words[0].to_string(), rust: "u32", value: words[1].to_string() }
        })
        .collect()
}
