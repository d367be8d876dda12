//! A mesh: triangles in object coordinates with the attributes their vertices were given. A
//! display list's glBegin/glEnd (or array draw, or a buffer object draw) becomes a `Mesh` once,
//! when capture first sees it; every glCallList then adds an instance of it (the modelview and
//! the state of that call, `instance`) instead of running its vertices again, and the tracer
//! keeps the mesh's BVH for as long as the mesh lives. That is what makes a program that draws
//! big lists every frame cheap to follow: its frames cost the instances, not the triangles.
//!
//! Vertices keep the attributes the list gave them. One the list did not give (a sphere list
//! drawn after a glColor) is the value current at the call: `Attribute::first` says from which
//! vertex on the list gives its own.
//!
//! A mesh's `id` is unique for the life of the process (`Mesh::seal` hands them out): the
//! tracer keys its BVHs by it, and the byte encoding (`encode`) sends a mesh once and then only
//! its id.

use glam::{DVec4, Vec3, Vec4};
use glray_core::threads::{collect_pieces, map_pieces, piece_of};
use serde::{Deserialize, Serialize};

/// One per-vertex attribute of a mesh.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(bound = "T: bytemuck::Pod")]
pub struct Attribute<T> {
    /// The first vertex that has its own value (the number of vertices if none has).
    pub first: u32,
    /// Values of vertices `first..`.
    #[serde(with = "crate::pod_vec")]
    pub values: Vec<T>,
}

impl<T> Attribute<T> {
    /// Every one of `n` vertices' values, or (None) none: all take the value current at the call.
    pub fn all_or_none(values: Option<Vec<T>>, n: u32) -> Attribute<T> {
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
    pub fn truncate(&mut self, n: u32) {
        self.values.truncate(n.saturating_sub(self.first) as usize);
    }

    /// Appends vertex `index`'s value (None: not given yet).
    pub fn push(&mut self, index: u32, value: Option<T>) {
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

/// Triangles in object coordinates with their vertices' attributes.
#[derive(Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    /// Unique for the life of the process (`seal`): the tracer keys its BVHs by it.
    pub id: u64,
    #[serde(with = "crate::pod_vec")]
    pub positions: Vec<Vec3>,
    /// w of every position when one is not 1 (such a mesh is never instanced).
    pub ws: Option<Vec<f32>>,
    pub normals: Attribute<Vec3>,
    pub colors: Attribute<Vec4>,
    /// Texture unit 0's coordinates.
    pub texcoords: Attribute<Vec4>,
    /// The triangles (vertex indices) and each one's provoking vertex.
    #[serde(with = "crate::pod_vec")]
    pub triangles: Vec<[u32; 3]>,
    #[serde(with = "crate::pod_vec")]
    pub provoking: Vec<u32>,
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
    crate::ids::next()
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
    pub fn of_triangles(
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

    /// The mesh with its positions' w, kept only when one is not 1 (an empty `ws`: every w is 1;
    /// such a mesh is never instanced).
    pub fn with_ws(self, ws: Vec<f32>) -> Mesh {
        Mesh { ws: ws.iter().any(|&w| w != 1.0).then_some(ws), ..self }
    }

    /// The mesh as made (its positions, attributes, triangles and provoking vertices), given a
    /// new id, its bounds and its corner layout: what every mesh made vertex by vertex ends with.
    pub fn seal(mut self) -> Mesh {
        self.id = next_id();
        (self.min, self.max) = bounds(&self.positions);
        self.sequential = sequential(&self.triangles);
        self
    }

    /// A mesh standing in for one that is not here (a paged mesh, whose triangles other ranks
    /// hold in blocks): its id, its bounds, nothing else. What a frame names it by and sizes it
    /// with; the tracer finds its triangles through its pager.
    pub fn stand_in(id: u64, min: Vec3, max: Vec3) -> Mesh {
        Mesh { id, min, max, sequential: true, ..Mesh::default() }
    }

    /// The triangles `triangles` of this mesh (in that order) as a mesh of their own, a new id:
    /// only the vertices they use, in the order of this mesh's, with every attribute they have
    /// here (a vertex without a value of its own keeps none, so that it takes the draw's
    /// current one as here). A block of a paged mesh.
    pub fn part(&self, triangles: &[u32]) -> Mesh {
        let mut used: Vec<u32> = triangles.iter().flat_map(|&t| self.corner_indices(t as usize)).collect();
        used.sort_unstable();
        used.dedup();
        let new = |v: u32| used.binary_search(&v).expect("a used vertex") as u32;
        fn part_of<T: Copy>(a: &Attribute<T>, used: &[u32]) -> Attribute<T> {
            let first = used.partition_point(|&v| v < a.first) as u32;
            Attribute { first, values: used.iter().filter_map(|&v| a.at(v)).collect() }
        }
        let mesh = Mesh {
            id: 0,
            positions: used.iter().map(|&v| self.positions[v as usize]).collect(),
            ws: self.ws.as_ref().map(|ws| used.iter().map(|&v| ws[v as usize]).collect()),
            normals: part_of(&self.normals, &used),
            colors: part_of(&self.colors, &used),
            texcoords: part_of(&self.texcoords, &used),
            triangles: triangles.iter().map(|&t| self.corner_indices(t as usize).map(new)).collect(),
            provoking: triangles.iter().map(|&t| new(self.provoking[t as usize])).collect(),
            ..Mesh::default()
        };
        mesh.seal()
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
    /// (`glray_core::hash::content_hash` of each, on glray's threads for a big mesh). Two meshes with the
    /// same shape have the same tree: a time step that sends the same vertices again (only its
    /// colours new) keeps the last step's tree as it is.
    pub fn shape_hash(&self) -> [i64; 4] {
        let [a, b] = glray_core::hash::content_hash(bytemuck::cast_slice(&self.positions));
        let [c, d] = glray_core::hash::content_hash(bytemuck::cast_slice(&self.triangles));
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
