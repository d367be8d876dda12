//! A frame's signature: a hash of everything that decides its picture (camera, geometry,
//! colours, state, lights, size, options), so that progressive refinement knows when a frame
//! shows the same scene as the last one and may add samples to it.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glray_capture::frame::Frame;

use crate::render::Options;

fn floats<H: Hasher>(h: &mut H, values: impl IntoIterator<Item = f32>) {
    for v in values {
        v.to_bits().hash(h);
    }
}

fn doubles<H: Hasher>(h: &mut H, values: impl IntoIterator<Item = f64>) {
    for v in values {
        v.to_bits().hash(h);
    }
}

pub(crate) fn signature(frame: &Frame, width: u32, height: u32, options: &Options) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (width, height, frame.cleared, options.per_pixel_lighting).hash(&mut h);
    format!("{:?}", options.effects).hash(&mut h);
    floats(&mut h, frame.clear_color.to_array());
    doubles(&mut h, frame.projection.map(|p| p.to_cols_array()).unwrap_or_default());
    for c in &frame.cameras {
        doubles(&mut h, c.projection.to_cols_array());
        (c.viewport.x, c.viewport.y, c.viewport.width, c.viewport.height).hash(&mut h);
    }
    frame.triangles.len().hash(&mut h);
    for t in &frame.triangles {
        floats(&mut h, t.positions.iter().flat_map(|p| p.to_array()));
        floats(&mut h, t.colors.iter().flat_map(|c| c.to_array()));
        floats(&mut h, t.secondary.iter().flat_map(|c| c.to_array()));
        floats(&mut h, t.texcoords.iter().flat_map(|c| c.to_array()));
        floats(&mut h, t.normals.iter().flat_map(|c| c.to_array()));
        (t.surface, t.sequence, t.camera, t.lighting, t.back).hash(&mut h);
    }
    for i in &frame.instances {
        (i.mesh.id, i.surface, i.camera, i.sequence, i.lighting, i.flat, i.front_ccw, i.cull).hash(&mut h);
        (i.normalize, i.rescale_normal).hash(&mut h);
        doubles(&mut h, i.modelview.to_cols_array());
        doubles(&mut h, i.texture_matrix.to_cols_array());
        doubles(&mut h, i.color.to_array().into_iter().chain(i.normal.to_array()).chain(i.texcoord.to_array()));
    }
    for l in &frame.lightings {
        format!("{l:?}").hash(&mut h);
    }
    for s in &frame.surfaces {
        // Textures by identity: a changed texture is a new object in capture.
        s.texturing.as_ref().map(|t| Arc::as_ptr(&t.texture) as usize).hash(&mut h);
        format!(
            "{:?} {:?} {:?} {:?} {:?}",
            s.fog,
            s.blend,
            s.alpha_test,
            s.clip_planes,
            (s.depth_test, s.depth_func, s.depth_mask)
        )
        .hash(&mut h);
    }
    h.finish()
}
