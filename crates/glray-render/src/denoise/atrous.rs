//! The spatial half of denoising: an edge-aware à-trous wavelet filter (Dammertz et al. 2010,
//! with SVGF's variance-guided weight, Schied et al. 2017). Five passes of a 3x3 kernel whose
//! taps spread out twice as far each pass (1, 2, 4, 8, 16 pixels): a wide blur for the cost of
//! 45 taps a pixel. A tap counts only as far as it lies on the same surface: on the pixel's
//! plane (within its own pixel footprint times the spread), facing the same way, on the same
//! object, and with an AO value the pixel's own noise could explain. The noise is known, not
//! estimated: one pass's value is the share of `rays` AO rays that hit, a binomial mean, so its
//! variance is m (1 - m) / rays, divided by the passes averaged; the filter narrows itself as
//! the passes add up, and a still scene's average converges to the unfiltered one.

use std::ops::Range;

use glam::{Vec3, Vec4};
use glray_scene::camera::Camera;
use rayon::prelude::*;

use super::temporal::{Averaged, Motion, Rows};
use super::AoPixel;

/// The passes of the kernel, each twice as wide as the one before.
const LEVELS: u32 = 5;

/// How many rows above and below a pixel the filter reads, all levels together: 1 + 2 + 4 + 8
/// + 16.
pub const FILTER_REACH: usize = (1 << LEVELS) - 1;

/// How many rows above and below a pixel `neighbourhood` reads: its two passes, 1 + 2.
pub const NEAR_REACH: usize = 3;

/// The rows a pass with taps `step` rows apart can work out from rows `known` of a frame of
/// `height` rows: all but `step` rows at each end, except at the frame's own edges (where the
/// taps beyond are left out, not read).
pub fn within(known: &Range<usize>, step: usize, height: usize) -> Range<usize> {
    let start = if known.start == 0 { 0 } else { known.start + step };
    let end = if known.end >= height { height } else { known.end.saturating_sub(step) };
    start..end.max(start)
}

/// How many standard deviations of a pixel's noise a neighbour's value may differ by and still
/// count fully (SVGF's sigma_l).
const VALUE_SIGMA: f32 = 4.0;

/// What guides the filter, a plane per quantity (structure of arrays: the kernel's loops run
/// along a row, and the compiler makes them SIMD, four or eight pixels a step).
pub struct Guides {
    eye: [Vec<f32>; 3],
    normal: [Vec<f32>; 3],
    /// n . eye: the pixel's plane.
    plane: Vec<f32>,
    /// The pixel's object (`Motion::object`: an instance's index, exact as a float up to 2^24;
    /// -1 for the frame's own triangles): compared four at a time as floats.
    object: Vec<f32>,
    /// 1 / the pixel's width at its point (eye units).
    per_size: Vec<f32>,
    /// 1 where the pixel has a surface, else 0.
    valid: Vec<f32>,
}

impl Guides {
    /// The guides of the pixels of `layer`, seen by `camera`, its objects those of `motion`.
    pub fn new(layer: &[AoPixel], camera: &Camera, motion: &Motion) -> Guides {
        let valid: Vec<f32> = layer.iter().map(|a| if a.is_surface() { 1.0 } else { 0.0 }).collect();
        let plane_of = |f: fn(&Vec3) -> f32, of_normal: bool| -> Vec<f32> {
            layer.iter().map(|a| f(if of_normal { &a.normal } else { &a.eye })).collect()
        };
        Guides {
            eye: [plane_of(|v| v.x, false), plane_of(|v| v.y, false), plane_of(|v| v.z, false)],
            normal: [plane_of(|v| v.x, true), plane_of(|v| v.y, true), plane_of(|v| v.z, true)],
            plane: layer.iter().map(|a| a.normal.dot(a.eye)).collect(),
            object: layer
                .iter()
                .map(|a| match motion.object(a.object) {
                    glray_scene::frame::TriangleId::FLAT => -1.0,
                    o => o as f32,
                })
                .collect(),
            per_size: layer
                .par_iter()
                .zip(&valid)
                .map(
                    |(a, &v)| if v > 0.0 { 1.0 / (camera.pixel_size(a.eye.as_dvec3()) as f32).max(1e-12) } else { 0.0 },
                )
                .collect(),
            valid,
        }
    }
}

/// Each pixel's value (`values`: 0 where there is no surface) averaged over its neighbourhood
/// on the same surface (two passes of the kernel, weighed by the surfaces alone): what this
/// frame alone says the AO around a pixel is, where one pixel's few rays cannot. The buffers
/// hold the rows from `at.first`; the averages are worked out for the rows they allow
/// (`within` them, twice).
pub fn neighbourhood(g: &Guides, values: &[f32], width: usize, at: Rows) -> Vec<f32> {
    let n = values.len();
    let (mut near, mut once) = (vec![0.0; n], vec![0.0; n]);
    let (ignored, mut spare) = (vec![0.0; n], vec![0.0; n]);
    let known = at.first..at.first + n / width.max(1);
    let first = within(&known, 1, at.height);
    pass(g, [values, &ignored], [&mut once, &mut spare], width, 1, false, at, &first);
    pass(g, [&once, &ignored], [&mut near, &mut spare], width, 2, false, at, &within(&first, 2, at.height));
    near
}

