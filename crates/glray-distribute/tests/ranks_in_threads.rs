//! The protocol between ranks run as threads (memory transport): a data-parallel scene, split
//! over 1 to 4 ranks, traced image-parallel, is the picture one process makes of all of it,
//! with secondary rays (AO, shadows, a reflection) crossing the ranks' pieces; a silent rank
//! and a rank set differently end the frame with the rank named.

use std::time::{Duration, Instant};

mod common;

use common::{call, lit_context, options};
use glray_core::trace::Value::{Int, F64};
use glray_distribute::node::{Roles, Setup};
use glray_distribute::transport::memory::MemoryTransport;
use glray_distribute::{Agreement, Fault, Limits, Node};
use glray_render::Renderer;
use glray_scene::frame::Frame;

const W: u32 = 150;
const H: u32 = 110;
const BOXES: usize = 6;

/// The frames of `frames` frames drawn by the rank `rank` of `ranks`: a ground (rank 0's) and
/// its block of the boxes, lit, with the same camera everywhere.
fn frames_of(rank: usize, ranks: usize, frames: usize) -> Vec<Frame> {
    frames_moving(rank, ranks, frames, 0.0)
}

/// `frames_of`, the boxes lifted by `lift` every other frame (their points move up and down
/// the window from frame to frame: across the ranks' bands).
fn frames_moving(rank: usize, ranks: usize, frames: usize, lift: f64) -> Vec<Frame> {
    let mut c = lit_context(W, H, [-0.6, 0.6, -0.45, 0.45, 1.0, 30.0]);
    call(&mut c, "glNewList", &[Int(1), Int(0x1300)]);
    call(&mut c, "glBegin", &[Int(4)]);
    let faces: [([f64; 3], [[f64; 3]; 4]); 3] = [
        ([0.0, 0.0, 1.0], [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]]),
        ([1.0, 0.0, 0.0], [[1.0, -1.0, 1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [1.0, 1.0, 1.0]]),
        ([0.0, 1.0, 0.0], [[-1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0]]),
    ];
    for (n, corners) in faces {
        call(&mut c, "glNormal3f", &n.map(F64));
        for k in [0, 1, 2, 0, 2, 3] {
            call(&mut c, "glVertex3f", &corners[k].map(F64));
        }
    }
    call(&mut c, "glEnd", &[]);
    call(&mut c, "glEndList", &[]);
    let mine = rank * BOXES / ranks..(rank + 1) * BOXES / ranks;
    (0..frames)
        .map(|f| {
            call(&mut c, "glClear", &[Int(0x4100)]);
            call(&mut c, "glLoadIdentity", &[]);
            call(&mut c, "glTranslatef", &[0.0, -1.0, -9.0].map(F64));
            call(&mut c, "glRotatef", &[25.0, 1.0, 0.0, 0.0].map(F64));
            if rank == 0 {
                call(&mut c, "glColor3f", &[0.8, 0.8, 0.8].map(F64));
                call(&mut c, "glBegin", &[Int(7)]);
                call(&mut c, "glNormal3f", &[0.0, 1.0, 0.0].map(F64));
                for (x, z) in [(-6.0, 4.0), (6.0, 4.0), (6.0, -6.0), (-6.0, -6.0)] {
                    call(&mut c, "glVertex3f", &[x, -1.0, z].map(F64));
                }
                call(&mut c, "glEnd", &[]);
            }
            for k in mine.clone() {
                call(&mut c, "glPushMatrix", &[]);
                let y = lift * (f % 2) as f64;
                call(&mut c, "glTranslatef", &[-3.75 + 1.5 * k as f64, y, -((k % 2) as f64)].map(F64));
                call(&mut c, "glScalef", &[0.6, 0.6, 0.6].map(F64));
                call(&mut c, "glColor3f", &[0.9, 0.2 + 0.12 * k as f64, 0.3].map(F64));
                // The current normal is part of a draw's state (a list leaves its last one
                // behind): set, every frame is the one before.
                call(&mut c, "glNormal3f", &[0.0, 0.0, 1.0].map(F64));
                call(&mut c, "glCallList", &[Int(1)]);
                call(&mut c, "glPopMatrix", &[]);
            }
            c.take_frame()
        })
        .collect()
}

/// Rank 0's pictures of `frames` frames over `ranks` ranks in threads.
fn traced(ranks: usize, preset: &str, frames: usize) -> Vec<glray_render::Rendered> {
    traced_with(ranks, preset, frames, Roles::Shared)
}

fn traced_with(ranks: usize, preset: &str, frames: usize, roles: Roles) -> Vec<glray_render::Rendered> {
    traced_frames(ranks, preset, roles, move |rank| frames_of(rank, ranks, frames))
}

