//! GLRAY_DUMP_SCENE: each ray-traced frame's captured scene as OBJ + MTL (eye coordinates,
//! one material per draw state, vertex colours as OBJ's per-vertex colour extension; display
//! list instances written out as the triangles they draw) and a JSON summary (triangles,
//! meshes, instances, lights, camera), for debugging and tests.

use std::fmt::Write as _;
use std::path::Path;

use glray_scene::frame::Frame;

pub fn write(dir: &Path, number: u64, frame: &Frame) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let stem = format!("scene-{number:04}");
    let mut obj = format!("# glray scene {number}: eye coordinates\nmtllib {stem}.mtl\n");
    let mut mtl = String::new();
    for (i, s) in frame.surfaces.iter().enumerate() {
        let _ = writeln!(mtl, "newmtl surface{i}\nKd 1 1 1\n# textured: {}\n", s.texturing.is_some());
    }
    let mut surface = u32::MAX;
    let triangles = frame.all_triangles();
    for (i, t) in triangles.iter().enumerate() {
        if t.surface != surface {
            surface = t.surface;
            let _ = writeln!(obj, "usemtl surface{surface}");
        }
        for (p, c) in t.positions.iter().zip(&t.colors) {
            let _ = writeln!(obj, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z);
        }
        let b = 3 * i + 1;
        let _ = writeln!(obj, "f {} {} {}", b, b + 1, b + 2);
    }
    let camera = match (frame.projection, frame.viewport) {
        (Some(p), Some(v)) => format!(
            "{{\"projection\":{:?},\"viewport\":[{},{},{},{}]}}",
            p.to_cols_array(),
            v.x,
            v.y,
            v.width,
            v.height
        ),
        _ => "null".into(),
    };
    let mut meshes: Vec<u64> = frame.instances.iter().map(|i| i.mesh.id).collect();
    meshes.sort_unstable();
    meshes.dedup();
    let lights = frame.lightings.iter().map(|l| l.lights().len()).max().unwrap_or(0);
    let json = format!(
        "{{\"frame\":{number},\"triangles\":{},\"frame_triangles\":{},\"meshes\":{},\"instances\":{},\"lights\":{lights},\"surfaces\":{},\"textured_surfaces\":{},\"cameras\":{},\"unsupported_draws\":{},\"width\":{},\"height\":{},\"clear_color\":{:?},\"camera\":{camera}}}\n",
        triangles.len(),
        frame.triangles.len(),
        meshes.len(),
        frame.instances.len(),
        frame.surfaces.len(),
        frame.surfaces.iter().filter(|s| s.texturing.is_some()).count(),
        frame.cameras.len(),
        frame.unsupported_draws,
        frame.width,
        frame.height,
        frame.clear_color.to_array(),
    );
    for (name, text) in [(format!("{stem}.obj"), obj), (format!("{stem}.mtl"), mtl), (format!("{stem}.json"), json)] {
        std::fs::write(dir.join(&name), text).map_err(|e| format!("{}: {e}", dir.join(&name).display()))?;
    }
    Ok(())
}
