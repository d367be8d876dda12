//! A draw a display list keeps, in object coordinates. A list's glBegin/glEnd (or array draw)
//! becomes a `Mesh` once, when the list is compiled; every glCallList then adds an instance of
//! it (the modelview and the state of that call) instead of running its vertices again, and the
//! tracer keeps the mesh's BVH for as long as the list lives. That is what makes a program that
//! draws big lists every frame cheap to follow: its frames cost the instances, not the
//! triangles.
//!
//! Vertices keep the attributes the list gave them. One the list did not give (a sphere list
//! drawn after a glColor) is the value current at the call: `Attribute::first` says from which
//! vertex on the list gives its own.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DVec3, DVec4, Vec3, Vec4};
use glray_core::threads::{collect_pieces, map_pieces, piece_of};

use crate::primitive::{assemble, QuadSplit};
use crate::vertex::Given;

/// One per-vertex attribute of a mesh.
#[derive(Debug, Clone, Default)]
pub struct Attribute<T> {
    /// The first vertex that has its own value (the number of vertices if none has).
    pub first: u32,
    /// Values of vertices `first..`.
    pub values: Vec<T>,
}

impl<T> Attribute<T> {
    /// Every one of `n` vertices' values, or (None) none: all take the value current at the call.
    fn all_or_none(values: Option<Vec<T>>, n: u32) -> Attribute<T> {
        match values {
            Some(values) => Attribute { first: 0, values },
            None => Attribute { first: n, values: Vec::new() },
        }
    }
}

impl<T: Copy> Attribute<T> {
    /// Vertex `i`'s own value; None when it takes the value current at the call.
    #[inline]
    pub fn at(&self, i: u32) -> Option<T> {
        self.value(i).copied()
    }

    /// Where vertex `i`'s own value is stored, if it has one.
    #[inline]
    pub fn value(&self, i: u32) -> Option<&T> {
        i.checked_sub(self.first).and_then(|k| self.values.get(k as usize))
    }

    /// Keeps the values of the first `n` vertices.
    fn truncate(&mut self, n: u32) {
        self.values.truncate(n.saturating_sub(self.first) as usize);
    }

    /// Appends vertex `index`'s value (None: not given yet).
    fn push(&mut self, index: u32, value: Option<T>) {
        match value {
            Some(v) => {
                if self.values.is_empty() {
                    self.first = index;
                }
                self.values.push(v);
            }
            None => self.first = index + 1,
        }
    }
}

/// One glBegin/glEnd of a mesh: its mode and its vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Run {
    pub mode: u32,
    pub start: u32,
    pub count: u32,
}

/// A compiled draw in object coordinates.
#[derive(Debug, Default)]
pub struct Mesh {
    /// Unique for the life of the process: the tracer keys its BVHs by it.
    pub id: u64,
    /// The glBegin/glEnd (or array draws) it was made of, in order, each a run of vertices
    /// (empty for an indexed mesh).
    pub runs: Vec<Run>,
    pub positions: Vec<Vec3>,
    /// w of every position when one is not 1 (such a mesh is never instanced).
    pub ws: Option<Vec<f32>>,
    pub normals: Attribute<Vec3>,
    pub colors: Attribute<Vec4>,
    /// Texture unit 0's coordinates.
    pub texcoords: Attribute<Vec4>,
    /// The runs' triangles (vertex indices) and each one's provoking vertex.
    pub triangles: Vec<[u32; 3]>,
    pub provoking: Vec<u32>,
    /// A run draws lines or points, which depend on the screen: never instanced.
    pub lines_or_points: bool,
    /// An array draw (GL leaves current values as Mesa does: only a colour array changes
    /// them) rather than glBegin/glEnd (the last values given stay current).
    pub from_arrays: bool,
    /// How its runs' quads are cut: as Mesa cuts a display list's or an indexed draw's, or a
    /// glDrawArrays'.
    pub quads: QuadSplit,
    /// The attribute values current after the draw, exactly as given.
    pub end_normal: Option<DVec3>,
    pub end_color: Option<DVec4>,
    pub end_texcoord: Option<DVec4>,
    /// Object-space bounds of the positions.
    pub min: Vec3,
    pub max: Vec3,
    /// Triangle i's corners are vertices 3i, 3i + 1 and 3i + 2 (glBegin(GL_TRIANGLES) lists,
    /// the common big display list): `corner_indices` works them out instead of reading
    /// `triangles`, one cache miss less for every hit on a big mesh. Private, so that only
    /// `finish` and `of_triangles`, which check it, set it.
    sequential: bool,
}

