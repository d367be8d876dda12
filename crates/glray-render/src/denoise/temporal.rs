//! Averaging a pixel's AO over the frames before, through motion: a surface point a pixel sees
//! now is followed back to where it was in the last frame (an instance's point through the
//! instance's last placement, the frame's own triangles where they are: they are made in eye
//! coordinates every frame), projected with the last camera, and the average kept there is
//! taken on if that pixel saw the same point: the same object, within two pixels of where the
//! point was, the normal turned less than ~25 degrees. Otherwise the pixel starts afresh.
//!
//! A point that is followed can still have changed its AO: something moved near it (a box
//! turning over a floor whose every point stays where it was). So the history is also held to
//! what this frame says: clamped to within a few standard deviations of the AO this frame's
//! pixels around the point show (`near`), and shortened when it had to be clamped (TAA's
//! neighbourhood clamping, by the known binomial noise rather than a measured one).

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

use glam::{DMat4, DVec3, Vec3};
use glray_scene::camera::Camera;
use glray_scene::frame::{Frame, TriangleId};
use rayon::prelude::*;

use super::AoPixel;

/// A frame's objects as the denoiser follows them: each instance's stable id (its mesh, and
/// which drawing of that mesh in the frame it is: glxgears' three gears are three lists) and
/// placement (object to eye). Instances drawn under one transform are one object (the first
/// of them's id and index): a dataset drawn in pieces under one transform (a data-parallel
/// program's ranks each drawing its piece) is then one surface to the denoiser, as it is drawn
/// whole by one process; with an object per piece, AO was not averaged across the pieces'
/// seams, and 1-3 ranks gave pictures 0.8-1.2% apart.
#[derive(Debug, Clone, Default)]
pub struct Motion {
    ids: Vec<u32>,
    placements: Vec<DMat4>,
    /// Each instance's object: the index of the first instance drawn under its transform.
    objects: Vec<u32>,
}

/// The id of the frame's own triangles (`TriangleId::FLAT`).
const FLAT: u32 = u32::MAX;

impl Motion {
    pub fn of(frame: &Frame) -> Motion {
        let mut drawn: HashMap<u64, u32> = HashMap::new();
        let own: Vec<u32> = frame
            .instances
            .iter()
            .map(|i| {
                let n = drawn.entry(i.mesh.id).or_default();
                *n += 1;
                // Never FLAT.
                crate::sampling::hash(&[i.mesh.id as u32, (i.mesh.id >> 32) as u32, *n]).min(FLAT - 1)
            })
            .collect();
        let mut first: HashMap<[u64; 16], u32> = HashMap::new();
        let objects: Vec<u32> = (0..frame.instances.len() as u32)
            .map(|k| *first.entry(frame.instances[k as usize].modelview.to_cols_array().map(f64::to_bits)).or_insert(k))
            .collect();
        Motion {
            ids: objects.iter().map(|&o| own[o as usize]).collect(),
            placements: frame.instances.iter().map(|i| i.modelview).collect(),
            objects,
        }
    }

    /// Instances with these ids and placements (for tests).
    #[cfg(test)]
    pub fn placed(instances: Vec<(u32, DMat4)>) -> Motion {
        let objects = (0..instances.len() as u32).collect();
        let (ids, placements) = instances.into_iter().unzip();
        Motion { ids, placements, objects }
    }

    /// The object `instance` is part of (an index into the frame's instances: the first drawn
    /// under its transform), or `TriangleId::FLAT` for the frame's own triangles.
    pub fn object(&self, instance: u32) -> u32 {
        if instance == TriangleId::FLAT {
            TriangleId::FLAT
        } else {
            self.objects.get(instance as usize).copied().unwrap_or(instance)
        }
    }

    /// The stable id of the object `instance` (an index into the frame's instances, or
    /// `TriangleId::FLAT`).
    pub fn id(&self, instance: u32) -> u32 {
        if instance == TriangleId::FLAT {
            FLAT
        } else {
            self.ids.get(instance as usize).copied().unwrap_or(FLAT)
        }
    }
}

/// About how many pixels' values `atrous::neighbourhood` averages (the inverse of the sum of its
/// squared weights).
const NEIGHBOURS: f32 = 12.0;

/// How many standard deviations of that mean's noise a history may be off before it is clamped.
const CLAMP: f32 = 2.0;

/// The passes a clamped history counts for at most: it was stale.
const CLAMPED: f32 = 2.0;

/// A pixel's average as kept for the next frame (plain bytes: rows of it cross ranks, for
/// the pixels of a band whose points were in another rank's band the frame before).
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Past {
    eye: Vec3,
    normal: Vec3,
    id: u32,
    mean: f32,
    /// The passes averaged (0: no surface).
    count: f32,
}

