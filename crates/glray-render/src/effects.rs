//! What a ray tracer adds to the GL look at a hit: ambient occlusion and hard shadows from the
//! GL lights (reflections and samples per pixel are the tracer's; the settings and presets are
//! `options::Effects`).

use glam::DVec3;
use glray_scene::lighting::Light;

use crate::offset::{leaving, Origin};
use crate::sampling::{Hemisphere, Sampler, Strata};
use crate::scene::Scene;

/// The fraction of the hemisphere above `at` that geometry closer than `distance` hides, from
/// `count` cosine-weighted rays, stratified (translucent surfaces hide their alpha's share).
pub fn occlusion(scene: &Scene, at: &Origin, count: u32, distance: f32, eps: f32, s: &mut Sampler) -> f32 {
    if count == 0 {
        return 0.0;
    }
    let around = Hemisphere::around(at.n);
    let mut strata = Strata::new(count, s.next2());
    scene.hidden(at, &around, count, distance, eps, || strata.direction()) / count as f32
}

/// How much of `light` reaches the point (0 to 1).
pub(crate) fn lit_by(scene: &Scene, at: &Origin, light: &Light, eps: f32) -> f32 {
    let p = at.p.as_dvec3();
    let (dir, tmax) = if light.position.w != 0.0 {
        let to = light.position.truncate() / light.position.w - p;
        let len = to.length();
        if len == 0.0 {
            return 1.0;
        }
        (to / len, len as f32 - eps)
    } else {
        (light.position.truncate().normalize_or_zero(), f32::INFINITY)
    };
    if dir == DVec3::ZERO {
        return 1.0;
    }
    scene.transmittance(leaving(at.p, at.n, dir.as_vec3(), eps, tmax), Some(at.draw))
}

#[cfg(test)]
mod tests {
    use crate::options::{Effects, Options, MAX_PASSES};
    use crate::render::{render, Rendered, Renderer};
    use glam::{DMat4, DVec4};
    use glray_capture::fixed::Context;
    use glray_core::trace::Value::{self, Int, F64};
    use glray_gl::{GL_ALPHA_TEST, GL_BLEND, GL_COLOR_MATERIAL, GL_DEPTH_TEST, GL_GREATER, GL_LIGHT0, GL_LIGHTING};
    use glray_scene::camera::{Camera, Viewport};
    use glray_scene::frame::Frame;

    const SIZE: u32 = 64;

    /// A context with a perspective camera at the origin looking down -z and depth testing.
    fn context() -> Context {
        let mut c = Context::default();
        c.set_drawable(SIZE, SIZE);
        call(&mut c, "glMatrixMode", &[Int(0x1701)]);
        call(&mut c, "glFrustum", &[-0.5, 0.5, -0.5, 0.5, 1.0, 30.0].map(F64));
        call(&mut c, "glMatrixMode", &[Int(0x1700)]);
        call(&mut c, "glEnable", &[Int(GL_DEPTH_TEST as i64)]); // GL_DEPTH_TEST
        call(&mut c, "glClear", &[Int(0x4100)]); // colour and depth
        c
    }

    fn call(c: &mut Context, name: &str, args: &[Value]) {
        let (op, ty) = glray_capture::ops::op_for(name).unwrap();
        c.call(op, ty, args);
    }

    /// A quad with a colour and a normal.
    fn quad(c: &mut Context, corners: [[f64; 3]; 4], color: [f64; 3], normal: [f64; 3]) {
        call(c, "glColor3f", &color.map(F64));
        call(c, "glNormal3f", &normal.map(F64));
        call(c, "glBegin", &[Int(7)]);
        for v in corners {
            call(c, "glVertex3f", &v.map(F64));
        }
        call(c, "glEnd", &[]);
    }

    /// A grey floor at y = -1, lit from straight above by GL_LIGHT0, with colour material.
    fn lit_floor() -> Context {
        let mut c = context();
        call(&mut c, "glEnable", &[Int(GL_LIGHTING as i64)]); // GL_LIGHTING
        call(&mut c, "glEnable", &[Int(GL_LIGHT0 as i64)]); // GL_LIGHT0
        call(&mut c, "glEnable", &[Int(GL_COLOR_MATERIAL as i64)]); // GL_COLOR_MATERIAL
        let up: Vec<u8> = [0.0f32, 1.0, 0.0, 0.0].iter().flat_map(|x| x.to_ne_bytes()).collect();
        call(&mut c, "glLightfv", &[Int(0x4000), Int(0x1203), Value::Blob(&up)]);
        let grey = [[-4.0, -1.0, -2.0], [4.0, -1.0, -2.0], [4.0, -1.0, -12.0], [-4.0, -1.0, -12.0]];
        quad(&mut c, grey, [0.5, 0.5, 0.5], [0.0, 1.0, 0.0]);
        c
    }

