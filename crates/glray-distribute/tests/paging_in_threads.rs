//! Paging (`distribute = paged`) between ranks run as threads (memory transport): a terrain
//! of 51,200 triangles split over 2 to 4 ranks (each rank's piece a paged mesh of its own, in
//! blocks), with small boxes above it that every rank holds, traced zoomed out and zoomed in.
//! Every picture is the replicated mode's byte for byte: fetching blocks through a cache of
//! 1/8 of the scene, parking the pieces whose rays miss a block (`park`) and waiting for each
//! (`wait`), with every block fetched before tracing (`all-resident`), and through a cache so
//! small it thrashes (1/64); and no rank holds another's blocks beyond its cache.

use std::time::Duration;

mod common;

use common::{call, lit_context, options};
use glray_core::trace::Value::{Int, F64};
use glray_distribute::node::{Setup, TileHomes};
use glray_distribute::paging::{Budget, PagingReport, PagingSetup, Resident};
use glray_distribute::transport::memory::MemoryTransport;
use glray_distribute::{Agreement, Limits, Node};
use glray_render::Renderer;
use glray_scene::frame::Frame;

const W: u32 = 160;
const H: u32 = 120;
/// Squares a side of the terrain (two triangles each).
const N: usize = 160;

fn height(x: f64, y: f64) -> f64 {
    0.35 * (1.3 * x).sin() * (1.1 * y).cos() + 0.1 * (3.0 * x + 2.0 * y).sin()
}

fn normal(x: f64, y: f64) -> [f64; 3] {
    let e = 1e-4;
    let dx = (height(x + e, y) - height(x - e, y)) / (2.0 * e);
    let dy = (height(x, y + e) - height(x, y - e)) / (2.0 * e);
    let n = [-dx, -dy, 1.0];
    let l = (n[0] * n[0] + n[1] * n[1] + 1.0).sqrt();
    n.map(|v| v / l)
}

