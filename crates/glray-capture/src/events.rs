//! Feeding recorded events (from a trace file, or from the live library's in-memory recorder)
//! into per-thread contexts, and handing out each frame when it ends.

use std::collections::HashMap;

use glray_core::trace::Event;

use crate::context::Context;
use crate::frame::Frame;
use crate::ops::{op_for, Op};

#[derive(Default)]
pub struct Capture {
    /// The op of each command number the trace has named.
    ops: Vec<Option<(Op, u32)>>,
    contexts: HashMap<u32, Context>,
    /// The thread of the last call: the one whose frame a frame event ends.
    last_thread: u32,
}

impl Capture {
    /// Follows one event; a frame end returns the frame just drawn (with its thread).
    /// `name` resolves a command number named by a Name event.
    pub fn event<'a>(&mut self, ev: &Event, name: impl Fn(usize) -> &'a [u8]) -> Option<(u32, Frame)> {
        match ev {
            Event::Name { number } => {
                let op = std::str::from_utf8(name(*number)).ok().and_then(op_for);
                if self.ops.len() <= *number {
                    self.ops.resize(*number + 1, None);
                }
                self.ops[*number] = op;
            }
            Event::Call { cmd, thread, args, .. } => {
                self.last_thread = *thread;
                if let Some(Some((op, ty))) = self.ops.get(*cmd) {
                    self.contexts.entry(*thread).or_default().call(*op, *ty, args);
                }
            }
            Event::Arrays { thread, arrays } => self.contexts.entry(*thread).or_default().set_arrays(arrays),
            Event::Drawable { thread, width, height, .. } => {
                self.contexts.entry(*thread).or_default().set_drawable(*width, *height)
            }
            Event::Frame { .. } => {
                let thread = self.last_thread;
                return Some((thread, self.contexts.entry(thread).or_default().take_frame()));
            }
            Event::End => {}
        }
        None
    }

    /// The context of a thread.
    pub fn context(&mut self, thread: u32) -> &mut Context {
        self.contexts.entry(thread).or_default()
    }
}
