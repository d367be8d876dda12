use glam::{DMat4, DVec3, Vec3};
use glray_scene::camera::{Camera, Viewport};

use super::temporal::{Averaged, History};
use super::*;
use crate::sampling::Sampler;

const W: usize = 64;

/// An orthographic camera over 64x64 pixels, eye x and y from -1 to 1.
fn camera() -> Camera {
    // glOrtho(-1, 1, -1, 1, 1, 10).
    let projection = DMat4::from_cols_array(&[
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        -2.0 / 9.0,
        0.0,
        0.0,
        0.0,
        -11.0 / 9.0,
        1.0,
    ]);
    Camera::new(projection, Viewport { x: 0, y: 0, width: W as i32, height: W as i32 }, (0.0, 1.0)).unwrap()
}

/// The eye point pixel (x, y) sees on the plane z = -5.
fn eye(x: usize, y: usize) -> Vec3 {
    Vec3::new((x as f32 + 0.5) / W as f32 * 2.0 - 1.0, (y as f32 + 0.5) / W as f32 * 2.0 - 1.0, -5.0)
}

/// A plane facing the camera whose true fraction hidden is `truth(x, y)`, each pixel's value
/// the share of `rays` random rays that hit (seeded by `seed`), on object `object(x, y)`.
fn noisy(
    truth: impl Fn(usize, usize) -> f32,
    object: impl Fn(usize, usize) -> u32,
    rays: u32,
    seed: u32,
) -> Vec<AoPixel> {
    (0..W * W)
        .map(|k| {
            let (x, y) = (k % W, k / W);
            let mut s = Sampler::new(&[x as u32, y as u32, seed]);
            let hits = (0..rays).filter(|_| s.uniform() < truth(x, y)).count();
            AoPixel {
                eye: eye(x, y),
                normal: Vec3::Z,
                object: object(x, y),
                hidden: hits as f32 / rays as f32,
                lit: Vec3::ONE,
            }
        })
        .collect()
}

/// The whole 64x64 frame's rows.
const WHOLE: super::temporal::Rows = super::temporal::Rows { first: 0, height: W };

/// `History::follow` over the whole frame, 16 rays a pixel.
fn follow_all(
    history: &mut History,
    layer: &[AoPixel],
    near: Option<&[f32]>,
    motion: &Motion,
    span: f32,
) -> Vec<Averaged> {
    history.follow(layer, near, W, WHOLE, 0..W, &camera(), motion, span, 16)
}

/// The root-mean-square difference from the truth over the pixels with a surface.
fn rms(values: &[f32], truth: impl Fn(usize, usize) -> f32) -> f32 {
    let sum: f32 = values.iter().enumerate().map(|(k, v)| (v - truth(k % W, k / W)).powi(2)).sum();
    (sum / values.len() as f32).sqrt()
}

#[test]
fn one_noisy_pass_comes_out_close_to_the_truth() {
    let truth = |x: usize, _y: usize| 0.2 + 0.5 * x as f32 / W as f32;
    let layer = noisy(truth, |_, _| TriangleIdFlat::ID, 16, 1);
    let raw: Vec<f32> = layer.iter().map(|a| a.hidden).collect();
    let out = Denoiser::default().denoise(&layer, W, &camera(), &Motion::default(), 16, false);
    let (before, after) = (rms(&raw, truth), rms(&out, truth));
    assert!(before > 0.08, "the input is noisy: {before}");
    assert!(after < before / 4.0, "denoised: {after} (from {before})");
}

#[test]
fn values_do_not_bleed_across_objects_or_creases() {
    // Left half object 1, fully open; right half object 2, half hidden. A wide blur would
    // darken the left near the seam.
    let truth = |x: usize, _y: usize| if x < W / 2 { 0.0 } else { 0.5 };
    let layer = noisy(truth, |x, _| if x < W / 2 { 1 } else { 2 }, 16, 2);
    let out = Denoiser::default().denoise(&layer, W, &camera(), &Motion::default(), 16, false);
    for y in 0..W {
        assert_eq!(out[y * W + W / 2 - 1], 0.0, "row {y}: the open side stays open at the seam");
    }
    // The same with one object folded along the seam (normals apart by 90 degrees).
    let mut folded = noisy(truth, |_, _| 1, 16, 3);
    for (k, a) in folded.iter_mut().enumerate() {
        if k % W >= W / 2 {
            a.normal = Vec3::X;
        }
    }
    let out = Denoiser::default().denoise(&folded, W, &camera(), &Motion::default(), 16, false);
    for y in 0..W {
        assert_eq!(out[y * W + W / 2 - 1], 0.0, "row {y}: the crease stops the blur");
    }
}