    /// A white floor at y = -1 from z = -2 to -12.
    fn floor(c: &mut Context) {
        let f = [[-4.0, -1.0, -2.0], [4.0, -1.0, -2.0], [4.0, -1.0, -12.0], [-4.0, -1.0, -12.0]];
        quad(c, f, [1.0, 1.0, 1.0], [0.0, 1.0, 0.0]);
    }

    /// The pixel an eye-space point lands on.
    fn pixel_at(frame: &Frame, r: &Rendered, p: [f64; 3]) -> [u8; 4] {
        let camera = Camera::new(frame.projection.unwrap(), frame.viewport.unwrap(), (0.0, 1.0)).unwrap();
        let (x, y) = camera.window_position(glam::DVec3::from_array(p));
        let i = 4 * (y as usize * SIZE as usize + x as usize);
        r.rgba[i..i + 4].try_into().unwrap()
    }

    fn with(effects: Effects) -> Options {
        Options { effects, ..Options::default() }
    }

    /// A floor meeting a wall at z = -7: the crease between them.
    fn crease() -> Frame {
        let mut c = context();
        floor(&mut c);
        let wall = [[-4.0, -1.0, -7.0], [4.0, -1.0, -7.0], [4.0, 3.0, -7.0], [-4.0, 3.0, -7.0]];
        quad(&mut c, wall, [1.0, 1.0, 1.0], [0.0, 0.0, 1.0]);
        c.take_frame()
    }

    #[test]
    fn ambient_occlusion_darkens_creases_and_not_open_planes() {
        let frame = crease();
        let ao = with(Effects { ao_samples: 64, ..Effects::GL });
        let gl = render(&frame, SIZE, SIZE, None, &with(Effects::GL));
        let r = render(&frame, SIZE, SIZE, None, &ao);
        let open = [0.0, -1.0, -3.0];
        let near_crease = [0.0, -1.0, -6.9];
        assert_eq!(pixel_at(&frame, &gl, open)[0], 255, "unlit white");
        assert_eq!(pixel_at(&frame, &r, open)[0], 255, "nothing within reach of an open floor");
        assert_eq!(pixel_at(&frame, &gl, near_crease)[0], 255);
        let dark = pixel_at(&frame, &r, near_crease)[0];
        assert!(dark < 200, "the crease is darkened: {dark}");
        let half = Effects { ao_samples: 64, ao_intensity: 0.5, ..Effects::GL };
        let lighter = pixel_at(&frame, &render(&frame, SIZE, SIZE, None, &with(half)), near_crease)[0];
        assert!(lighter > dark && lighter < 255, "intensity scales it: {lighter} vs {dark}");
    }

    #[test]
    fn shadows_fall_only_where_an_occluder_hides_the_light() {
        let mut c = lit_floor();
        // A board over the floor (above the camera's height: the camera sees its underside).
        let board = [[-1.0, 0.5, -4.0], [1.0, 0.5, -4.0], [1.0, 0.5, -6.0], [-1.0, 0.5, -6.0]];
        quad(&mut c, board, [0.5, 0.5, 0.5], [0.0, 1.0, 0.0]);
        let frame = c.take_frame();
        let plain = render(&frame, SIZE, SIZE, None, &with(Effects::GL));
        let shadowed = render(&frame, SIZE, SIZE, None, &with(Effects { shadows: true, ..Effects::GL }));
        let (under, beside) = ([0.0, -1.0, -5.0], [2.5, -1.0, -5.0]);
        // Colour material: 0.5 x 0.2 ambient, plus 0.5 diffuse where the light reaches.
        let value = |r: &Rendered, p| pixel_at(&frame, r, p)[0];
        assert_eq!(value(&plain, under), 153, "no shadows in the GL look");
        assert_eq!(value(&shadowed, beside), 153, "lit beside the board");
        let dark = value(&shadowed, under);
        assert!((25..=26).contains(&dark), "only ambient under it: {dark}");
    }

