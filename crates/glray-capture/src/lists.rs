//! Display lists with Mesa's rules (src/mesa/main/dlist.c), generic over what a compiled list
//! holds (the capture decides: state commands and meshes):
//! - glGenLists reserves a block of consecutive free names, each an empty list (glIsList is true);
//! - glNewList(0) is INVALID_VALUE, a bad mode INVALID_ENUM, glNewList while compiling
//!   INVALID_OPERATION; the list's old contents stay until glEndList replaces them;
//! - glEndList with no list open is INVALID_OPERATION;
//! - a nested glCallList is resolved when called (late binding), to a depth of 64;
//! - glCallLists adds glListBase to names decoded from BYTE..FLOAT and 2/3/4_BYTES.

use glray_gl::{
    GL_BYTE, GL_COMPILE, GL_COMPILE_AND_EXECUTE, GL_FLOAT, GL_INT, GL_SHORT, GL_UNSIGNED_BYTE, GL_UNSIGNED_INT,
    GL_UNSIGNED_SHORT,
};
use std::collections::HashMap;
use std::sync::Arc;

use crate::error::{GlError, GlResult};

/// How deep glCallList may nest (Mesa's MAX_LIST_NESTING).
pub const MAX_NESTING: usize = 64;

/// The list being compiled.
#[derive(Debug)]
struct Open<T> {
    name: u32,
    execute: bool,
    items: Vec<T>,
}

/// The display lists of a context (shared between contexts that share lists).
#[derive(Debug)]
pub struct DisplayLists<T> {
    lists: HashMap<u32, Arc<Vec<T>>>,
    open: Option<Open<T>>,
    base: u32,
}

impl<T> Default for DisplayLists<T> {
    fn default() -> Self {
        DisplayLists { lists: HashMap::new(), open: None, base: 0 }
    }
}

/// Bytes of one list name of `ty` in glCallLists (which also takes 2/3/4_BYTES); None for a
/// type glCallLists does not accept. The recorder sizes the array with it too.
pub fn name_size(ty: u32) -> Option<usize> {
    Some(match ty {
        GL_BYTE | GL_UNSIGNED_BYTE => 1,                   // BYTE, UNSIGNED_BYTE
        GL_SHORT | GL_UNSIGNED_SHORT | 0x1407 => 2,        // SHORT, UNSIGNED_SHORT, 2_BYTES
        0x1408 => 3,                                       // 3_BYTES
        GL_INT | GL_UNSIGNED_INT | GL_FLOAT | 0x1409 => 4, // INT, UNSIGNED_INT, FLOAT, 4_BYTES
        _ => return None,
    })
}