#[test]
fn a_still_scene_averages_its_passes_and_converges_to_the_unfiltered_mean() {
    let truth = |x: usize, y: usize| if (x / 8 + y / 8) % 2 == 0 { 0.1 } else { 0.6 };
    let mut history = History::default();
    let mut sum = vec![0.0f32; W * W];
    let mut last = Vec::new();
    for pass in 0..64 {
        let layer = noisy(truth, |_, _| TriangleIdFlat::ID, 16, 100 + pass);
        for (s, a) in sum.iter_mut().zip(&layer) {
            *s += a.hidden;
        }
        last = follow_all(&mut history, &layer, None, &Motion::default(), 64.0);
    }
    for (k, a) in last.iter().enumerate() {
        assert_eq!(a.count, 64.0);
        assert!((a.mean - sum[k] / 64.0).abs() < 1e-4, "pixel {k}: {} against {}", a.mean, sum[k] / 64.0);
    }
    // The filter hardly moves a converged average (the checker's edges stay).
    let averaged: Vec<Averaged> = last.clone();
    let layer = noisy(truth, |_, _| TriangleIdFlat::ID, 16, 1);
    let guides = super::atrous::Guides::new(&layer, &camera(), &Motion::default());
    let out = super::atrous::filter(&guides, &averaged, &near(&layer), W, 16, WHOLE, 0..W);
    let means: Vec<f32> = last.iter().map(|a| a.mean).collect();
    assert!(rms(&out, truth) <= rms(&means, truth) * 1.1 + 0.003, "{} {}", rms(&out, truth), rms(&means, truth));
}

#[test]
fn a_moved_object_is_followed_and_a_new_one_starts_afresh() {
    // One instance, moved right by 8 pixels between two frames: its pixels keep their
    // history; pixels that now see another object start again.
    let shift = 8.0 * 2.0 / W as f64;
    let place = |dx: f64| DMat4::from_translation(DVec3::new(dx, 0.0, 0.0));
    let motion = |dx: f64| Motion::placed(vec![(7, place(dx))]);
    let mut history = History::default();
    let first: Vec<AoPixel> = (0..W * W)
        .map(|k| AoPixel { eye: eye(k % W, k / W), normal: Vec3::Z, object: 0, hidden: 0.25, lit: Vec3::ONE })
        .collect();
    follow_all(&mut history, &first, Some(&near(&first)), &motion(0.0), 16.0);
    let second: Vec<AoPixel> = (0..W * W)
        .map(|k| AoPixel { eye: eye(k % W, k / W), normal: Vec3::Z, object: 0, hidden: 0.75, lit: Vec3::ONE })
        .collect();
    let out = follow_all(&mut history, &second, Some(&near(&first)), &motion(shift), 16.0);
    // Pixel x now saw the point pixel x - 8 saw before.
    assert_eq!(out[10 * W + 20], Averaged { mean: 0.5, count: 2.0 }, "followed back 8 pixels");
    assert_eq!(out[10 * W + 3], Averaged { mean: 0.75, count: 1.0 }, "came from outside the last frame");
    // Another object's id, or a frame of flat triangles only: nothing to follow.
    let other = Motion::placed(vec![(8, place(shift))]);
    let out = follow_all(&mut history, &second, Some(&near(&first)), &other, 16.0);
    assert!(out.iter().all(|a| a.count == 1.0));
}

/// What each pixel's neighbourhood shows of `layer` this frame: its own values (they are
/// noiseless in these tests, or their history is not clamped by them).
fn near(layer: &[AoPixel]) -> Vec<f32> {
    layer.iter().map(|a| a.hidden).collect()
}

/// Flat triangles' object.
struct TriangleIdFlat;
impl TriangleIdFlat {
    const ID: u32 = glray_scene::frame::TriangleId::FLAT;
}