/// Rank `rank`'s frames (of `ranks`): its rows of the terrain as a display list; rank 0 also
/// the boxes above it. Frame 0 seen from afar, the others from close by.
fn frames(rank: usize, ranks: usize, count: usize) -> Vec<Frame> {
    let mut c = lit_context(W, H, [-0.6, 0.6, -0.45, 0.45, 1.0, 40.0]);
    let step = 8.0 / N as f64;
    let at = |i: usize, j: usize| (-4.0 + i as f64 * step, -4.0 + j as f64 * step);
    call(&mut c, "glNewList", &[Int(1), Int(0x1300)]);
    call(&mut c, "glBegin", &[Int(4)]);
    for j in rank * N / ranks..(rank + 1) * N / ranks {
        for i in 0..N {
            for (di, dj) in [(0, 0), (1, 0), (1, 1), (0, 0), (1, 1), (0, 1)] {
                let (x, y) = at(i + di, j + dj);
                call(&mut c, "glNormal3f", &normal(x, y).map(F64));
                call(&mut c, "glVertex3f", &[x, y, height(x, y)].map(F64));
            }
        }
    }
    call(&mut c, "glEnd", &[]);
    call(&mut c, "glEndList", &[]);
    // A box: small, every rank holds it whole.
    call(&mut c, "glNewList", &[Int(2), Int(0x1300)]);
    call(&mut c, "glBegin", &[Int(7)]);
    for (n, corners) in [
        ([0.0, 0.0, 1.0], [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]]),
        ([0.0, 0.0, -1.0], [[-1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [1.0, 1.0, -1.0], [1.0, -1.0, -1.0]]),
        ([1.0, 0.0, 0.0], [[1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [1.0, 1.0, 1.0], [1.0, -1.0, 1.0]]),
        ([0.0, 1.0, 0.0], [[-1.0, 1.0, -1.0], [-1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, -1.0]]),
    ] {
        call(&mut c, "glNormal3f", &n.map(F64));
        for v in corners {
            call(&mut c, "glVertex3f", &v.map(F64));
        }
    }
    call(&mut c, "glEnd", &[]);
    call(&mut c, "glEndList", &[]);
    (0..count)
        .map(|f| {
            call(&mut c, "glClear", &[Int(0x4100)]);
            call(&mut c, "glLoadIdentity", &[]);
            let (distance, turn) = if f == 0 { (11.0, -55.0) } else { (4.5, -62.0) };
            call(&mut c, "glTranslatef", &[0.0, 0.0, -distance].map(F64));
            call(&mut c, "glRotatef", &[turn, 1.0, 0.0, 0.0].map(F64));
            call(&mut c, "glRotatef", &[10.0 * f as f64, 0.0, 0.0, 1.0].map(F64));
            call(&mut c, "glColor3f", &[0.7, 0.75, 0.6].map(F64));
            call(&mut c, "glNormal3f", &[0.0, 0.0, 1.0].map(F64));
            call(&mut c, "glCallList", &[Int(1)]);
            if rank == 0 {
                for (k, (x, y)) in [(-1.0, 0.5), (1.2, -0.8), (0.2, 1.5)].into_iter().enumerate() {
                    call(&mut c, "glPushMatrix", &[]);
                    call(&mut c, "glTranslatef", &[x, y, 0.9].map(F64));
                    call(&mut c, "glScalef", &[0.3, 0.3, 0.3].map(F64));
                    call(&mut c, "glColor3f", &[0.9, 0.25 + 0.2 * k as f64, 0.3].map(F64));
                    call(&mut c, "glCallList", &[Int(2)]);
                    call(&mut c, "glPopMatrix", &[]);
                }
            }
            c.take_frame()
        })
        .collect()
}

/// Every rank's pictures and reports of the frames, over `ranks` ranks in threads, paged as
/// `paging` says (None: replicated).
fn run(
    ranks: usize,
    preset: &str,
    paging: Option<PagingSetup>,
    tiles: TileHomes,
    count: usize,
) -> Vec<Vec<(glray_render::Rendered, Option<PagingReport>)>> {
    let handles: Vec<_> = MemoryTransport::group(ranks)
        .into_iter()
        .enumerate()
        .map(|(rank, t)| {
            let preset = preset.to_string();
            std::thread::spawn(move || {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
                let limits = Limits { fixed: Some(Duration::from_secs(60)) };
                let mut node =
                    Node::new(t, Agreement { settings: 7 }, Setup { limits, paging, tiles, ..Setup::default() });
                let mut renderer = Renderer::new(options(&preset));
                frames(rank, ranks, count)
                    .iter()
                    .map(|f| {
                        let (picture, report) = node.frame(f, None, &mut renderer, Some(&pool), true).unwrap();
                        (picture.unwrap(), report.paging)
                    })
                    .collect::<Vec<_>>()
            })
        })
        .collect();
    handles.into_iter().map(|h| h.join().unwrap()).collect()
}

fn paged(resident: Resident, fraction: f64, park: bool) -> Option<PagingSetup> {
    Some(PagingSetup { resident, budget: Budget::Fraction(fraction), block_bytes: 16 * 1024, park, prefetch: false })
}

#[test]
fn paged_pictures_are_the_replicated_ones_for_two_three_and_four_ranks() {
    for (preset, ranks) in [("gl", 2), ("gl", 3), ("gl", 4), ("ao", 2), ("ao", 3), ("ao", 4), ("full", 2), ("full", 4)]
    {
        {
            let count = 3;
            let replicated = run(ranks, preset, None, TileHomes::Bands, count);
            assert_ne!(replicated[0][0].0.rgba, replicated[0][1].0.rgba, "zoomed in");
            let mut setups = vec![
                ("a cache of 1/8", paged(Resident::Fetch, 1.0 / 8.0, true)),
                ("all-resident", paged(Resident::All, 1.0, false)),
            ];
            // Tiles dealt at random (`mpi_tiles = random`): other ranks' blocks, the same picture.
            if ranks == 4 {
                setups.push(("a cache of 1/8, tiles at random", paged(Resident::Fetch, 1.0 / 8.0, false)));
            }
            // (A thrashing cache with shadows and reflections too takes a minute here: every
            // secondary ray's blocks come again and again.)
            if preset != "full" {
                setups.push(("a cache of 1/64", paged(Resident::Fetch, 1.0 / 64.0, true)));
            }
            // Last frame's blocks asked for as a frame starts (`prefetch`): a thrashing cache
            // has evicted many of them.
            if preset != "full" && ranks == 2 {
                let prefetching =
                    paged(Resident::Fetch, 1.0 / 64.0, false).map(|s| PagingSetup { prefetch: true, ..s });
                setups.push(("a cache of 1/64, prefetching", prefetching));
            }
            // The blocking baseline (`paging = wait`), where parking has most to set aside.
            if preset == "ao" {
                setups.push(("a cache of 1/8, waiting", paged(Resident::Fetch, 1.0 / 8.0, false)));
            }
            for (what, setup) in setups {
                let started = std::time::Instant::now();
                let tiles = if what.ends_with("at random") { TileHomes::Random } else { TileHomes::Bands };
                let got = run(ranks, preset, setup, tiles, count);
                eprintln!("{preset}, {ranks} ranks, {what}: {:.2} s", started.elapsed().as_secs_f64());
                let all: Vec<PagingReport> = got.iter().flatten().map(|(_, r)| r.unwrap()).collect();
                assert!(all.iter().map(|r| r.resident).sum::<u64>() > 0, "{what}: ranks read their own blocks");
                let (accesses, cached) = all.iter().fold((0, 0), |(a, c), r| (a + r.accesses, c + r.cached));
                assert!(cached > 0 && cached < accesses, "{what}: {cached} of {accesses} accesses in the cache");
                // Ranks fetch others' blocks in the first frame (not every rank: one whose tiles
                // show only the sky, and whose band no other rank left it tiles of, reaches none).
                let first: Vec<PagingReport> = got.iter().map(|g| g[0].1.unwrap()).collect();
                assert!(first.iter().any(|r| r.misses > 0 && r.bytes_fetched > 0), "{what}: {first:?}");
                for (rank, (g, e)) in got.iter().zip(&replicated).enumerate() {
                    for (k, ((g, report), (e, _))) in g.iter().zip(e).enumerate() {
                        let differ = g.rgba.chunks(4).zip(e.rgba.chunks(4)).filter(|(a, b)| a != b).count();
                        if differ > 0 {
                            if let Ok(dir) = std::env::var("GLRAY_TEST_PICTURES") {
                                for (name, p) in [("paged", g), ("replicated", e)] {
                                    let image = glray_core::image::Image::from_bottom_up(W, H, &p.rgba, 4);
                                    let path = format!("{dir}/{preset}-{ranks}-{rank}-{k}-{name}.png");
                                    image.write_png(std::path::Path::new(&path)).unwrap();
                                }
                            }
                        }
                        assert!(
                            g == e,
                            "{preset}, {ranks} ranks, {what}: rank {rank}'s frame {k} is not the replicated picture \
                             ({differ} pixels differ)"
                        );
                        let r = report.expect("paged frames report paging");
                        // Every rank holds its own piece and reaches the others'.
                        assert!(r.own_bytes > 0 && r.own_bytes < r.scene_bytes, "{what}: {r:?}");
                        if setup.unwrap().resident == Resident::Fetch {
                            assert!(r.cache_bytes <= r.cache_capacity || r.over > 0, "{what}: {r:?}");
                        }
                    }
                    if what == "all-resident" {
                        // Every block came before tracing: the tracer never missed.
                        assert!(g.iter().all(|(_, r)| r.unwrap().waits == 0));
                    }
                    // Parked pieces (traced again once their blocks came) only where parking.
                    let parked: u64 = g.iter().map(|(_, r)| r.unwrap().parked).sum();
                    match setup.unwrap() {
                        s if s.park => assert!(parked > 0, "{what}, rank {rank}: misses park pieces"),
                        _ => assert_eq!(parked, 0, "{what}, rank {rank}"),
                    }
                    let prefetched: u64 = g.iter().map(|(_, r)| r.unwrap().prefetched).sum();
                    if setup.unwrap().prefetch {
                        // Nothing before the first frame; then blocks the last frame used, some of
                        // them used again.
                        assert_eq!(g[0].1.unwrap().prefetched, 0, "{what}, rank {rank}");
                        let used: u64 = g.iter().map(|(_, r)| r.unwrap().prefetch_used).sum();
                        assert!(prefetched > 0 && used > 0 && used <= prefetched, "{what}, rank {rank}: {g:?}");
                    } else {
                        assert_eq!(prefetched, 0, "{what}, rank {rank}");
                    }
                    if what.starts_with("a cache of 1/64") {
                        let evicted: u64 = g.iter().map(|(_, r)| r.unwrap().evictions).sum();
                        assert!(evicted > 0, "rank {rank}: a thrashing cache evicts");
                    }
                }
            }
        }
    }
}
