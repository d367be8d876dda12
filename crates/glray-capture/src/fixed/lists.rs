//! Display lists with Mesa's rules (src/mesa/main/dlist.c), generic over what a compiled list
//! holds (the capture decides: state commands and meshes):
//! - glGenLists reserves a block of consecutive free names, each an empty list (glIsList is true);
//! - glNewList(0) is INVALID_VALUE, a bad mode INVALID_ENUM, glNewList while compiling
//!   INVALID_OPERATION; the list's old contents stay until glEndList replaces them;
//! - glEndList with no list open is INVALID_OPERATION;
//! - a nested glCallList is resolved when called (late binding), to a depth of 64;
//! - glCallLists adds glListBase to names decoded from BYTE..FLOAT and 2/3/4_BYTES.

use crate::args;
use crate::fixed::mesh_builder::Compiled;
use crate::fixed::mesh_builder::MeshBuilder;
use crate::fixed::vertex::decode_attribute;
use crate::fixed::vertex::Given;
use crate::fixed::Context;
use crate::fixed::EyeVertex;
use crate::fixed::Fetched;
use crate::ops::Attr;
use crate::ops::AttrForm;
use crate::ops::Op;
use crate::primitive::QuadSplit;
use glray_core::trace::Value;
use glray_gl::{
    GL_BYTE, GL_COMPILE, GL_COMPILE_AND_EXECUTE, GL_DOUBLE, GL_FLOAT, GL_INT, GL_POLYGON, GL_SHORT, GL_TRIANGLES,
    GL_UNSIGNED_BYTE, GL_UNSIGNED_INT, GL_UNSIGNED_SHORT,
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

// What a display list keeps, and the list commands of a context (Mesa's dlist.c).

/// An argument kept by a display list.
#[derive(Debug, Clone)]
pub(crate) enum ListArg {
    Int(i64),
    Float(f64),
    Bytes(Vec<u8>),
    Null,
}

/// What a display list holds.
#[derive(Debug, Clone)]
pub(crate) enum Item {
    Call(Op, u32, Vec<ListArg>),
    /// A glBegin/glEnd, or an array draw resolved to its vertices at compile time.
    Mesh(Arc<Compiled>),
}

fn keep(v: &Value) -> ListArg {
    match v {
        Value::Int(x) => ListArg::Int(*x),
        Value::UInt(x) | Value::Opaque(x) | Value::Offset(x) => ListArg::Int(*x as i64),
        Value::F32(x) => ListArg::Float(*x as f64),
        Value::F64(x) => ListArg::Float(*x),
        Value::Blob(b) | Value::Str(b) => ListArg::Bytes(b.to_vec()),
        _ => ListArg::Null,
    }
}

fn unkeep(k: &ListArg) -> Value<'_> {
    match k {
        ListArg::Int(x) => Value::Int(*x),
        ListArg::Float(x) => Value::F64(*x),
        ListArg::Bytes(b) => Value::Blob(b),
        ListArg::Null => Value::Null,
    }
}

/// An array draw's fetched vertices as a mesh, its quads cut as `quads` says.
pub(crate) fn fetched_mesh(mode: u32, verts: &[Fetched], quads: QuadSplit) -> Compiled {
    let mut b = MeshBuilder::new(true, quads);
    b.begin(mode);
    for v in verts {
        b.give(v);
    }
    b.finish()
}

impl Context {
    /// Follows a display-list command (`Concern::Lists`).
    pub(crate) fn list_command(&mut self, op: Op, a: &[Value]) -> GlResult {
        match op {
            Op::NewList => self.shared.lists.new_list(args::uint(a, 0), args::uint(a, 1))?,
            Op::EndList => {
                // The mesh being compiled ends; a glBegin left open stays calls.
                for item in self.spill() {
                    self.shared.lists.compile(item);
                }
                self.shared.lists.end_list()?
            }
            Op::CallList => self.run_list(args::uint(a, 0))?,
            Op::CallLists => {
                let names =
                    self.shared.lists.call_lists_names(args::int(a, 0) as i32, args::uint(a, 1), args::bytes(a, 2))?;
                for n in names {
                    self.run_list(n)?;
                }
            }
            Op::ListBase => self.shared.lists.list_base(args::uint(a, 0)),
            Op::GenLists => {
                self.shared.lists.gen_lists(args::int(a, 0) as i32)?;
            }
            Op::DeleteLists => self.shared.lists.delete_lists(args::uint(a, 0), args::int(a, 1) as i32)?,
            _ => unreachable!("{op:?} is not a display-list command"),
        }
        Ok(())
    }

