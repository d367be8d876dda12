//! Big glBegin/glEnd runs kept as meshes, by what they give.
//!
//! An immediate-mode program gives its vertices call by call, every frame. Each vertex went
//! through the vertex stage (transformed and lit in double precision) and each frame's
//! triangles through a new BVH: a million triangles given as glNormal3fv/glVertex3fv cost ~1.1 s
//! of capture and ~0.27 s of BVH build a frame, where llvmpipe draws the frame in ~0.15 s.
//!
//! Between glBegin and glEnd only the attributes can change, not the state a vertex is
//! transformed and lit with. So once a glBegin of filled primitives reaches
//! `MESH_FROM_VERTICES` vertices, and its state lets a mesh be drawn as an instance
//! (`Context::instances_now`), it is taken from the vertex stage and recorded as a display
//! list records one: its object-space attributes in a `MeshBuilder`, drawn at glEnd as an
//! instance (lit per hit, as a list's mesh is). A run that gives the same values as one the
//! last frame drew is that frame's mesh again, so its BVH is not built again either.
//!
//! Until then the run is the vertex stage's, and only what each vertex was given is noted
//! beside it (`Noted`), to make the mesh from should the run get that far: smaller runs stay
//! on the vertex stage at nearly no cost, as they must (thousands of small instances would
//! each be a BVH under the top level). A call inside the run that a mesh cannot keep
//! (glMaterial, glEdgeFlag, another texture unit's coordinates, glCallList, a vertex with w
//! not 1) ends the watch; after the run was taken, what was given so far goes back through the
//! vertex stage and the rest of the run follows it there.

use glray_gl::{GL_POLYGON, GL_QUADS, GL_TRIANGLES};
use std::sync::Arc;

use glam::{DVec3, DVec4, Vec3, Vec4};

use crate::fixed::arrays::BufferDraw;
use crate::fixed::mesh_builder::{MeshBuilder, Run};
use crate::fixed::vertex::Given;
use crate::fixed::Context;
use crate::primitive::QuadSplit;
use glray_core::hash::content_hash;
use glray_scene::mesh::{Attribute, Mesh};

/// How many vertices a run reaches before it is taken from the vertex stage and kept as a mesh
/// (as many as a client-array draw needs to be kept).
pub(crate) const MESH_FROM_VERTICES: usize = crate::fixed::arrays::KEEP_FROM_ELEMENTS as usize;

// A run is taken before the vertex stage draws any of it (it draws a long one in chunks).
const _: () = assert!(MESH_FROM_VERTICES <= crate::fixed::vertex::IMMEDIATE_CHUNK);

/// What a vertex of a watched run was given: its position and the current values it took.
#[derive(Clone, Copy)]
struct Noted {
    position: DVec4,
    normal: DVec3,
    color: DVec4,
    texcoord: DVec4,
}

/// A context's watch over its open glBegin.
#[derive(Default)]
pub(crate) struct Recordings {
    /// The open glBegin's vertices so far, while it may yet be taken as a mesh.
    watched: Option<Vec<Noted>>,
    /// The open glBegin, taken from the vertex stage.
    taken: Option<MeshBuilder>,
    /// The room of the last watch, for the next.
    spare: Vec<Noted>,
    /// The vectors of the last mesh recorded that was not kept (the same as one already
    /// kept), for the next.
    room: Option<MeshBuilder>,
}

impl Recordings {
    /// Whether the open glBegin is watched or taken.
    #[inline]
    pub(crate) fn is_open(&self) -> bool {
        self.watched.is_some() || self.taken.is_some()
    }

    /// The watch is over; its room is kept for the next.
    fn unwatch(&mut self) {
        if let Some(v) = self.watched.take() {
            self.spare = v;
        }
    }
}

impl Context {
    /// A glBegin of `mode` has opened: watched, if it draws filled primitives.
    pub(crate) fn record_begin(&mut self, mode: u32) {
        let r = &mut self.recording;
        r.unwatch();
        r.taken = None;
        if (GL_TRIANGLES..=GL_POLYGON).contains(&mode) {
            let mut noted = std::mem::take(&mut r.spare);
            noted.clear();
            r.watched = Some(noted);
        }
    }

