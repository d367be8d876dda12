//! Fuzzes glray's trace reader: any bytes must give events or a TraceError naming an offset
//! inside the data, never a panic, a hang or a huge allocation.
#![no_main]

use glray_core::trace::Reader;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(mut r) = Reader::new(data) else { return };
    let mut events = 0usize;
    loop {
        match r.next_event() {
            Ok(Some(_)) => events += 1,
            Ok(None) => break,
            Err(e) => {
                assert!(e.offset <= data.len(), "error offset {} beyond {} bytes", e.offset, data.len());
                break;
            }
        }
        // Every event takes at least one byte: the reader always advances.
        assert!(events <= data.len());
    }
});
