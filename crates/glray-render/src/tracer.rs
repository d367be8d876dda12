//! The work of one pixel: its samples, each a camera ray resolved the way the rasterizer would
//! (the closest hit, or every hit in drawing order when blending, alpha or depth state asks for
//! it), and at each surface the effects: shadows, ambient occlusion, reflections.

use std::cell::Cell;

use glam::{DVec3, Vec2, Vec3, Vec4, Vec4Swizzles};
use glray_scene::camera::{Camera, Ray as EyeRay};
use glray_scene::frame::{Frame, TriangleId};
use glray_scene::lighting::Light;
use glray_scene::triangle::Triangle;
use obvhs::ray::Ray;

use crate::denoise::AoPixel;
use crate::effects::{lit_by, occlusion};
use crate::fragment::{shade, Fragment};
use crate::gouraud::{Corners, Gouraud};
use crate::offset::{leaving, Origin};
use crate::options::Options;
use crate::recent::Recent;
use crate::resolve::{cleared_only, in_drawing_order, offset_depth, opaque, resolve_in_order};
use crate::sampling::{stratified, Sampler};
use crate::scene::{Hit, Scene};
use crate::smooth::{mirror, reflectance, Smooth};

/// What a frame's pixels share.
pub(crate) struct Tracer<'a> {
    pub frame: &'a Frame,
    pub camera: &'a Camera,
    pub scene: &'a Scene<'a>,
    pub options: &'a Options,
    /// The closest hit decides every pixel (no blending, alpha test or unusual depth state).
    pub simple: bool,
    /// Even the closest hit is depth tested against what the buffer held
    /// (`Frame::depth_starts_near`, worked out once a frame).
    pub depth_starts_near: bool,
    /// How far secondary rays start off a surface, and how far occluders count.
    pub eps: f32,
    pub ao_distance: f32,
    /// The progressive-refinement pass: which samples this frame takes.
    pub pass: u32,
    /// Which frame of a denoised sequence (0: not denoised): mixed into the samples' seeds, so
    /// that frames the denoiser averages take other AO rays even when all are pass 0.
    pub seed: u32,
    /// The hits shaded the short way, when the frame asks for the GL look alone.
    pub gouraud: Option<Gouraud>,
    /// Ambient occlusion is left out of the colours and kept apart for the denoiser
    /// (`Scratch::ao`).
    pub split_ao: bool,
}

/// `AoPixel::object` as `surface` leaves it: the object of the hit it shaded, which the caller
/// knows and fills in (`of_hit`).
const HIT_OBJECT: u32 = u32::MAX - 1;

/// `a`, its object filled in with `instance` where it is the hit's own (`HIT_OBJECT`).
fn of_hit(a: AoPixel, instance: u32) -> AoPixel {
    AoPixel { object: if a.object == HIT_OBJECT { instance } else { a.object }, ..a }
}

/// How close (in pixels' widths at its depth) a line or point lies to a surface to show that
/// surface's AO: edges drawn on a mesh, a grid a hair above the ground.
const ON_SURFACE: f64 = 4.0;

/// Per-thread buffers, reused from pixel to pixel, and the rays traced (for the statistics).
#[derive(Default)]
pub(crate) struct Scratch {
    hits: Vec<Hit>,
    frags: Vec<(Hit, Fragment)>,
    /// The AO each of `frags` kept apart (with `Tracer::split_ao`), in the order they were
    /// made, and for each place of `frags` once resolving sorted them, where it was made.
    frag_ao: Vec<Option<AoPixel>>,
    made_at: Vec<usize>,
    /// `frags`' colours before AO darkens them, for resolving a blended pixel again.
    colors: Vec<Vec4>,
    pub rays: Cell<u64>,
    /// What recent camera rays' triangles were made into: whole triangles, and the corners'
    /// colours of those shaded the short way (`Gouraud`).
    triangles: Recent<Triangle>,
    corners: Recent<Corners>,
    /// With `Tracer::split_ao`: the AO of the sample being traced, then (after `pixel`) of the
    /// whole pixel.
    ao: Cell<Option<AoPixel>>,
}

impl Scratch {
    /// The AO `pixel` kept apart for the pixel it last traced (with `Tracer::split_ao`).
    pub fn take_ao(&self) -> Option<AoPixel> {
        self.ao.take()
    }
}

/// Adds `n` rays to a thread's count (for the statistics).
pub(crate) fn count(rays: &Cell<u64>, n: u64) {
    rays.set(rays.get() + n);
}