    /// What the open list keeps of a call. Consecutive glBegin/glEnd of vertex attributes, and
    /// attributes given between them, become one mesh (glMaterial or a nested glCallList inside
    /// a glBegin, which a mesh cannot keep, turn that glBegin back into calls); array draws
    /// become meshes of the vertices they fetch now.
    pub(crate) fn compile_items(&mut self, op: Op, ty: u32, a: &[Value]) -> Vec<Item> {
        let draw = matches!(
            op,
            Op::DrawArrays | Op::DrawElements | Op::DrawRangeElements | Op::MultiDrawArrays | Op::MultiDrawElements
        );
        let mut items = Vec::new();
        // glArrayElement's client data is copied at compile time: the element's values now.
        let element = (op == Op::ArrayElement && args::int(a, 0) >= 0).then(|| self.element(args::int(a, 0) as u64));
        let given = match op {
            Op::Attr(f) if self.building.is_some() => decode_attribute(f, a).ok(),
            _ => None,
        };
        if given.is_some_and(|g| self.compile_given(&g)) {
            return items;
        }
        if let Some(b) = self.building.as_mut() {
            let open = b.is_open();
            let kept = match op {
                Op::End if open => {
                    b.end();
                    true
                }
                Op::Begin if !open && args::uint(a, 0) <= GL_POLYGON => {
                    b.begin(args::uint(a, 0));
                    true
                }
                Op::ArrayElement if open && element.is_some() => {
                    b.give(&element.expect("fetched"));
                    true
                }
                _ => false,
            };
            if kept {
                return items;
            }
            items = self.spill();
            if open {
                // Inside glBegin, a call a mesh cannot keep: the glBegin stays calls.
                items.push(Item::Call(op, ty, a.iter().map(keep).collect()));
                return items;
            }
        }
        if draw {
            // Client data is copied at compile time: keep the vertices the draw would fetch.
            if let Some(mesh) = self.indexed_triangles(op, a) {
                items.push(Item::Mesh(Arc::new(mesh)));
                return items;
            }
            let runs = self.fetch_draw(op, a).unwrap_or_default();
            // Mesa compiles every list into indexed draws, glDrawArrays' quads too.
            let mesh = |(mode, verts): (u32, Vec<Fetched>)| fetched_mesh(mode, &verts, QuadSplit::Indexed);
            items.extend(runs.into_iter().map(|run| Item::Mesh(Arc::new(mesh(run)))));
            return items;
        }
        if op == Op::Begin && args::uint(a, 0) <= GL_POLYGON {
            let mut b = MeshBuilder::new(false, QuadSplit::Indexed);
            b.begin(args::uint(a, 0));
            self.building = Some(b);
            return items;
        }
        items.push(Item::Call(op, ty, a.iter().map(keep).collect()));
        items
    }

    /// What an attribute command gives, kept by the mesh the open list is making from its
    /// glBegin/glEnd runs, if it is making one and can keep it (all but another texture unit's
    /// coordinates and edge flags).
    pub(crate) fn compile_given(&mut self, given: &Given) -> bool {
        let Some(b) = self.building.as_mut() else { return false };
        match *given {
            Given::Normal(n) => b.normal(n),
            Given::Color(c) => b.color(c),
            Given::TexCoord(0, t) => b.texcoord(t),
            // (Outside glBegin a vertex does nothing: the builder ignores it.)
            Given::Vertex(p) => b.vertex(p),
            Given::SecondaryColor => {}
            Given::TexCoord(..) | Given::EdgeFlag(_) => return false,
        }
        true
    }

    /// Ends the mesh being compiled: its closed glBegin/glEnd as a mesh, an open one back as
    /// the calls that made it.
    fn spill(&mut self) -> Vec<Item> {
        let Some(b) = self.building.take() else { return Vec::new() };
        if !b.is_open() {
            return vec![Item::Mesh(Arc::new(b.finish()))];
        }
        let (closed, mode, given) = b.split_open();
        let attr = |attr, n| Op::Attr(AttrForm { attr, n, ty: GL_DOUBLE, vector: false });
        let call = |op, v: &[f64]| Item::Call(op, GL_DOUBLE, v.iter().map(|x| ListArg::Float(*x)).collect());
        let mut items: Vec<Item> = closed.map(|m| Item::Mesh(Arc::new(m))).into_iter().collect();
        items.push(Item::Call(Op::Begin, GL_FLOAT, vec![ListArg::Int(mode as i64)]));
        items.extend(given.into_iter().map(|g| match g {
            Given::Vertex(p) => call(attr(Attr::Vertex, 4), &p.to_array()),
            Given::Normal(n) => call(attr(Attr::Normal, 3), &n.to_array()),
            Given::Color(c) => call(attr(Attr::Color, 4), &c.to_array()),
            Given::TexCoord(_, t) => call(attr(Attr::TexCoord, 4), &t.to_array()),
            Given::SecondaryColor | Given::EdgeFlag(_) => unreachable!("a builder keeps neither"),
        }));
        items
    }

