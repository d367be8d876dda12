//! GLRAY_STATS: per-frame statistics, like VirtualGL's profiling output: what capturing the
//! frame's calls, building its BVHs, tracing and presenting took, the rays and triangles, as
//! a line on standard error or a JSON line appended to a file.

use std::fs::File;
use std::io::Write;
use std::time::Duration;

pub enum StatsSink {
    Stderr,
    File(File),
}

/// One presented frame.
pub struct FrameStats {
    pub frame: u64,
    pub thread: u32,
    pub width: u32,
    pub height: u32,
    /// Following the frame's calls in capture (since the last present).
    pub capture: Duration,
    pub render: glray_render::Stats,
    pub present: Duration,
    /// Draws through shader programs left to the real GL since the last line (the overlays
    /// drawn over the last picture, and any before this one).
    pub passed_draws: u64,
    /// In an MPI rank sharing frames: its part.
    pub ranks: Option<RankStats>,
}

/// A rank's part in a shared frame.
pub struct RankStats {
    pub rank: usize,
    pub ranks: usize,
    pub report: glray_distribute::FrameReport,
}

impl RankStats {
    /// Bytes received per pixel other ranks traced (what the frame cost this rank's link).
    fn per_pixel(&self) -> f64 {
        let r = &self.report;
        if r.pixels_elsewhere == 0 {
            0.0
        } else {
            r.bytes_received as f64 / r.pixels_elsewhere as f64
        }
    }

    fn text(&self) -> String {
        let r = &self.report;
        format!(
            "; rank {} of {}: {} of {} tiles, {:.2} MB sent, {:.2} MB received ({:.2} MB before compression, {:.1} \
             bytes a pixel traced elsewhere), waited {:.2} ms, band {:.2} ms{}{}",
            self.rank,
            self.ranks,
            r.tiles,
            r.tiles_total,
            mb(r.bytes_sent),
            mb(r.bytes_received),
            mb(r.raw_received),
            self.per_pixel(),
            ms(r.wait),
            ms(r.band),
            r.imbalance.map_or(String::new(), |i| format!(", imbalance {i:.2} (slowest / mean)")),
            r.paging.map_or(String::new(), |p| format!(
                "; paging: {} block accesses ({} own, {} cached, {} fetched: {:.2}% missed), {} evicted, {:.2} MB \
                 fetched ({:.2} ms mean, {:.2} ms p99, {:.2} ms max), stalled {:.2} ms, {} pieces parked, {} prefetched ({} used), served {} blocks ({:.2} MB, {} compressed), \
                 cache {:.1} of {:.1} MB, own {:.1} of {:.1} MB, peak memory {:.1} MB",
                p.accesses,
                p.resident,
                p.cached,
                p.misses,
                p.miss_percent(),
                p.evictions,
                mb(p.bytes_fetched),
                p.fetch_mean_ms,
                p.fetch_p99_ms,
                p.fetch_max_ms,
                ms(p.stall),
                p.parked,
                p.prefetched,
                p.prefetch_used,
                p.served,
                mb(p.served_bytes),
                p.served_packed,
                mb(p.cache_bytes),
                mb(p.cache_capacity.min(p.scene_bytes)),
                mb(p.own_bytes),
                mb(p.scene_bytes),
                mb(p.peak_memory)
            ))
        )
    }

