//! A frame's signature: a hash of everything that decides its picture (camera, geometry,
//! colours, state, lights, size, options), so that progressive refinement knows when a frame
//! shows the same scene as the last one and may add samples to it, or show its picture again.
//!
//! XXH3 over each triangle's numbers as bytes: a frame of a million triangles drawn in place is
//! hashed every frame, and SipHash (std's) word by word took 180 ms for it, xxh3 ~10x less.
//! Sixty-four bits of a hash of that quality: two different frames mistaken for one another
//! (the last picture shown for a new scene) is a chance in 2^64.

use std::hash::{Hash, Hasher};

use glam::Vec2;
use glray_scene::frame::Frame;
use glray_scene::triangle::Triangle;
use rayon::prelude::*;
use xxhash_rust::xxh3::Xxh3;

use crate::options::Options;

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

/// A triangle's words: positions 9, colours 12, secondary colours 9, texture coordinates 6,
/// normals 9, colours before lighting 12, clip w 3 (floats, as bits), then surface, sequence,
/// camera, lighting and facing: every field of a `Triangle`.
const TRIANGLE_WORDS: usize = 9 + 12 + 9 + 6 + 9 + 12 + 3 + 5;

/// Triangles hashed together on one thread.
const CHUNK: usize = 1 << 14;

/// The hash of `triangles`' numbers, each triangle's in one run of bytes (one call into the
/// hasher, not fifty).
fn triangles_hash(triangles: &[Triangle], textured: &[bool]) -> u64 {
    let mut h = Xxh3::new();
    for t in triangles {
        // Texture coordinates only where they are read: an untextured draw's are what a
        // previous frame left current, and would make an unchanged scene look changed.
        let texcoords =
            if textured.get(t.surface as usize).copied().unwrap_or(false) { t.texcoords } else { [Vec2::ZERO; 3] };
        let mut words = [0u32; TRIANGLE_WORDS];
        let ints = [t.surface, t.sequence, t.camera, t.lighting, u32::from(t.back)];
        let parts: [&[u32]; 8] = [
            bytemuck::cast_slice(&t.positions),
            bytemuck::cast_slice(&t.colors),
            bytemuck::cast_slice(&t.secondary),
            bytemuck::cast_slice(&texcoords),
            bytemuck::cast_slice(&t.normals),
            bytemuck::cast_slice(&t.base_colors),
            bytemuck::cast_slice(&t.clip_w),
            &ints,
        ];
        let mut at = 0;
        for part in parts {
            words[at..at + part.len()].copy_from_slice(part);
            at += part.len();
        }
        h.write(bytemuck::cast_slice(&words));
    }
    h.digest()
}

