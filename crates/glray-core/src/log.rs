//! Messages to standard error, each line starting with `glray:`. The level is a global atomic so
//! that checking it costs one load; it is set once the settings are read.

use std::io::Write;
use std::sync::atomic::{AtomicU8, Ordering};

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub enum Level {
    Off = 0,
    Error = 1,
    Warn = 2,
    Info = 3,
    Debug = 4,
}

impl Level {
    pub fn parse(s: &str) -> Option<Level> {
        Some(match s {
            "off" => Level::Off,
            "error" => Level::Error,
            "warn" => Level::Warn,
            "info" => Level::Info,
            "debug" => Level::Debug,
            _ => return None,
        })
    }

    fn word(self) -> &'static str {
        match self {
            Level::Off => "",
            Level::Error => "error",
            Level::Warn => "warning",
            Level::Info => "info",
            Level::Debug => "debug",
        }
    }
}

static LEVEL: AtomicU8 = AtomicU8::new(Level::Warn as u8);

pub fn set_level(level: Level) {
    LEVEL.store(level as u8, Ordering::Relaxed);
}

pub fn enabled(level: Level) -> bool {
    level != Level::Off && level as u8 <= LEVEL.load(Ordering::Relaxed)
}

/// Writes one message if `level` is enabled. One write call per line, so that lines from
/// several threads do not interleave.
pub fn write(level: Level, msg: std::fmt::Arguments) {
    if enabled(level) {
        let line = format!("glray: {}: {msg}\n", level.word());
        let kept = CAPTURED.try_with(|c| c.borrow_mut().as_mut().map(|kept| kept.push_str(&line)).is_some());
        if kept != Ok(true) {
            let _ = std::io::stderr().write_all(line.as_bytes());
        }
    }
}

thread_local! {
    /// This thread's messages, kept instead of written while `captured` runs.
    static CAPTURED: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` with the messages this thread writes kept rather than printed, and returns them:
/// a test that expects an error reads it instead of printing it among passing tests' output.
pub fn captured<R>(f: impl FnOnce() -> R) -> (R, String) {
    let before = CAPTURED.with(|c| c.borrow_mut().replace(String::new()));
    let r = f();
    let kept = CAPTURED.with(|c| std::mem::replace(&mut *c.borrow_mut(), before)).unwrap_or_default();
    (r, kept)
}

/// "1 frame", "2 frames", "3 passes".
pub fn plural(n: u64, word: &str) -> String {
    match (n, word.ends_with('s')) {
        (1, _) => format!("1 {word}"),
        (_, true) => format!("{n} {word}es"),
        (_, false) => format!("{n} {word}s"),
    }
}

#[macro_export]
macro_rules! error { ($($t:tt)*) => { $crate::log::write($crate::log::Level::Error, format_args!($($t)*)) } }
#[macro_export]
macro_rules! warn { ($($t:tt)*) => { $crate::log::write($crate::log::Level::Warn, format_args!($($t)*)) } }
#[macro_export]
macro_rules! info { ($($t:tt)*) => { $crate::log::write($crate::log::Level::Info, format_args!($($t)*)) } }
#[macro_export]
macro_rules! debug { ($($t:tt)*) => { $crate::log::write($crate::log::Level::Debug, format_args!($($t)*)) } }

#[cfg(test)]
mod tests {
    #[test]
    fn counts_are_said_in_the_right_number() {
        use super::plural;
        assert_eq!(plural(1, "frame"), "1 frame");
        assert_eq!(plural(0, "sample"), "0 samples");
        assert_eq!(plural(3, "pass"), "3 passes");
    }
}
