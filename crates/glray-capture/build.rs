//! Generates ops.rs (capture's `Op` enum, `op_for`, the list and glBegin rules, the context
//! calls) from gl-spec/capture.txt, classes.txt and the Khronos registry, through glray-spec.
fn main() {
    let spec_dir = glray_spec::spec_dir();
    glray_spec::rerun_if_changed(&spec_dir);
    let spec = glray_spec::load(&spec_dir);
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap());
    glray_spec::write(&out.join("ops.rs"), &glray_spec::gen::ops::generate(&spec));
}