pub(crate) fn signature(frame: &Frame, width: u32, height: u32, options: &Options) -> u64 {
    let mut h = Xxh3::new();
    (width, height, frame.cleared, frame.depth_cleared.map(f32::to_bits), options.per_pixel_lighting).hash(&mut h);
    doubles(&mut h, [frame.depth_range.0, frame.depth_range.1]);
    format!("{:?}", options.effects).hash(&mut h);
    floats(&mut h, frame.clear_color.to_array());
    doubles(&mut h, frame.projection.map(|p| p.to_cols_array()).unwrap_or_default());
    for c in &frame.cameras {
        doubles(&mut h, c.projection.to_cols_array());
        (c.viewport.x, c.viewport.y, c.viewport.width, c.viewport.height).hash(&mut h);
    }
    (frame.cameras.len(), frame.lightings.len(), frame.surfaces.len()).hash(&mut h);
    frame.triangles.len().hash(&mut h);
    // Chunks hashed on the pool, their hashes taken in order: the same number for any thread
    // count.
    let textured: Vec<bool> = frame.surfaces.iter().map(|s| s.texturing.is_some()).collect();
    let chunks: Vec<u64> = frame.triangles.par_chunks(CHUNK).map(|c| triangles_hash(c, &textured)).collect();
    for c in chunks {
        c.hash(&mut h);
    }
    frame.solids.len().hash(&mut h);
    for l in &frame.solids {
        floats(&mut h, l.a.to_array().into_iter().chain(l.b.to_array()).chain([l.radius]));
        (l.sequence, l.camera).hash(&mut h);
    }
    frame.instances.len().hash(&mut h);
    for i in &frame.instances {
        (i.mesh.id, i.surface, i.camera, i.sequence, i.lighting, i.flat, i.front_ccw, i.cull).hash(&mut h);
        (i.normalize, i.rescale_normal).hash(&mut h);
        doubles(&mut h, i.modelview.to_cols_array());
        doubles(&mut h, i.color.to_array().into_iter().chain(i.normal.to_array()));
        // Texture coordinates only where they are read: the current one a previous frame left
        // would otherwise make an unchanged scene look changed.
        if textured.get(i.surface as usize).copied().unwrap_or(false) {
            doubles(&mut h, i.texture_matrix.to_cols_array());
            doubles(&mut h, i.texcoord.to_array());
        }
    }
    for l in &frame.lightings {
        format!("{l:?}").hash(&mut h);
    }
    format!("{:?}", frame.scissored_clears).hash(&mut h);
    for c in &frame.depth_clears {
        (c.before, c.depth.to_bits()).hash(&mut h);
    }
    for c in &frame.masked_clears {
        (c.before, c.mask).hash(&mut h);
        floats(&mut h, c.color.to_array());
    }
    for s in &frame.surfaces {
        // Textures by version: every change to a texture gives it a new one.
        if let Some(t) = &s.texturing {
            (t.texture.version, t.env_mode).hash(&mut h);
            floats(&mut h, t.env_color.to_array());
        }
        s.texturing.is_some().hash(&mut h);
        format!(
            "{:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            s.fog,
            s.blend,
            s.logic_op,
            s.alpha_test,
            s.clip_planes,
            (s.depth_test, s.depth_func, s.depth_mask),
            s.polygon_offset,
            s.color_mask,
            s.coverage
        )
        .hash(&mut h);
    }
    h.finish()
}
#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec3, Vec4};
    use std::sync::Arc;

    fn triangle(k: usize) -> Triangle {
        let x = k as f32;
        let corners = [Vec3::new(x, 0.0, -1.0), Vec3::new(x + 1.0, 0.0, -1.0), Vec3::new(x, 1.0, -1.0)];
        crate::fragment::tests::plain(corners, [1.0; 3])
    }

    /// A change made to a triangle or a frame.
    type Change<T> = fn(&mut T);

    #[test]
    fn any_number_of_any_triangle_changes_the_signature_and_threads_do_not() {
        use glray_scene::surface::{Surface, Texturing};
        use glray_scene::texture::Texture;
        // Several chunks' worth, the change in a middle one; surface 0 textured, 1 not.
        let mut textured = Surface::depth_tested();
        let texture = Arc::new(Texture::default());
        textured.texturing =
            Some(Texturing { texture, env_mode: glray_scene::surface::TexEnvMode::Modulate, env_color: Vec4::ZERO });
        let frame = Frame {
            triangles: (0..3 * CHUNK + 5).map(triangle).collect(),
            surfaces: vec![textured, Surface::depth_tested()],
            ..Frame::default()
        };
        let options = Options::default();
        let sign = |f: &Frame| signature(f, 64, 64, &options);
        let base = sign(&frame);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| sign(&frame))
        };
        assert_eq!((on(1), on(3)), (base, base));
        let k = CHUNK + CHUNK / 2;
        let changes: [(&str, Change<Triangle>); 10] = [
            ("position", |t| t.positions[2].y += 1e-6),
            ("colour before lighting", |t| t.base_colors[0].x = 0.5),
            ("clip w", |t| t.clip_w[1] = 2.0),
            ("colour", |t| t.colors[1].w = 0.5),
            ("secondary colour", |t| t.secondary[0].x = 0.1),
            ("texture coordinate", |t| t.texcoords[2].y = 0.25),
            ("normal", |t| t.normals[1] = Vec3::Y),
            ("surface", |t| t.surface = 1),
            ("lighting", |t| t.lighting = 1),
            ("facing", |t| t.back = true),
        ];
        for (what, change) in changes {
            let mut changed = frame.clone();
            change(&mut changed.triangles[k]);
            assert_ne!(sign(&changed), base, "{what}");
        }
        // An untextured triangle's texture coordinates are never read: they do not count.
        let mut untextured = frame.clone();
        untextured.triangles[k].surface = 1;
        let base_untextured = sign(&untextured);
        untextured.triangles[k].texcoords[0].x = 0.5;
        assert_eq!(sign(&untextured), base_untextured, "untextured texture coordinates");
        let mut fewer = frame.clone();
        fewer.triangles.pop();
        assert_ne!(sign(&fewer), base, "one triangle fewer");
        assert_ne!(signature(&frame, 64, 65, &options), base, "the size");
    }

    #[test]
    fn lines_depth_state_and_texture_environment_change_the_signature() {
        use glray_scene::frame::{DepthClear, Solid};
        use glray_scene::surface::{Surface, Texturing};
        use glray_scene::texture::Texture;
        let texture = Arc::new(Texture::default());
        let mut surface = Surface::depth_tested();
        surface.texturing =
            Some(Texturing { texture, env_mode: glray_scene::surface::TexEnvMode::Modulate, env_color: Vec4::ZERO });
        let line = Solid { a: Vec3::ZERO, b: Vec3::X, radius: 0.1, sequence: 0, camera: 0 };
        let frame = Frame {
            triangles: vec![triangle(0)],
            solids: vec![line],
            surfaces: vec![surface],
            depth_cleared: Some(1.0),
            depth_clears: vec![DepthClear { before: 1, depth: 1.0 }],
            ..Frame::default()
        };
        let options = Options::default();
        let base = signature(&frame, 64, 64, &options);
        let changes: [(&str, Change<Frame>); 16] = [
            // Changed in place (nothing else held it): the same object, a new version.
            ("the texture changed", |f| {
                Arc::make_mut(&mut f.surfaces[0].texturing.as_mut().unwrap().texture).changed()
            }),
            ("a line moved", |f| f.solids[0].b.y = 1.0),
            ("a line thicker", |f| f.solids[0].radius = 0.2),
            ("a line more", |f| f.solids.push(f.solids[0])),
            ("the depth range", |f| f.depth_range.1 = 0.5),
            ("depth not cleared", |f| f.depth_cleared = None),
            ("depth cleared to another value", |f| f.depth_cleared = Some(0.5)),
            ("the texture environment", |f| {
                f.surfaces[0].texturing.as_mut().unwrap().env_mode = glray_scene::surface::TexEnvMode::Replace
            }),
            ("the texture environment's colour", |f| f.surfaces[0].texturing.as_mut().unwrap().env_color.x = 1.0),
            ("the colour mask", |f| f.surfaces[0].color_mask[1] = false),
            ("the polygon offset", |f| f.surfaces[0].polygon_offset = Some((1.0, 1.0))),
            ("antialiased lines", |f| f.surfaces[0].coverage = Some(glray_scene::surface::Coverage::Line(1.0))),
            ("a scissored clear", |f| {
                let rect = glray_scene::camera::Viewport { x: 0, y: 0, width: 8, height: 8 };
                f.scissored_clears.push(glray_scene::frame::ScissoredClear { rect, color: None, depth: Some(1.0) })
            }),
            ("a depth clear between draws", |f| f.depth_clears.push(DepthClear { before: 2, depth: 1.0 })),
            ("a depth clear between draws to another depth", |f| f.depth_clears[0].depth = 0.5),
            ("a logic op", |f| f.surfaces[0].logic_op = Some(glray_scene::surface::LogicOp::Xor)),
        ];
        for (what, change) in changes {
            let mut changed = frame.clone();
            change(&mut changed);
            assert_ne!(signature(&changed, 64, 64, &options), base, "{what}");
        }
    }
}
