//! Meshes made from GL calls: a display list's consecutive glBegin/glEnd runs (with the
//! attributes given between them), an array draw's vertices, a long glBegin taken from the
//! vertex stage (`immediate_meshes`). `MeshBuilder` gathers what the calls give and makes a
//! `Compiled`: the scene's `Mesh` (what the tracer needs) with what capture itself needs to
//! draw it again through the vertex stage and to leave GL's current values as the draw did
//! (its runs, how its quads are cut, the values current after it).

use std::sync::Arc;

use glam::{DVec3, DVec4, Vec3, Vec4};
use glray_scene::mesh::{Attribute, Mesh};

use crate::fixed::vertex::Given;
use crate::primitive::{assemble, QuadSplit};

/// One glBegin/glEnd of a mesh: its mode and its vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Run {
    pub mode: u32,
    pub start: u32,
    pub count: u32,
}

/// A mesh as capture keeps it: the scene's mesh, and how it was drawn.
#[derive(Debug)]
pub struct Compiled {
    pub mesh: Arc<Mesh>,
    /// The glBegin/glEnd (or array draws) it was made of, in order, each a run of vertices
    /// (empty for an indexed mesh).
    pub runs: Vec<Run>,
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
}

/// A compiled mesh reads as its scene mesh (positions, attributes, triangles).
impl std::ops::Deref for Compiled {
    type Target = Mesh;

    fn deref(&self) -> &Mesh {
        &self.mesh
    }
}

impl Compiled {
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
    ) -> Compiled {
        let n = positions.len() as u32;
        let mesh = Mesh::of_triangles(
            positions,
            Attribute::all_or_none(normals, n),
            Attribute::all_or_none(colors, n),
            Attribute::all_or_none(texcoords, n),
            triangles,
        )
        .with_ws(ws);
        Compiled {
            mesh: Arc::new(mesh),
            runs: Vec::new(),
            lines_or_points: false,
            from_arrays: true,
            quads: QuadSplit::default(),
            end_normal: end.0,
            end_color: end.1,
            end_texcoord: end.2,
        }
    }
}

/// A mesh being compiled: the attribute values given so far, and the vertices.
#[derive(Debug)]
pub struct MeshBuilder {
    mesh: Mesh,
    runs: Vec<Run>,
    lines_or_points: bool,
    from_arrays: bool,
    quads: QuadSplit,
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
            mesh: Mesh::default(),
            runs: Vec::new(),
            lines_or_points: false,
            from_arrays,
            quads,
            normal: None,
            color: None,
            texcoord: None,
            open: None,
        }
    }

    /// `new`, in the room of `room`'s vectors (a mesh made again every frame would otherwise
    /// fault in fresh pages for all of them each time).
    pub(crate) fn reusing(room: MeshBuilder, from_arrays: bool, quads: QuadSplit) -> MeshBuilder {
        let mut b = MeshBuilder::new(from_arrays, quads);
        let (m, mut r) = (&mut b.mesh, room.mesh);
        r.positions.clear();
        r.normals.values.clear();
        r.colors.values.clear();
        r.texcoords.values.clear();
        r.triangles.clear();
        r.provoking.clear();
        (m.positions, m.normals.values, m.colors.values, m.texcoords.values) =
            (r.positions, r.normals.values, r.colors.values, r.texcoords.values);
        (m.triangles, m.provoking) = (r.triangles, r.provoking);
        b.runs = room.runs;
        b.runs.clear();
        b
    }

    /// The mesh so far with its open glBegin closed, as `finish` would give it but for its id,
    /// bounds and corner layout (enough to tell it from another), with its runs, how its quads
    /// are cut and the values current after it.
    pub(crate) fn closed(&mut self) -> (&Mesh, &[Run], QuadSplit, [Option<DVec4>; 3]) {
        self.end();
        let m = &mut self.mesh;
        let n = m.positions.len() as u32;
        for a in [&mut m.normals.first, &mut m.colors.first, &mut m.texcoords.first] {
            *a = (*a).min(n);
        }
        let ends = [self.normal.map(|n| n.extend(0.0)), self.color, self.texcoord];
        (&self.mesh, &self.runs, self.quads, ends)
    }

    /// Its vectors, for `reusing`.
    pub(crate) fn into_room(self) -> MeshBuilder {
        self
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
        if let Ok(asm) = assemble(mode, count as usize, self.quads) {
            self.lines_or_points |= !asm.lines.is_empty() || !asm.points.is_empty();
            m.triangles.extend(asm.triangles.iter().map(|(t, _)| t.map(|i| i + start)));
            m.provoking.extend(asm.triangles.iter().map(|(_, p)| p + start));
        }
        self.runs.push(Run { mode, start, count });
    }

    /// The positions given so far.
    pub(crate) fn positions(&self) -> &[Vec3] {
        &self.mesh.positions
    }

    /// Cuts its quads as `quads` says from now on (its runs are assembled as they close).
    pub(crate) fn cut_quads(&mut self, quads: QuadSplit) {
        self.quads = quads;
    }

    /// Whether a glBegin is open.
    pub fn is_open(&self) -> bool {
        self.open.is_some()
    }

    /// Whether it holds any run.
    pub fn is_empty(&self) -> bool {
        self.runs.is_empty() && self.open.is_none()
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
    pub(crate) fn give(&mut self, v: &crate::fixed::Fetched) {
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
    pub fn finish(mut self) -> Compiled {
        self.closed();
        Compiled {
            mesh: Arc::new(self.mesh.seal()),
            runs: self.runs,
            lines_or_points: self.lines_or_points,
            from_arrays: self.from_arrays,
            quads: self.quads,
            end_normal: self.normal,
            end_color: self.color,
            end_texcoord: self.texcoord,
        }
    }

    /// Splits off the open glBegin, for a list that cannot keep it as a mesh after all (one
    /// with glMaterial or glCallList inside): the runs before it as a mesh (None if there are
    /// none), and the open one's mode with what was given in it, in order, as commands.
    pub(crate) fn split_open(self) -> (Option<Compiled>, u32, Vec<Given>) {
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
        let mesh = (!closed.runs.is_empty()).then(|| closed.finish());
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