/// Whether every triangle's corners are the next three vertices (see `Mesh::sequential`).
fn sequential(triangles: &[[u32; 3]]) -> bool {
    triangles.iter().enumerate().all(|(i, t)| {
        let first = 3 * i as u64;
        t.map(u64::from) == [first, first + 1, first + 2]
    })
}

/// The box around `positions` (empty: min above max), a big mesh's in pieces on glray's threads.
fn bounds(positions: &[Vec3]) -> (Vec3, Vec3) {
    let fold =
        |ps: &[Vec3]| ps.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let piece = piece_of::<Vec3>();
    if positions.len() <= piece {
        return fold(positions);
    }
    let boxes = map_pieces(positions, piece, fold);
    boxes.into_iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
}

/// Each triangle's provoking vertex, its last (GL_TRIANGLES), in pieces on glray's threads.
fn last_corners(triangles: &[[u32; 3]]) -> Vec<u32> {
    let made = collect_pieces(triangles.len(), piece_of::<[u32; 3]>(), |first, piece| {
        for t in &triangles[first..first + piece.room()] {
            piece.push(t[2]);
        }
    });
    made.map_or_else(|| triangles.iter().map(|t| t[2]).collect(), |(provoking, _)| provoking)
}

/// A new mesh's id.
fn next_id() -> u64 {
    static NEXT_ID: AtomicU64 = AtomicU64::new(1);
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

impl Mesh {
    /// Indexed triangles with a normal per vertex (a mesh file's, a benchmark's): as a list of
    /// GL_TRIANGLES would keep them, without repeating shared vertices. None if an index is out
    /// of range.
    pub fn indexed(positions: Vec<Vec3>, normals: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Option<Mesh> {
        let n = positions.len() as u32;
        if normals.len() != positions.len() || triangles.iter().flatten().any(|&i| i >= n) {
            return None;
        }
        Some(Mesh::of_triangles(
            positions,
            Attribute::all_or_none(Some(normals), n),
            Attribute::all_or_none(None, n),
            Attribute::all_or_none(None, n),
            triangles,
        ))
    }

    /// An indexed mesh of GL_TRIANGLES (each triangle's provoking vertex its third), with its
    /// bounds and a new id.
    fn of_triangles(
        positions: Vec<Vec3>,
        normals: Attribute<Vec3>,
        colors: Attribute<Vec4>,
        texcoords: Attribute<Vec4>,
        triangles: Vec<[u32; 3]>,
    ) -> Mesh {
        let (min, max) = bounds(&positions);
        Mesh {
            id: next_id(),
            sequential: sequential(&triangles),
            provoking: last_corners(&triangles),
            triangles,
            positions,
            normals,
            colors,
            texcoords,
            min,
            max,
            ..Mesh::default()
        }
    }

    /// An indexed array draw of GL_TRIANGLES, its vertices fetched once each: the arrays'
    /// values (None: that array is off, the value current at the call applies), the triangles'
    /// vertex indices, and what the draw leaves current (normal, colour, texture coordinates).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn from_arrays(
        positions: Vec<Vec3>,
        ws: Vec<f32>,
        normals: Option<Vec<Vec3>>,
        colors: Option<Vec<Vec4>>,
        texcoords: Option<Vec<Vec4>>,
        triangles: Vec<[u32; 3]>,
        end: (Option<DVec3>, Option<DVec4>, Option<DVec4>),
    ) -> Mesh {
        let n = positions.len() as u32;
        // Kept only when one is not 1 (an empty `ws`: every w is 1).
        let ws = ws.iter().any(|&w| w != 1.0).then_some(ws);
        Mesh {
            ws,
            from_arrays: true,
            end_normal: end.0,
            end_color: end.1,
            end_texcoord: end.2,
            ..Mesh::of_triangles(
                positions,
                Attribute::all_or_none(normals, n),
                Attribute::all_or_none(colors, n),
                Attribute::all_or_none(texcoords, n),
                triangles,
            )
        }
    }

    /// The bytes its vertices and triangles take (what shading a hit on it reads from).
    pub fn bytes(&self) -> usize {
        use std::mem::size_of;
        self.positions.len() * size_of::<Vec3>()
            + self.normals.values.len() * size_of::<Vec3>()
            + self.colors.values.len() * size_of::<Vec4>()
            + self.texcoords.values.len() * size_of::<Vec4>()
            + self.triangles.len() * size_of::<[u32; 3]>()
    }

    pub fn vertex_count(&self) -> u32 {
        self.positions.len() as u32
    }

    /// The vertex indices of triangle `index`'s corners (`triangles[index]`).
    #[inline]
    pub fn corner_indices(&self, index: usize) -> [u32; 3] {
        if self.sequential && index < self.triangles.len() {
            let first = 3 * index as u32;
            [first, first + 1, first + 2]
        } else {
            self.triangles[index]
        }
    }

    /// Whether `corner_indices` works the corners out without reading `triangles`.
    pub fn is_sequential(&self) -> bool {
        self.sequential
    }

    /// The object-space corners of triangle `index`.
    #[inline]
    pub fn corners(&self, index: usize) -> [Vec3; 3] {
        self.corner_indices(index).map(|i| self.positions[i as usize])
    }

    /// A hash of what a BVH over the mesh depends on: its positions and its triangles' corners
    /// (`arrays::content_hash` of each, on glray's threads for a big mesh). Two meshes with the
    /// same shape have the same tree: a time step that sends the same vertices again (only its
    /// colours new) keeps the last step's tree as it is.
    pub fn shape_hash(&self) -> [i64; 4] {
        let [a, b] = crate::arrays::content_hash(bytemuck::cast_slice(&self.positions));
        let [c, d] = crate::arrays::content_hash(bytemuck::cast_slice(&self.triangles));
        [a, b, c, d]
    }

    /// Starts loading what reading triangle `index`'s corners needs, in two calls a few
    /// triangles apart: with `corners` false, its vertex indices (a sequential mesh has none
    /// to read: its corners go then, through `vertex`), with true its corners (`vertex` of
    /// each one's index, in cache by then if loaded before).
    #[inline]
    pub fn load_ahead(&self, index: usize, corners: bool, vertex: impl FnMut(u32)) {
        let Some(indices) = self.triangles.get(index) else { return };
        match (self.sequential, corners) {
            (false, false) => glray_core::prefetch::line(indices),
            (true, true) => {}
            (false, true) | (true, false) => self.corner_indices(index).into_iter().for_each(vertex),
        }
    }

    /// `load_ahead` of what `corners(index)` reads: the indices, then the positions.
    #[inline]
    pub fn load_corners(&self, index: usize, corners: bool) {
        self.load_ahead(index, corners, |v| {
            if let Some(p) = self.positions.get(v as usize) {
                glray_core::prefetch::line(p);
            }
        });
    }

    /// Position `i` with its w.
    #[inline]
    pub fn position(&self, i: u32) -> DVec4 {
        let w = self.ws.as_ref().map_or(1.0, |ws| ws[i as usize]);
        self.positions[i as usize].as_dvec3().extend(w as f64)
    }
}

/// A mesh being compiled: the attribute values given so far, and the vertices.
#[derive(Debug)]
pub struct MeshBuilder {
    mesh: Mesh,
    normal: Option<DVec3>,
    color: Option<DVec4>,
    texcoord: Option<DVec4>,
    /// The open glBegin's mode and first vertex.
    open: Option<(u32, u32)>,
}

impl MeshBuilder {
    /// A mesh of glBegin/glEnd runs (`from_arrays`: of array draws), its quads cut as `quads`
    /// says.
    pub fn new(from_arrays: bool, quads: QuadSplit) -> MeshBuilder {
        MeshBuilder {
            mesh: Mesh { from_arrays, quads, ..Mesh::default() },
            normal: None,
            color: None,
            texcoord: None,
            open: None,
        }
    }

    /// `new`, in the room of `room`'s vectors (a mesh made again every frame would otherwise
    /// fault in fresh pages for all of them each time).
    pub(crate) fn reusing(room: Mesh, from_arrays: bool, quads: QuadSplit) -> MeshBuilder {
        let mut b = MeshBuilder::new(from_arrays, quads);
        let (m, mut r) = (&mut b.mesh, room);
        r.positions.clear();
        r.normals.values.clear();
        r.colors.values.clear();
        r.texcoords.values.clear();
        r.triangles.clear();
        r.provoking.clear();
        r.runs.clear();
        (m.positions, m.normals.values, m.colors.values, m.texcoords.values) =
            (r.positions, r.normals.values, r.colors.values, r.texcoords.values);
        (m.triangles, m.provoking, m.runs) = (r.triangles, r.provoking, r.runs);
        b
    }

    /// The mesh so far with its open glBegin closed, as `finish` would give it but for its id,
    /// bounds and corner layout (enough to tell it from another).
    pub(crate) fn closed(&mut self) -> &Mesh {
        self.end();
        let m = &mut self.mesh;
        (m.end_normal, m.end_color, m.end_texcoord) = (self.normal, self.color, self.texcoord);
        let n = m.positions.len() as u32;
        for a in [&mut m.normals.first, &mut m.colors.first, &mut m.texcoords.first] {
            *a = (*a).min(n);
        }
        &self.mesh
    }

    /// Its vectors, for `reusing`.
    pub(crate) fn into_room(self) -> Mesh {
        self.mesh
    }

    /// A glBegin: the vertices that follow make a run of `mode`.
    pub fn begin(&mut self, mode: u32) {
        self.end();
        self.open = Some((mode, self.mesh.positions.len() as u32));
    }

    /// A glEnd: the open run's vertices are assembled into triangles.
    pub fn end(&mut self) {
        let Some((mode, start)) = self.open.take() else { return };
        let m = &mut self.mesh;
        let count = m.positions.len() as u32 - start;
        if let Ok(asm) = assemble(mode, count as usize, m.quads) {
            m.lines_or_points |= !asm.lines.is_empty() || !asm.points.is_empty();
            m.triangles.extend(asm.triangles.iter().map(|(t, _)| t.map(|i| i + start)));
            m.provoking.extend(asm.triangles.iter().map(|(_, p)| p + start));
        }
        m.runs.push(Run { mode, start, count });
    }

    /// The positions given so far.
    pub(crate) fn positions(&self) -> &[Vec3] {
        &self.mesh.positions
    }

    /// Cuts its quads as `quads` says from now on (its runs are assembled as they close).
    pub(crate) fn cut_quads(&mut self, quads: QuadSplit) {
        self.mesh.quads = quads;
    }

    /// Whether a glBegin is open.
    pub fn is_open(&self) -> bool {
        self.open.is_some()
    }

    /// Whether it holds any run.
    pub fn is_empty(&self) -> bool {
        self.mesh.runs.is_empty() && self.open.is_none()
    }

    pub fn normal(&mut self, n: DVec3) {
        self.normal = Some(n);
    }

    pub fn color(&mut self, c: DVec4) {
        self.color = Some(c);
    }

    pub fn texcoord(&mut self, t: DVec4) {
        self.texcoord = Some(t);
    }

    /// A vertex as an array gives it: the attributes of the enabled arrays, then the position.
    pub(crate) fn give(&mut self, v: &crate::context::Fetched) {
        if let Some(n) = v.normal {
            self.normal(n);
        }
        if let Some(c) = v.color {
            self.color(c);
        }
        if let Some(t) = v.tex {
            self.texcoord(t);
        }
        if let Some(p) = v.position {
            self.vertex(p);
        }
    }

    /// A vertex: it takes the attributes given so far (outside a glBegin it does nothing).
    pub fn vertex(&mut self, p: DVec4) {
        if self.open.is_none() {
            return;
        }
        let m = &mut self.mesh;
        let i = m.positions.len() as u32;
        m.positions.push(p.truncate().as_vec3());
        if p.w != 1.0 || m.ws.is_some() {
            m.ws.get_or_insert_with(|| vec![1.0; i as usize]).push(p.w as f32);
        }
        m.normals.push(i, self.normal.map(|n| n.as_vec3()));
        m.colors.push(i, self.color.map(|c| c.as_vec4()));
        m.texcoords.push(i, self.texcoord.map(|t| t.as_vec4()));
    }

    /// The finished mesh (an open glBegin is closed).
    pub fn finish(mut self) -> Mesh {
        self.closed();
        let mut m = self.mesh;
        m.id = next_id();
        (m.min, m.max) = bounds(&m.positions);
        m.sequential = sequential(&m.triangles);
        m
    }

    /// Splits off the open glBegin, for a list that cannot keep it as a mesh after all (one
    /// with glMaterial or glCallList inside): the runs before it as a mesh (None if there are
    /// none), and the open one's mode with what was given in it, in order, as commands.
    pub(crate) fn split_open(self) -> (Option<Mesh>, u32, Vec<Given>) {
        let Some((mode, start)) = self.open else { return (Some(self.finish()), 0, Vec::new()) };
        let given = self.given(start);
        let mut closed = MeshBuilder { open: None, ..self };
        let m = &mut closed.mesh;
        m.positions.truncate(start as usize);
        if let Some(ws) = m.ws.as_mut() {
            ws.truncate(start as usize);
        }
        m.normals.truncate(start);
        m.colors.truncate(start);
        m.texcoords.truncate(start);
        let mesh = (!closed.mesh.runs.is_empty()).then(|| closed.finish());
        (mesh, mode, given)
    }

    /// What was given from vertex `from` on, in order, as commands.
    fn given(&self, from: u32) -> Vec<Given> {
        let m = &self.mesh;
        let mut out = Vec::new();
        let (mut normal, mut color, mut texcoord) = (None, None, None);
        for i in from..m.positions.len() as u32 {
            if let Some(n) = m.normals.at(i).filter(|n| Some(*n) != normal) {
                out.push(Given::Normal(n.as_dvec3()));
                normal = Some(n);
            }
            if let Some(c) = m.colors.at(i).filter(|c| Some(*c) != color) {
                out.push(Given::Color(c.as_dvec4()));
                color = Some(c);
            }
            if let Some(t) = m.texcoords.at(i).filter(|t| Some(*t) != texcoord) {
                out.push(Given::TexCoord(0, t.as_dvec4()));
                texcoord = Some(t);
            }
            out.push(Given::Vertex(m.position(i)));
        }
        // Attributes given after the last vertex.
        let tail = [
            self.normal.filter(|n| Some(n.as_vec3()) != normal).map(Given::Normal),
            self.color.filter(|c| Some(c.as_vec4()) != color).map(Given::Color),
            self.texcoord.filter(|t| Some(t.as_vec4()) != texcoord).map(|t| Given::TexCoord(0, t)),
        ];
        out.extend(tail.into_iter().flatten());
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_gl::{GL_LINES, GL_QUADS, GL_TRIANGLES, GL_TRIANGLE_STRIP};

    #[test]
    fn a_meshs_bytes_count_its_vertices_values_and_triangles() {
        // Four vertices with normals and two triangles: 4 x 12 + 4 x 12 + 2 x 12 bytes; no
        // colours or texture coordinates of their own.
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
        let mesh = Mesh::indexed(positions, vec![Vec3::Z; 4], vec![[0, 1, 2], [2, 1, 3]]).expect("in range");
        assert_eq!(mesh.bytes(), 48 + 48 + 24);
        // Colours given per vertex count too.
        let mut b = MeshBuilder::new(false, QuadSplit::Indexed);
        b.begin(GL_TRIANGLES);
        for k in 0..3 {
            b.color(DVec4::ONE);
            b.vertex(DVec4::new(k as f64, 0.0, 0.0, 1.0));
        }
        assert_eq!(b.finish().bytes(), 3 * 12 + 3 * 16 + 12);
    }

    #[test]
    fn attributes_start_where_the_list_gives_them() {
        let mut b = MeshBuilder::new(false, QuadSplit::Indexed);
        b.begin(GL_TRIANGLES);
        b.vertex(DVec4::new(0.0, 0.0, 0.0, 1.0));
        b.normal(DVec3::X);
        b.vertex(DVec4::new(1.0, 0.0, 0.0, 1.0));
        b.vertex(DVec4::new(0.0, 1.0, 0.0, 1.0));
        b.color(DVec4::new(1.0, 0.0, 0.0, 1.0));
        let given = b.given(0);
        let m = b.finish();
        assert_eq!(m.normals.at(0), None, "the first vertex takes the normal current at the call");
        assert_eq!(m.normals.at(1), Some(Vec3::X));
        assert_eq!(m.normals.at(2), Some(Vec3::X));
        assert_eq!(m.colors.first, 3, "no vertex has its own colour");
        assert_eq!(m.end_color, Some(DVec4::new(1.0, 0.0, 0.0, 1.0)), "but it stays current after");
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!((m.min, m.max), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert!(m.ws.is_none() && !m.lines_or_points);
        assert_eq!(given.len(), 5, "{given:?}");
        assert_eq!(given[1], Given::Normal(DVec3::X));
        assert_eq!(given[4], Given::Color(DVec4::new(1.0, 0.0, 0.0, 1.0)));
    }

    #[test]
    fn runs_assemble_into_one_mesh_and_ids_differ() {
        let quad = |b: &mut MeshBuilder, mode, x: f64| {
            b.begin(mode);
            for (dx, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                b.vertex(DVec4::new(x + dx, y, 0.0, 1.0));
            }
            b.end();
        };
        let mut b = MeshBuilder::new(false, QuadSplit::Indexed);
        quad(&mut b, GL_QUADS, 0.0);
        b.vertex(DVec4::ONE); // outside glBegin: nothing
        quad(&mut b, GL_TRIANGLE_STRIP, 2.0);
        let a = b.finish();
        assert_eq!(
            a.runs,
            vec![Run { mode: GL_QUADS, start: 0, count: 4 }, Run { mode: GL_TRIANGLE_STRIP, start: 4, count: 4 }]
        );
        assert_eq!(a.triangles.len(), 4);
        assert_eq!(a.triangles[2], [4, 5, 6], "the second run's indices follow the first's");
        assert_eq!(a.provoking[..2], [3, 3]);
        let mut l = MeshBuilder::new(false, QuadSplit::Indexed);
        quad(&mut l, GL_LINES, 0.0);
        let l = l.finish();
        assert!(l.lines_or_points && l.triangles.is_empty());
        assert_ne!(a.id, l.id);
        let mut h = MeshBuilder::new(false, QuadSplit::Indexed);
        h.begin(GL_TRIANGLES);
        h.vertex(DVec4::new(0.0, 0.0, 0.0, 2.0));
        assert_eq!(h.finish().position(0).w, 2.0);
    }

    #[test]
    fn corners_are_worked_out_only_for_lists_of_separate_triangles() {
        let mesh = |modes: &[u32]| {
            let mut b = MeshBuilder::new(false, QuadSplit::Indexed);
            for &mode in modes {
                b.begin(mode);
                for k in 0..6 {
                    b.vertex(DVec4::new(k as f64, (k % 2) as f64, (k / 3) as f64, 1.0));
                }
                b.end();
            }
            b.finish()
        };
        for (modes, sequential) in [
            (&[GL_TRIANGLES][..], true),
            (&[GL_TRIANGLES, GL_TRIANGLES], true),
            (&[GL_QUADS], false),
            (&[GL_TRIANGLE_STRIP], false),
            (&[GL_TRIANGLES, GL_QUADS], false),
        ] {
            let m = mesh(modes);
            assert_eq!(m.is_sequential(), sequential, "{modes:?}");
            for (i, t) in m.triangles.iter().enumerate() {
                assert_eq!(m.corner_indices(i), *t, "{modes:?} triangle {i}");
            }
        }
        let indexed = |t: Vec<[u32; 3]>| Mesh::indexed(vec![Vec3::ZERO; 6], vec![Vec3::Z; 6], t).unwrap();
        assert!(indexed(vec![[0, 1, 2], [3, 4, 5]]).is_sequential());
        assert!(!indexed(vec![[0, 1, 2], [2, 1, 3]]).is_sequential());
    }

    #[test]
    fn an_open_glbegin_splits_off_with_what_was_given_in_it() {
        let mut b = MeshBuilder::new(false, QuadSplit::Indexed);
        b.begin(GL_TRIANGLES);
        for x in [0.0, 1.0, 2.0] {
            b.vertex(DVec4::new(x, 0.0, 0.0, 1.0));
        }
        b.end();
        b.color(DVec4::new(0.0, 1.0, 0.0, 1.0));
        b.begin(GL_QUADS);
        b.vertex(DVec4::new(5.0, 0.0, 0.0, 1.0));
        let (closed, mode, given) = b.split_open();
        let closed = closed.unwrap();
        assert_eq!((closed.positions.len(), closed.triangles.len(), mode), (3, 1, GL_QUADS));
        assert_eq!(closed.colors.at(2), None);
        assert_eq!(
            given,
            vec![Given::Color(DVec4::new(0.0, 1.0, 0.0, 1.0)), Given::Vertex(DVec4::new(5.0, 0.0, 0.0, 1.0))]
        );
    }
}
