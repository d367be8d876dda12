//! The live control panel (docs/panel.md) on real programs: glxgears under `glray run --panel`
//! steered through the JSON API over real HTTP (the token checked, bad values refused with the
//! reason, many requests at once, a slow client that stalls no frame, the TOML download read
//! back by a fresh run), its page in headless Chromium turning AO on, and a change reaching
//! both ranks of `glray run --np 2`.

mod common;

use common::*;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The tests here one at a time: each runs a program tracing frames (the MPI one two ranks),
/// and Chromium; at once on two cores, their frames and waits would crowd each other out.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// A program running under `glray run --panel`, killed by PID when dropped.
struct Running {
    child: Stopped,
    /// host:port and the access token, as printed.
    address: String,
    token: String,
}

/// Starts `cmd` (a `glray run --panel ...`), waiting (bounded) for the panel's line on stderr.
fn start(mut cmd: Command, log: &Path) -> Running {
    let file = std::fs::File::create(log).unwrap();
    let child = cmd.stderr(file).stdout(Stdio::null()).spawn().expect("glray run");
    // Killed when dropped, on a failure below too.
    let mut running = Running { child: Stopped(child), address: String::new(), token: String::new() };
    let started = Instant::now();
    loop {
        let text = std::fs::read_to_string(log).unwrap_or_default();
        if let Some(line) = text.lines().find(|l| l.starts_with("glray: panel http://")) {
            let url = line.trim_start_matches("glray: panel http://");
            let (address, query) = url.split_once("/?token=").expect("the panel's URL carries a token");
            (running.address, running.token) = (address.to_string(), query.trim().to_string());
            return running;
        }
        assert!(started.elapsed() < Duration::from_secs(60), "no panel line within 60 s:\n{text}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A response: status, headers (lowercase names) and body.
struct Reply {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Reply {
    fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body).unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.text()))
    }
    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
}

/// One HTTP/1.1 request over a fresh connection (`Connection: close`), bounded in time.
fn request(address: &str, method: &str, path: &str, body: &str) -> Reply {
    let mut s = TcpStream::connect(address).unwrap_or_else(|e| panic!("connect {address}: {e}"));
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let head = format!(
        "{method} {path} HTTP/1.1\r\nHost: {address}\r\nConnection: close\r\nContent-Type: application/json\r\n\
         Content-Length: {}\r\n\r\n{body}",
        body.len()
    );
    s.write_all(head.as_bytes()).unwrap();
    let mut all = Vec::new();
    s.read_to_end(&mut all).unwrap();
    let end = all.windows(4).position(|w| w == b"\r\n\r\n").expect("a response head");
    let head = String::from_utf8_lossy(&all[..end]).into_owned();
    let mut lines = head.lines();
    let status = lines.next().and_then(|l| l.split(' ').nth(1)).and_then(|c| c.parse().ok()).expect("a status");
    let headers: Vec<(String, String)> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_string()))
        .collect();
    let mut body = all[end + 4..].to_vec();
    if headers.iter().any(|(k, v)| k == "transfer-encoding" && v.contains("chunked")) {
        body = unchunk(&body);
    }
    Reply { status, headers, body }
}

fn unchunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let Some(eol) = b.windows(2).position(|w| w == b"\r\n") else { return out };
        let size = usize::from_str_radix(String::from_utf8_lossy(&b[..eol]).trim(), 16).unwrap_or(0);
        if size == 0 {
            return out;
        }
        out.extend_from_slice(&b[eol + 2..eol + 2 + size]);
        b = &b[eol + 2 + size + 2..];
    }
}

