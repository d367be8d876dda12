//! Which fragments of a pixel survive, as GL's per-fragment operations decide in drawing order:
//! the depth test (with its function and mask), the alpha test, blending and the colour mask. When every draw
//! of a frame is opaque and depth-tested with LESS or LEQUAL, that is simply the closest hit;
//! otherwise every hit along the ray is replayed in drawing order against a depth and colour
//! that start as the clear values.

use glam::{BVec4A, DVec3, Vec3, Vec4, Vec4Swizzles};
use glray_scene::camera::Camera;
use glray_scene::frame::Frame;
use glray_scene::surface::{BlendFactor, CompareFunc, LogicOp, Surface};
use glray_scene::triangle::Triangle;

use crate::fragment::Fragment;
use crate::scene::Hit;

/// Whether the closest hit decides every pixel of the frame.
pub fn closest_hit_suffices(frame: &Frame) -> bool {
    frame.depth_clears.is_empty()
        && frame.masked_clears.is_empty()
        && frame.surfaces.iter().all(|s| {
            s.depth_test
                && s.depth_mask
                && matches!(s.depth_func, CompareFunc::Less | CompareFunc::LessOrEqual)
                && s.blend.is_none()
                && s.logic_op.is_none()
                && s.alpha_test.is_none()
                && s.clip_planes.is_empty()
                && s.polygon_offset.is_none()
                && s.color_mask == [true; 4]
        })
}

/// The smallest difference of window depth that the depth buffer (24 bits) tells apart.
const RESOLVABLE: f64 = 1.0 / ((1 << 24) - 1) as f64;

/// `depth`, a fragment of triangle `t` (eye-space corners), moved by glPolygonOffset's `factor`
/// and `units` (OpenGL 2.1, 3.5.5): factor times the triangle's largest window-depth slope
/// across x or y, plus units times the smallest resolvable difference; clamped to [0, 1].
pub fn offset_depth(camera: &Camera, t: &Triangle, depth: f64, (factor, units): (f32, f32)) -> f64 {
    let window = t.positions.map(|p| {
        let eye = p.as_dvec3();
        let (x, y) = camera.window_position(eye);
        DVec3::new(x, y, camera.window_depth(eye))
    });
    let n = (window[1] - window[0]).cross(window[2] - window[0]);
    // Seen edge-on, the slope is unbounded; such a triangle covers no pixel anyway.
    let slope = if n.z != 0.0 { (n.x / n.z).abs().max((n.y / n.z).abs()) } else { 0.0 };
    (depth + factor as f64 * slope + units as f64 * RESOLVABLE).clamp(0.0, 1.0)
}

fn factor(f: BlendFactor, src: Vec4, dst: Vec4) -> Vec4 {
    match f {
        BlendFactor::Zero => Vec4::ZERO,
        BlendFactor::One => Vec4::ONE,
        BlendFactor::SrcColor => src,
        BlendFactor::OneMinusSrcColor => Vec4::ONE - src,
        BlendFactor::SrcAlpha => Vec4::splat(src.w),
        BlendFactor::OneMinusSrcAlpha => Vec4::splat(1.0 - src.w),
        BlendFactor::DstAlpha => Vec4::splat(dst.w),
        BlendFactor::OneMinusDstAlpha => Vec4::splat(1.0 - dst.w),
        BlendFactor::DstColor => dst,
        BlendFactor::OneMinusDstColor => Vec4::ONE - dst,
        BlendFactor::SrcAlphaSaturate => {
            let f = src.w.min(1.0 - dst.w);
            Vec3::splat(f).extend(1.0)
        }
        // The constant colour (glBlendColor) is not followed.
        BlendFactor::ConstantColor
        | BlendFactor::OneMinusConstantColor
        | BlendFactor::ConstantAlpha
        | BlendFactor::OneMinusConstantAlpha => Vec4::ONE,
    }
}

/// Colour of the framebuffer after `fragment` of `surface` (that passed the tests) lands on `dst`.
fn blend(surface: &Surface, src: Vec4, dst: Vec4) -> Vec4 {
    match surface.blend {
        None => src,
        Some((sf, df)) => (src * factor(sf, src, dst) + dst * factor(df, src, dst)).clamp(Vec4::ZERO, Vec4::ONE),
    }
}