impl Tracer<'_> {
    /// Pixel (x, y) over what it held (`under`, `depth_under`): its colour and, when a surface
    /// covers its centre, its depth; None when no sample hit anything (it keeps what it held).
    /// `center`: the closest hit of the ray through the pixel's centre, when `centers` found it.
    pub fn pixel(
        &self,
        x: usize,
        y: usize,
        under: Vec4,
        depth_under: f64,
        center: Option<Option<Hit>>,
        s: &mut Scratch,
    ) -> Option<(Vec4, Option<f64>)> {
        let n = self.options.effects.samples.max(1);
        let mut sum = Vec4::ZERO;
        let mut depth = None;
        let mut any = false;
        // With the AO kept apart: the first sample's surface, and the samples' AO added up.
        let (mut first, mut hidden, mut hits, mut lit) = (None, 0.0f32, 0u32, Vec3::ZERO);
        for i in 0..n {
            s.ao.set(None);
            let k = self.pass * n + i;
            let mut sampler = match self.seed {
                0 => Sampler::new(&[x as u32, y as u32, k]),
                seed => Sampler::new(&[x as u32, y as u32, k, seed]),
            };
            // The first sample of all at the pixel centre: exactly where GL samples.
            let at = if k == 0 { Vec2::splat(0.5) } else { stratified(i, n, sampler.next2()) };
            let known = if k == 0 { center } else { None };
            match self.sample(
                x as f64 + at.x as f64,
                y as f64 + at.y as f64,
                under,
                depth_under,
                known,
                &mut sampler,
                s,
            ) {
                Some((c, d)) => {
                    any = true;
                    sum += c;
                    if i == 0 {
                        depth = Some(d);
                    }
                }
                None => sum += under,
            }
            if let Some(a) = s.ao.take() {
                first = first.or(Some(a));
                hidden += a.hidden;
                hits += 1;
                lit += a.lit;
            }
        }
        // The hidden fraction of the samples that hit; what it darkens, of all the samples
        // (those that missed add nothing to darken).
        s.ao.set(first.map(|a| AoPixel { hidden: hidden / hits as f32, lit: lit / n as f32, ..a }));
        any.then(|| (sum / n as f32, depth))
    }

    /// The camera ray `r` as traced (in single precision, with its reciprocal direction).
    fn traced(r: &EyeRay) -> Ray {
        // GL keeps what lies exactly on the near and far planes (backgrounds are often drawn at
        // z = 1): a hair of slack keeps float rounding from dropping them.
        let slack = (r.t_max * 1e-4) as f32;
        crate::bvh::ray(r.origin.as_vec3a(), r.direction.as_vec3a(), -slack, r.t_max as f32 + slack)
    }

    /// Starts loading what shading a hit on triangle `id` reads (see `Frame::prefetch_triangle`):
    /// `vertices` false, the triangle or its vertex indices; true, its vertices.
    #[inline]
    pub fn prefetch(&self, id: TriangleId, vertices: bool) {
        let positions = self.gouraud.as_ref().is_none_or(|g| g.reads_positions(id));
        self.scene.prefetch_triangle(id, vertices, positions);
    }

    /// The closest hits of the rays through the centres of `N` neighbouring pixels (a
    /// multiple of four), traced together into `hits`, when the closest hit is what decides a
    /// pixel's first sample (false otherwise, `hits` untouched).
    pub fn centers<const N: usize>(&self, pixels: &[(usize, usize); N], hits: &mut [Option<Hit>; N]) -> bool {
        if !self.simple || self.pass != 0 {
            return false;
        }
        let rays = self.camera.rays(&pixels.map(|(x, y)| (x as f64 + 0.5, y as f64 + 0.5))).map(|r| Self::traced(&r));
        self.scene.closest_packet(&rays, hits);
        true
    }

    /// One camera ray through window position (px, py); `known`, its closest hit if found
    /// already.
    #[allow(clippy::too_many_arguments)]
    fn sample(
        &self,
        px: f64,
        py: f64,
        under: Vec4,
        depth_under: f64,
        known: Option<Option<Hit>>,
        sampler: &mut Sampler,
        s: &mut Scratch,
    ) -> Option<(Vec4, f64)> {
        count(&s.rays, 1);
        if self.simple && matches!(known, Some(None)) {
            // Known to miss (most pixels of many frames): no ray to make again.
            return None;
        }
        // The eye ray in double precision, for where the hit is; traced again only when its
        // hits are not known already.
        let r = self.camera.ray(px, py);
        let at = |hit: &Hit| r.origin + r.direction * hit.t as f64;
        if self.simple {
            let hit = match known {
                Some(hit) => hit,
                None => self.scene.closest(Self::traced(&r)),
            }?;
            let f = match &self.gouraud {
                Some(g) if g.takes(hit.id) => {
                    g.fragment(self.scene, self.camera, &hit, at(&hit), r.direction, &mut s.corners)?
                }
                _ => {
                    let t = s.triangles.get(hit.id, || self.scene.triangle(hit.id))?;
                    let split = self.split_ao.then_some(&s.ao);
                    let f = self.surface(t, at(&hit), r.direction, sampler, &s.rays, split, 0);
                    if let Some(a) = s.ao.get() {
                        s.ao.set(Some(of_hit(a, hit.id.instance)));
                    }
                    f
                }
            };
            // Over the last frame (no clear), or a depth cleared nearer than the far plane, the
            // closest hit is depth tested too.
            if self.depth_starts_near && f.depth >= depth_under {
                return None;
            }
            return Some((opaque(&f), f.depth));
        }
        self.scene.all(Self::traced(&r), &mut s.hits);
        if s.hits.is_empty() {
            // No fragment; a depth clear between draws still leaves its depth, a masked colour
            // clear its channels.
            if !self.frame.masked_clears.is_empty() {
                let depth = self.frame.depth_clears.last().map_or(depth_under, |c| c.depth as f64);
                return Some((cleared_only(self.frame, under), depth));
            }
            return self.frame.depth_clears.last().map(|c| (under, c.depth as f64));
        }
        s.hits.sort_by(|a, b| a.sequence.cmp(&b.sequence).then(a.t.total_cmp(&b.t)).then(a.id.cmp(&b.id)));
        s.frags.clear();
        s.frag_ao.clear();
        let split = self.split_ao;
        let mut last: Option<(Hit, [Vec3; 3])> = None;
        for hit in &s.hits {
            let Some(t) = self.scene.triangle(hit.id) else { continue };
            // A ray through an edge two triangles of a draw share hits both; the rasterizer's
            // fill rule gives the pixel to one of them.
            if last.is_some_and(|(a, corners)| edge_twin(&a, &corners, hit, &t.positions)) {
                continue;
            }
            last = Some((*hit, t.positions));
            let p = on_plane(&r, &t.positions).unwrap_or_else(|| at(hit));
            s.ao.set(None);
            let mut f = self.surface(&t, p, r.direction, sampler, &s.rays, split.then_some(&s.ao), 0);
            if let Some(offset) = self.frame.surfaces[f.surface as usize].polygon_offset {
                f.depth = offset_depth(self.camera, &t, f.depth, offset);
            }
            s.frags.push((*hit, f));
            s.frag_ao.push(s.ao.take().map(|a| of_hit(a, hit.id.instance)));
        }
        if !split {
            return Some(in_drawing_order(self.frame, &mut s.frags, under, depth_under));
        }
        // Where each fragment lands once `resolve_in_order` sorts them (by draw, stably: the
        // same sort), so that the one it names as the last writer finds its AO.
        s.made_at.clear();
        s.made_at.extend(0..s.frags.len());
        let frags = &s.frags;
        s.made_at.sort_by_key(|&k| (frags[k].0.sequence, frags[k].0.id));
        let resolved = resolve_in_order(self.frame, &mut s.frags, under, depth_under);
        if !resolved.mixed {
            // The last fragment's colour is the pixel's: its AO is the pixel's, to denoise.
            s.ao.set(resolved.last.and_then(|k| s.frag_ao[s.made_at[k]]));
            return Some((resolved.color, resolved.depth));
        }
        // Fragments blended (a translucent overlay over the scene, an antialiased line's edge):
        // the pixel's AO is that of the fragment whose AO darkens it most, denoised as any
        // pixel's, with the share of the pixel's colour it darkens found by resolving the pixel
        // with that fragment fully hidden (blending is linear in it). The others are darkened by
        // their own AO, as without denoising.
        let intensity = self.options.effects.ao_intensity;
        if intensity <= 0.0 {
            s.ao.set(None);
            return Some((resolved.color, resolved.depth));
        }
        s.colors.clear();
        s.colors.extend(s.frags.iter().map(|(_, f)| f.color));
        let darkened = |s: &mut Scratch, hidden: &dyn Fn(usize, &AoPixel) -> f32| {
            for (k, (_, f)) in s.frags.iter_mut().enumerate() {
                f.color = s.colors[k];
                if let Some(a) = s.frag_ao[s.made_at[k]] {
                    f.color = a.darken(f.color, hidden(k, &a), intensity);
                }
            }
            resolve_in_order(self.frame, &mut s.frags, under, depth_under)
        };
        // Which fragment's AO counts most: the one that darkens the pixel most when hidden.
        let mut most: Option<(usize, f32)> = None;
        for j in 0..s.frags.len() {
            if s.frag_ao[s.made_at[j]].is_some() {
                let c = darkened(s, &|k, _| if k == j { 1.0 } else { 0.0 }).color;
                let share = (resolved.color - c).truncate().element_sum();
                if share > most.map_or(1e-6, |(_, m)| m) {
                    most = Some((j, share));
                }
            }
        }
        let others = |j: Option<usize>| move |k: usize, a: &AoPixel| if Some(k) == j { 0.0 } else { a.hidden };
        let Some((j, _)) = most else {
            s.ao.set(None);
            let again = darkened(s, &others(None));
            return Some((again.color, again.depth));
        };
        let hidden = darkened(s, &|k, a| if k == j { 1.0 } else { a.hidden }).color;
        let again = darkened(s, &others(Some(j)));
        let lit = ((again.color - hidden).truncate() / intensity).max(Vec3::ZERO);
        s.ao.set(s.frag_ao[s.made_at[j]].map(|a| AoPixel { lit, ..a }));
        Some((again.color, again.depth))
    }

    /// The surface a line or point (of draw `line`) seen at `p` along `dir` lies on: the
    /// nearest hit of another kind of draw within `ON_SURFACE` pixels' widths before or behind
    /// it (a line is drawn on a surface or a hair off it), as where AO rays start and its
    /// object. None for a line in the open.
    fn beneath(&self, line: u32, p: DVec3, dir: DVec3) -> Option<(Origin, u32)> {
        let d = dir.normalize_or_zero();
        let reach = ON_SURFACE * self.camera.pixel_size(p);
        if reach <= 0.0 || d == DVec3::ZERO {
            return None;
        }
        let start = p - d * reach;
        let mut hits = Vec::new();
        let ray = crate::bvh::ray(start.as_vec3a(), d.as_vec3a(), 0.0, (2.0 * reach) as f32);
        self.scene.all(ray, &mut hits);
        let hit = hits
            .iter()
            .filter(|h| !self.scene.is_line(h.sequence))
            .min_by(|a, b| (a.t as f64 - reach).abs().total_cmp(&(b.t as f64 - reach).abs()))?;
        let t = self.scene.triangle(hit.id)?;
        let n = facet_facing(&t, d.as_vec3());
        let at = (start + d * hit.t as f64).as_vec3();
        // The AO rays start as from the line's own draw: its solids (a hair above the surface,
        // as thick as on the screen) would hide most of the sky otherwise.
        Some((Origin { p: at, n, draw: line }, hit.id.instance))
    }

    /// The fragment of triangle `t` at eye-space point `p`, reached along `dir`, with the
    /// effects: shadows, ambient occlusion (first surfaces only; kept apart in `split` rather
    /// than darkening the colour, when given), reflections up to the depth.
    #[allow(clippy::too_many_arguments)]
    fn surface(
        &self,
        t: &Triangle,
        p: DVec3,
        dir: DVec3,
        sampler: &mut Sampler,
        rays: &Cell<u64>,
        split: Option<&Cell<Option<AoPixel>>>,
        bounce: u32,
    ) -> Fragment {
        let e = &self.options.effects;
        let n = facet_facing(t, dir.as_vec3());
        let from = Origin { p: p.as_vec3(), n, draw: t.sequence };
        // Shadow and mirror rays follow the smooth surface a lit mesh's normals describe, not
        // its flat facets (`smooth`): they leave from the point lifted onto it.
        let reflects = bounce < e.reflections && e.reflectivity > 0.0;
        let smooth = if e.shadows || reflects { Smooth::at(t, p, n) } else { None };
        let lifted = smooth.as_ref().map(|s| Origin { p: s.lifted().as_vec3(), ..from });
        let leave = lifted.as_ref().unwrap_or(&from);
        let reaches = |light: &Light| {
            count(rays, 1);
            lit_by(self.scene, leave, light, self.eps)
        };
        let visible: Option<&dyn Fn(&Light) -> f32> = if e.shadows { Some(&reaches) } else { None };
        let mut f = shade(self.frame, self.camera, t, p, self.options.per_pixel_lighting, visible);
        if e.ao_samples > 0 && bounce == 0 {
            count(rays, e.ao_samples as u64);
            // A line or point has no hemisphere of its own: lying on a surface, it shows that
            // surface's AO, as if drawn onto it.
            let beneath = if self.scene.is_line(t.sequence) { self.beneath(t.sequence, p, dir) } else { None };
            let (at, object) = match &beneath {
                Some((o, object)) => (o, *object),
                None => (&from, HIT_OBJECT),
            };
            let hidden = occlusion(self.scene, at, e.ao_samples, self.ao_distance, self.eps, sampler);
            match split {
                // What AO darkens: the surface's own colour, not what it reflects (below).
                Some(ao) => ao.set(Some(AoPixel { eye: at.p, normal: at.n, object, hidden, lit: f.color.xyz() })),
                None => {
                    let keep = 1.0 - e.ao_intensity * hidden;
                    f.color = (f.color.xyz() * keep).extend(f.color.w);
                }
            }
        }
        if reflects {
            let d = dir.as_vec3().normalize_or_zero();
            let reflected = mirror(d, n, smooth.as_ref().and_then(Smooth::normal));
            let ray = leaving(leave.p, n, reflected, self.eps, f32::INFINITY);
            count(rays, 1);
            let seen = match self.scene.closest(ray).and_then(|h| Some((h, self.scene.triangle(h.id)?))) {
                Some((hit, t2)) => {
                    let p2 = (Vec3::from(ray.origin) + reflected * hit.t).as_dvec3();
                    self.surface(&t2, p2, reflected.as_dvec3(), sampler, rays, None, bounce + 1).color
                }
                None => self.frame.clear_color,
            };
            let r = reflectance(e.reflectivity, d, reflected);
            f.color = (f.color.xyz() * (1.0 - r) + seen.xyz() * r).extend(f.color.w);
            if let Some((ao, a)) = split.and_then(|ao| Some((ao, ao.get()?))) {
                ao.set(Some(AoPixel { lit: a.lit * (1.0 - r), ..a }));
            }
        }
        f
    }
}