impl Running {
    fn get(&self, path: &str) -> Reply {
        let sep = if path.contains('?') { '&' } else { '?' };
        request(&self.address, "GET", &format!("{path}{sep}token={}", self.token), "")
    }
    fn put(&self, body: &str) -> Reply {
        request(&self.address, "PUT", &format!("/api/settings?token={}", self.token), body)
    }
    /// The statistics' frames.
    fn frames(&self) -> Vec<serde_json::Value> {
        let r = self.get("/api/stats");
        assert_eq!(r.status, 200, "{}", r.text());
        r.json()["frames"].as_array().cloned().unwrap_or_default()
    }
    fn last_frame(&self) -> u64 {
        self.frames().last().and_then(|f| f["frame"].as_u64()).unwrap_or(0)
    }
    /// Waits (bounded) until frame `n` is in the statistics; the frames since the call.
    fn wait_for_frame(&self, n: u64) -> Vec<serde_json::Value> {
        let started = Instant::now();
        loop {
            let frames = self.frames();
            if frames.last().and_then(|f| f["frame"].as_u64()).is_some_and(|f| f >= n) {
                return frames;
            }
            assert!(started.elapsed() < Duration::from_secs(60), "frame {n} did not come within 60 s");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// glxgears at 300x300 under `glray run --panel` on `display`, with `settings`.
fn glxgears(display: &str, log: &Path, settings: &[&str]) -> Running {
    let mut cmd = Command::new(glray_bin());
    cmd.arg("run").arg("--panel");
    for s in settings {
        cmd.arg("--set").arg(s);
    }
    cmd.arg("--").arg(which("glxgears")).args(["-geometry", "300x300"]).env("DISPLAY", display);
    without_glray(&mut cmd);
    start(cmd, log)
}

/// The mean brightness of the gears (pixels brighter than the background) over four frames
/// the panel shows, a few frames apart, each numbered after `after` (its X-Glray-Frame): the
/// gears turn, so pictures are compared by it.
fn mean_brightness(run: &Running, after: u64) -> f64 {
    let (mut sum, mut n) = (0u64, 0u64);
    for _ in 0..4 {
        let png = run.get("/api/frame.png");
        assert_eq!(png.status, 200, "{}", png.text());
        let number: u64 = png
            .headers
            .iter()
            .find(|(k, _)| k == "x-glray-frame")
            .and_then(|(_, v)| v.parse().ok())
            .expect("a frame's number in X-Glray-Frame");
        assert!(number > after, "frame {number} is from before frame {after}");
        let (_, _, p) = png_pixels(&png.body);
        for c in p.chunks(4) {
            let v: u64 = c[..3].iter().map(|&v| v as u64).sum();
            if v > 30 {
                (sum, n) = (sum + v, n + 1);
            }
        }
        run.wait_for_frame(number + 3);
    }
    sum as f64 / n.max(1) as f64
}

/// Every address of this machine's interfaces (IPv4 and IPv6, link-local ones with their
/// interface), as getifaddrs(3) lists them, and 127.0.0.2 and ::1: loopback addresses that are
/// not the one the panel listens on.
fn addresses_of_this_machine() -> Vec<std::net::SocketAddr> {
    use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, SocketAddrV6};
    let mut all: Vec<SocketAddr> = vec![
        SocketAddr::new(IpAddr::V4(Ipv4Addr::new(127, 0, 0, 2)), 0),
        SocketAddr::new(IpAddr::V6(Ipv6Addr::LOCALHOST), 0),
    ];
    let mut list: *mut libc::ifaddrs = std::ptr::null_mut();
    // SAFETY: getifaddrs fills `list`, freed below; each entry is read while the list lives.
    unsafe {
        assert_eq!(libc::getifaddrs(&mut list), 0, "getifaddrs: {}", std::io::Error::last_os_error());
        let mut at = list;
        while !at.is_null() {
            let a = (*at).ifa_addr;
            if !a.is_null() {
                match i32::from((*a).sa_family) {
                    libc::AF_INET => {
                        let v4 = &*(a as *const libc::sockaddr_in);
                        all.push(SocketAddr::new(IpAddr::V4(Ipv4Addr::from(u32::from_be(v4.sin_addr.s_addr))), 0));
                    }
                    libc::AF_INET6 => {
                        let v6 = &*(a as *const libc::sockaddr_in6);
                        let ip = Ipv6Addr::from(v6.sin6_addr.s6_addr);
                        all.push(SocketAddr::V6(SocketAddrV6::new(ip, 0, 0, v6.sin6_scope_id)));
                    }
                    _ => {}
                }
            }
            at = (*at).ifa_next;
        }
        libc::freeifaddrs(list);
    }
    all.retain(|a| a.ip() != IpAddr::V4(Ipv4Addr::LOCALHOST));
    all.sort();
    all.dedup();
    all
}

/// After a change to AO the panel took while frame `taken` was the last (or before): every
/// frame from two after it on traces AO.
fn ao_within_two_frames(run: &Running, taken: u64) {
    let frames = run.wait_for_frame(taken + 5);
    let later: Vec<_> = frames.iter().filter(|f| f["frame"].as_u64().unwrap() > taken + 2).collect();
    assert!(!later.is_empty());
    for f in later {
        assert!(traced_ao(f), "frame {} (the change taken by frame {taken}) traces no AO: {f}", f["frame"]);
    }
}

/// A frame's AO rays: more rays than pixels (one camera ray each).
fn traced_ao(frame: &serde_json::Value) -> bool {
    let pixels = frame["width"].as_u64().unwrap() * frame["height"].as_u64().unwrap();
    frame["rays"].as_u64().unwrap() > 2 * pixels
}

fn png_pixels(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn the_panel_steers_glxgears_over_http_and_refuses_requests_without_the_token() {
    let _one = one_at_a_time();
    let x = Xvfb::start();
    let dir = scratch("panel-api");
    let run = glxgears(&x.display, &dir.join("glxgears.log"), &["preset=gl"]);

    // Without the token, with a wrong one, or with the token and a wrong path or method:
    // refused, and nothing in the body but the reason.
    let plain = request(&run.address, "GET", "/api/settings", "");
    assert_eq!(plain.status, 401, "{}", plain.text());
    let wrong = request(&run.address, "GET", "/api/frame.png?token=0123456789abcdef0123456789abcdef", "");
    assert_eq!(wrong.status, 403, "{}", wrong.text());
    assert!(!wrong.text().contains("preset") && wrong.json()["error"].is_string());
    let change = request(&run.address, "PUT", "/api/settings", r#"{"preset":"ao"}"#);
    assert_eq!(change.status, 401, "a change without the token");
    assert_eq!(run.get("/api/nothing").status, 404);
    assert_eq!(request(&run.address, "DELETE", &format!("/api/settings?token={}", run.token), "").status, 405);
    // The listener is on 127.0.0.1 alone (the kernel's table of listening sockets says so),
    // and this machine's other addresses get a refused connection.
    let port = run.address.rsplit(':').next().unwrap().parse::<u16>().unwrap();
    let tcp = std::fs::read_to_string("/proc/net/tcp").unwrap();
    let listening: Vec<&str> = tcp
        .lines()
        .filter(|l| l.split_whitespace().nth(1).is_some_and(|a| a.ends_with(&format!(":{port:04X}"))))
        .filter(|l| l.split_whitespace().nth(3) == Some("0A"))
        .collect();
    assert_eq!(listening.len(), 1, "{listening:?}");
    assert!(listening[0].split_whitespace().nth(1).unwrap().starts_with("0100007F:"), "{listening:?}");
    // Every other address this machine has, IPv6 ones too: refused (nothing else listens on
    // the port, so a refusal says the panel is not there).
    let others = addresses_of_this_machine();
    assert!(others.len() >= 2, "{others:?}");
    for mut other in others {
        other.set_port(port);
        let answered = TcpStream::connect_timeout(&other, Duration::from_secs(2));
        assert!(answered.is_err(), "the panel answered on {other}");
    }

    // The settings, then a bad value refused with the reason (and nothing changed).
    let s = run.get("/api/settings");
    assert_eq!(s.status, 200);
    assert_eq!(s.json()["settings"]["preset"], "gl");
    let bad = run.put(r#"{"ao_samples": "lots", "preset": "ao"}"#);
    assert_eq!(bad.status, 400);
    let why = bad.json()["error"].as_str().unwrap().to_string();
    assert!(why.contains("ao_samples") && why.contains("0 to 1024"), "{why}");
    assert_eq!(run.get("/api/settings").json()["settings"]["preset"], "gl", "a refused change changes nothing");
    assert_eq!(run.put(r#"{"threads": 1}"#).status, 400, "a setting fixed at start");
    assert_eq!(run.put("not json").status, 400);

    // Frames come in the GL look: camera rays alone.
    let before = run.last_frame();
    let frames = run.wait_for_frame(before + 3);
    assert!(!traced_ao(frames.last().unwrap()), "the GL look traces no AO");
    let gl_mean = mean_brightness(&run, 0);
    let gl_png = run.get("/api/frame.png");
    assert_eq!(gl_png.status, 200);
    assert!(gl_png.headers.iter().any(|(k, v)| k == "content-type" && v == "image/png"));
    let (w, h, _) = png_pixels(&gl_png.body);
    assert_eq!((w, h), (300, 300));

    // AO on: from the next frame on, at the latest within two.
    let on = run.put(r#"{"preset": "ao"}"#);
    assert_eq!(on.status, 200, "{}", on.text());
    assert_eq!(on.json()["settings"]["preset"], "ao");
    let taken = run.last_frame();
    ao_within_two_frames(&run, taken);
    let ao_mean = mean_brightness(&run, taken + 2);
    assert!(ao_mean < 0.985 * gl_mean, "AO darkens the gears: mean {ao_mean:.1} against {gl_mean:.1} in the GL look");

    // Many requests at once: all answered.
    let handles: Vec<_> = (0..12)
        .map(|k| {
            let (address, token) = (run.address.clone(), run.token.clone());
            std::thread::spawn(move || {
                let path = if k % 2 == 0 { "/api/stats" } else { "/api/frame.png" };
                request(&address, "GET", &format!("{path}?token={token}"), "").status
            })
        })
        .collect();
    for h in handles {
        assert_eq!(h.join().unwrap(), 200);
    }
    // A slow client (half a request, then silence) stalls no frame.
    let mut slow = TcpStream::connect(&run.address).unwrap();
    slow.write_all(b"GET /api/stats?token=").unwrap();
    let held = run.last_frame();
    run.wait_for_frame(held + 5);
    // Still held open by the server (it has not given up on the client): the frames went on
    // beside it, not after it.
    slow.set_nonblocking(true).unwrap();
    let mut byte = [0u8; 1];
    let open = matches!(slow.read(&mut byte), Err(e) if e.kind() == std::io::ErrorKind::WouldBlock);
    assert!(open, "the stalled request was still open while frames {held} to {} came", held + 5);
    drop(slow);

    // The settings as a TOML file, which a fresh run reads back (GLRAY_CONFIG).
    let toml = run.get("/api/config.toml");
    assert_eq!(toml.status, 200);
    assert!(toml.headers.iter().any(|(k, v)| k == "content-disposition" && v.contains("attachment")));
    let file = dir.join("settings.toml");
    std::fs::write(&file, &toml.body).unwrap();
    drop(run);
    let mut info = Command::new(glray_bin());
    info.arg("info");
    without_glray(&mut info);
    info.env("GLRAY_CONFIG", &file);
    let said = stdout(&run_ok(&mut info, "glray info with the downloaded settings"));
    let preset = said.lines().find(|l| l.trim_start().starts_with("preset")).unwrap_or("");
    assert!(preset.contains("ao") && preset.contains("settings.toml"), "{preset}");
    let fresh_run = {
        let mut cmd = Command::new(glray_bin());
        cmd.arg("run").arg("--panel").arg("--").arg(which("glxgears")).args(["-geometry", "300x300"]);
        cmd.env("DISPLAY", &x.display);
        without_glray(&mut cmd);
        cmd.env("GLRAY_CONFIG", &file);
        start(cmd, &dir.join("fresh.log"))
    };
    assert_eq!(fresh_run.get("/api/settings").json()["settings"]["preset"], "ao");
    let frames = fresh_run.wait_for_frame(3);
    assert!(traced_ao(frames.last().unwrap()), "the fresh run traces AO from its settings file");
}

#[test]
fn a_change_on_rank_zeros_panel_reaches_both_ranks_of_glray_run_np_2() {
    let _one = one_at_a_time();
    // The MPI example host, 2 ranks image-parallel over TCP, 250 frames 20 ms apart, started
    // in the GL look; from the panel, mid-run: `full` without denoising or refinement (each
    // frame a picture of its own). Its last frame must be one process's with those settings
    // from the start, byte for byte: rank 1's tiles traced with rank 0's new settings.
    let dir = scratch("panel-mpi");
    let (frames, size) = ("250", ["96", "72"]);
    let changed = [("preset", "full"), ("denoise", "false"), ("progressive", "false")];
    let steered = dir.join("steered.png");
    let mut cmd = Command::new(glray_bin());
    cmd.args(["run", "--panel", "--np", "2", "--set", "preset=gl"]);
    cmd.args(["--mpirun-arg=--mca", "--mpirun-arg=btl", "--mpirun-arg=self,tcp", "--"]);
    cmd.arg(icet_like()).arg(&steered).arg(frames).args(size).env("ICET_LIKE_FRAME_MS", "20");
    without_glray(&mut cmd);
    cmd.env("ICET_LIKE_FRAME_MS", "20");
    let mut run = start(cmd, &dir.join("np2.log"));
    run.wait_for_frame(10);
    let body = serde_json::Value::Object(changed.iter().map(|(k, v)| (k.to_string(), (*v).into())).collect());
    let put = run.put(&body.to_string());
    assert_eq!(put.status, 200, "{}", put.text());
    // The change came in time: frames traced with secondary rays before the end.
    let at = run.last_frame();
    ao_within_two_frames(&run, at);
    let frames_seen = run.frames();
    assert!(frames_seen.iter().all(|f| f["ranks"] == 2), "the frames are shared by 2 ranks");
    let started = Instant::now();
    let status = loop {
        if let Some(s) = run.child.0.try_wait().unwrap() {
            break s;
        }
        assert!(started.elapsed() < Duration::from_secs(120), "the job did not end within 120 s");
        std::thread::sleep(Duration::from_millis(100));
    };
    let log = std::fs::read_to_string(dir.join("np2.log")).unwrap();
    assert!(status.success() && !log.contains("glray: error"), "{log}");

    // One process, the same settings from the start, the same number of frames.
    let alone = dir.join("alone.png");
    let mut cmd = command(Way::Preload, &[], &icet_like(), 120);
    cmd.arg(&alone).arg(frames).args(size).env("GLRAY_DISTRIBUTE", "local");
    cmd.envs(changed.iter().map(|(k, v)| (format!("GLRAY_{}", k.to_ascii_uppercase()), *v)));
    run_ok(&mut cmd, "icet_like alone");
    assert_same_file(&steered, &alone, "2 ranks steered from the panel against one process");
}

/// Headless Chromium driven over the DevTools protocol through a pipe
/// (`--remote-debugging-pipe`: commands in on its fd 3, answers out on fd 4, each a JSON text
/// ended by a NUL byte); killed by PID when dropped.
struct Chromium {
    _browser: Stopped,
    to: std::fs::File,
    from: std::sync::mpsc::Receiver<serde_json::Value>,
    next: u64,
    session: String,
}

impl Chromium {
    fn open(url: &str, profile: &Path) -> Chromium {
        use std::os::fd::{FromRawFd, IntoRawFd, OwnedFd};
        use std::os::unix::process::CommandExt;
        let pipe = || {
            let mut fds = [0; 2];
            // SAFETY: a fresh pair of descriptors, owned below.
            assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
            // SAFETY: just made, owned by nothing else.
            unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) }
        };
        let ((commands_r, commands_w), (answers_r, answers_w)) = (pipe(), pipe());
        let (cr, aw) = (commands_r.into_raw_fd(), answers_w.into_raw_fd());
        let mut cmd = Command::new(which("chromium"));
        cmd.args(["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"]);
        cmd.args(["--no-first-run", "--remote-debugging-pipe", "--window-size=1100,800"]);
        cmd.arg(format!("--user-data-dir={}", profile.display())).arg(url);
        cmd.stdout(Stdio::null()).stderr(Stdio::null());
        // SAFETY: only dup2 between fork and exec.
        unsafe {
            cmd.pre_exec(move || {
                if libc::dup2(cr, 3) < 0 || libc::dup2(aw, 4) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let child = cmd.spawn().expect("chromium: scripts/test installs it");
        // SAFETY: the child has its copies; these ends are the parent's to close.
        unsafe {
            drop(OwnedFd::from_raw_fd(cr));
            drop(OwnedFd::from_raw_fd(aw));
        }
        let (tx, from) = std::sync::mpsc::channel();
        let mut reader = BufReader::new(std::fs::File::from(answers_r));
        std::thread::spawn(move || loop {
            let mut message = Vec::new();
            match reader.read_until(0, &mut message) {
                Ok(0) | Err(_) => return,
                Ok(_) => {
                    message.pop();
                    if let Ok(v) = serde_json::from_slice(&message) {
                        if tx.send(v).is_err() {
                            return;
                        }
                    }
                }
            }
        });
        let mut c = Chromium {
            _browser: Stopped(child),
            to: std::fs::File::from(commands_w),
            from,
            next: 1,
            session: String::new(),
        };
        let started = Instant::now();
        let target = loop {
            let targets = c.call("Target.getTargets", serde_json::json!({}), false);
            let page = targets["targetInfos"]
                .as_array()
                .and_then(|t| {
                    t.iter().find(|t| t["type"] == "page" && t["url"].as_str().is_some_and(|u| u.contains("token=")))
                })
                .map(|t| t["targetId"].as_str().unwrap().to_string());
            if let Some(p) = page {
                break p;
            }
            assert!(started.elapsed() < Duration::from_secs(90), "no page in Chromium: {targets}");
            std::thread::sleep(Duration::from_millis(200));
        };
        let attached =
            c.call("Target.attachToTarget", serde_json::json!({ "targetId": target, "flatten": true }), false);
        c.session = attached["sessionId"].as_str().expect("a session").to_string();
        c
    }

    /// A DevTools command's result (in the page's session with `in_page`), bounded in time.
    fn call(&mut self, method: &str, params: serde_json::Value, in_page: bool) -> serde_json::Value {
        let id = self.next;
        self.next += 1;
        let mut m = serde_json::json!({ "id": id, "method": method, "params": params });
        if in_page {
            m["sessionId"] = self.session.clone().into();
        }
        let mut bytes = m.to_string().into_bytes();
        bytes.push(0);
        self.to.write_all(&bytes).unwrap();
        let deadline = Instant::now() + Duration::from_secs(90);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let v = self.from.recv_timeout(left).unwrap_or_else(|_| panic!("Chromium did not answer {method}"));
            if v["id"] == id {
                assert!(v["error"].is_null(), "{method}: {v}");
                return v["result"].clone();
            }
        }
    }

    /// A JavaScript expression's value in the page (promises awaited).
    fn eval(&mut self, expression: &str) -> serde_json::Value {
        let params = serde_json::json!({ "expression": expression, "awaitPromise": true, "returnByValue": true });
        let r = self.call("Runtime.evaluate", params, true);
        assert!(r["exceptionDetails"].is_null(), "{expression}: {r}");
        r["result"]["value"].clone()
    }

    /// Waits (bounded) until `expression` is true in the page.
    fn wait_until(&mut self, expression: &str, what: &str) {
        let started = Instant::now();
        while self.eval(expression) != serde_json::Value::Bool(true) {
            assert!(started.elapsed() < Duration::from_secs(90), "{what}: not within 90 s");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// The mean brightness of the gears in the frames the page shows, over four frames it shows
    /// numbered after `after`. The page puts a frame in place only once it is decoded whole
    /// (src/panel/page.html), so the shown element is read in one synchronous step: no script
    /// of the page's can swap it between the check and the drawing. (A `decode()` awaited on
    /// the shown element was rejected whenever the page changed its `src` meanwhile: the
    /// "EncodingError: The source image cannot be decoded" this test failed with.)
    fn shown_brightness(&mut self, after: u64) -> f64 {
        const MEAN: &str = "(() => { const img = document.getElementById('frame'); \
            if (!img.complete || !img.naturalWidth || img.dataset.frame === undefined) return null; \
            const c = document.createElement('canvas'); c.width = img.naturalWidth; c.height = img.naturalHeight; \
            const g = c.getContext('2d'); g.drawImage(img, 0, 0); const d = g.getImageData(0, 0, c.width, c.height).data; \
            let s = 0, n = 0; for (let i = 0; i < d.length; i += 4) { const v = d[i] + d[i + 1] + d[i + 2]; \
            if (v > 30) { s += v; n++; } } return [s, n, Number(img.dataset.frame)]; })()";
        let (mut sum, mut n, mut last) = (0.0, 0.0, after);
        for _ in 0..4 {
            let started = Instant::now();
            let v = loop {
                let v = self.eval(MEAN);
                if v[2].as_u64().is_some_and(|shown| shown > last) {
                    break v;
                }
                assert!(started.elapsed() < Duration::from_secs(90), "the page shows no frame after {last}: {v}");
                std::thread::sleep(Duration::from_millis(100));
            };
            last = v[2].as_u64().unwrap();
            (sum, n) = (sum + v[0].as_f64().unwrap(), n + v[1].as_f64().unwrap());
        }
        sum / n.max(1.0)
    }
}

#[test]
fn the_panels_page_in_headless_chromium_shows_frames_and_turns_ao_on() {
    let _one = one_at_a_time();
    let x = Xvfb::start();
    let dir = scratch("panel-page");
    let run = glxgears(&x.display, &dir.join("glxgears.log"), &["preset=gl"]);
    let url = format!("http://{}/?token={}", run.address, run.token);
    let profile = dir.join("chromium-profile");
    let _ = std::fs::remove_dir_all(&profile);
    let mut page = Chromium::open(&url, &profile);
    // It loads: a control for every setting the panel changes, and a frame.
    page.wait_until("document.querySelectorAll('[data-key]').length === 12", "the controls");
    assert_eq!(page.eval("document.getElementById('setting-preset').value"), "gl");
    page.wait_until("document.getElementById('frame').naturalWidth === 300", "a frame");
    page.wait_until("document.querySelectorAll('canvas').length >= 8", "the plots");
    let gl = page.shown_brightness(0);
    // A bad value: refused, the reason on the page.
    page.eval(
        "document.getElementById('setting-ao_samples').value = 'lots'; document.getElementById('apply').click(); 0",
    );
    page.wait_until("document.getElementById('error').textContent.includes('ao_samples')", "the refusal");
    // AO on, from the page: the frames after it trace AO and the picture darkens.
    page.eval(
        "document.getElementById('setting-ao_samples').value = ''; document.getElementById('setting-preset').value = 'ao'; \
         document.getElementById('apply').click(); 0",
    );
    page.wait_until("document.getElementById('ok').textContent.includes('preset = ao')", "the change");
    let taken = run.last_frame();
    ao_within_two_frames(&run, taken);
    // Frames from two after the change on trace AO: the page's, from then on, show it.
    let ao = page.shown_brightness(taken + 2);
    assert!(ao < 0.985 * gl, "the page's frame darkens with AO: {ao:.1} against {gl:.1}");
}
