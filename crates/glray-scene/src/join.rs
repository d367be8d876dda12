//! The pieces of one dataset that MPI ranks drew, joined into one mesh (`Joined::join`): a
//! data-parallel host draws its data split over its ranks, each piece under the same transform
//! and in the same state, and traced as pieces the scene has a tree per piece under a tree of
//! pieces whose boxes overlap. One process drawing the whole has one mesh and one tree: the
//! same frame in two pieces traced 10-15% slower (docs/distributed.md). Joined in rank order,
//! the pieces of a mesh split by triangles are that mesh again.
//!
//! Only draws from different ranks are joined (one rank's own draws are traced as one process
//! traces them), and only draws that differ in nothing but their mesh and their place in
//! drawing order. The joined mesh is kept from frame to frame while its pieces are the same, so
//! its tree is built once.

use std::collections::HashMap;
use std::sync::Arc;

use glam::DMat4;

use crate::instance::Instance;
use crate::mesh::{Attribute, Mesh};

/// The joined meshes of the last frame, by the ids of their pieces.
#[derive(Default)]
pub struct Joined {
    meshes: HashMap<Vec<u64>, Arc<Mesh>>,
}

impl Joined {
    /// Joins, in `instances` (the merged frame's, rank after rank: `ranks[k]` is the rank that
    /// drew instance k), the draws of different ranks that are pieces of one mesh: each group
    /// becomes one instance, at its first piece's place, of the pieces' meshes joined in order.
    pub fn join(&mut self, instances: &mut Vec<Instance>, ranks: &[usize]) {
        self.join_with(instances, ranks, |pieces| Some(joined(pieces.iter().copied())));
    }

    /// `join`, with the joined mesh of a group's pieces made by `make` (once while the pieces
    /// are the same; None: they stay pieces): paging joins stand-ins (`Mesh::stand_in`) whose
    /// blocks its pager lists.
    pub fn join_with(
        &mut self,
        instances: &mut Vec<Instance>,
        ranks: &[usize],
        mut make: impl FnMut(&[&Instance]) -> Option<Mesh>,
    ) {
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut by_key: HashMap<u64, Vec<usize>> = HashMap::new();
        for (k, i) in instances.iter().enumerate() {
            let candidates = by_key.entry(key(i)).or_default();
            match candidates.iter().find(|&&g| pieces_of_one(&instances[groups[g][0]], i)) {
                Some(&g) => groups[g].push(k),
                None => {
                    candidates.push(groups.len());
                    groups.push(vec![k]);
                }
            }
        }
        let mut kept = HashMap::new();
        let mut out = Vec::with_capacity(instances.len());
        let mut first_of = vec![None; instances.len()];
        for (g, members) in groups.iter().enumerate() {
            first_of[members[0]] = Some(g);
        }
        for (k, i) in instances.iter().enumerate() {
            let Some(g) = first_of[k] else { continue };
            let members = &groups[g];
            let from_ranks = members.iter().any(|&m| ranks.get(m) != ranks.get(members[0]));
            if members.len() < 2 || !from_ranks || members.iter().any(|&m| instances[m].mesh.ws.is_some()) {
                out.extend(members.iter().map(|&m| instances[m].clone()));
                continue;
            }
            let ids: Vec<u64> = members.iter().map(|&m| instances[m].mesh.id).collect();
            let made = match self.meshes.remove(&ids) {
                Some(m) => Some(m),
                None => make(&members.iter().map(|&m| &instances[m]).collect::<Vec<_>>()).map(Arc::new),
            };
            let Some(mesh) = made else {
                out.extend(members.iter().map(|&m| instances[m].clone()));
                continue;
            };
            kept.insert(ids, mesh.clone());
            let sequence = members.iter().map(|&m| instances[m].sequence).min().unwrap_or(i.sequence);
            out.push(Instance { mesh, sequence, ..i.clone() });
        }
        self.meshes = kept;
        *instances = out;
    }
}

/// A hash of what must be equal for two draws to be pieces of one mesh (their transform, and
/// which surface, lighting and camera they use).
fn key(i: &Instance) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    i.modelview.to_cols_array().map(f64::to_bits).hash(&mut h);
    (i.surface, i.lighting, i.camera, i.flat, i.front_ccw, i.mirrored).hash(&mut h);
    h.finish()
}

/// Whether `a` and `b` differ in nothing but their mesh and their place in drawing order (the
/// projection through which they are seen may differ by rounding: each rank works out its own).
fn pieces_of_one(a: &Instance, b: &Instance) -> bool {
    let rounded = |x: &DMat4, y: &DMat4| {
        x.to_cols_array()
            .iter()
            .zip(y.to_cols_array())
            .all(|(p, q)| (p - q).abs() <= 1e-6 * p.abs().max(q.abs()) + 1e-12)
    };
    let same = Instance { mesh: b.mesh.clone(), sequence: b.sequence, object_to_clip: b.object_to_clip, ..a.clone() };
    same == *b && rounded(&a.object_to_clip, &b.object_to_clip)
}