/// Triangle `t`'s facet normal, turned to face a ray along `dir`: the side secondary rays leave.
fn facet_facing(t: &Triangle, dir: Vec3) -> Vec3 {
    let [a, b, c] = t.positions;
    let n = (b - a).cross(c - a).normalize_or_zero();
    if n.dot(dir) > 0.0 {
        -n
    } else {
        n
    }
}

/// Where eye ray `r` meets the plane of a triangle's `corners`, in double precision. The
/// walk's distance is single precision, a unit in the last place off: when fragments are
/// resolved in drawing order, two draws in one plane must get the same depth to tie, as GL's
/// interpolated depths do (razzledazzle's sea, drawn depth tested at z = 0 over a ship drawn
/// into the depth buffer at z = 0, came out an ulp nearer and covered it). None when the ray
/// runs along the plane.
fn on_plane(r: &EyeRay, corners: &[Vec3; 3]) -> Option<DVec3> {
    let [a, b, c] = corners.map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a);
    let along = n.dot(r.direction);
    if along.abs() <= 1e-12 * n.length() * r.direction.length() {
        return None;
    }
    let t = n.dot(a - r.origin) / along;
    t.is_finite().then(|| r.origin + r.direction * t)
}

/// Whether hit `b` is hit `a` again, on the other side of an edge: the same draw at the same
/// distance, both on an edge of their triangles (corners `ac`, `bc`), and not the same
/// triangle drawn twice. Two quads drawn over each other in one glBegin (glblur's blur layers,
/// added up with blending) are two fragments each pixel, as in GL; a ray through the diagonal
/// of one quad, or the edge two strip triangles share, is one.
fn edge_twin(a: &Hit, ac: &[Vec3; 3], b: &Hit, bc: &[Vec3; 3]) -> bool {
    // Barycentric weights this close to zero put a hit on an edge: a ray through a shared edge
    // reaches both triangles within the intersection test's rounding.
    const EDGE: f32 = 1e-4;
    let on_edge = |h: &Hit| h.uv.x.min(h.uv.y).min(1.0 - h.uv.x - h.uv.y) <= EDGE;
    let same_triangle = bc.iter().all(|c| ac.contains(c));
    a.sequence == b.sequence
        && (a.t - b.t).abs() <= 1e-5 * a.t.abs().max(1e-3)
        && !same_triangle
        && on_edge(a)
        && on_edge(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_meets_a_triangles_plane_in_double_precision() {
        // Triangles in the plane z = 0 at odd positions, rays from z = 1 at odd pixels (an
        // orthographic camera's): the point lies in the plane to double precision, so two draws
        // in it get one window depth. A ray along the plane meets none.
        let corners = [Vec3::new(-0.5, -0.495_015_4, 0.0), Vec3::new(1.5, 0.655, 0.0), Vec3::new(-0.5, 0.655, 0.0)];
        for k in 0..100 {
            let origin = DVec3::new(0.013 * k as f64 - 0.3, 0.0071 * k as f64 - 0.2, 1.0);
            let r = EyeRay { origin, direction: DVec3::new(0.0, 0.0, -1.0), t_max: 2.0 };
            let p = on_plane(&r, &corners).expect("meets the plane");
            assert!(p.z.abs() < 1e-15, "ray {k}: z {}", p.z);
        }
        let along = EyeRay { origin: DVec3::new(0.0, 0.0, 0.0), direction: DVec3::X, t_max: 2.0 };
        assert_eq!(on_plane(&along, &corners), None);
    }

    #[test]
    fn hits_across_a_shared_edge_are_one_fragment_and_triangles_drawn_twice_two() {
        let hit = |index: u32, u: f32, v: f32| Hit {
            id: TriangleId { instance: TriangleId::FLAT, index },
            t: 2.0,
            sequence: 3,
            normal: Vec3::Z,
            uv: Vec2::new(u, v),
        };
        // A quad's two triangles, sharing the diagonal (0,0)-(1,1).
        let lower = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)];
        let upper = [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        // Through the diagonal: one fragment.
        assert!(edge_twin(&hit(0, 0.5, 0.5), &lower, &hit(1, 0.5, 0.0), &upper));
        // Inside both copies of a triangle drawn twice in one draw: two.
        assert!(!edge_twin(&hit(0, 0.3, 0.3), &lower, &hit(2, 0.3, 0.3), &lower));
        // On the diagonal of a quad drawn twice: the copy of the same triangle is another.
        assert!(!edge_twin(&hit(0, 0.5, 0.5), &lower, &hit(2, 0.5, 0.5), &lower));
        // Overlapping triangles of one draw, at the same depth, inside both: two.
        let small = lower.map(|c| c * 0.5 + Vec3::new(0.25, 0.0, 0.0));
        assert!(!edge_twin(&hit(0, 0.4, 0.2), &lower, &hit(2, 0.3, 0.3), &small));
        // Another draw, or another depth: never the same fragment.
        let other_draw = Hit { sequence: 4, ..hit(1, 0.5, 0.0) };
        assert!(!edge_twin(&hit(0, 0.5, 0.5), &lower, &other_draw, &upper));
        let farther = Hit { t: 2.1, ..hit(1, 0.5, 0.0) };
        assert!(!edge_twin(&hit(0, 0.5, 0.5), &lower, &farther, &upper));
    }

    #[test]
    fn recent_lends_each_id_what_was_made_of_it() {
        // Triangles told apart by their first corner; ids asked in an order that revisits,
        // and (more ids than slots) that makes them share slots.
        let triangle =
            |i: u32| crate::fragment::tests::plain([Vec3::new(i as f32, 0.0, 0.0), Vec3::X, Vec3::Y], [1.0; 3]);
        let frame = Frame { triangles: (0..100).map(triangle).collect(), ..Frame::default() };
        let mut recent = Recent::default();
        let flat = |index: u32| TriangleId { instance: TriangleId::FLAT, index };
        for step in 0..1000u32 {
            let index = (step * 37 + step / 7) % 100;
            let got = recent.get(flat(index), || frame.triangle(flat(index))).copied();
            assert_eq!(got, Some(triangle(index)), "step {step}, triangle {index}");
        }
        // An id past the frame's triangles has none; the next id asked still gets its own.
        assert_eq!(recent.get(flat(100), || frame.triangle(flat(100))), None);
        assert_eq!(recent.get(flat(99), || frame.triangle(flat(99))).copied(), Some(triangle(99)));
    }
}
