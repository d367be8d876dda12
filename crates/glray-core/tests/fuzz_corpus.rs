//! Every input the fuzzer kept (fuzz/corpus/trace_reader, and any crash it found in
//! fuzz/artifacts) goes through the trace reader again on every test run: events or an error
//! inside the data, never a panic.

use glray_core::trace::Reader;
use std::path::Path;

fn read_all(data: &[u8]) -> usize {
    let Ok(mut r) = Reader::new(data) else { return 0 };
    let mut events = 0;
    loop {
        match r.next_event() {
            Ok(Some(_)) => events += 1,
            Ok(None) => return events,
            Err(e) => {
                assert!(e.offset <= data.len(), "error offset {} beyond {} bytes", e.offset, data.len());
                return events;
            }
        }
    }
}

#[test]
fn the_fuzz_corpus_reads_without_panicking() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut files = 0;
    for dir in ["corpus/trace_reader", "artifacts/trace_reader"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else { continue };
        for e in entries {
            let path = e.unwrap().path();
            let data = std::fs::read(&path).unwrap();
            read_all(&data);
            files += 1;
        }
    }
    assert!(files >= 50, "only {files} corpus files: the corpus is missing");
}