/// The filtered fraction hidden of each pixel of rows `out` (NaN where there is no surface),
/// from its average over frames (`averaged`, known for the rows `out` and `FILTER_REACH` rows
/// around them), and `near`, this frame's AO around it (`neighbourhood`), which says how noisy
/// a pass is there: a binomial mean's variance p (1 - p) / rays (a pixel's own value is too
/// noisy to say it: one none of whose few rays hit would count as certain, and keep its
/// speckle), with a floor, over the passes averaged. The buffers hold the rows from
/// `at.first`.
pub fn filter(
    g: &Guides,
    averaged: &[Averaged],
    near: &[f32],
    width: usize,
    rays: u32,
    at: Rows,
    out: Range<usize>,
) -> Vec<f32> {
    let rays = rays as f32;
    let n = averaged.len();
    let mut mean: Vec<f32> = averaged.iter().zip(&g.valid).map(|(m, &v)| if v > 0.0 { m.mean } else { 0.0 }).collect();
    let mut variance: Vec<f32> = near
        .iter()
        .zip(averaged)
        .map(|(p, m)| {
            let p = p.clamp(0.0, 1.0);
            (p * (1.0 - p) + 0.25 / rays) / (rays * m.count.max(1.0))
        })
        .collect();
    let (mut next_mean, mut next_variance) = (vec![0.0; n], vec![0.0; n]);
    // Each level works out fewer rows: the last, `out`.
    let mut known = out.start.saturating_sub(FILTER_REACH)..(out.end + FILTER_REACH).min(at.height);
    for level in 0..LEVELS {
        known = within(&known, 1 << level, at.height);
        pass(g, [&mean, &variance], [&mut next_mean, &mut next_variance], width, 1 << level, true, at, &known);
        std::mem::swap(&mut mean, &mut next_mean);
        std::mem::swap(&mut variance, &mut next_variance);
    }
    debug_assert!(known.start <= out.start && known.end >= out.end, "{known:?} covers {out:?}");
    let rows = (out.start - at.first) * width..(out.end - at.first) * width;
    mean[rows.clone()].iter().zip(&g.valid[rows]).map(|(&m, &v)| if v > 0.0 { m } else { f32::NAN }).collect()
}

/// e^-x for x >= 0 (four at a time), near enough for weights: (1 + x/8)^-8 (three squarings
/// and a division; within 0.03 of it everywhere, and 0 as it should be far out).
#[inline(always)]
fn falloff4(x: Vec4) -> Vec4 {
    let a = Vec4::ONE + x * 0.125;
    let a2 = a * a;
    let a4 = a2 * a2;
    Vec4::ONE / (a4 * a4)
}

/// How sharply the weight falls with the angle between normals (four at a time): cos^32
/// (facets of a 32-sided cylinder, 11 degrees apart, still count half), as five squarings.
#[inline(always)]
fn along4(cos: Vec4) -> Vec4 {
    let c2 = cos * cos;
    let c4 = c2 * c2;
    let c8 = c4 * c4;
    let c16 = c8 * c8;
    c16 * c16
}

