//! The panel's HTTP side (tiny_http): the access token checked on every request, then the page
//! and the JSON API. Each request on a thread of its own (at most `CONCURRENT`), so that a slow
//! client holds up no other, and none holds up a frame (the shared state is locked only to copy).

use std::io::Read;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use tiny_http::{Header, Method, Request, Response};

use super::changes::{change, CONTROLS};
use super::Shared;

/// Requests served at once; more are refused (503) until one ends.
const CONCURRENT: usize = 16;
/// The largest request body read (a settings change is a few hundred bytes).
const BODY: u64 = 64 * 1024;

const PAGE: &str = include_str!("page.html");

pub(super) fn serve(server: tiny_http::Server, shared: Arc<Shared>) {
    let busy = Arc::new(AtomicUsize::new(0));
    for request in server.incoming_requests() {
        if busy.fetch_add(1, Ordering::AcqRel) >= CONCURRENT {
            busy.fetch_sub(1, Ordering::AcqRel);
            let _ = request.respond(json_error(503, "the panel is busy; try again"));
            continue;
        }
        let (shared, busy) = (shared.clone(), busy.clone());
        let spawned = std::thread::Builder::new().name("glray-panel-request".into()).spawn(move || {
            // A panic in a request ends that request only.
            let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| handle(request, &shared)));
            busy.fetch_sub(1, Ordering::AcqRel);
        });
        if spawned.is_err() {
            glray_core::warn!("panel: no thread for a request");
        }
    }
}

type Reply = Response<std::io::Cursor<Vec<u8>>>;

fn header(name: &str, value: &str) -> Header {
    Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("a valid header")
}

fn reply(status: u16, kind: &str, body: Vec<u8>) -> Reply {
    Response::from_data(body)
        .with_status_code(status)
        .with_header(header("Content-Type", kind))
        .with_header(header("Cache-Control", "no-store"))
}

fn json_error(status: u16, why: &str) -> Reply {
    reply(status, "application/json", serde_json::json!({ "error": why }).to_string().into_bytes())
}

/// The token a request carries: `?token=` in its URL, or an `X-Glray-Token` or
/// `Authorization: Bearer` header.
fn token_of(request: &Request) -> Option<String> {
    let query = request.url().split_once('?').map_or("", |(_, q)| q);
    let from_query = query.split('&').find_map(|kv| kv.strip_prefix("token=")).map(str::to_string);
    from_query.or_else(|| {
        request.headers().iter().find_map(|h| {
            let value = h.value.as_str();
            if h.field.equiv("X-Glray-Token") {
                Some(value.trim().to_string())
            } else if h.field.equiv("Authorization") {
                value.strip_prefix("Bearer ").map(|t| t.trim().to_string())
            } else {
                None
            }
        })
    })
}

/// Compares in time that does not depend on where the strings differ.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

fn handle(mut request: Request, shared: &Shared) {
    let response = match token_of(&request) {
        None => json_error(401, "no access token: add ?token=... as printed at start (glray: panel http://...)"),
        Some(t) if !same(&t, &shared.token) => json_error(403, "wrong access token"),
        Some(_) => route(&mut request, shared),
    };
    let _ = request.respond(response);
}

fn route(request: &mut Request, shared: &Shared) -> Reply {
    let path = request.url().split('?').next().unwrap_or("/").to_string();
    match (request.method(), path.as_str()) {
        (Method::Get, "/" | "/index.html") => reply(200, "text/html; charset=utf-8", PAGE.as_bytes().to_vec()),
        (Method::Get, "/api/settings") => settings(shared),
        (Method::Put | Method::Post, "/api/settings") => put_settings(request, shared),
        (Method::Get, "/api/stats") => stats(shared),
        (Method::Get, "/api/frame.png") => frame_png(shared),
        (Method::Get, "/api/config.toml") => {
            let text = shared.state().config.to_toml(CONTROLS, "downloaded from the live control panel");
            reply(200, "application/toml", text.into_bytes())
                .with_header(header("Content-Disposition", "attachment; filename=\"glray.toml\""))
        }
        (_, "/" | "/index.html" | "/api/settings" | "/api/stats" | "/api/frame.png" | "/api/config.toml") => {
            json_error(405, "method not allowed")
        }
        _ => json_error(404, "no such page: see docs/panel.md"),
    }
}

/// The panel's settings: values, where each came from, and what each accepts.
fn settings(shared: &Shared) -> Reply {
    let s = shared.state();
    let mut values = serde_json::Map::new();
    let mut sources = serde_json::Map::new();
    let mut allowed = serde_json::Map::new();
    for key in CONTROLS {
        values.insert(key.to_string(), s.config.value(key).unwrap_or("").into());
        sources.insert(key.to_string(), s.config.source(key).map_or(String::new(), |x| x.to_string()).into());
        allowed.insert(key.to_string(), glray_core::config::Config::allowed(key).unwrap_or_default().into());
    }
    let body = serde_json::json!({ "settings": values, "sources": sources, "allowed": allowed, "order": CONTROLS });
    reply(200, "application/json", body.to_string().into_bytes())
}

/// A change: a JSON object of settings and values (strings, numbers or booleans), made whole or
/// not at all; the settings as they now are, or the reason it was refused (400).
fn put_settings(request: &mut Request, shared: &Shared) -> Reply {
    let mut body = String::new();
    if request.as_reader().take(BODY).read_to_string(&mut body).is_err() {
        return json_error(400, "the request's body is not UTF-8 text");
    }
    let object: serde_json::Map<String, serde_json::Value> = match serde_json::from_str(&body) {
        Ok(o) => o,
        Err(e) => return json_error(400, &format!("the body must be a JSON object of settings: {e}")),
    };
    let mut changes = Vec::new();
    for (key, value) in object {
        let text = match value {
            serde_json::Value::String(s) => s,
            serde_json::Value::Bool(b) => b.to_string(),
            serde_json::Value::Number(n) => n.to_string(),
            serde_json::Value::Null => String::new(),
            other => return json_error(400, &format!("setting `{key}`: {other} is not a value")),
        };
        changes.push((key, text));
    }
    {
        let mut s = shared.state();
        match change(&s.config, &changes) {
            Ok((config, _)) => {
                s.config = config;
                s.pending.extend(changes);
            }
            Err(why) => return json_error(400, &why),
        }
    }
    settings(shared)
}

/// The last frames' statistics (oldest first; in an MPI job each says the ranks sharing it).
fn stats(shared: &Shared) -> Reply {
    let s = shared.state();
    let frames: Vec<&str> = s.stats.iter().map(String::as_str).collect();
    let last = s.frame.as_ref().map_or("null".to_string(), |f| f.0.to_string());
    let body = format!("{{\"last_frame\":{last},\"frames\":[{}]}}", frames.join(","));
    reply(200, "application/json", body.into_bytes())
}

/// The last frame, scaled down, as a PNG (rows top first); 404 before the first.
fn frame_png(shared: &Shared) -> Reply {
    let Some((number, w, h, rgba)) = shared.state().frame.clone() else {
        return json_error(404, "no frame presented yet");
    };
    let row = 4 * w as usize;
    let flipped: Vec<u8> = rgba.chunks_exact(row).rev().flatten().copied().collect();
    let mut png = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png, w, h);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Fast);
        let written = encoder.write_header().and_then(|mut w| w.write_image_data(&flipped));
        if let Err(e) = written {
            return json_error(500, &format!("the frame did not encode: {e}"));
        }
    }
    reply(200, "image/png", png).with_header(header("X-Glray-Frame", &number.to_string()))
}
