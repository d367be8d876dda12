//! The scene's byte encoding (what crosses MPI ranks): every frame of the trace suite, captured
//! as the live library captures it, comes back from its bytes as the same frame and renders to
//! the same image, with effects; meshes and textures travel once; damaged and foreign messages
//! are refused with what is wrong.

use std::path::Path;

use glray_capture::events::Capture;
use glray_core::trace::Reader;
use glray_render::{Effects, Options, Renderer};
use glray_scene::encode::{decode, encode, DecodeError, ObjectStore, MAGIC, VERSION};
use glray_scene::frame::Frame;

/// Every frame of a trace, as capture hands them out.
fn frames_of(trace: &Path) -> Vec<Frame> {
    let data = std::fs::read(trace).unwrap();
    let mut reader = Reader::new(&data).unwrap();
    let mut capture = Capture::default();
    let mut frames = Vec::new();
    while let Some(event) = reader.next_event().unwrap() {
        if let Some((_, frame)) = capture.event(&event, |n| reader.name(n)) {
            frames.push(frame);
        }
    }
    frames
}

fn traces() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/traces");
    let mut t: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "trace"))
        .collect();
    t.sort();
    t
}

#[test]
fn every_frame_of_the_trace_suite_round_trips_to_the_same_frame_and_image() {
    let options = Options { effects: Effects::preset("full").unwrap(), ..Options::default() };
    let mut checked = 0;
    let mut instanced = 0;
    for trace in traces() {
        let (mut sender, mut receiver) = (ObjectStore::default(), ObjectStore::default());
        let (mut here, mut there) = (Renderer::new(options), Renderer::new(options));
        for (n, frame) in frames_of(&trace).into_iter().enumerate() {
            // The meshes this message must carry: those not sent with an earlier frame.
            let mut fresh: Vec<_> =
                frame.instances.iter().map(|i| &i.mesh).filter(|m| !sender.has_mesh(m.id)).collect();
            fresh.sort_by_key(|m| m.id);
            fresh.dedup_by_key(|m| m.id);
            let fresh: usize = fresh.iter().map(|m| m.bytes()).sum();
            let bytes = encode(&frame, &mut sender);
            let decoded = decode(&bytes, &mut receiver).unwrap_or_else(|e| panic!("{trace:?} frame {n}: {e}"));
            assert!(decoded == frame, "{trace:?} frame {n}: the decoded frame differs");
            let (w, h) = frame.size();
            if w == 0 || h == 0 || frame.is_empty() {
                continue;
            }
            let a = here.render(&frame, w, h, None);
            let b = there.render(&decoded, w, h, None);
            assert!(a.rgba == b.rgba && a.depth == b.depth, "{trace:?} frame {n}: the pictures differ");
            assert!(a.rgba.chunks(4).any(|p| p != &a.rgba[..4]), "{trace:?} frame {n}: a picture of one colour");
            checked += 1;
            if !frame.instances.is_empty() {
                instanced += 1;
                // Sent again, the frame names its meshes and textures by id only.
                let again = encode(&frame, &mut sender);
                let saved = bytes.len() - again.len();
                assert!(
                    saved >= fresh,
                    "{trace:?} frame {n}: {} then {} bytes, new meshes {fresh}",
                    bytes.len(),
                    again.len()
                );
                assert!(decode(&again, &mut receiver).unwrap() == frame);
            }
        }
    }
    assert!(checked >= 10 && instanced >= 3, "{checked} frames checked, {instanced} with instances");
}

#[test]
fn damaged_and_foreign_messages_are_refused_with_the_reason() {
    let trace = traces().into_iter().find(|t| t.ends_with("osmesa-lists.trace")).unwrap();
    let frame = frames_of(&trace).into_iter().find(|f| !f.instances.is_empty()).unwrap();
    let bytes = encode(&frame, &mut ObjectStore::default());
    assert_eq!(&bytes[..8], MAGIC);

    let receiver = || ObjectStore::default();
    assert_eq!(decode(b"not a scene at all", &mut receiver()), Err(DecodeError::NotAScene));
    let mut other = bytes.clone();
    other[8..10].copy_from_slice(&(VERSION + 1).to_le_bytes());
    assert_eq!(decode(&other, &mut receiver()), Err(DecodeError::Version { found: VERSION + 1, expected: VERSION }));
    let mut swapped = bytes.clone();
    swapped[10] ^= 3;
    assert_eq!(decode(&swapped, &mut receiver()), Err(DecodeError::ByteOrder));
    let cut = decode(&bytes[..bytes.len() / 2], &mut receiver());
    assert!(matches!(cut, Err(DecodeError::Damaged { .. })), "{cut:?}");
    assert!(cut.unwrap_err().to_string().contains("near byte"));

    // A frame whose meshes were never sent: the sender believes the receiver holds them.
    let mut believed = ObjectStore::default();
    let _ = encode(&frame, &mut believed);
    let second = encode(&frame, &mut believed);
    let missing = decode(&second, &mut receiver());
    let id = frame.instances[0].mesh.id;
    assert!(matches!(missing, Err(DecodeError::Missing { what: "mesh", id: m }) if m == id), "{missing:?} (mesh {id})");
}