/// One pass of the kernel with taps `step` pixels apart, from `from` (means, variances) into
/// `to`, for the rows `rows` of a frame (the buffers hold the rows from `at.first`: those of
/// `rows`, and `step` rows each side within the frame); `by_value`: weighing taps by how far
/// their value is from the pixel's too (else by the surfaces alone). Each row: for each of the
/// nine taps, a loop along the row adding that tap's weighted value to every pixel's sums,
/// without branches (a tap off the surface weighs 0).
#[allow(clippy::too_many_arguments)]
fn pass(
    g: &Guides,
    from: [&[f32]; 2],
    to: [&mut [f32]; 2],
    width: usize,
    step: usize,
    by_value: bool,
    at: Rows,
    rows: &Range<usize>,
) {
    const KERNEL: [f32; 3] = [0.25, 0.5, 0.25];
    let [mean, variance] = from;
    let [to_mean, to_variance] = to;
    let height = at.height;
    to_mean.par_chunks_mut(width.max(1)).zip(to_variance.par_chunks_mut(width.max(1))).enumerate().for_each(
        |(k, (out_mean, out_variance))| {
            // (`y` the frame's row, `k` the buffers'.)
            let y = at.first + k;
            if !rows.contains(&y) {
                return;
            }
            let row = k * width..(k + 1) * width;
            let (row_mean, pv) = (&mean[row.clone()], &g.valid[row.clone()]);
            // Only the row's pixels from its first surface to its last are filtered (most of a
            // small program's window is background).
            let (Some(first), Some(last)) = (pv.iter().position(|&v| v > 0.0), pv.iter().rposition(|&v| v > 0.0))
            else {
                out_mean.fill(0.0);
                out_variance.fill(0.0);
                return;
            };
            let per_tolerance: Vec<f32> = if by_value {
                variance[row.clone()].iter().map(|v| 1.0 / (VALUE_SIGMA * v.sqrt() + 1e-4)).collect()
            } else {
                vec![0.0; width]
            };
            let per_reach: Vec<f32> = g.per_size[row.clone()].iter().map(|s| s / step as f32).collect();
            let (mut sum, mut weights, mut spread) = (vec![0.0f32; width], vec![0.0f32; width], vec![0.0f32; width]);
            for (j, ky) in KERNEL.iter().enumerate() {
                let qy = y as isize + (j as isize - 1) * step as isize;
                if qy < 0 || qy >= height as isize {
                    continue;
                }
                // (Within the buffers: `rows` leaves room for the taps.)
                let qk = qy as usize - at.first;
                for (i, kx) in KERNEL.iter().enumerate() {
                    let dx = (i as isize - 1) * step as isize;
                    // The pixels x whose tap x + dx lies in the row.
                    let (x0, x1) = ((-dx).max(0) as usize, (width as isize - dx.max(0)).max(0) as usize);
                    let (x0, x1) = (x0.max(first), x1.min(last + 1));
                    if x0 >= x1 {
                        continue;
                    }
                    let q0 = (qk * width) as isize + x0 as isize + dx;
                    let q = q0 as usize..q0 as usize + (x1 - x0);
                    let p = k * width + x0..k * width + x1;
                    let k = kx * ky;
                    let (qm, qv, qvalid, qobj) =
                        (&mean[q.clone()], &variance[q.clone()], &g.valid[q.clone()], &g.object[q.clone()]);
                    let [qex, qey, qez] = [&g.eye[0][q.clone()], &g.eye[1][q.clone()], &g.eye[2][q.clone()]];
                    let [qnx, qny, qnz] = [&g.normal[0][q.clone()], &g.normal[1][q.clone()], &g.normal[2][q.clone()]];
                    let [nx, ny, nz] = [&g.normal[0][p.clone()], &g.normal[1][p.clone()], &g.normal[2][p.clone()]];
                    let (plane, obj) = (&g.plane[p.clone()], &g.object[p.clone()]);
                    let n = x1 - x0;
                    let (pm, per_reach, per_tolerance) =
                        (&row_mean[x0..x1], &per_reach[x0..x1], &per_tolerance[x0..x1]);
                    let (sum, weights, spread) = (&mut sum[x0..x1], &mut weights[x0..x1], &mut spread[x0..x1]);
                    // Four pixels a step (glam's Vec4 is an SSE register), then the rest one by one.
                    let v = |s: &[f32], t: usize| Vec4::from_slice(&s[t..t + 4]);
                    let mut t = 0;
                    while t + 4 <= n {
                        let facing =
                            (v(nx, t) * v(qnx, t) + v(ny, t) * v(qny, t) + v(nz, t) * v(qnz, t)).max(Vec4::ZERO);
                        let off_plane =
                            (v(nx, t) * v(qex, t) + v(ny, t) * v(qey, t) + v(nz, t) * v(qez, t) - v(plane, t)).abs()
                                * v(per_reach, t);
                        let off_value = (v(pm, t) - v(qm, t)).abs() * v(per_tolerance, t);
                        let same = Vec4::select(v(obj, t).cmpeq(v(qobj, t)), v(qvalid, t), Vec4::ZERO);
                        let w = k * same * along4(facing) * falloff4(off_plane + off_value);
                        (v(sum, t) + w * v(qm, t)).write_to_slice(&mut sum[t..t + 4]);
                        (v(weights, t) + w).write_to_slice(&mut weights[t..t + 4]);
                        (v(spread, t) + w * w * v(qv, t)).write_to_slice(&mut spread[t..t + 4]);
                        t += 4;
                    }
                    for t in t..n {
                        let facing = (nx[t] * qnx[t] + ny[t] * qny[t] + nz[t] * qnz[t]).max(0.0);
                        let off_plane =
                            (nx[t] * qex[t] + ny[t] * qey[t] + nz[t] * qez[t] - plane[t]).abs() * per_reach[t];
                        let off_value = (pm[t] - qm[t]).abs() * per_tolerance[t];
                        let same = if obj[t] == qobj[t] { qvalid[t] } else { 0.0 };
                        let w =
                            k * same * along4(Vec4::splat(facing)).x * falloff4(Vec4::splat(off_plane + off_value)).x;
                        sum[t] += w * qm[t];
                        weights[t] += w;
                        spread[t] += w * w * qv[t];
                    }
                }
            }
            for x in 0..width {
                // A pixel with a surface weighs itself 1/4 at most: its own plane and value (a
                // rounding off its own plane can weigh it down to nothing where a pixel's width
                // is tiny, and then it keeps its value).
                if pv[x] > 0.0 && (weights[x].is_nan() || weights[x] <= 1e-6) {
                    out_mean[x] = row_mean[x];
                    out_variance[x] = variance[k * width + x];
                } else if pv[x] > 0.0 {
                    out_mean[x] = sum[x] / weights[x];
                    out_variance[x] = spread[x] / (weights[x] * weights[x]);
                } else {
                    (out_mean[x], out_variance[x]) = (0.0, 0.0);
                }
            }
        },
    );
}