/// How long denoising a 300x300 frame of surface takes (`cargo test --release -- --ignored
/// denoise_time --nocapture`).
#[test]
#[ignore]
fn denoise_time() {
    let w = 300;
    let camera =
        Camera::new(*camera().projection(), Viewport { x: 0, y: 0, width: w as i32, height: w as i32 }, (0.0, 1.0))
            .unwrap();
    let layer: Vec<AoPixel> = (0..w * w)
        .map(|k| AoPixel {
            eye: Vec3::new((k % w) as f32 * 0.01, (k / w) as f32 * 0.01, -5.0),
            normal: Vec3::Z,
            object: 1,
            hidden: (k % 7) as f32 / 7.0,
            lit: Vec3::ONE,
        })
        .collect();
    let mut d = Denoiser::default();
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let out = d.denoise(&layer, w, &camera, &Motion::default(), 16, false);
        let t1 = t.elapsed();
        eprintln!("follow {:?}, filter {:?} ({})", t1, t.elapsed() - t1, out[5]);
    }
}

#[test]
fn instances_drawn_under_one_transform_are_one_object() {
    use glray_scene::frame::{Frame, TriangleId};
    use glray_scene::instance::Instance;
    use glray_scene::mesh::Mesh;
    use std::sync::Arc;
    let mesh =
        || Arc::new(Mesh::indexed(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![Vec3::Z; 3], vec![[0, 1, 2]]).unwrap());
    let (here, there) = (DMat4::from_translation(DVec3::NEG_Z), DMat4::from_translation(DVec3::new(1.0, 0.0, -1.0)));
    // Two pieces of a dataset under one transform, another object, the pieces' transform again.
    let frame = Frame {
        instances: [here, there, here].map(|m| Instance::new(mesh(), m, DMat4::IDENTITY)).to_vec(),
        ..Frame::default()
    };
    let motion = Motion::of(&frame);
    assert_eq!([0, 1, 2].map(|k| motion.object(k)), [0, 1, 0]);
    assert_eq!(motion.id(0), motion.id(2), "one object, one id to follow it by");
    assert_ne!(motion.id(0), motion.id(1));
    assert_eq!(motion.object(TriangleId::FLAT), TriangleId::FLAT);
}

#[test]
fn a_frame_denoised_in_bands_is_the_frame_denoised_whole() {
    // A plane moving 8 pixels right and 5 down a frame (its points followed back across the
    // bands' edges), a corner of background, noisy AO: each band of a frame cut as MPI ranks
    // cut it, denoised from the rows around it and the last frame's rows fetched from the band
    // that held them, comes out as the whole frame denoised at once, bit for bit.
    let step = glam::DVec3::new(8.0, -5.0, 0.0) * 2.0 / W as f64;
    let layer_of = |frame: u32| -> Vec<AoPixel> {
        noisy(|x, y| 0.2 + 0.5 * ((x + 2 * y) % 17) as f32 / 17.0, |_, _| 0, 16, 40 + frame)
            .into_iter()
            .enumerate()
            .map(|(k, a)| if (k % W) + (k / W) < 12 { AoPixel::NONE } else { a })
            .collect()
    };
    for cuts in [vec![0, 64], vec![0, 30, 64], vec![0, 7, 25, 50, 64]] {
        let bands: Vec<Band> = cuts.windows(2).map(|c| Band { rows: c[0]..c[1], width: W, height: W }).collect();
        let mut whole = Denoiser::default();
        let mut parts: Vec<Denoiser> = bands.iter().map(|_| Denoiser::default()).collect();
        let mut fetched = 0;
        for frame in 0..5u32 {
            let layer = layer_of(frame);
            let motion = Motion::placed(vec![(7, DMat4::from_translation(step * f64::from(frame)))]);
            let still = frame == 4;
            let expected = whole.denoise(&layer, W, &camera(), &motion, 16, still);
            let held: Vec<HeldRows> = parts.iter().map(Denoiser::held).collect();
            for (band, d) in bands.iter().zip(&mut parts) {
                let rows = band.layer_rows();
                let own = &layer[rows.start * W..rows.end * W];
                for run in d.missing(own, band, &motion) {
                    let past = held.iter().find_map(|h| h.rows(run.clone())).expect("another band held them");
                    d.take_rows(run.start, &past);
                    fetched += 1;
                }
                let out = d.denoise_band(own, band, &camera(), &motion, 16, still);
                let want = &expected[band.rows.start * W..band.rows.end * W];
                assert_eq!(out.len(), want.len());
                let differ = out.iter().zip(want).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
                assert_eq!(differ, 0, "frame {frame}, band {:?} of {cuts:?}", band.rows);
            }
        }
        // Moving down 5 rows a frame, the bands' points came from other bands' rows.
        assert_eq!(fetched > 0, bands.len() > 1, "{cuts:?}: {fetched} rows fetched");
    }
}