const NOTHING: Past = Past { eye: Vec3::ZERO, normal: Vec3::ZERO, id: FLAT, mean: 0.0, count: 0.0 };

/// A pixel's AO averaged over frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Averaged {
    pub mean: f32,
    /// The passes in it (0 where there is no surface).
    pub count: f32,
}

/// The last frame's averages, by row (the rows this denoiser worked out, and those fetched for
/// it: a band of a frame shared by MPI ranks holds only the rows around its own), where they
/// were, and its camera and placements.
#[derive(Default)]
pub struct History {
    width: usize,
    height: usize,
    rows: Vec<Option<Arc<[Past]>>>,
    camera: Option<Camera>,
    placements: HashMap<u32, DMat4>,
}

/// Rows of a frame: a part of the frame's pixels, row by row from `first` (buffers of a band
/// and the rows around it), in a frame of `height` rows.
#[derive(Debug, Clone, Copy)]
pub struct Rows {
    pub first: usize,
    pub height: usize,
}

impl History {
    /// Every pixel's AO of rows `followed` averaged with what the last frame had where its
    /// point was (up to `span` passes), kept as the history for the next frame (the rows
    /// held before go). `layer` and `near` are the pixels of the rows from `at.first`, which
    /// cover `followed`; the averages come back in the same rows (NaN outside `followed`).
    /// `near`: this frame's AO around each pixel (`atrous::neighbourhood`), from `rays` rays
    /// per pixel, to hold the history to (None: the scene is still, and the history holds).
    #[allow(clippy::too_many_arguments)]
    pub fn follow(
        &mut self,
        layer: &[AoPixel],
        near: Option<&[f32]>,
        width: usize,
        at: Rows,
        followed: Range<usize>,
        camera: &Camera,
        motion: &Motion,
        span: f32,
        rays: u32,
    ) -> Vec<Averaged> {
        let rays = rays as f32;
        let back = self.back(motion);
        let last = self.last(width, at.height);
        let height = at.height;
        let mut past = vec![NOTHING; layer.len()];
        let mut averaged = vec![Averaged { mean: f32::NAN, count: 0.0 }; layer.len()];
        past.par_chunks_mut(width.max(1)).zip(averaged.par_chunks_mut(width.max(1))).enumerate().for_each(
            |(k, (past_row, out_row))| {
                let y = at.first + k;
                if !followed.contains(&y) {
                    return;
                }
                for x in 0..width {
                    let a = &layer[k * width + x];
                    if !a.is_surface() {
                        continue;
                    }
                    let id = motion.id(a.object);
                    let found = last.and_then(|before| {
                        let (eye, normal) = whence(a, &back)?;
                        self.seen(before, eye, normal.normalize_or_zero(), id, width, height)
                    });
                    let (mean, count) = match found {
                        Some(q) => {
                            // How far this frame's AO around the point may be from the history's
                            // by noise alone: the neighbourhood's mean is over a dozen pixels'.
                            let (before, count) = match near.map(|n| n[k * width + x].clamp(0.0, 1.0)) {
                                Some(p) => {
                                    let sigma = ((p * (1.0 - p) + 0.25 / rays) / (rays * NEIGHBOURS)).sqrt();
                                    let (low, high) = (p - CLAMP * sigma - 0.01, p + CLAMP * sigma + 0.01);
                                    if q.mean < low || q.mean > high {
                                        (q.mean.clamp(low, high), q.count.min(CLAMPED))
                                    } else {
                                        (q.mean, q.count)
                                    }
                                }
                                None => (q.mean, q.count),
                            };
                            let count = (count + 1.0).min(span.max(1.0));
                            (before + (a.hidden - before) / count, count)
                        }
                        None => (a.hidden, 1.0),
                    };
                    past_row[x] = Past { eye: a.eye, normal: a.normal, id, mean, count };
                    out_row[x] = Averaged { mean, count };
                }
            },
        );
        let mut rows: Vec<Option<Arc<[Past]>>> = vec![None; height];
        for y in followed {
            let k = y - at.first;
            rows[y] = Some(Arc::from(&past[k * width..(k + 1) * width]));
        }
        self.rows = rows;
        (self.width, self.height) = (width, height);
        self.camera = Some(camera.clone());
        self.placements = motion.ids.iter().copied().zip(motion.placements.iter().copied()).collect();
        averaged
    }

    /// For each instance, the way from its point now to where it was: the last placement after
    /// the inverse of this one (None: not drawn last frame).
    fn back(&self, motion: &Motion) -> Vec<Option<DMat4>> {
        motion
            .ids
            .iter()
            .zip(&motion.placements)
            .map(|(id, now)| {
                let before = self.placements.get(id)?;
                let inverse = now.inverse();
                inverse.is_finite().then(|| *before * inverse)
            })
            .collect()
    }

