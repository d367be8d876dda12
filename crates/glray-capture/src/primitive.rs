//! Primitive assembly: the vertices of one glBegin/glEnd (or one glDrawArrays/glDrawElements)
//! as points, lines and triangles, with the vertex whose colour flat shading uses (the
//! "provoking vertex", GL's table for the last-vertex convention: the last vertex of each line
//! and triangle, the last of each quad, the first of a polygon, and the first vertex for the
//! segment that closes a line loop). Incomplete trailing primitives are dropped, as GL does.
//! Quads, quad strips and polygons become triangles, keeping their winding.
//!
//! Which diagonal cuts a quad is the implementation's choice, and where a quad's corners differ
//! (colours, generated texture coordinates) the picture shows it. glray cuts as Mesa does
//! (`QuadSplit`), so that the GL look matches what programs were written against.

use crate::error::{GlError, GlResult};
use glray_gl::{
    GL_LINES, GL_LINE_LOOP, GL_LINE_STRIP, GL_POINTS, GL_POLYGON, GL_QUADS, GL_QUAD_STRIP, GL_TRIANGLES,
    GL_TRIANGLE_FAN, GL_TRIANGLE_STRIP,
};

/// The diagonal a GL_QUADS quad (corners 0, 1, 2, 3) is cut along. Mesa (llvmpipe, 22.3) cuts
/// quads drawn directly (glBegin/glEnd, glDrawArrays) from corner 0 to 2, and quads drawn
/// through indices (glDrawElements, and every display list, which Mesa compiles into indexed
/// draws) from 1 to 3. Quad strips and polygons are cut the same way either way.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub enum QuadSplit {
    /// Triangles (0, 1, 2) and (0, 2, 3).
    #[default]
    Direct,
    /// Triangles (0, 1, 3) and (1, 2, 3).
    Indexed,
}

/// Primitives over vertex indices 0..n of the stream.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Assembly {
    pub points: Vec<u32>,
    /// (the two ends, the provoking vertex)
    pub lines: Vec<([u32; 2], u32)>,
    /// (the three corners in winding order, the provoking vertex)
    pub triangles: Vec<([u32; 3], u32)>,
}

