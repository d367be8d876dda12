//! Reading the registry and gl-spec/ into the model (`Spec`).

use std::collections::BTreeMap;
use std::path::Path;

use crate::fail;
use crate::files;
use crate::model::{Class, Command, Flags, Lib, ListRule, Spec};
use crate::registry;

/// Reads the registry and gl-spec/ (`spec`); any inconsistency stops the build.
pub fn load(spec: &Path) -> Spec {
    let types = files::read_types(&spec.join("types.txt"));
    let mut commands: BTreeMap<String, Command> = BTreeMap::new();
    let mut enums = Vec::new();
    for line in files::data_lines(&spec.join("exports.txt")) {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 4 {
            fail(&format!("gl-spec/exports.txt: expected `api registry features extensions`: {line}"));
        }
        let lib = Lib::parse(f[0]);
        // `gl.xml@gles2` reads the features and extensions of API gles2 from gl.xml.
        let (file, api) = f[1].split_once('@').unwrap_or((f[1], f[0]));
        let found = match file {
            "gl.xml" => registry::commands(khronos_api::GL_XML, api, f[2], &f[3..], &types),
            "glx.xml" => registry::commands(khronos_api::GLX_XML, api, f[2], &f[3..], &types),
            "egl.xml" => registry::commands(khronos_api::EGL_XML, api, f[2], &f[3..], &types),
            other => registry::prototype_file(&spec.join(other), &types),
        };
        if file == f[1] {
            // Once per registry file (not again for gl.xml@gles2).
            match file {
                "gl.xml" => enums.extend(registry::enums(khronos_api::GL_XML, "gl", "u32")),
                "glx.xml" => enums.extend(registry::enums(khronos_api::GLX_XML, "glx", "i32")),
                "egl.xml" => enums.extend(registry::enums(khronos_api::EGL_XML, "egl", "i32")),
                other => enums.extend(registry::prototype_file_enums(&spec.join(other))),
            }
        }
        for (name, (ret, params)) in found {
            commands.entry(name.clone()).or_insert(Command {
                name,
                lib,
                ret,
                params,
                class: Class::Pass,
                list: ListRule::NotGl,
                flags: Flags::default(),
            });
        }
    }
    files::classify(&spec.join("classes.txt"), &mut commands);
    let sizes = files::read_sizes(&spec.join("sizes.txt"));
    let ops = files::read_ops(&spec.join("capture.txt"), &commands);
    Spec { commands, types, sizes, enums, ops }
}
