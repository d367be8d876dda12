//! A tree as bytes and back, checked (`TriBvh::to_bytes`, `TriBvh::from_bytes`): paging sends a
//! block's tree with its triangles, so that the rank that fetches it does not build it again
//! (a block's SAH build costs several times its bytes' trip over loopback). Bytes from another
//! process are not trusted: every reference must lie inside the tree, every node be reached
//! once from the root, every triangle index be one of the block's.

use glam::Vec4;

use super::node::{Node, NODE_BYTES};
use super::{leaf_blocks, stack, Tri4, TriBvh, EMPTY, FAR, LEAF};

/// What the bytes start with: a tag and the layout's version.
const MAGIC: u32 = 0x4254_0001;
const TRI4_BYTES: usize = 4 * (3 * 3 * 4 + 4);
const HEADER: usize = 4 * 4;

impl TriBvh {
    /// The tree's bytes: a header (tag, root, nodes, leaves), then its nodes and leaves.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(HEADER + self.nodes.len() * NODE_BYTES + self.leaves.len() * TRI4_BYTES);
        for u in [MAGIC, self.root, self.nodes.len() as u32, self.leaves.len() as u32] {
            out.extend(u.to_le_bytes());
        }
        for n in &self.nodes {
            n.put(&mut out);
        }
        for t in &self.leaves {
            let floats = t.v0.iter().chain(&t.e1).chain(&t.e2).flat_map(|v| v.to_array());
            out.extend(floats.flat_map(f32::to_le_bytes));
            out.extend(t.id.iter().flat_map(|u| u.to_le_bytes()));
        }
        out
    }

    /// The tree `to_bytes` wrote, over `triangles` triangles; an error saying what is wrong
    /// with bytes that are not such a tree.
    pub fn from_bytes(bytes: &[u8], triangles: usize) -> Result<TriBvh, String> {
        let word = |at: usize| bytes.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
        let header: Option<Vec<u32>> = (0..4).map(|k| word(4 * k)).collect();
        let Some(&[magic, root, nodes, leaves]) = header.as_deref() else {
            return Err(format!("a tree of {} bytes, shorter than its header", bytes.len()));
        };
        if magic != MAGIC {
            return Err(format!("not a tree (tag {magic:#x})"));
        }
        let (nodes, leaves) = (nodes as usize, leaves as usize);
        let size = HEADER + nodes * NODE_BYTES + leaves * TRI4_BYTES;
        if bytes.len() != size {
            return Err(format!("a tree of {nodes} nodes and {leaves} leaves is {size} bytes, not {}", bytes.len()));
        }
        let body = &bytes[HEADER..];
        let nodes: Vec<Node> = body[..nodes * NODE_BYTES].chunks_exact(NODE_BYTES).map(Node::take).collect();
        let leaves: Vec<Tri4> = body[nodes.len() * NODE_BYTES..]
            .chunks_exact(TRI4_BYTES)
            .map(|b| {
                let f = |k: usize| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
                let v = |k: usize| Vec4::new(f(4 * k), f(4 * k + 1), f(4 * k + 2), f(4 * k + 3));
                let u = |k: usize| u32::from_le_bytes([b[144 + 4 * k], b[145 + 4 * k], b[146 + 4 * k], b[147 + 4 * k]]);
                Tri4 {
                    v0: [v(0), v(1), v(2)],
                    e1: [v(3), v(4), v(5)],
                    e2: [v(6), v(7), v(8)],
                    id: std::array::from_fn(u),
                }
            })
            .collect();
        if let Some(t) = leaves.iter().find(|t| t.id.iter().any(|&i| i != EMPTY && i as usize >= triangles)) {
            return Err(format!("a leaf names triangle {:?} of {triangles}", t.id));
        }
        // Every reference inside the tree, every node reached once from the root (no cycle); on
        // the way, the most entries a walk can have pending (`stack::most_pending`'s measure,
        // which the builder works out as it builds).
        let mut seen = vec![false; nodes.len()];
        let mut todo = vec![(root, 0usize)];
        let mut most = 0;
        while let Some((c, above)) = todo.pop() {
            if c & LEAF != 0 {
                let (first, count) = leaf_blocks(c);
                if first + count > leaves.len() {
                    return Err(format!("a leaf of blocks {first}..{} of {}", first + count, leaves.len()));
                }
                most = most.max(above);
                continue;
            }
            let Some(s) = seen.get_mut(c as usize) else {
                return Err(format!("node {c} of {}", nodes.len()));
            };
            if std::mem::replace(s, true) {
                return Err(format!("node {c} reached twice"));
            }
            let children = nodes[c as usize].child.iter().filter(|&&k| k != EMPTY);
            let here = above + children.clone().count().saturating_sub(1);
            todo.extend(children.map(|&k| (k, here)));
        }
        let bytes = nodes.len() * std::mem::size_of::<Node>() + leaves.len() * std::mem::size_of::<Tri4>();
        Ok(TriBvh { nodes, leaves, root, shallow: most <= stack::FIXED, far: bytes > FAR })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::ray;
    use glam::{Vec3, Vec3A};

    #[test]
    fn a_tree_comes_back_from_its_bytes_the_same_and_damaged_bytes_are_refused() {
        let tris: Vec<[Vec3; 3]> = (0..3000)
            .map(|i| {
                let (x, y) = ((i % 60) as f32, (i / 60) as f32);
                [Vec3::new(x, y, (x * 0.3).sin()), Vec3::new(x + 1.0, y, 0.0), Vec3::new(x, y + 1.0, (y * 0.2).cos())]
            })
            .collect();
        for n in [1, 4, 9, 3000] {
            let bvh = TriBvh::build(n, |i| tris[i]);
            let bytes = bvh.to_bytes();
            let back = TriBvh::from_bytes(&bytes, n).unwrap();
            assert_eq!(back.to_bytes(), bytes, "{n} triangles");
            assert_eq!((back.root, back.shallow, back.far), (bvh.root, bvh.shallow, bvh.far));
            let most = if bvh.root & LEAF != 0 { 0 } else { stack::most_pending(&bvh.nodes, bvh.root) };
            assert_eq!(back.shallow, most <= stack::FIXED, "{n} triangles: the walk's measure");
            for k in 0..200 {
                let o = Vec3A::new((k % 61) as f32 + 0.37, (k / 4) as f32 + 0.21, 5.0);
                let ray = ray(o, Vec3A::new(0.05, 0.02, -1.0).normalize(), 0.0, f32::INFINITY);
                let (a, b) = (bvh.closest(&ray, |_, _| true), back.closest(&ray, |_, _| true));
                assert_eq!(a.map(|h| (h.index, h.t.to_bits())), b.map(|h| (h.index, h.t.to_bits())), "{n}: ray {k}");
            }
            assert!(TriBvh::from_bytes(&bytes[..bytes.len() - 1], n).is_err(), "cut short");
            assert!(TriBvh::from_bytes(&bytes, n - 1).is_err() || n == 1, "a triangle too many");
        }
        let bvh = TriBvh::build(3000, |i| tris[i]);
        let mut bytes = bvh.to_bytes();
        // The root's first child pointed back at the root: a cycle.
        let first_child = HEADER + bvh.root as usize * NODE_BYTES + 2 * 3 * 8 + 4 * 7;
        bytes[first_child..first_child + 4].copy_from_slice(&bvh.root.to_le_bytes());
        let why = |bytes: &[u8], n| TriBvh::from_bytes(bytes, n).err().expect("refused");
        assert!(why(&bytes, 3000).contains("twice"));
        bytes[first_child..first_child + 4].copy_from_slice(&(bvh.nodes.len() as u32 + 5).to_le_bytes());
        assert!(why(&bytes, 3000).starts_with("node"));
        assert!(why(&[0; 16], 3).contains("not a tree"));
        assert!(TriBvh::from_bytes(&[1, 2], 3).is_err());
    }
}