    fn json(&self) -> String {
        let r = &self.report;
        format!(
            ",\"rank\":{},\"ranks\":{},\"tiles\":{},\"tiles_total\":{},\"bytes_sent\":{},\"bytes_received\":{},\
             \"raw_sent\":{},\"raw_received\":{},\"pixels_elsewhere\":{},\"received_per_pixel\":{:.3},\
             \"wait_ms\":{:.3},\"exchange_ms\":{:.3},\"rank_trace_ms\":{:.3},\"band_wait_ms\":{:.3},\"band_ms\":{:.3},\
             \"pack_ms\":{:.3},\"unpack_ms\":{:.3},\"picture_pixels\":{},\"peak_memory\":{},\"imbalance\":{}{}",
            self.rank,
            self.ranks,
            r.tiles,
            r.tiles_total,
            r.bytes_sent,
            r.bytes_received,
            r.raw_sent,
            r.raw_received,
            r.pixels_elsewhere,
            self.per_pixel(),
            ms(r.wait),
            ms(r.exchange),
            ms(r.trace),
            ms(r.band_wait),
            ms(r.band),
            ms(r.pack),
            ms(r.unpack),
            r.picture_pixels,
            glray_core::memory::peak(),
            r.imbalance.map_or("null".to_string(), |i| format!("{i:.3}")),
            r.paging.map_or(String::new(), |p| format!(
                ",\"paging\":{{\"accesses\":{},\"resident\":{},\"cached\":{},\"misses\":{},\"waits\":{},\
                 \"miss_percent\":{:.4},\"evictions\":{},\"bytes_fetched\":{},\"fetch_mean_ms\":{:.3},\
                 \"fetch_p99_ms\":{:.3},\"fetch_max_ms\":{:.3},\"stall_ms\":{:.3},\"parked\":{},\"prefetched\":{},\"prefetch_used\":{},\"served\":{},\"served_bytes\":{},\"served_packed\":{},\
                 \"cache_bytes\":{},\"cache_capacity\":{},\"over\":{},\"own_bytes\":{},\"scene_bytes\":{},\
                 \"peak_memory\":{}}}",
                p.accesses,
                p.resident,
                p.cached,
                p.misses,
                p.waits,
                p.miss_percent(),
                p.evictions,
                p.bytes_fetched,
                p.fetch_mean_ms,
                p.fetch_p99_ms,
                p.fetch_max_ms,
                ms(p.stall),
                p.parked,
                p.prefetched,
                p.prefetch_used,
                p.served,
                p.served_bytes,
                p.served_packed,
                p.cache_bytes,
                p.cache_capacity.min(p.scene_bytes),
                p.over,
                p.own_bytes,
                p.scene_bytes,
                p.peak_memory
            ))
        )
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn mb(bytes: u64) -> f64 {
    bytes as f64 / (1 << 20) as f64
}

impl StatsSink {
    /// `stderr`, or a file to append to.
    pub fn open(spec: &str) -> Result<StatsSink, String> {
        if spec == "stderr" {
            return Ok(StatsSink::Stderr);
        }
        let f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(spec)
            .map_err(|e| format!("stats: {spec}: {e}"))?;
        Ok(StatsSink::File(f))
    }

    pub fn write(&mut self, s: &FrameStats) {
        let r = &s.render;
        let trace = r.trace.as_secs_f64();
        let mrays = if trace > 0.0 { r.rays as f64 / trace / 1e6 } else { 0.0 };
        // Each line is formatted first and written in one piece: the ranks of an MPI job write
        // their lines to the same stream or file at once.
        use std::fmt::Write as _;
        let mut line = String::new();
        let made = match self {
            StatsSink::Stderr => writeln!(
                line,
                "glray: frame {} ({}x{}): capture {:.2} ms, build {:.2} ms{}{}, trace {:.2} ms ({} rays, {:.2} Mrays/s), \
                 {}present {:.2} ms; {}, {} per pixel{}{}{}{}",
                s.frame,
                s.width,
                s.height,
                ms(s.capture),
                ms(r.build),
                match r.fast_builds {
                    0 => String::new(),
                    n => format!(" ({n} built fast)"),
                },
                match r.refits {
                    0 => String::new(),
                    n => format!(" ({n} refitted)"),
                },
                ms(r.trace),
                r.rays,
                mrays,
                if r.denoise.is_zero() { String::new() } else { format!("denoise {:.2} ms, ", ms(r.denoise)) },
                ms(s.present),
                glray_core::log::plural(r.triangles, "triangle"),
                glray_core::log::plural(u64::from(r.samples), "sample"),
                if r.reused { " (unchanged: the last picture shown again)" } else { "" },
                match r.kept_bytes {
                    0 => String::new(),
                    b => format!("; {:.1} MB kept for the next frame", mb(b)),
                },
                match s.passed_draws {
                    0 => String::new(),
                    n => format!("; {} left to the real GL", glray_core::log::plural(n, "shader draw")),
                },
                s.ranks.as_ref().map_or(String::new(), RankStats::text)
            ),
            StatsSink::File(_) => writeln!(line, "{}", json(s)),
        };
        let result = match self {
            _ if made.is_err() => return,
            StatsSink::Stderr => std::io::stderr().write_all(line.as_bytes()),
            StatsSink::File(f) => f.write_all(line.as_bytes()),
        };
        if let Err(e) = result {
            glray_core::warn!("stats: {e}");
        }
    }
}

/// One frame's statistics as a JSON object (a `GLRAY_STATS` file's line; the panel's plots).
pub fn json(s: &FrameStats) -> String {
    let r = &s.render;
    let trace = r.trace.as_secs_f64();
    let mrays = if trace > 0.0 { r.rays as f64 / trace / 1e6 } else { 0.0 };
    format!(
        "{{\"frame\":{},\"thread\":{},\"width\":{},\"height\":{},\"capture_ms\":{:.3},\"build_ms\":{:.3},\
         \"trace_ms\":{:.3},\"denoise_ms\":{:.3},\"present_ms\":{:.3},\"rays\":{},\"mrays_per_s\":{:.3},\"triangles\":{},\"samples\":{},\"reused\":{},\"builds\":{},\"fast_builds\":{},\"refits\":{},\"loose_triangles\":{},\"kept_mb\":{:.1},\"passed_draws\":{}{}}}",
        s.frame,
        s.thread,
        s.width,
        s.height,
        ms(s.capture),
        ms(r.build),
        ms(r.trace),
        ms(r.denoise),
        ms(s.present),
        r.rays,
        mrays,
        r.triangles,
        r.samples,
        r.reused,
        r.builds,
        r.fast_builds,
        r.refits,
        r.loose,
        mb(r.kept_bytes),
        s.passed_draws,
        s.ranks.as_ref().map_or(String::new(), RankStats::json)
    )
}