/// Colour of the framebuffer after glLogicOp's `op` combines `src` with `dst`, bit by bit on
/// the 8-bit values the framebuffer holds.
fn logic(op: LogicOp, src: Vec4, dst: Vec4) -> Vec4 {
    let bits = |c: Vec4| c.to_array().map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8);
    let (s, d) = (bits(src), bits(dst));
    let out: [f32; 4] = std::array::from_fn(|k| {
        let (s, d) = (s[k], d[k]);
        let v = match op {
            LogicOp::Clear => 0,
            LogicOp::And => s & d,
            LogicOp::AndReverse => s & !d,
            LogicOp::Copy => s,
            LogicOp::AndInverted => !s & d,
            LogicOp::Noop => d,
            LogicOp::Xor => s ^ d,
            LogicOp::Or => s | d,
            LogicOp::Nor => !(s | d),
            LogicOp::Equiv => !(s ^ d),
            LogicOp::Invert => !d,
            LogicOp::OrReverse => s | !d,
            LogicOp::CopyInverted => !s,
            LogicOp::OrInverted => !s | d,
            LogicOp::Nand => !(s & d),
            LogicOp::Set => 0xFF,
        };
        v as f32 / 255.0
    });
    Vec4::from_array(out)
}

/// What a pixel's colour `color` is after the frame's masked colour clears (`Frame::
/// masked_clears`) before draw `sequence` (all of them: `u32::MAX`), from `from` on.
fn masked(frame: &Frame, from: &mut usize, sequence: u32, mut color: Vec4) -> Vec4 {
    while let Some(c) = frame.masked_clears.get(*from).filter(|c| c.before <= sequence) {
        color = Vec4::select(BVec4A::from(c.mask), c.color, color);
        *from += 1;
    }
    color
}

/// A pixel's colour after the frame's masked colour clears, when none of its draws reach it.
pub fn cleared_only(frame: &Frame, color: Vec4) -> Vec4 {
    masked(frame, &mut 0, u32::MAX, color)
}

/// A pixel's colour and depth after all its fragments, in drawing order. `hits` come with
/// their fragments; `color` and `depth` are what the pixel held before the frame's draws. A
/// glClear of the depth buffer between draws (`Frame::depth_clears`) sets the depth to its value,
/// one of some colour channels (`Frame::masked_clears`) those channels.
pub fn in_drawing_order(frame: &Frame, hits: &mut [(Hit, Fragment)], color: Vec4, depth: f64) -> (Vec4, f64) {
    let r = resolve_in_order(frame, hits, color, depth);
    (r.color, r.depth)
}

/// What `resolve_in_order` found: the pixel's colour and depth, which of the hits (once sorted)
/// wrote its colour last, if any did, and whether any write mixed the fragment with what was
/// there (blending that was not just the fragment's own colour, a logic op).
pub struct Resolved {
    pub color: Vec4,
    pub depth: f64,
    pub last: Option<usize>,
    pub mixed: bool,
}

/// `in_drawing_order`, saying which fragment wrote last and whether any mixed (`Resolved`).
pub fn resolve_in_order(frame: &Frame, hits: &mut [(Hit, Fragment)], color: Vec4, depth: f64) -> Resolved {
    hits.sort_by_key(|(h, _)| (h.sequence, h.id));
    let (mut last, mut mixed) = (None, false);
    let (mut color, mut depth) = (color, depth);
    let mut clears = frame.depth_clears.iter().peekable();
    let mut masked_from = 0;
    for (k, (h, f)) in hits.iter().enumerate() {
        while let Some(c) = clears.next_if(|c| c.before <= h.sequence) {
            depth = c.depth as f64;
        }
        color = masked(frame, &mut masked_from, h.sequence, color);
        let s = &frame.surfaces[f.surface as usize];
        if s.clip_planes.iter().any(|p| p.dot(f.eye.extend(1.0)) < 0.0) {
            continue;
        }
        if let Some((func, reference)) = s.alpha_test {
            if !func.passes(f.color.w as f64, reference as f64) {
                continue;
            }
        }
        if s.depth_test {
            if !s.depth_func.passes(f.depth, depth) {
                continue;
            }
            if s.depth_mask {
                depth = f.depth;
            }
        }
        let blended = match s.logic_op {
            Some(op) => logic(op, f.color, color),
            None => blend(s, f.color, color),
        };
        let mask = BVec4A::from(s.color_mask);
        mixed |= Vec4::select(mask, (blended - f.color).abs(), Vec4::ZERO).max_element() > 1e-6;
        color = Vec4::select(mask, blended, color);
        if s.color_mask.contains(&true) {
            last = Some(k);
        }
    }
    if let Some(c) = clears.last() {
        // Clears after the pixel's last fragment: the last one's depth stands.
        depth = c.depth as f64;
    }
    Resolved { color: masked(frame, &mut masked_from, u32::MAX, color), depth, last, mixed }
}