    /// An attribute (or vertex) given inside the open glBegin: true when the vertex stage is
    /// not to see it (the run is taken from it).
    pub(crate) fn record_given(&mut self, given: &Given) -> bool {
        if let Some(b) = self.recording.taken.as_mut() {
            match *given {
                Given::Normal(n) => b.normal(n),
                Given::Color(c) => b.color(c),
                Given::TexCoord(0, t) => b.texcoord(t),
                // The vertex stage drops it too.
                Given::SecondaryColor => {}
                Given::Vertex(p) if p.w == 1.0 => b.vertex(p),
                _ => {
                    self.stop_recording();
                    return false;
                }
            }
            return true;
        }
        match *given {
            // Noted with the vertex that takes it.
            Given::Normal(_) | Given::Color(_) | Given::TexCoord(0, _) | Given::SecondaryColor => false,
            Given::Vertex(p) if p.w == 1.0 => self.note_vertex(p),
            _ => {
                self.stop_recording();
                false
            }
        }
    }

    /// Vertex `p` of the watched run, noted: true when it was the one that made the run long
    /// enough to be taken as a mesh (and so the vertex stage is not to see it).
    fn note_vertex(&mut self, p: DVec4) -> bool {
        let cur = &self.imm.current;
        let noted = Noted { position: p, normal: cur.normal, color: cur.color, texcoord: cur.texcoords[0] };
        let Some(watched) = self.recording.watched.as_mut() else { return false };
        watched.push(noted);
        if watched.len() < MESH_FROM_VERTICES {
            return false;
        }
        if !self.instances_now() {
            self.recording.unwatch();
            return false;
        }
        let (Some(mode), Some(watched)) = (self.imm.mode(), self.recording.watched.take()) else { return false };
        let room = self.recording.room.take();
        self.recording.taken = Some(taken(mode, &watched, room));
        self.recording.spare = watched;
        // What the vertex stage made of the run so far is not needed.
        self.open.clear();
        true
    }

    /// Something a mesh cannot keep happened inside the open glBegin: the watch ends, and a
    /// run the vertex stage no longer saw is given to it again (from the current values it
    /// was taken with: its first vertices' own values are those that changed in it).
    pub(crate) fn stop_recording(&mut self) {
        self.recording.unwatch();
        let Some(b) = self.recording.taken.take() else { return };
        let (_, _, given) = b.split_open();
        for g in given {
            match g {
                Given::Vertex(p) => self.vertex(p),
                Given::Normal(n) => self.imm.normal(n),
                Given::Color(c) => self.imm.color(c),
                Given::TexCoord(unit, t) => {
                    // Only unit 0's are recorded.
                    let _ = self.imm.tex_coord(unit, t);
                }
                Given::SecondaryColor | Given::EdgeFlag(_) => {}
            }
        }
    }

    /// glEnd of the open glBegin: when it was taken from the vertex stage, its mesh (the last
    /// frame's, if that gave the same) drawn, and true; false when the run was the vertex
    /// stage's.
    pub(crate) fn end_recording(&mut self, mode: u32) -> bool {
        self.recording.unwatch();
        let Some(mut b) = self.recording.taken.take() else { return false };
        if mode == GL_QUADS && self.any_clipped(b.positions()) {
            // As the vertex stage's draw would cut them (`Context::draw`).
            b.cut_quads(QuadSplit::Indexed);
        }
        let (mesh, runs, quads, ends) = b.closed();
        let key = key(mesh, runs, quads, ends);
        let mesh = match self.client_draws.get(&key) {
            Some(kept) => {
                self.recording.room = Some(b.into_room());
                kept
            }
            None => Arc::new(b.finish()),
        };
        self.client_draws.insert(key, mesh.clone());
        // The glBegin is closed, `instances_now` held in it, and every position's w was 1 in a
        // run of filled primitives: drawn as an instance.
        let _ = self.run_mesh(&mesh);
        true
    }
}

impl Context {
    /// Whether any of `positions` (object coordinates) is outside the view volume or a clip
    /// plane (`Context::clipped`).
    fn any_clipped(&self, positions: &[Vec3]) -> bool {
        let modelview = *self.matrices.modelview.top();
        let to_clip = *self.matrices.projection.top() * modelview;
        positions.iter().any(|p| {
            let p = p.as_dvec3().extend(1.0);
            self.clipped(to_clip * p, modelview * p)
        })
    }
}