    /// The last frame's camera, if its averages are of a frame of this size.
    fn last(&self, width: usize, height: usize) -> Option<&Camera> {
        self.camera.as_ref().filter(|_| self.width == width && self.height == height)
    }

    /// The rows of the last frame that following rows `followed` of `layer` (the pixels of
    /// the rows from `at.first`) reads and this history does not hold: where another rank's
    /// band kept them (`take_rows`).
    pub fn missing(
        &self,
        layer: &[AoPixel],
        width: usize,
        at: Rows,
        followed: Range<usize>,
        motion: &Motion,
    ) -> Vec<Range<usize>> {
        let Some(before) = self.last(width, at.height) else { return Vec::new() };
        let back = self.back(motion);
        let mut wanted = vec![false; at.height];
        for y in followed {
            for a in layer[(y - at.first) * width..(y - at.first + 1) * width].iter().filter(|a| a.is_surface()) {
                // The pixel `seen` reads.
                let Some((eye, _)) = whence(a, &back) else { continue };
                let (x, y) = before.window_position(eye);
                if x >= 0.0 && y >= 0.0 && x < width as f64 && y < at.height as f64 {
                    wanted[y as usize] = true;
                }
            }
        }
        runs(&wanted, |y| self.rows.get(y).is_none_or(Option::is_none))
    }

    /// The last frame's rows from `first` (another rank's), to follow from.
    pub fn take_rows(&mut self, first: usize, past: &[Past]) {
        let width = self.width.max(1);
        for (k, row) in past.chunks_exact(width).enumerate() {
            if let Some(slot) = self.rows.get_mut(first + k) {
                *slot = Some(Arc::from(row));
            }
        }
    }

    /// The rows this history holds, for other ranks to fetch while it is followed (cheap: the
    /// rows are shared).
    pub fn held(&self) -> HeldRows {
        HeldRows { width: self.width, rows: self.rows.clone() }
    }

    /// What the last frame kept at the pixel where eye-space point `eye` (facing `normal`,
    /// on object `id`) was, if that pixel saw it.
    fn seen(&self, camera: &Camera, eye: DVec3, normal: DVec3, id: u32, width: usize, height: usize) -> Option<Past> {
        let (x, y) = camera.window_position(eye);
        if !(x >= 0.0 && y >= 0.0 && x < width as f64 && y < height as f64) {
            return None;
        }
        // (A row not held is a row no rank fetched for this band: `missing` names every row
        // read here, so only a frame traced without them would meet one.)
        let q = *self.rows.get(y as usize)?.as_ref()?.get(x as usize)?;
        let reach = 2.0 * camera.pixel_size(eye) + 1e-6 * eye.length();
        let close = (q.eye.as_dvec3() - eye).length() <= reach;
        (q.count > 0.0 && q.id == id && close && q.normal.as_dvec3().dot(normal) > 0.9).then_some(q)
    }
}

/// Where the point a pixel sees was, and which way it faced, in the last frame's eye space:
/// an instance's point through its motion (None: the instance was not drawn then), the frame's
/// own triangles' where it is.
fn whence(a: &AoPixel, back: &[Option<DMat4>]) -> Option<(DVec3, DVec3)> {
    match a.object {
        TriangleId::FLAT => Some((a.eye.as_dvec3(), a.normal.as_dvec3())),
        i => {
            let m = back.get(i as usize).copied().flatten()?;
            Some((m.transform_point3(a.eye.as_dvec3()), m.transform_vector3(a.normal.as_dvec3())))
        }
    }
}

/// The runs of rows that are `wanted` and `lacking`.
fn runs(wanted: &[bool], lacking: impl Fn(usize) -> bool) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = Vec::new();
    for y in (0..wanted.len()).filter(|&y| wanted[y] && lacking(y)) {
        match out.last_mut() {
            Some(r) if r.end == y => r.end = y + 1,
            _ => out.push(y..y + 1),
        }
    }
    out
}

/// A history's rows as another rank fetches them: shared with the history, unchanged while the
/// next frame is followed.
#[derive(Clone, Default)]
pub struct HeldRows {
    width: usize,
    rows: Vec<Option<Arc<[Past]>>>,
}

impl HeldRows {
    /// Rows `rows`, if all are held.
    pub fn rows(&self, rows: Range<usize>) -> Option<Vec<Past>> {
        let mut out = Vec::with_capacity(rows.len() * self.width);
        for y in rows {
            out.extend_from_slice(self.rows.get(y)?.as_ref()?);
        }
        Some(out)
    }
}