/// The colour a fragment leaves over the background when it is the closest hit.
pub fn opaque(fragment: &Fragment) -> Vec4 {
    fragment.color.xyz().extend(fragment.color.w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_scene::frame::{DepthClear, TriangleId};

    #[test]
    fn comparisons_and_blending() {
        assert!(
            CompareFunc::Less.passes(0.2, 0.5)
                && !CompareFunc::Less.passes(0.5, 0.5)
                && CompareFunc::LessOrEqual.passes(0.5, 0.5)
        );
        let s =
            Surface { blend: Some((BlendFactor::SrcAlpha, BlendFactor::OneMinusSrcAlpha)), ..Surface::depth_tested() };
        let c = blend(&s, Vec4::new(1.0, 0.0, 0.0, 0.25), Vec4::new(0.0, 0.0, 1.0, 1.0));
        assert!((c - Vec4::new(0.25, 0.0, 0.75, 0.8125)).length() < 1e-6, "{c}");
    }

    #[test]
    fn a_colour_masked_draw_writes_only_the_channels_it_may() {
        // Transparent shells as molecule draws them: a depth-only pass (every channel masked),
        // then the same surface again with GL_EQUAL and blending, over a red model behind it.
        let hit = |sequence: u32| Hit {
            id: TriangleId { instance: 0, index: 0 },
            t: 1.0,
            sequence,
            normal: Vec3::Z,
            uv: Default::default(),
        };
        let fragment = |color: Vec4, depth: f64, surface: u32| Fragment { color, depth, eye: DVec3::ZERO, surface };
        let masked = Surface { color_mask: [false; 4], ..Surface::depth_tested() };
        let equal = Surface {
            depth_func: CompareFunc::Equal,
            blend: Some((BlendFactor::SrcAlpha, BlendFactor::OneMinusSrcAlpha)),
            ..Surface::depth_tested()
        };
        let frame = Frame { surfaces: vec![Surface::depth_tested(), masked, equal], ..Frame::default() };
        assert!(!closest_hit_suffices(&frame));
        let shell = Vec4::new(0.0, 0.0, 1.0, 0.5);
        let mut hits = [
            (hit(0), fragment(Vec4::new(1.0, 0.0, 0.0, 1.0), 0.6, 0)),
            (hit(1), fragment(shell, 0.4, 1)),
            (hit(2), fragment(shell, 0.4, 2)),
        ];
        let (color, depth) = in_drawing_order(&frame, &mut hits, Vec4::ZERO, 1.0);
        assert_eq!(depth, 0.4);
        assert!((color - Vec4::new(0.5, 0.0, 0.5, 0.75)).length() < 1e-6, "{color}");
        // Green alone masked: the draw keeps what was under it in green.
        let frame = Frame {
            surfaces: vec![Surface { color_mask: [true, false, true, true], ..Surface::depth_tested() }],
            ..frame
        };
        let mut hits = [(hit(0), fragment(Vec4::ONE, 0.5, 0))];
        let (color, _) = in_drawing_order(&frame, &mut hits, Vec4::new(0.0, 0.25, 0.0, 1.0), 1.0);
        assert_eq!(color, Vec4::new(1.0, 0.25, 1.0, 1.0));
    }

    #[test]
    fn a_masked_colour_clear_sets_its_channels_between_draws_and_keeps_the_rest() {
        // glplanet: the day side drawn opaque (alpha 1), the alpha channel alone cleared to 0,
        // then the night side blended by destination alpha: where the clear reached, the night
        // side lands whole; without it, the day side would stay.
        use glray_scene::frame::MaskedClear;
        let hit = |sequence: u32| Hit {
            id: TriangleId { instance: 0, index: sequence },
            t: 1.0,
            sequence,
            normal: Vec3::Z,
            uv: Default::default(),
        };
        let fragment = |color: Vec4, surface: u32| Fragment { color, depth: 0.5, eye: DVec3::ZERO, surface };
        let by_dst_alpha = Surface {
            blend: Some((BlendFactor::OneMinusDstAlpha, BlendFactor::DstAlpha)),
            depth_test: false,
            ..Surface::depth_tested()
        };
        let (day, night) = (Vec4::new(0.2, 0.6, 1.0, 1.0), Vec4::new(0.1, 0.1, 0.3, 1.0));
        let clear = MaskedClear { before: 1, color: Vec4::ZERO, mask: [false, false, false, true] };
        let mut frame = Frame { surfaces: vec![Surface::depth_tested(), by_dst_alpha], ..Frame::default() };
        let hits = || vec![(hit(0), fragment(day, 0)), (hit(1), fragment(night, 1))];
        let (kept, _) = in_drawing_order(&frame, &mut hits(), Vec4::ZERO, 1.0);
        assert_eq!(kept.truncate(), day.truncate(), "no clear: the day side's alpha keeps it");
        frame.masked_clears = vec![clear];
        assert!(!closest_hit_suffices(&frame));
        let (color, _) = in_drawing_order(&frame, &mut hits(), Vec4::ZERO, 1.0);
        assert_eq!(color.truncate(), night.truncate(), "the cleared alpha lets the night side in");
        // A clear after every draw of the pixel, and one over a pixel nothing reached: its
        // channels are set, the others kept.
        frame.masked_clears =
            vec![MaskedClear { before: 2, color: Vec4::new(0.5, 0.5, 0.5, 0.0), mask: [true, false, false, false] }];
        let (color, _) = in_drawing_order(&frame, &mut hits()[..1].to_vec(), Vec4::ZERO, 1.0);
        assert_eq!(color, Vec4::new(0.5, 0.6, 1.0, 1.0));
        assert_eq!(cleared_only(&frame, Vec4::ONE), Vec4::new(0.5, 1.0, 1.0, 1.0));
    }

    #[test]
    fn a_depth_clear_between_draws_starts_the_depth_test_again() {
        // A near red fragment, a depth clear, then a farther green one: green lands over red,
        // with its own depth; with the clear after both, the pixel keeps green at depth 1.
        let hit = |sequence: u32, t: f32| Hit {
            id: TriangleId { instance: 0, index: 0 },
            t,
            sequence,
            normal: Vec3::Z,
            uv: Default::default(),
        };
        let fragment = |color: Vec4, depth: f64| Fragment { color, depth, eye: DVec3::ZERO, surface: 0 };
        let (red, green) = (Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 1.0, 0.0, 1.0));
        let mut frame = Frame { surfaces: vec![Surface::depth_tested()], ..Frame::default() };
        let hits = || vec![(hit(0, 1.0), fragment(red, 0.3)), (hit(1, 2.0), fragment(green, 0.6))];
        assert_eq!(in_drawing_order(&frame, &mut hits(), Vec4::ZERO, 1.0), (red, 0.3));
        let clear = |before: u32, depth: f32| DepthClear { before, depth };
        frame.depth_clears = vec![clear(1, 1.0)];
        assert!(!closest_hit_suffices(&frame));
        assert_eq!(in_drawing_order(&frame, &mut hits(), Vec4::ZERO, 1.0), (green, 0.6));
        frame.depth_clears = vec![clear(1, 1.0), clear(2, 1.0)];
        assert_eq!(in_drawing_order(&frame, &mut hits(), Vec4::ZERO, 1.0), (green, 1.0));
        // Cleared to 0.5 (glClearDepth): green, at 0.6, fails against it; after both, the last
        // clear's depth stands.
        frame.depth_clears = vec![clear(1, 0.5)];
        assert_eq!(in_drawing_order(&frame, &mut hits(), Vec4::ZERO, 1.0), (red, 0.5));
        frame.depth_clears = vec![clear(1, 1.0), clear(2, 0.25), clear(2, 0.75)];
        assert_eq!(in_drawing_order(&frame, &mut hits(), Vec4::ZERO, 1.0), (green, 0.75));
    }
}