impl<T> DisplayLists<T> {
    pub fn gen_lists(&mut self, range: i32) -> GlResult<u32> {
        if range < 0 {
            return Err(GlError::InvalidValue);
        }
        if range == 0 {
            return Ok(0);
        }
        // The first block of `range` free names, starting at 1.
        let mut start = 1u32;
        'search: loop {
            for k in 0..range as u32 {
                let name = start.checked_add(k).ok_or(GlError::OutOfMemory)?;
                if self.lists.contains_key(&name) {
                    start = name + 1;
                    continue 'search;
                }
            }
            break;
        }
        for k in 0..range as u32 {
            self.lists.insert(start + k, Arc::new(Vec::new()));
        }
        Ok(start)
    }

    pub fn delete_lists(&mut self, list: u32, range: i32) -> GlResult {
        if range < 0 {
            return Err(GlError::InvalidValue);
        }
        for name in list..list.saturating_add(range as u32) {
            self.lists.remove(&name);
        }
        Ok(())
    }

    pub fn is_list(&self, list: u32) -> bool {
        self.lists.contains_key(&list)
    }

    pub fn new_list(&mut self, list: u32, mode: u32) -> GlResult {
        if list == 0 {
            return Err(GlError::InvalidValue);
        }
        let execute = match mode {
            GL_COMPILE => false,
            GL_COMPILE_AND_EXECUTE => true,
            _ => return Err(GlError::InvalidEnum),
        };
        if self.open.is_some() {
            return Err(GlError::InvalidOperation);
        }
        self.open = Some(Open { name: list, execute, items: Vec::new() });
        Ok(())
    }

    /// The list being compiled: its name and whether its commands also run now.
    pub fn compiling(&self) -> Option<(u32, bool)> {
        self.open.as_ref().map(|o| (o.name, o.execute))
    }

    /// Adds a compiled command to the open list (the caller checks `compiling` first).
    pub fn compile(&mut self, item: T) {
        if let Some(o) = self.open.as_mut() {
            o.items.push(item);
        }
    }

    /// glEndList: the list's contents are replaced now, not at glNewList.
    pub fn end_list(&mut self) -> GlResult {
        let o = self.open.take().ok_or(GlError::InvalidOperation)?;
        self.lists.insert(o.name, Arc::new(o.items));
        Ok(())
    }

    /// A list's contents, as they are when it is called.
    pub fn get(&self, list: u32) -> Option<Arc<Vec<T>>> {
        self.lists.get(&list).cloned()
    }

    pub fn list_base(&mut self, base: u32) {
        self.base = base;
    }

    /// The list names glCallLists(n, type, lists) calls, glListBase added.
    pub fn call_lists_names(&self, n: i32, ty: u32, data: &[u8]) -> GlResult<Vec<u32>> {
        if n < 0 {
            return Err(GlError::InvalidValue);
        }
        let n = n as usize;
        let size = name_size(ty).ok_or(GlError::InvalidEnum)?;
        let bytes = data.get(..n * size).ok_or(GlError::InvalidValue)?;
        let names = bytes.chunks_exact(size).map(|c| {
            let offset: i64 = match ty {
                0x1400 => c[0] as i8 as i64,
                0x1401 => c[0] as i64,
                0x1402 => i16::from_ne_bytes([c[0], c[1]]) as i64,
                0x1403 => u16::from_ne_bytes([c[0], c[1]]) as i64,
                0x1404 => i32::from_ne_bytes([c[0], c[1], c[2], c[3]]) as i64,
                0x1405 => u32::from_ne_bytes([c[0], c[1], c[2], c[3]]) as i64,
                0x1406 => f32::from_ne_bytes([c[0], c[1], c[2], c[3]]) as i64,
                // 2/3/4_BYTES: big-endian bytes, as the spec defines them.
                _ => c.iter().fold(0i64, |acc, b| acc * 256 + *b as i64),
            };
            (self.base as i64 + offset) as u32
        });
        Ok(names.collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gen_reserves_empty_lists_in_free_blocks() {
        let mut l: DisplayLists<&str> = DisplayLists::default();
        assert_eq!(l.gen_lists(3), Ok(1));
        assert!(l.is_list(1) && l.is_list(3) && !l.is_list(4));
        assert_eq!(l.get(2).unwrap().len(), 0);
        l.delete_lists(2, 1).unwrap();
        assert_eq!(l.gen_lists(1), Ok(2), "a hole of one fits one");
        assert_eq!(l.gen_lists(2), Ok(4), "but not two");
        assert_eq!(l.gen_lists(0), Ok(0));
        assert_eq!(l.gen_lists(-1), Err(GlError::InvalidValue));
        assert_eq!(l.delete_lists(1, -1), Err(GlError::InvalidValue));
    }

    #[test]
    fn a_list_is_replaced_at_end_list_not_at_new_list() {
        let mut l: DisplayLists<&str> = DisplayLists::default();
        l.new_list(7, GL_COMPILE).unwrap();
        l.compile("old");
        l.end_list().unwrap();
        l.new_list(7, GL_COMPILE_AND_EXECUTE).unwrap();
        assert_eq!(l.compiling(), Some((7, true)));
        l.compile("new");
        assert_eq!(*l.get(7).unwrap(), vec!["old"], "the old contents stay while compiling");
        l.end_list().unwrap();
        assert_eq!(*l.get(7).unwrap(), vec!["new"]);
        assert_eq!(l.compiling(), None);
    }

    #[test]
    fn list_errors_follow_mesa() {
        let mut l: DisplayLists<u8> = DisplayLists::default();
        assert_eq!(l.new_list(0, GL_COMPILE), Err(GlError::InvalidValue));
        assert_eq!(l.new_list(1, 0x1234), Err(GlError::InvalidEnum));
        assert_eq!(l.end_list(), Err(GlError::InvalidOperation));
        l.new_list(1, GL_COMPILE).unwrap();
        assert_eq!(l.new_list(2, GL_COMPILE), Err(GlError::InvalidOperation));
        assert_eq!(l.compiling(), Some((1, false)), "the failed glNewList changed nothing");
    }

    #[test]
    fn call_lists_decodes_every_type_and_adds_the_base() {
        let mut l: DisplayLists<u8> = DisplayLists::default();
        l.list_base(100);
        assert_eq!(l.call_lists_names(3, 0x1401, b"abc").unwrap(), vec![197, 198, 199]);
        assert_eq!(l.call_lists_names(1, 0x1400, &[0xFF]).unwrap(), vec![99]);
        assert_eq!(l.call_lists_names(2, 0x1403, &[1, 0, 2, 0]).unwrap(), vec![101, 102]);
        assert_eq!(l.call_lists_names(1, 0x1406, &2.0f32.to_ne_bytes()).unwrap(), vec![102]);
        assert_eq!(l.call_lists_names(1, 0x1407, &[1, 2]).unwrap(), vec![100 + 258]);
        assert_eq!(l.call_lists_names(1, 0x1408, &[0, 1, 2]).unwrap(), vec![100 + 258]);
        assert_eq!(l.call_lists_names(1, 0x1409, &[0, 0, 1, 0]).unwrap(), vec![100 + 256]);
        assert_eq!(l.call_lists_names(1, 0x1234, &[0]), Err(GlError::InvalidEnum));
        assert_eq!(l.call_lists_names(-1, 0x1401, &[]), Err(GlError::InvalidValue));
        assert_eq!(l.call_lists_names(4, 0x1401, b"ab"), Err(GlError::InvalidValue));
    }
}