    /// A sphere of radius 1 around `center`, `segments` around and `rings` from pole to pole,
    /// each vertex with its own normal (smooth shading), lit by GL_LIGHT0 from `light`.
    fn smooth_sphere(center: [f64; 3], segments: u32, rings: u32, light: [f32; 3]) -> Frame {
        let mut c = context();
        call(&mut c, "glEnable", &[Int(GL_LIGHTING as i64)]); // GL_LIGHTING
        call(&mut c, "glEnable", &[Int(GL_LIGHT0 as i64)]); // GL_LIGHT0
        call(&mut c, "glEnable", &[Int(GL_COLOR_MATERIAL as i64)]); // GL_COLOR_MATERIAL
        let at: Vec<u8> = [light[0], light[1], light[2], 0.0].iter().flat_map(|x| x.to_ne_bytes()).collect();
        call(&mut c, "glLightfv", &[Int(0x4000), Int(0x1203), Value::Blob(&at)]);
        call(&mut c, "glColor3f", &[1.0, 1.0, 1.0].map(F64));
        let point = |i: u32, j: u32| {
            let (around, down) =
                (std::f64::consts::TAU * i as f64 / segments as f64, std::f64::consts::PI * j as f64 / rings as f64);
            [down.sin() * around.cos(), down.cos(), down.sin() * around.sin()]
        };
        call(&mut c, "glBegin", &[Int(4)]); // GL_TRIANGLES
        for j in 0..rings {
            for i in 0..segments {
                let quad = [point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)];
                for k in [0, 1, 2, 0, 2, 3] {
                    let n = quad[k];
                    call(&mut c, "glNormal3f", &n.map(F64));
                    call(&mut c, "glVertex3f", &[0, 1, 2].map(|a| F64(center[a] + n[a])));
                }
            }
        }
        call(&mut c, "glEnd", &[]);
        c.take_frame()
    }

    #[test]
    fn a_smooth_shaded_surface_does_not_shadow_itself_where_its_normals_face_the_light() {
        // A coarse sphere alone, lit from the side: nothing else casts a shadow, and where its
        // shading normals face the light it is lit, on facets that face away too (with shadow
        // rays leaving the flat facets, such points went dark in jagged, faceted bands along
        // the line between light and shade).
        let frame = smooth_sphere([0.0, 0.0, -4.0], 12, 8, [1.0, 0.4, 0.6]);
        let per_pixel = Options { per_pixel_lighting: true, ..with(Effects::GL) };
        let plain = render(&frame, SIZE, SIZE, None, &per_pixel);
        let shadowed = render(&frame, SIZE, SIZE, None, &with(Effects { shadows: true, ..Effects::GL }));
        let differ = plain.rgba.chunks(4).zip(shadowed.rgba.chunks(4)).filter(|(a, b)| a != b).count();
        let covered = plain.rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
        assert!(covered > 500, "the sphere covers {covered} pixels");
        assert_eq!(differ, 0, "{differ} of {covered} pixels darkened by the sphere's own facets");
    }

    #[test]
    fn translucent_surfaces_let_their_share_of_light_through() {
        let mut c = lit_floor();
        // Left: a half-transparent board, blended. Right: a board the alpha test discards.
        call(&mut c, "glEnable", &[Int(GL_BLEND as i64)]); // GL_BLEND
        call(&mut c, "glBlendFunc", &[Int(0x0302), Int(0x0303)]);
        call(&mut c, "glColor4f", &[F64(0.5), F64(0.5), F64(0.5), F64(0.5)]);
        let left = [[-2.0, 0.5, -4.0], [-0.5, 0.5, -4.0], [-0.5, 0.5, -6.0], [-2.0, 0.5, -6.0]];
        corners_only(&mut c, left);
        call(&mut c, "glDisable", &[Int(0x0BE2)]);
        call(&mut c, "glEnable", &[Int(GL_ALPHA_TEST as i64)]); // GL_ALPHA_TEST
        call(&mut c, "glAlphaFunc", &[Int(GL_GREATER as i64), F64(0.5)]); // GL_GREATER 0.5
        call(&mut c, "glColor4f", &[F64(0.5), F64(0.5), F64(0.5), F64(0.2)]);
        let right = [[0.5, 0.5, -4.0], [2.0, 0.5, -4.0], [2.0, 0.5, -6.0], [0.5, 0.5, -6.0]];
        corners_only(&mut c, right);
        let frame = c.take_frame();
        let r = render(&frame, SIZE, SIZE, None, &with(Effects { shadows: true, ..Effects::GL }));
        let value = |p| pixel_at(&frame, &r, p)[0];
        // Ambient 0.1 plus half of the 0.5 diffuse: 0.35.
        let half = value([-1.25, -1.0, -5.0]);
        assert!((88..=90).contains(&half), "half the light through the blended board: {half}");
        assert_eq!(value([1.25, -1.0, -5.0]), 153, "the discarded board casts nothing");
    }

    /// A quad of the current colour, normal up.
    fn corners_only(c: &mut Context, corners: [[f64; 3]; 4]) {
        call(c, "glNormal3f", &[F64(0.0), F64(1.0), F64(0.0)]);
        call(c, "glBegin", &[Int(7)]);
        for v in corners {
            call(c, "glVertex3f", &v.map(F64));
        }
        call(c, "glEnd", &[]);
    }

    #[test]
    fn thick_lines_cast_shadows_as_the_cylinders_they_look_like() {
        let mut c = lit_floor();
        // A 16-pixel line across the view at y = 0.5, z = -5: a pixel there is 5/64 wide, so
        // the line is a cylinder of radius 0.625 (z from -4.375 to -5.625).
        call(&mut c, "glDisable", &[Int(0x0B50)]);
        call(&mut c, "glColor3f", &[F64(1.0), F64(1.0), F64(1.0)]);
        call(&mut c, "glLineWidth", &[F64(16.0)]);
        call(&mut c, "glBegin", &[Int(1)]);
        call(&mut c, "glVertex3f", &[F64(-1.5), F64(0.5), F64(-5.0)]);
        call(&mut c, "glVertex3f", &[F64(1.5), F64(0.5), F64(-5.0)]);
        call(&mut c, "glEnd", &[]);
        let frame = c.take_frame();
        assert_eq!(frame.solids.len(), 1);
        // The raw samples (denoising blends the line's AO with its neighbours').
        let effects = Effects { shadows: true, ao_samples: 16, denoise: false, ..Effects::GL };
        let r = render(&frame, SIZE, SIZE, None, &with(effects));
        let value = |p| pixel_at(&frame, &r, p)[0];
        // Under the cylinder but beside the flat quad the camera sees: in its shadow.
        assert!(value([0.0, -1.0, -5.4]) < 40, "in the line's shadow: {}", value([0.0, -1.0, -5.4]));
        assert!(value([0.0, -1.0, -3.0]) > 140, "lit in front of it: {}", value([0.0, -1.0, -3.0]));
        // The line itself is not darkened by its own solid.
        let line = pixel_at(&frame, &r, [0.0, 0.5, -5.0]);
        assert_eq!(line[..3], [255, 255, 255], "the white line, unoccluded: {line:?}");
    }

    #[test]
    fn a_mirror_shows_the_reflected_object() {
        let mut c = context();
        floor(&mut c);
        let red = [[-1.0, -1.0, -6.0], [1.0, -1.0, -6.0], [1.0, 1.0, -6.0], [-1.0, 1.0, -6.0]];
        quad(&mut c, red, [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let frame = c.take_frame();
        let mirror = Effects { reflections: 1, reflectivity: 1.0, ..Effects::GL };
        let plain = render(&frame, SIZE, SIZE, None, &with(Effects::GL));
        let r = render(&frame, SIZE, SIZE, None, &with(mirror));
        // The camera ray to (0, -1, -4) leaves the floor towards (0, 1, -4): it meets the red
        // quad at (0, -0.5, -6). Further out, the reflection sees the black background.
        let (on, off) = ([0.0, -1.0, -4.0], [1.2, -1.0, -3.0]);
        assert_eq!(pixel_at(&frame, &plain, on), [255, 255, 255, 255]);
        assert_eq!(pixel_at(&frame, &r, on)[..3], [255, 0, 0], "the red quad, reflected");
        assert_eq!(pixel_at(&frame, &r, off)[..3], [0, 0, 0], "the background, reflected");
        // Half a mirror head-on, more at this angle (Fresnel, as Schlick has it): the ray meets
        // the floor at cos = 1 / sqrt(17) (about: the pixel centre is near that point), and
        // 0.5 + 0.5 (1 - cos)^5 of the red quad is seen.
        let half = Effects { reflectivity: 0.5, ..mirror };
        let p = pixel_at(&frame, &render(&frame, SIZE, SIZE, None, &with(half)), on);
        let r = 0.5 + 0.5 * (1.0 - 1.0 / 17f32.sqrt()).powi(5);
        let white = (255.0 * (1.0 - r)).round() as u8;
        assert!(p[0] == 255 && p[1].abs_diff(white) <= 3 && p[1] == p[2], "{p:?}: {r} of the red quad");
    }

    #[test]
    fn a_smooth_shaded_mirror_reflects_about_its_shading_normal() {
        // A lit quad facing the camera whose normals lean 30 degrees up (as a curved mesh's do
        // away from its facets' centres), and an unlit green board above it. About the facet's
        // own normal, the ray to the quad's centre would come straight back and see the black
        // background; about the shading normal it goes up to the board.
        let mut c = context();
        call(&mut c, "glEnable", &[Int(GL_LIGHTING as i64)]); // GL_LIGHTING
        call(&mut c, "glEnable", &[Int(GL_LIGHT0 as i64)]); // GL_LIGHT0
        call(&mut c, "glEnable", &[Int(GL_COLOR_MATERIAL as i64)]); // GL_COLOR_MATERIAL
        let facing = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [1.0, 1.0, -5.0], [-1.0, 1.0, -5.0]];
        quad(&mut c, facing, [1.0, 1.0, 1.0], [0.0, 0.5, 0.75f64.sqrt()]);
        call(&mut c, "glDisable", &[Int(0x0B50)]);
        let board = [[-3.0, 1.5, -2.0], [3.0, 1.5, -2.0], [3.0, 1.5, -6.0], [-3.0, 1.5, -6.0]];
        quad(&mut c, board, [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]);
        let frame = c.take_frame();
        let mirror = Effects { reflections: 1, reflectivity: 1.0, ..Effects::GL };
        let r = render(&frame, SIZE, SIZE, None, &with(mirror));
        assert_eq!(pixel_at(&frame, &r, [0.0, 0.0, -5.0])[..3], [0, 255, 0], "the green board, reflected");
    }

    #[test]
    fn samples_per_pixel_antialias_edges() {
        let frame = crease();
        let one = render(&frame, SIZE, SIZE, None, &with(Effects::GL));
        let many = render(&frame, SIZE, SIZE, None, &with(Effects { samples: 16, ..Effects::GL }));
        let between = |r: &Rendered| r.rgba.chunks(4).filter(|p| p[0] > 0 && p[0] < 255).count();
        assert_eq!(between(&one), 0, "one sample: every pixel is floor or background");
        assert!(between(&many) > 20, "edge pixels are mixed: {}", between(&many));
        assert_eq!(one.depth, many.depth, "depth stays the pixel centre's");
    }

    #[test]
    fn effects_images_do_not_depend_on_the_thread_count() {
        let frame = crease();
        let full = with(Effects::preset("full").unwrap());
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render(&frame, SIZE, SIZE, None, &full))
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(8));
    }

    #[test]
    fn progressive_refinement_adds_samples_while_the_scene_stays() {
        let frame = crease();
        let mut renderer = Renderer::new(with(Effects { ao_samples: 4, ..Effects::GL }));
        let first = renderer.render(&frame, SIZE, SIZE, None);
        assert_eq!(renderer.stats().samples, 1);
        let second = renderer.render(&frame, SIZE, SIZE, None);
        assert_eq!(renderer.stats().samples, 2);
        assert_ne!(first.rgba, second.rgba, "new samples change the noisy pixels");
        for _ in 2..MAX_PASSES + 3 {
            renderer.render(&frame, SIZE, SIZE, None);
        }
        assert_eq!(renderer.stats().samples, MAX_PASSES, "it stops when converged");
        assert!(renderer.stats().reused, "and shows the converged picture again");
        // A different camera starts again.
        let mut moved = frame.clone();
        moved.projection =
            Some(moved.projection.unwrap() * DMat4::from_translation(DVec4::new(0.1, 0.0, 0.0, 0.0).truncate()));
        renderer.render(&moved, SIZE, SIZE, None);
        assert_eq!(renderer.stats().samples, 1);
        let _ = Viewport { x: 0, y: 0, width: 1, height: 1 };
    }

    #[test]
    fn an_unchanged_gl_look_frame_is_shown_again_and_a_changed_one_traced() {
        use glam::Vec4;
        use glray_scene::surface::Texturing;
        use glray_scene::texture::{Level, Texture};
        use std::sync::Arc;
        let frame = crease();
        let mut renderer = Renderer::new(with(Effects::GL));
        let first = renderer.render(&frame, SIZE, SIZE, None);
        assert!(!renderer.stats().reused && renderer.stats().rays > 0);
        assert_eq!(renderer.render(&frame, SIZE, SIZE, None), first);
        assert!(renderer.stats().reused, "nothing changed: the picture is shown again");
        assert_eq!((renderer.stats().rays, renderer.stats().samples), (0, 1));
        // A moved camera, a new size, a frame drawn over the last one: traced.
        let mut moved = frame.clone();
        moved.projection =
            Some(moved.projection.unwrap() * DMat4::from_translation(DVec4::new(0.0, 0.5, 0.0, 0.0).truncate()));
        let other = renderer.render(&moved, SIZE, SIZE, None);
        assert!(!renderer.stats().reused && renderer.stats().rays > 0);
        assert_ne!(other, first);
        renderer.render(&moved, SIZE, SIZE - 1, None);
        assert!(!renderer.stats().reused);
        let mut over = moved.clone();
        over.cleared = false;
        renderer.render(&over, SIZE, SIZE, None);
        renderer.render(&over, SIZE, SIZE, None);
        assert!(!renderer.stats().reused, "a frame drawn over the last depends on it");
        // Textures: the signature knows one by its version, which every change renews.
        let texture = |c: f32| {
            let texels = vec![Vec4::new(c, c, c, 1.0)];
            Arc::new(Texture { levels: vec![Level { width: 1, height: 1, texels }], ..Texture::default() })
        };
        let mut textured = frame.clone();
        let texturing = |t| {
            Some(Texturing { texture: t, env_mode: glray_scene::surface::TexEnvMode::Modulate, env_color: Vec4::ZERO })
        };
        textured.surfaces[0].texturing = texturing(texture(1.0));
        renderer.render(&textured, SIZE, SIZE, None);
        assert!(!renderer.stats().reused);
        renderer.render(&textured, SIZE, SIZE, None);
        assert!(renderer.stats().reused, "the same texture");
        // The renderer does not hold it, so capture can change it in place (the same object).
        let held = textured.surfaces[0].texturing.as_mut().map(|t| &mut t.texture).unwrap();
        let t = Arc::get_mut(held).expect("held by the frame alone");
        t.levels[0].texels[0] = Vec4::new(0.25, 0.25, 0.25, 1.0);
        t.changed();
        let changed = renderer.render(&textured, SIZE, SIZE, None);
        assert!(!renderer.stats().reused, "a texture changed in place");
        assert!(changed.rgba.chunks(4).any(|p| p[0] == 64), "traced with the new texel");
        // The old texture freed first, as capture frees a replaced one.
        textured.surfaces[0].texturing = None;
        textured.surfaces[0].texturing = texturing(texture(0.5));
        renderer.render(&textured, SIZE, SIZE, None);
        assert!(!renderer.stats().reused, "a new texture");
        // Without progressive refinement, every frame is traced.
        let mut every = Renderer::new(with(Effects { progressive: false, ..Effects::GL }));
        every.render(&frame, SIZE, SIZE, None);
        every.render(&frame, SIZE, SIZE, None);
        assert!(!every.stats().reused && every.stats().rays > 0);
    }

    #[test]
    fn presets_are_named_and_gl_is_only_the_gl_look() {
        assert!(!Effects::preset("gl").unwrap().beyond_gl());
        assert_eq!(Effects::preset("ao").unwrap().ao_samples, 16);
        let full = Effects::preset("full").unwrap();
        assert_eq!((full.ao_samples, full.shadows, full.reflections, full.samples), (36, true, 1, 4));
        assert!(Effects::preset("fancy").is_none());
        // Every preset the settings accept but `off` (no ray tracing) has its effects.
        for name in glray_core::config::PRESETS {
            assert_eq!(Effects::preset(name).is_some(), *name != "off", "{name}");
        }
    }
}
