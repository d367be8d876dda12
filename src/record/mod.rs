//! The trace file (`GLRAY_RECORD=path`, `glray run --record path`): one of the two sinks of the
//! stream of calls (the `calls` module encodes the calls; this writes them). The file is created at
//! the first recorded call, so processes that load glray but never call GL (a shell under
//! `glray run`) leave it alone; `%p` in the path becomes the process id, and a forked child
//! with `%p` in the path writes a trace of its own. docs/trace-format.md describes the file.

use std::fs::File;
use std::io::{self, Write};
use std::path::PathBuf;

use glray_core::trace::Encoder;

/// A trace file being written.
pub struct TraceFile {
    /// The path as the user gave it (with `%p`), for children.
    template: String,
    path: PathBuf,
    file: Option<File>,
}

impl TraceFile {
    /// The trace at `template` (`%p`: this process's id), not created yet.
    pub fn new(template: &str) -> TraceFile {
        let path = PathBuf::from(template.replace("%p", &std::process::id().to_string()));
        TraceFile { template: template.to_string(), path, file: None }
    }

    /// A forked child's trace: a file of its own when the path names the process (`%p`), else
    /// none (the parent's file and buffer are not the child's to write).
    pub fn for_child(&self) -> Option<TraceFile> {
        self.template.contains("%p").then(|| TraceFile::new(&self.template))
    }

    pub fn is_open(&self) -> bool {
        self.file.is_some()
    }

    /// Creates the file and writes the trace header.
    pub fn open(&mut self) -> Result<(), String> {
        let path = &self.path;
        let file = File::create(path).map_err(|e| format!("cannot create the trace {}: {e}", path.display()))?;
        let mut header = Encoder::new();
        header.header();
        let file = self.file.insert(file);
        header.flush_to(file).map_err(|e| format!("writing {}: {e}", path.display()))?;
        glray_core::info!("recording to {}", path.display());
        Ok(())
    }

    /// Writes what `encoded` writes into the file (what the stream encoded since the last
    /// write), and flushes it.
    pub fn write(&mut self, encoded: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<(), String> {
        let Some(f) = self.file.as_mut() else { return Ok(()) };
        encoded(f).and_then(|_| f.flush()).map_err(|e| format!("writing {}: {e}", self.path.display()))
    }
}