/// Assembles `n` vertices drawn with `mode`, quads cut as `quads` says; GL_INVALID_ENUM for a
/// mode that is not one of the ten fixed-function primitives.
pub fn assemble(mode: u32, n: usize, quads: QuadSplit) -> GlResult<Assembly> {
    let mut a = Assembly::default();
    let n32 = u32::try_from(n).map_err(|_| GlError::InvalidValue)?;
    match mode {
        GL_POINTS => a.points.extend(0..n32),
        GL_LINES => a.lines.extend((0..n32 / 2).map(|i| ([2 * i, 2 * i + 1], 2 * i + 1))),
        GL_LINE_STRIP | GL_LINE_LOOP => {
            if n32 >= 2 {
                a.lines.extend((0..n32 - 1).map(|i| ([i, i + 1], i + 1)));
                if mode == GL_LINE_LOOP {
                    a.lines.push(([n32 - 1, 0], 0));
                }
            }
        }
        GL_TRIANGLES => a.triangles.extend((0..n32 / 3).map(|i| ([3 * i, 3 * i + 1, 3 * i + 2], 3 * i + 2))),
        GL_TRIANGLE_STRIP => {
            // Every other triangle is flipped so that all keep the first one's winding.
            a.triangles.extend((0..n32.saturating_sub(2)).map(|i| {
                let t = if i % 2 == 0 { [i, i + 1, i + 2] } else { [i + 1, i, i + 2] };
                (t, i + 2)
            }));
        }
        GL_TRIANGLE_FAN => a.triangles.extend((0..n32.saturating_sub(2)).map(|i| ([0, i + 1, i + 2], i + 2))),
        GL_QUADS => {
            for q in 0..n32 / 4 {
                let (v, p) = (4 * q, 4 * q + 3);
                let halves = match quads {
                    QuadSplit::Direct => [[v, v + 1, v + 2], [v, v + 2, v + 3]],
                    QuadSplit::Indexed => [[v, v + 1, v + 3], [v + 1, v + 2, v + 3]],
                };
                a.triangles.extend(halves.map(|t| (t, p)));
            }
        }
        GL_QUAD_STRIP => {
            // Quad q is vertices 2q, 2q+1, 2q+3, 2q+2 around its edge.
            for q in 0..n32.saturating_sub(2) / 2 {
                let (a0, b, c, d) = (2 * q, 2 * q + 1, 2 * q + 3, 2 * q + 2);
                a.triangles.push(([a0, b, c], c));
                a.triangles.push(([a0, c, d], c));
            }
        }
        GL_POLYGON => a.triangles.extend((0..n32.saturating_sub(2)).map(|i| ([0, i + 1, i + 2], 0))),
        _ => return Err(GlError::InvalidEnum),
    }
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn tri(a: &Assembly) -> Vec<[u32; 3]> {
        a.triangles.iter().map(|(t, _)| *t).collect()
    }

    #[test]
    fn small_cases_match_the_gl_spec() {
        assert_eq!(
            tri(&assemble(GL_TRIANGLE_STRIP, 5, QuadSplit::Direct).unwrap()),
            vec![[0, 1, 2], [2, 1, 3], [2, 3, 4]]
        );
        assert_eq!(tri(&assemble(GL_QUADS, 4, QuadSplit::Direct).unwrap()), vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(
            tri(&assemble(GL_QUAD_STRIP, 6, QuadSplit::Direct).unwrap()),
            vec![[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]]
        );
        assert_eq!(
            assemble(GL_LINE_LOOP, 3, QuadSplit::Direct).unwrap().lines,
            vec![([0, 1], 1), ([1, 2], 2), ([2, 0], 0)]
        );
        assert_eq!(assemble(GL_POLYGON, 4, QuadSplit::Direct).unwrap().triangles, vec![([0, 1, 2], 0), ([0, 2, 3], 0)]);
        assert_eq!(assemble(GL_QUADS, 4, QuadSplit::Direct).unwrap().triangles[0].1, 3);
        // Through indices, Mesa cuts a quad along its other diagonal, keeping the winding.
        assert_eq!(
            tri(&assemble(GL_QUADS, 8, QuadSplit::Indexed).unwrap()),
            vec![[0, 1, 3], [1, 2, 3], [4, 5, 7], [5, 6, 7]]
        );
        assert_eq!(assemble(GL_QUADS, 4, QuadSplit::Indexed).unwrap().triangles[0].1, 3);
        // Nothing else depends on it.
        for mode in [GL_TRIANGLE_STRIP, GL_TRIANGLE_FAN, GL_QUAD_STRIP, GL_POLYGON, GL_LINE_LOOP] {
            assert_eq!(assemble(mode, 7, QuadSplit::Indexed), assemble(mode, 7, QuadSplit::Direct));
        }
        assert_eq!(assemble(GL_QUAD_STRIP, 4, QuadSplit::Direct).unwrap().triangles[1].1, 3);
        assert_eq!(assemble(10, 3, QuadSplit::Direct), Err(GlError::InvalidEnum));
        assert_eq!(assemble(GL_TRIANGLES, 2, QuadSplit::Direct).unwrap(), Assembly::default());
    }

    /// How many primitives GL draws for n vertices.
    fn expected(mode: u32, n: u32) -> (u32, u32, u32) {
        let s = |k: u32| n.saturating_sub(k);
        match mode {
            GL_POINTS => (n, 0, 0),
            GL_LINES => (0, n / 2, 0),
            GL_LINE_STRIP => (0, s(1), 0),
            GL_LINE_LOOP => (0, if n >= 2 { n } else { 0 }, 0),
            GL_TRIANGLES => (0, 0, n / 3),
            GL_TRIANGLE_STRIP | GL_TRIANGLE_FAN | GL_POLYGON => (0, 0, s(2)),
            GL_QUADS => (0, 0, 2 * (n / 4)),
            GL_QUAD_STRIP => (0, 0, 2 * (s(2) / 2)),
            _ => unreachable!(),
        }
    }

    proptest! {
        #[test]
        fn counts_indices_and_provoking_vertices_hold(mode in 0u32..10, n in 0u32..300, indexed: bool) {
            let quads = if indexed { QuadSplit::Indexed } else { QuadSplit::Direct };
            let a = assemble(mode, n as usize, quads).unwrap();
            prop_assert_eq!((a.points.len() as u32, a.lines.len() as u32, a.triangles.len() as u32), expected(mode, n));
            for p in &a.points { prop_assert!(*p < n); }
            for (l, pv) in &a.lines {
                prop_assert!(l.iter().all(|v| *v < n) && l[0] != l[1]);
                prop_assert!(l.contains(pv));
            }
            for (t, pv) in &a.triangles {
                prop_assert!(t.iter().all(|v| *v < n));
                prop_assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
                if mode == GL_QUADS {
                    // Both halves of a quad take the quad's last vertex.
                    prop_assert_eq!(*pv, t[0] / 4 * 4 + 3);
                } else {
                    prop_assert!(t.contains(pv));
                }
            }
        }

        /// Neighbouring triangles of a strip, fan, quad strip or polygon share an edge in
        /// opposite directions: the surface keeps one winding, so front faces stay front faces.
        #[test]
        fn connected_primitives_keep_one_winding(
            mode in prop::sample::select(vec![GL_TRIANGLE_STRIP, GL_TRIANGLE_FAN, GL_QUAD_STRIP, GL_POLYGON, GL_QUADS]),
            n in 3u32..200,
            indexed: bool,
        ) {
            let quads = if indexed { QuadSplit::Indexed } else { QuadSplit::Direct };
            let t = tri(&assemble(mode, n as usize, quads).unwrap());
            let edges = |t: &[u32; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
            for w in t.windows(2) {
                let shared: Vec<_> = edges(&w[0]).into_iter().filter(|(a, b)| edges(&w[1]).contains(&(*b, *a))).collect();
                let same_direction = edges(&w[0]).into_iter().any(|e| edges(&w[1]).contains(&e));
                prop_assert!(!same_direction, "{:?} and {:?} share an edge in the same direction", w[0], w[1]);
                if mode != GL_QUADS {
                    prop_assert!(!shared.is_empty(), "{:?} and {:?} share no edge", w[0], w[1]);
                }
            }
        }
    }
}