/// The meshes of `pieces` as one: their vertices and triangles one after another. A vertex a
/// piece gave no value of an attribute takes its draw's current one (the same for every piece).
fn joined<'a>(pieces: impl Iterator<Item = &'a Instance> + Clone) -> Mesh {
    let first = pieces.clone().next().expect("a piece");
    let meshes: Vec<&Mesh> = pieces.map(|i| &*i.mesh).collect();
    let mut out = Mesh::default();
    for m in &meshes {
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&m.positions);
        out.triangles.extend(m.triangles.iter().map(|t| t.map(|v| v + base)));
        out.provoking.extend(m.provoking.iter().map(|v| v + base));
    }
    out.normals = gathered(&meshes, |m| &m.normals, first.normal.as_vec3());
    out.colors = gathered(&meshes, |m| &m.colors, first.color.as_vec4());
    out.texcoords = gathered(&meshes, |m| &m.texcoords, first.texcoord.as_vec4());
    out.seal()
}

/// One attribute of the pieces' meshes as one: given for no vertex when no piece gave any;
/// else for every vertex, `current` standing for the values a piece did not give.
fn gathered<T: Copy>(meshes: &[&Mesh], of: impl Fn(&Mesh) -> &Attribute<T>, current: T) -> Attribute<T> {
    let n: u32 = meshes.iter().map(|m| m.vertex_count()).sum();
    if meshes.iter().all(|m| of(m).first >= m.vertex_count()) {
        return Attribute::all_or_none(None, n);
    }
    let values = meshes.iter().flat_map(|m| (0..m.vertex_count()).map(|v| of(m).at(v).unwrap_or(current))).collect();
    Attribute::all_or_none(Some(values), n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Vec3};

    fn strip(from: usize, to: usize) -> Arc<Mesh> {
        let mut corners = Vec::new();
        let mut triangles = Vec::new();
        for k in from..to {
            let x = k as f32;
            let base = corners.len() as u32;
            corners.extend([Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::new(x, 1.0, 0.0)]);
            triangles.push([base, base + 1, base + 2]);
        }
        let n = corners.len();
        Arc::new(Mesh::indexed(corners, vec![Vec3::Z; n], triangles).unwrap())
    }

    #[test]
    fn pieces_of_one_mesh_from_different_ranks_are_joined_into_it() {
        let place = DMat4::from_translation(DVec3::new(0.0, 0.0, -5.0));
        let draw =
            |mesh: Arc<Mesh>, sequence: u32| Instance { sequence, ..Instance::new(mesh, place, DMat4::IDENTITY) };
        let whole = strip(0, 10);
        let mut joined = Joined::default();
        // Rank 0 drew triangles 0..4 and rank 1 4..10, and rank 1 a box elsewhere.
        let other = Instance::new(strip(0, 1), DMat4::from_translation(DVec3::X), DMat4::IDENTITY);
        let (a, b) = (strip(0, 4), strip(4, 10));
        let mut frame = vec![draw(a.clone(), 0), draw(b.clone(), 1), Instance { sequence: 2, ..other.clone() }];
        joined.join(&mut frame, &[0, 1, 1]);
        assert_eq!(frame.len(), 2);
        let m = &frame[0].mesh;
        assert_eq!((m.positions.clone(), m.triangles.clone()), (whole.positions.clone(), whole.triangles.clone()));
        assert_eq!((m.normals.clone(), m.min, m.max), (whole.normals.clone(), whole.min, whole.max));
        assert!(m.is_sequential() && frame[0].sequence == 0 && frame[1].sequence == 2);
        // The next frame's same pieces: the same joined mesh (its tree kept).
        let mut next = vec![draw(a, 0), draw(b, 1)];
        joined.join(&mut next, &[0, 1]);
        assert_eq!(next[0].mesh.id, frame[0].mesh.id, "kept");
        // One rank's own pieces stay as they are; so do draws in another state.
        let mut own = vec![draw(strip(0, 4), 0), draw(strip(4, 10), 1)];
        joined.join(&mut own, &[0, 0]);
        assert_eq!(own.len(), 2);
        let mut apart = vec![draw(strip(0, 4), 0), Instance { surface: 1, ..draw(strip(4, 10), 1) }];
        joined.join(&mut apart, &[0, 1]);
        assert_eq!(apart.len(), 2);
    }
}
