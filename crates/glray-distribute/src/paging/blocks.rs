//! A rank's own meshes cut into blocks: triangles close in space (median cuts of their
//! centres), each a mesh of its own (`Mesh::part`) of about the block size with its BVH
//! inside (`Block`: a ray that reaches a block's box finds the tree and the triangles it needs
//! in one fetch), and the byte form blocks travel in.

use glam::Vec3;
use glray_render::paged::Block;
use glray_render::render::FLATTEN_INSTANCES;
use glray_scene::mesh::Mesh;

/// What a block's tree adds to its triangles, a triangle (measured: a tree of four-triangle
/// leaves over a few thousand triangles).
const TREE_BYTES_PER_TRIANGLE: usize = 60;
/// The fewest triangles a block holds, however small the block size.
const MIN_TRIANGLES: usize = 32;

/// Whether a mesh is paged: big enough to be worth blocks (a mesh the tracer would draw as
/// flat triangles, or one block's worth, goes whole as in replicated mode, once), and with
/// w = 1 everywhere (a mesh with other w is never instanced).
pub fn pages(mesh: &Mesh, block_bytes: usize) -> bool {
    mesh.ws.is_none() && mesh.triangles.len() > FLATTEN_INSTANCES.max(triangles_a_block(mesh, block_bytes))
}

/// How many of `mesh`'s triangles make a block of about `block_bytes`.
pub fn triangles_a_block(mesh: &Mesh, block_bytes: usize) -> usize {
    let per = mesh.bytes() / mesh.triangles.len().max(1) + TREE_BYTES_PER_TRIANGLE;
    (block_bytes / per.max(1)).max(MIN_TRIANGLES)
}

/// `mesh`'s triangles cut into blocks of about `block_bytes`: halved again and again across
/// the longest side of their centres' box, at the median, until a part fits in a block (parts
/// close in space and about as wide as they are long: a ray crosses few of their boxes).
pub fn cut(mesh: &Mesh, block_bytes: usize) -> Vec<Mesh> {
    let per = triangles_a_block(mesh, block_bytes);
    let mut ids: Vec<(Vec3, u32)> = (0..mesh.triangles.len())
        .map(|i| {
            let [a, b, c] = mesh.corners(i);
            ((a + b + c) / 3.0, i as u32)
        })
        .collect();
    let mut runs = Vec::new();
    halve(&mut ids, per, &mut runs);
    runs.iter().map(|run| mesh.part(run)).collect()
}

/// Cuts `ids` (centres and triangles) into runs of at most `per`, in order, into `out`.
fn halve(ids: &mut [(Vec3, u32)], per: usize, out: &mut Vec<Vec<u32>>) {
    if ids.len() <= per {
        let mut run: Vec<u32> = ids.iter().map(|(_, i)| *i).collect();
        run.sort_unstable();
        out.push(run);
        return;
    }
    let (lo, hi) = ids.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (c, _)| (lo.min(*c), hi.max(*c)));
    let axis = (hi - lo).max_position();
    // (Ties in the triangles' order: the same cut every time.)
    let key = |e: &(Vec3, u32)| (e.0[axis], e.1);
    let half = ids.len() / 2;
    ids.select_nth_unstable_by(half, |a, b| key(a).0.total_cmp(&key(b).0).then(key(a).1.cmp(&key(b).1)));
    let (left, right) = ids.split_at_mut(half);
    halve(left, per, out);
    halve(right, per, out);
}

/// A block's bytes on the wire: its mesh (postcard, after its length), then its tree
/// (`Block::tree_bytes`: building it again where it lands cost ~0.5 ms a 128 KB block, four
/// times the block's encoding, compression and decoding together).
pub fn encode(block: &Block) -> Vec<u8> {
    let mesh = postcard::to_allocvec(&block.mesh).expect("a mesh encodes");
    let mut out = Vec::with_capacity(8 + mesh.len() + block.bytes());
    out.extend((mesh.len() as u64).to_le_bytes());
    out.extend(mesh);
    out.extend(block.tree_bytes());
    out
}

/// A block from its bytes.
pub fn decode(bytes: &[u8]) -> Result<Block, String> {
    let damaged = |why: String| format!("a damaged block ({} bytes): {why}", bytes.len());
    let len = bytes.get(..8).map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")) as usize);
    let (mesh, tree) = match len {
        Some(len) if len <= bytes.len() - 8 => bytes[8..].split_at(len),
        _ => return Err(damaged("its mesh's length is wrong".into())),
    };
    let mesh: Mesh = postcard::from_bytes(mesh).map_err(|e| damaged(e.to_string()))?;
    Block::with_tree(mesh, tree).map_err(damaged)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of n x n squares (two triangles each) in the z = 0 plane, its vertices coloured.
    pub(crate) fn grid(n: u32) -> Mesh {
        let mut positions = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                positions.push(Vec3::new(x as f32, y as f32, ((x * y) % 7) as f32 * 0.1));
            }
        }
        let at = |x: u32, y: u32| y * (n + 1) + x;
        let mut triangles = Vec::new();
        for y in 0..n {
            for x in 0..n {
                triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
        let normals = vec![Vec3::Z; positions.len()];
        Mesh::indexed(positions, normals, triangles).unwrap()
    }

    #[test]
    fn a_mesh_cut_into_blocks_keeps_every_triangle_once_with_its_corners_and_normals() {
        let mesh = grid(120);
        let blocks = cut(&mesh, 16 * 1024);
        assert!(blocks.len() > 10, "{} blocks", blocks.len());
        let mut seen: Vec<[[u32; 3]; 3]> = Vec::new();
        for b in &blocks {
            assert!(b.triangles.len() <= triangles_a_block(&mesh, 16 * 1024));
            assert_eq!(b.normals.first, 0);
            for i in 0..b.triangles.len() {
                seen.push(b.corners(i).map(|c| c.to_array().map(f32::to_bits)));
                assert!(b.corner_indices(i).iter().all(|&v| b.normals.at(v) == Some(Vec3::Z)));
            }
            // Close in space: a block spans a small part of the grid.
            let span = b.max - b.min;
            assert!(span.x * span.y < 0.1 * 120.0 * 120.0, "{span}");
        }
        let mut whole: Vec<[[u32; 3]; 3]> =
            (0..mesh.triangles.len()).map(|i| mesh.corners(i).map(|c| c.to_array().map(f32::to_bits))).collect();
        seen.sort_unstable();
        whole.sort_unstable();
        assert_eq!(seen, whole);
        // Across the wire and back: the same mesh, the same tree.
        let b = Block::new(blocks[3].clone_mesh());
        let back = decode(&encode(&b)).unwrap();
        assert_eq!(back.mesh, b.mesh);
        assert_eq!(back.bytes(), b.bytes());
        assert_eq!(back.tree_bytes(), b.tree_bytes(), "the tree comes with the block");
        let bytes = encode(&b);
        for cut in [0, 7, 40, bytes.len() - 1] {
            assert!(decode(&bytes[..cut]).is_err(), "cut at {cut}");
        }
    }

    trait CloneMesh {
        fn clone_mesh(&self) -> Mesh;
    }

    impl CloneMesh for Mesh {
        fn clone_mesh(&self) -> Mesh {
            postcard::from_bytes(&postcard::to_allocvec(self).unwrap()).unwrap()
        }
    }
}