    fn run_list(&mut self, list: u32) -> GlResult {
        if self.nesting >= MAX_NESTING {
            return Ok(()); // GL ignores calls nested deeper
        }
        let Some(items) = self.shared.lists.get(list) else { return Ok(()) };
        self.nesting += 1;
        for item in items.iter() {
            match item {
                Item::Call(op, ty, kept) => {
                    let a: Vec<Value> = kept.iter().map(unkeep).collect();
                    let r = self.execute(*op, *ty, &a);
                    self.raise(r);
                }
                Item::Mesh(mesh) => {
                    let r = self.run_mesh(mesh);
                    self.raise(r);
                }
            }
        }
        self.nesting -= 1;
        Ok(())
    }

    /// A list's mesh, called: an instance when the state allows, else its vertices through
    /// the vertex stage as the calls that made it would have gone. The attribute values it
    /// gave last stay current either way.
    pub(crate) fn run_mesh(&mut self, compiled: &Arc<Compiled>) -> GlResult {
        if self.imm.inside() && !compiled.from_arrays {
            // The list's glBegin, inside the caller's.
            self.unseen_error.record::<()>(Err(GlError::InvalidOperation));
            return Err(GlError::InvalidOperation);
        }
        let saved = self.imm.current;
        let mesh = &compiled.mesh;
        if self.instances(compiled) {
            self.instance(compiled);
        } else {
            let mut outs = Vec::with_capacity(mesh.positions.len());
            for i in 0..mesh.vertex_count() {
                let cur = &mut self.imm.current;
                if let Some(n) = mesh.normals.at(i) {
                    cur.normal = n.as_dvec3();
                }
                if let Some(c) = mesh.colors.at(i) {
                    cur.color = c.as_dvec4();
                }
                if let Some(t) = mesh.texcoords.at(i) {
                    cur.texcoords[0] = t.as_dvec4();
                }
                outs.push(self.vertex_stage(mesh.position(i)));
            }
            if compiled.runs.is_empty() {
                // An indexed mesh: its triangles.
                let corners: Vec<EyeVertex> = mesh.triangles.iter().flatten().map(|&i| outs[i as usize]).collect();
                self.draw(GL_TRIANGLES, &corners, compiled.quads);
            }
            for r in &compiled.runs {
                self.draw(r.mode, &outs[r.start as usize..(r.start + r.count) as usize], compiled.quads);
            }
        }
        // GL leaves the current values of enabled arrays undefined after a draw; Mesa keeps
        // the last one of a colour array only.
        let cur = &mut self.imm.current;
        *cur = saved;
        if !compiled.from_arrays || compiled.end_color.is_some() {
            cur.normal = compiled.end_normal.unwrap_or(cur.normal);
            cur.color = compiled.end_color.unwrap_or(cur.color);
            cur.texcoords[0] = compiled.end_texcoord.unwrap_or(cur.texcoords[0]);
        }
        Ok(())
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

    // Through the context, as a program calls them.
    use crate::fixed::tests::*;
    use glam::{DVec4, Vec3, Vec4};
    use glray_core::trace::Value;
    use glray_gl::*;
    use glray_scene::frame::TriangleId;
    use glray_scene::triangle::Triangle;

    #[test]
    fn lists_compile_execute_and_nest() {
        let mut c = context();
        call(&mut c, "glNewList", &[i(1), i(GL_COMPILE as i64)]); // GL_COMPILE
        triangle(&mut c, true);
        call(&mut c, "glEndList", &[]);
        assert_eq!(c.frame().triangles.len(), 0, "GL_COMPILE draws nothing");
        call(&mut c, "glNewList", &[i(2), i(GL_COMPILE_AND_EXECUTE as i64)]); // COMPILE_AND_EXECUTE, calling list 1
        call(&mut c, "glTranslatef", &[f(0.5), f(0.0), f(0.0)]);
        call(&mut c, "glCallList", &[i(1)]);
        call(&mut c, "glEndList", &[]);
        assert_eq!(c.frame().instances.len(), 1, "list 1's mesh, instanced");
        call(&mut c, "glLoadIdentity", &[]);
        call(&mut c, "glListBase", &[i(1)]);
        call(&mut c, "glCallLists", &[i(2), i(0x1401), Value::Blob(&[0, 1])]);
        let t = &c.frame().all_triangles();
        assert_eq!(t.len(), 3, "lists 1 and 2 through glListBase");
        assert!(c.frame().triangles.is_empty() && c.frame().instances.len() == 3);
        assert_eq!(t[1].positions[0].x, 0.0);
        assert_eq!(t[2].positions[0].x, 0.5, "list 2's translate, then list 1 nested");
        call(&mut c, "glNewList", &[i(3), i(0x1300)]);
        call(&mut c, "glNewList", &[i(4), i(0x1300)]);
        assert_eq!(c.errors.take(), 0x0502, "glNewList inside glNewList");
    }
    #[test]
    fn list_meshes_are_instanced_as_the_vertex_stage_would_draw_them() {
        let mut c = context();
        lit_scene(&mut c);
        call(&mut c, "glNewList", &[i(1), i(0x1300)]);
        strip(&mut c);
        call(&mut c, "glEndList", &[]);
        for (flat, front_face) in [(false, GL_CCW), (true, GL_CCW), (false, GL_CW)] {
            call(&mut c, "glShadeModel", &[i(if flat { GL_FLAT } else { GL_SMOOTH } as i64)]);
            call(&mut c, "glFrontFace", &[i(front_face as i64)]);
            let current = |c: &mut Context| {
                call(c, "glColor3f", &[f(1.0), f(0.0), f(0.0)]);
                call(c, "glNormal3f", &[f(0.0), f(0.0), f(1.0)]);
                call(c, "glTexCoord2f", &[f(0.125), f(0.0)]);
            };
            current(&mut c);
            strip(&mut c);
            current(&mut c);
            call(&mut c, "glCallList", &[i(1)]);
            assert_eq!(c.imm.current.color, DVec4::new(0.0, 1.0, 0.0, 1.0), "the list's last colour stays current");
            let frame = c.take_frame();
            assert_eq!(frame.instances.len(), 1);
            let direct = &frame.triangles;
            let instanced = frame.instances[0].triangles(&frame.lightings);
            assert_eq!(direct.len(), 2);
            assert_eq!(instanced.len(), 2);
            for (a, b) in direct.iter().zip(&instanced) {
                let close = |x: &[f32], y: &[f32]| x.iter().zip(y).all(|(p, q)| (p - q).abs() < 1e-5);
                let flat4 = |v: [Vec4; 3]| v.iter().flat_map(|c| c.to_array()).collect::<Vec<_>>();
                let flat3 = |v: [Vec3; 3]| v.iter().flat_map(|c| c.to_array()).collect::<Vec<_>>();
                assert!(close(&flat3(a.positions), &flat3(b.positions)), "{a:?}\n{b:?}");
                assert!(close(&flat4(a.colors), &flat4(b.colors)), "flat {flat}: {:?} vs {:?}", a.colors, b.colors);
                assert!(close(&flat3(a.normals), &flat3(b.normals)));
                assert!(close(&flat4(a.base_colors), &flat4(b.base_colors)));
                let uv = |t: &Triangle| t.texcoords.iter().flat_map(|c| c.to_array()).collect::<Vec<_>>();
                assert!(close(&uv(a), &uv(b)), "{:?} vs {:?}", a.texcoords, b.texcoords);
                assert_eq!((a.back, a.clip_w), (b.back, b.clip_w));
                assert_eq!(a.sequence + 1, b.sequence);
            }
        }
    }
    #[test]
    fn instances_cull_and_fall_back_to_the_vertex_stage_when_they_must() {
        let mut c = context();
        call(&mut c, "glNewList", &[i(1), i(0x1300)]);
        triangle(&mut c, true);
        triangle(&mut c, false);
        call(&mut c, "glEndList", &[]);
        call(&mut c, "glEnable", &[i(GL_CULL_FACE as i64)]);
        call(&mut c, "glCallList", &[i(1)]);
        let frame = c.take_frame();
        assert_eq!(frame.instances.len(), 1, "the list's two glBegin/glEnd make one mesh");
        let id = |index| TriangleId { instance: 0, index };
        assert!(frame.triangle(id(0)).is_some() && frame.triangle(id(1)).is_none(), "the back one is culled");
        assert_eq!(frame.all_triangles().len(), 1);
        // Outlines are screen-space quads: the list's vertices go through the vertex stage.
        call(&mut c, "glPolygonMode", &[i(GL_FRONT_AND_BACK as i64), i(GL_LINE as i64)]);
        call(&mut c, "glCallList", &[i(1)]);
        let frame = c.take_frame();
        assert!(frame.instances.is_empty());
        assert_eq!(frame.triangles.len(), 6, "three edges of the front triangle");
    }
    #[test]
    fn the_facing_a_ray_sees_is_the_facing_on_the_window() {
        // Triangles of both windings at several places, under modelviews that rotate and mirror,
        // with either front face: the one dot product a camera ray gives must cull as the
        // window winding does.
        for (mv, front) in [("glRotatef", GL_CCW), ("glScalef", GL_CCW), ("glScalef", GL_CW), ("glRotatef", GL_CW)] {
            let mut c = Context::default();
            c.set_drawable(64, 64);
            call(&mut c, "glMatrixMode", &[i(0x1701)]);
            call(&mut c, "glFrustum", &[f(-0.5), f(0.5), f(-0.5), f(0.5), f(1.0), f(20.0)]);
            call(&mut c, "glMatrixMode", &[i(0x1700)]);
            call(&mut c, "glNewList", &[i(1), i(0x1300)]);
            call(&mut c, "glBegin", &[i(4)]);
            for k in 0..8 {
                let (x, z) = ((k % 4) as f64 - 1.5, -3.0 - (k / 4) as f64);
                let pts = if k % 2 == 0 {
                    [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5)]
                } else {
                    [(0.0, 0.0), (0.0, 0.5), (0.5, 0.2)]
                };
                for (dx, dy) in pts {
                    call(&mut c, "glVertex3f", &[f(x + dx), f(dy - 0.2), f(z + dx * 0.7)]);
                }
            }
            call(&mut c, "glEnd", &[]);
            call(&mut c, "glEndList", &[]);
            call(&mut c, "glFrontFace", &[i(front as i64)]);
            call(&mut c, "glEnable", &[i(GL_CULL_FACE as i64)]);
            call(&mut c, "glTranslatef", &[f(0.0), f(0.0), f(-2.0)]);
            match mv {
                "glScalef" => call(&mut c, "glScalef", &[f(-1.0), f(1.0), f(1.0)]),
                _ => call(&mut c, "glRotatef", &[f(35.0), f(0.3), f(1.0), f(0.2)]),
            }
            call(&mut c, "glTranslatef", &[f(0.0), f(0.0), f(2.0)]);
            call(&mut c, "glCallList", &[i(1)]);
            let frame = c.take_frame();
            let inst = &frame.instances[0];
            let eye = inst.modelview.inverse() * DVec4::new(0.0, 0.0, 0.0, 1.0);
            for (k, t) in inst.mesh.triangles.iter().enumerate() {
                let p = t.map(|v| inst.mesh.positions[v as usize].as_dvec3());
                let normal = (p[1] - p[0]).cross(p[2] - p[0]);
                let toward = (p[0] + p[1] + p[2]) / 3.0 - eye.truncate() / eye.w;
                assert_eq!(
                    inst.keeps_seen(normal.dot(toward) as f32),
                    on_window(inst, k),
                    "{mv} {front:#x} triangle {k}"
                );
            }
            let kept = (0..8).filter(|&k| on_window(inst, k)).count();
            assert!(kept > 0 && kept < 8, "{mv} {front:#x}: both facings present ({kept} kept)");
        }
    }
    #[test]
    fn a_glbegin_a_mesh_cannot_keep_stays_calls() {
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_LIGHTING as i64)]);
        call(&mut c, "glNewList", &[i(1), i(0x1300)]);
        call(&mut c, "glBegin", &[i(4)]);
        call(&mut c, "glVertex2f", &[f(0.0), f(0.0)]);
        // glMaterial between glBegin and glEnd: allowed, but not in a mesh.
        call(&mut c, "glMaterialfv", &[i(GL_FRONT as i64), i(0x1200), Value::Blob(&f32s(&[1.0, 0.0, 0.0, 1.0]))]);
        call(&mut c, "glVertex2f", &[f(1.0), f(0.0)]);
        call(&mut c, "glVertex2f", &[f(0.0), f(1.0)]);
        call(&mut c, "glEnd", &[]);
        // Left open: stays calls too, and raises INVALID_OPERATION at the next glBegin.
        call(&mut c, "glBegin", &[i(4)]);
        call(&mut c, "glEndList", &[]);
        call(&mut c, "glCallList", &[i(1)]);
        let frame = c.take_frame();
        assert!(frame.instances.is_empty());
        assert_eq!(frame.triangles.len(), 1);
        assert!(frame.triangles[0].colors[2].x > 0.1, "the material changed mid-glBegin: {:?}", frame.triangles[0]);
        assert_eq!(c.errors.take(), 0, "the list's glBegin is open, not an error yet");
        triangle(&mut c, true);
        assert_eq!(c.errors.take(), 0x0502, "glBegin inside the list's glBegin");
    }
}