/// The builder a watched run of `mode` continues in (in `room`'s vectors, if given), from its
/// noted vertices. An attribute that kept one value over them is left to the current value at
/// the draw (which it is: nothing changed it since the last vertex); one that changed is each
/// vertex's own.
fn taken(mode: u32, noted: &[Noted], room: Option<MeshBuilder>) -> MeshBuilder {
    let mut b = match room {
        Some(room) => MeshBuilder::reusing(room, false, QuadSplit::Direct),
        None => MeshBuilder::new(false, QuadSplit::Direct),
    };
    b.begin(mode);
    let first = noted[0];
    let normals = noted.iter().any(|v| v.normal != first.normal);
    let colors = noted.iter().any(|v| v.color != first.color);
    let texcoords = noted.iter().any(|v| v.texcoord != first.texcoord);
    for v in noted {
        if normals {
            b.normal(v.normal);
        }
        if colors {
            b.color(v.color);
        }
        if texcoords {
            b.texcoord(v.texcoord);
        }
        b.vertex(v.position);
    }
    b
}

/// A recorded run's key among the kept meshes: every value it gave, and the values it left
/// current (first word 2: client-array draws' keys start with 0 or 1).
fn key(mesh: &Mesh, runs: &[Run], quads: QuadSplit, ends: [Option<DVec4>; 3]) -> BufferDraw {
    let mut words = vec![2, quads as i64];
    for run in runs {
        words.extend([i64::from(run.mode), i64::from(run.start), i64::from(run.count)]);
    }
    words.extend(content_hash(bytemuck::cast_slice::<Vec3, u8>(&mesh.positions)));
    attribute_words(&mut words, &mesh.normals);
    attribute_words(&mut words, &mesh.colors);
    attribute_words(&mut words, &mesh.texcoords);
    for end in ends {
        let v = end.unwrap_or(DVec4::NAN);
        words.extend([i64::from(end.is_some())].into_iter().chain(v.to_array().map(|x| x.to_bits() as i64)));
    }
    BufferDraw::of_words(words)
}

/// An attribute's first own value and a hash of its values, onto `words`.
fn attribute_words<T: bytemuck::Pod>(words: &mut Vec<i64>, a: &Attribute<T>) {
    words.extend([i64::from(a.first), a.values.len() as i64]);
    words.extend(content_hash(bytemuck::cast_slice::<T, u8>(&a.values)));
}