/// Rank 0's pictures of the frames `frames(rank)` each rank draws, over `ranks` ranks in
/// threads.
fn traced_frames(
    ranks: usize,
    preset: &str,
    roles: Roles,
    frames: impl Fn(usize) -> Vec<Frame> + Send + Sync + Copy + 'static,
) -> Vec<glray_render::Rendered> {
    let transports = MemoryTransport::group(ranks);
    let handles: Vec<_> = transports
        .into_iter()
        .enumerate()
        .map(|(rank, t)| {
            let preset = preset.to_string();
            std::thread::spawn(move || {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
                let setup =
                    Setup { limits: Limits { fixed: Some(Duration::from_secs(30)) }, roles, ..Setup::default() };
                let mut node = Node::new(t, Agreement { settings: 7 }, setup);
                let mut renderer = Renderer::new(options(&preset));
                frames(rank)
                    .iter()
                    .map(|f| node.frame(f, None, &mut renderer, Some(&pool), true).unwrap())
                    .collect::<Vec<_>>()
            })
        })
        .collect();
    let mut all: Vec<_> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    // Rank 0 (the display) gets the whole picture; every other rank the part its own boxes
    // cover, over its background (the clear colour at the far depth), which is what a
    // sort-last compositor takes from it.
    for (rank, out) in all.iter().enumerate().skip(1) {
        for (k, (p, _)) in out.iter().enumerate() {
            let (p, whole) = (p.as_ref().unwrap(), all[0][k].0.as_ref().unwrap());
            let mut sent = 0;
            for i in 0..(W * H) as usize {
                let same = p.rgba[4 * i..4 * i + 4] == whole.rgba[4 * i..4 * i + 4] && p.depth[i] == whole.depth[i];
                let background = p.rgba[4 * i..4 * i + 4] == [0, 0, 0, 0] && p.depth[i] == 1.0;
                assert!(
                    same || background,
                    "rank {rank}, frame {k}, pixel {i}: neither the picture nor the background"
                );
                sent += usize::from(same && !background);
            }
            assert!(sent > 0, "rank {rank} got its part of frame {k}");
        }
    }
    let zero = all.swap_remove(0);
    let tiles: u32 = zero.iter().map(|(_, r)| r.tiles_total).max().unwrap();
    assert!(tiles > 1);
    if roles == Roles::Dedicated && ranks > 1 {
        assert!(zero.iter().all(|(_, r)| r.tiles == 0), "a dedicated master traces nothing");
    }
    zero.into_iter().map(|(p, _)| p.expect("rank 0's picture")).collect()
}

#[test]
fn a_scene_split_over_ranks_is_traced_as_one_process_traces_it_all() {
    for preset in ["gl", "ao", "full"] {
        let whole = frames_of(0, 1, 2);
        let mut one = Renderer::new(options(preset));
        let expected: Vec<_> = whole.iter().map(|f| one.render(f, W, H, None)).collect();
        // The ground is lit and shaded by the boxes of other ranks: not the picture of rank 0's
        // pieces alone.
        let alone = Renderer::new(options(preset)).render(&frames_of(0, 3, 1)[0], W, H, None);
        assert_ne!(alone.rgba, expected[0].rgba);
        for ranks in [2, 1, 3, 4] {
            let got = traced(ranks, preset, 2);
            for (k, (g, e)) in got.iter().zip(&expected).enumerate() {
                assert!(g == e, "{preset}, {ranks} ranks, frame {k}: not the one-process picture");
            }
        }
        // Rank 0 as a dedicated master and display: the same picture.
        let got = traced_with(3, preset, 2, Roles::Dedicated);
        assert!(got == expected, "{preset}, a dedicated master");
    }
}

#[test]
fn a_moving_scene_denoised_in_bands_over_ranks_is_one_process_picture() {
    // The boxes lifted every other frame, their surfaces move up and down the window by ~40
    // rows: each band's denoising follows their pixels back into rows another rank's band held
    // the frame before, fetched from it. Every frame, for 1 to 4 ranks, one process's picture.
    for preset in ["ao", "full"] {
        let mut one = Renderer::new(options(preset));
        let expected: Vec<_> = frames_moving(0, 1, 4, 2.5).iter().map(|f| one.render(f, W, H, None)).collect();
        assert_ne!(expected[1].rgba, expected[2].rgba, "the scene moves");
        for ranks in [2, 3, 4, 1] {
            let got = traced_frames(ranks, preset, Roles::Shared, move |rank| frames_moving(rank, ranks, 4, 2.5));
            for (k, (g, e)) in got.iter().zip(&expected).enumerate() {
                assert!(g == e, "{preset}, {ranks} ranks, frame {k}: not the one-process picture");
            }
        }
    }
}

#[test]
fn a_silent_rank_is_named_within_the_limit() {
    let mut transports = MemoryTransport::group(3);
    let _silent = transports.pop();
    let limit = Duration::from_millis(400);
    let handles: Vec<_> = transports
        .into_iter()
        .enumerate()
        .map(|(rank, t)| {
            std::thread::spawn(move || {
                let setup = Setup { limits: Limits { fixed: Some(limit) }, ..Setup::default() };
                let mut node = Node::new(t, Agreement { settings: 1 }, setup);
                let start = Instant::now();
                let f = &frames_of(rank, 3, 1)[0];
                let r = node.frame(f, None, &mut Renderer::new(options("gl")), None, true);
                (r.map(|_| ()), start.elapsed())
            })
        })
        .collect();
    for h in handles {
        let (r, took) = h.join().unwrap();
        match r {
            Err(Fault::Silent { ranks, .. }) => assert_eq!(ranks, vec![2]),
            other => panic!("{other:?}"),
        }
        assert!(took < limit * 10, "{took:?}");
        let text = Fault::Silent { ranks: vec![2], waited: limit, frame: 0, waiting_for: "its scene" }.to_string();
        assert!(text.contains("rank 2 did not answer within 0.4 s"), "{text}");
    }
}

#[test]
fn a_rank_set_differently_is_refused_by_name() {
    let handles: Vec<_> = MemoryTransport::group(2)
        .into_iter()
        .enumerate()
        .map(|(rank, t)| {
            std::thread::spawn(move || {
                let setup = Setup { limits: Limits { fixed: Some(Duration::from_secs(5)) }, ..Setup::default() };
                let mut node = Node::new(t, Agreement { settings: rank as u64 }, setup);
                node.frame(&frames_of(rank, 2, 1)[0], None, &mut Renderer::new(options("gl")), None, true).map(|_| ())
            })
        })
        .collect();
    let results: Vec<_> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    assert!(matches!(&results[0], Err(Fault::Refused { rank: 1, .. })), "{:?}", results[0]);
    assert!(matches!(&results[1], Err(Fault::Refused { rank: 0, .. })), "{:?}", results[1]);
}
