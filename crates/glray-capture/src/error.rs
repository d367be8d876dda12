//! GL errors. Like Mesa, a context keeps the first error raised since the last glGetError; later
//! errors are dropped until it is read.

/// The GL error codes glray raises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum GlError {
    InvalidEnum = 0x0500,
    InvalidValue = 0x0501,
    InvalidOperation = 0x0502,
    StackOverflow = 0x0503,
    StackUnderflow = 0x0504,
    OutOfMemory = 0x0505,
}

pub type GlResult<T = ()> = Result<T, GlError>;

/// The error flag of a context.
#[derive(Debug, Default, Clone)]
pub struct ErrorFlag(Option<GlError>);

impl ErrorFlag {
    /// Records the outcome of a command: the first error sticks.
    pub fn record<T>(&mut self, r: GlResult<T>) -> Option<T> {
        match r {
            Ok(v) => Some(v),
            Err(e) => {
                self.0.get_or_insert(e);
                None
            }
        }
    }

    /// glGetError: the recorded error (0 = GL_NO_ERROR), and the flag is cleared.
    pub fn take(&mut self) -> u32 {
        self.0.take().map_or(0, |e| e as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_error_sticks_until_read() {
        let mut f = ErrorFlag::default();
        assert_eq!(f.record::<()>(Err(GlError::InvalidEnum)), None);
        assert_eq!(f.record::<()>(Err(GlError::InvalidValue)), None);
        assert_eq!(f.record(Ok(5)), Some(5));
        assert_eq!(f.take(), 0x0500);
        assert_eq!(f.take(), 0);
    }
}