// Positions and attributes are hashed as their bytes.
const _: () = assert!(std::mem::size_of::<Vec3>() == 12 && std::mem::size_of::<Vec4>() == 16);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed::tests::*;

    use glray_gl::*;

    #[test]
    fn a_long_glbegin_is_drawn_whole_in_the_order_given_and_its_vertices_are_not_all_held() {
        // 39,999 vertices of separate triangles (more than three chunks) and of a strip: every
        // triangle, in order; for the first, fewer vertices held at once than given. Texture
        // coordinates generated: a state no instance can be drawn with, so the vertex stage
        // keeps the run (below, without it, the run is taken as a mesh).
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_TEXTURE_GEN_S as i64)]); // GL_TEXTURE_GEN_S
        let n = 39_999;
        let give = |c: &mut Context, mode: i64| {
            call(c, "glBegin", &[i(mode)]);
            for k in 0..n {
                call(c, "glColor3f", &[f(k as f64 / n as f64), f(0.0), f(0.0)]);
                let (x, y) = ((k % 3 == 1) as i32 as f64 * 0.5, (k % 3 == 2) as i32 as f64 * 0.5);
                call(c, "glVertex2f", &[f(x - 0.5 + k as f64 / n as f64 * 0.1), f(y - 0.5)]);
            }
            call(c, "glEnd", &[]);
        };
        give(&mut c, 4); // GL_TRIANGLES
        assert!(c.open.capacity() < n, "{}", c.open.capacity());
        let frame = c.take_frame();
        assert_eq!(frame.triangles.len(), n / 3);
        for (t, tri) in frame.triangles.iter().enumerate() {
            let first = (3 * t) as f32 / n as f32;
            let reds: Vec<f32> = tri.colors.iter().map(|c| c.x).collect();
            assert!(reds.iter().all(|r| (r - first).abs() < 3.0 / n as f32), "triangle {t}: {reds:?}");
        }
        assert!(frame.triangles.windows(2).all(|w| w[0].sequence <= w[1].sequence), "in drawing order");
        give(&mut c, 5); // GL_TRIANGLE_STRIP
        assert_eq!(c.take_frame().triangles.len(), n - 2);
        // Without generated coordinates the run is taken from the vertex stage as one mesh,
        // drawn as an instance: the same triangles, in order, with the same colours.
        call(&mut c, "glDisable", &[i(0x0C60)]);
        give(&mut c, 4);
        let frame = c.take_frame();
        assert_eq!((frame.triangles.len(), frame.instances.len()), (0, 1));
        let all = frame.all_triangles();
        assert_eq!(all.len(), n / 3);
        for (t, tri) in all.iter().enumerate() {
            let first = (3 * t) as f32 / n as f32;
            let reds: Vec<f32> = tri.colors.iter().map(|c| c.x).collect();
            assert!(reds.iter().all(|r| (r - first).abs() < 3.0 / n as f32), "instanced triangle {t}: {reds:?}");
        }
        assert_eq!(c.errors.take(), 0);
    }
    #[test]
    fn a_glbegin_is_taken_as_a_mesh_from_its_4096th_vertex_and_kept_while_it_gives_the_same() {
        use crate::fixed::immediate_meshes::MESH_FROM_VERTICES;
        let mut c = context();
        // Vertex k of separate triangles, none of them degenerate.
        let corner = |c: &mut Context, k: usize| {
            let (x, y) = ((k % 3 == 1) as i32 as f64 * 0.5, (k % 3 == 2) as i32 as f64 * 0.5);
            call(c, "glVertex2f", &[f(x - 0.5 + k as f64 * 1e-5), f(y - 0.5)]);
        };
        let give = |c: &mut Context, vertices: usize, mode: i64, red: f64| {
            call(c, "glBegin", &[i(mode)]);
            for k in 0..vertices {
                call(c, "glColor3f", &[f(red * (k % 2) as f64), f(0.0), f(0.0)]);
                corner(c, k);
            }
            call(c, "glEnd", &[]);
        };
        let n = MESH_FROM_VERTICES - MESH_FROM_VERTICES % 3;
        // One vertex short: the vertex stage's. Lines: never a mesh.
        give(&mut c, n - 3, 4, 1.0);
        let frame = c.take_frame();
        assert_eq!((frame.instances.len(), frame.triangles.len()), (0, (n - 3) / 3));
        give(&mut c, MESH_FROM_VERTICES + 10, 1, 1.0);
        assert_eq!(c.take_frame().instances.len(), 0, "lines");
        // Long enough: one mesh, the same one the next frame while the calls give the same.
        give(&mut c, n + 3, 4, 1.0);
        let first = c.take_frame();
        assert_eq!((first.instances.len(), first.triangles.len()), (1, 0));
        assert_eq!(first.instances[0].mesh.triangles.len(), n / 3 + 1);
        give(&mut c, n + 3, 4, 1.0);
        let second = c.take_frame();
        assert!(Arc::ptr_eq(&first.instances[0].mesh, &second.instances[0].mesh), "kept by what it gives");
        give(&mut c, n + 3, 4, 0.5);
        let third = c.take_frame();
        assert!(!Arc::ptr_eq(&second.instances[0].mesh, &third.instances[0].mesh), "new colours, a new mesh");
        // A colour given once is the instance's, not the mesh's: the same mesh.
        for red in [1.0, 0.5] {
            call(&mut c, "glColor3f", &[f(red), f(0.0), f(0.0)]);
            call(&mut c, "glBegin", &[i(4)]);
            (0..n + 3).for_each(|k| corner(&mut c, k));
            call(&mut c, "glEnd", &[]);
        }
        let frame = c.take_frame();
        assert!(Arc::ptr_eq(&frame.instances[0].mesh, &frame.instances[1].mesh));
        assert_eq!((frame.instances[0].color.x, frame.instances[1].color.x), (1.0, 0.5));
        // A glMaterial inside after the run was taken: back to the vertex stage, whole.
        call(&mut c, "glBegin", &[i(4)]);
        for k in 0..n + 3 {
            if k == n {
                call(&mut c, "glMaterialf", &[i(0x0408), i(0x1601), f(10.0)]);
            }
            corner(&mut c, k);
        }
        call(&mut c, "glEnd", &[]);
        let frame = c.take_frame();
        assert_eq!((frame.instances.len(), frame.triangles.len()), (0, n / 3 + 1));
        assert_eq!(c.errors.take(), 0);
    }
}
