//! At load: the settings are read (so that a bad one is reported at program start) and the
//! stream of calls is started with its sinks: the live feed when ray tracing (any preset but
//! `off`), the trace file when recording.

use crate::abi::runtime;
use crate::calls;
use crate::feed;
use crate::record::TraceFile;

fn start() {
    crate::distribute::at_load();
    let config = &runtime::get().config;
    let capture = config.enable() && config.preset() != "off";
    let live = capture.then(|| feed::configure(config));
    if capture || config.record().is_some() {
        calls::start(config.record().map(TraceFile::new), live);
    }
}

/// Runs `start` as the library loads.
#[used]
#[link_section = ".init_array"]
static INIT: extern "C" fn() = {
    extern "C" fn init_at_load() {
        let _ = std::panic::catch_unwind(start);
    }
    init_at_load
};
