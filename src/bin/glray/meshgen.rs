//! The anchors' benchmark mesh, made here so that `glray bench` needs no file: the isosurface
//! ../shared/anchors/meshgen.c makes (a gyroid with detail, bounded by a sphere, extracted by
//! marching tetrahedra on an N^3 grid with the Freudenthal split, vertices shared, normals the
//! field's gradient), computed the same way in the same precision, so that the same N gives the
//! same vertices and triangles and the bench's numbers stand beside the anchors' (N = 57, 181,
//! 573: ~100K, 1M, 10M triangles).

use std::f64::consts::PI;

const K1: f64 = 3.0 * PI;
const K2: f64 = 2.0 * PI * 3.3;
const AG: f64 = 0.6;
const AD: f64 = 0.08;
const AS: f64 = 2.2;
const RS: f64 = 0.45;

/// An indexed mesh with a normal per vertex, as the anchors' ISOMESH1 files hold it.
#[derive(Debug)]
pub struct IsoMesh {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// The grid size whose mesh has about `triangles` triangles (~30.5 N^2): the anchors' sizes for
/// 100K, 1M and 10M.
pub fn cells_for(triangles: u64) -> u32 {
    match triangles {
        100_000 => 57,
        1_000_000 => 181,
        10_000_000 => 573,
        t => ((t as f64 / 30.5).sqrt().round() as u32).max(2),
    }
}

/// The field's unit gradient at a point (the vertex normal).
fn gradient(x: f64, y: f64, z: f64) -> [f32; 3] {
    let (sx, cx, sy, cy, sz, cz) =
        ((K1 * x).sin(), (K1 * x).cos(), (K1 * y).sin(), (K1 * y).cos(), (K1 * z).sin(), (K1 * z).cos());
    let (tx, ux, ty, uy, tz, uz) =
        ((K2 * x).sin(), (K2 * x).cos(), (K2 * y).sin(), (K2 * y).cos(), (K2 * z).sin(), (K2 * z).cos());
    let gx = AG * K1 * (cx * cy - sz * sx) + AD * K2 * ux * ty * tz + AS * 2.0 * x;
    let gy = AG * K1 * (-sx * sy + cy * cz) + AD * K2 * tx * uy * tz + AS * 2.0 * y;
    let gz = AG * K1 * (-sy * sz + cz * cx) + AD * K2 * tx * ty * uz + AS * 2.0 * z;
    let mut l = (gx * gx + gy * gy + gz * gz).sqrt();
    if l == 0.0 {
        l = 1.0;
    }
    [(gx / l) as f32, (gy / l) as f32, (gz / l) as f32]
}

/// The sign of det(q - p, r - p, s - p) for cube corners given as 3-bit masks (exact).
fn corner_det(p: usize, q: usize, r: usize, s: usize) -> i32 {
    let c = |m: usize| [(m & 1) as i32, (m >> 1 & 1) as i32, (m >> 2 & 1) as i32];
    let (p, q, r, s) = (c(p), c(q), c(r), c(s));
    let u: [i32; 3] = std::array::from_fn(|i| q[i] - p[i]);
    let v: [i32; 3] = std::array::from_fn(|i| r[i] - p[i]);
    let w: [i32; 3] = std::array::from_fn(|i| s[i] - p[i]);
    let d =
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
    if d > 0 {
        1
    } else {
        -1
    }
}

/// The isosurface on an `n`^3 cell grid.
pub fn generate(n: u32) -> IsoMesh {
    let n = n as usize;
    let p = n + 1;
    let h = 2.0 / n as f64;
    // Fused multiply-adds where meshgen.c's `-1.0 + i * h` and `pa + t * (pb - pa)` are
    // contracted into them (gcc -O2 -march=native, as the anchors build it): the same
    // positions to the last bit.
    let axis = |i: usize| (i as f64).mul_add(h, -1.0);
    let s1: Vec<f64> = (0..p).map(|i| (K1 * axis(i)).sin()).collect();
    let c1: Vec<f64> = (0..p).map(|i| (K1 * axis(i)).cos()).collect();
    let s2: Vec<f64> = (0..p).map(|i| (K2 * axis(i)).sin()).collect();
    let q: Vec<f64> = (0..p).map(|i| axis(i) * axis(i)).collect();
    let field = |i: usize, j: usize, k: usize| {
        (AG * (s1[i] * c1[j] + s1[j] * c1[k] + s1[k] * c1[i])
            + AD * s2[i] * s2[j] * s2[k]
            + AS * (q[i] + q[j] + q[k] - RS)) as f32
    };
    let sp = p * p;
    let mut val = [vec![0f32; sp], vec![0f32; sp]];
    let mut edge = [vec![-1i32; 7 * sp], vec![-1i32; 7 * sp]];
    let mut mesh = IsoMesh { positions: Vec::new(), normals: Vec::new(), triangles: Vec::new() };
    // The 6 Freudenthal tetrahedra: corners 0, 1<<a, (1<<a)|(1<<b), 7.
    const PERM: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let tet: [[usize; 4]; 6] = PERM.map(|pm| [0, 1 << pm[0], (1 << pm[0]) | (1 << pm[1]), 7]);
    for j in 0..p {
        for i in 0..p {
            val[0][j * p + i] = field(i, j, 0);
        }
    }
    for k in 0..n {
        for j in 0..p {
            for i in 0..p {
                val[1][j * p + i] = field(i, j, k + 1);
            }
        }
        for j in 0..n {
            for i in 0..n {
                let mut cv = [0f32; 8];
                let mut inside = 0u32;
                for (c, v) in cv.iter_mut().enumerate() {
                    *v = val[c >> 2][(j + ((c >> 1) & 1)) * p + i + (c & 1)];
                    if *v == 0.0 {
                        *v = 1e-30; // avoid exact zeros
                    }
                    inside |= u32::from(*v < 0.0) << c;
                }
                if inside == 0 || inside == 255 {
                    continue;
                }
                for t in &tet {
                    let mut m = 0u32;
                    for (a, &corner) in t.iter().enumerate() {
                        m |= u32::from(cv[corner] < 0.0) << a;
                    }
                    if m == 0 || m == 15 {
                        continue;
                    }
                    // The vertex on tet edge (a, b), corners t[a] a subset of t[b]: made once per
                    // grid edge (kept in `edge` by slab, direction and grid point).
                    let mut ev = |a: usize, b: usize| -> u32 {
                        let (mut ca, mut cb) = (t[a], t[b]);
                        if ca > cb {
                            std::mem::swap(&mut ca, &mut cb);
                        }
                        let dir = (ca ^ cb) - 1;
                        let slab = ca >> 2;
                        let gi = (j + ((ca >> 1) & 1)) * p + i + (ca & 1);
                        let slot = &mut edge[slab][dir * sp + gi];
                        if *slot < 0 {
                            let (va, vb) = (cv[ca], cv[cb]);
                            let tpar = (va / (va - vb)) as f64;
                            let corner = |c: usize| [axis(i + (c & 1)), axis(j + ((c >> 1) & 1)), axis(k + (c >> 2))];
                            let (pa, pb) = (corner(ca), corner(cb));
                            let pt: [f64; 3] = std::array::from_fn(|d| tpar.mul_add(pb[d] - pa[d], pa[d]));
                            *slot = mesh.positions.len() as i32;
                            mesh.positions.push(pt.map(|x| x as f32));
                            mesh.normals.push(gradient(pt[0], pt[1], pt[2]));
                        }
                        *slot as u32
                    };
                    let count = m.count_ones();
                    if count == 1 || count == 3 {
                        let lone = if count == 1 { m.trailing_zeros() } else { (!m & 15).trailing_zeros() } as usize;
                        let others: Vec<usize> = (0..4).filter(|&a| a != lone).collect();
                        let e = |o: usize| (lone.min(o), lone.max(o));
                        let (a0, b0) = e(others[0]);
                        let v0 = ev(a0, b0);
                        let (a1, b1) = e(others[1]);
                        let v1 = ev(a1, b1);
                        let (a2, b2) = e(others[2]);
                        let v2 = ev(a2, b2);
                        // Outward iff det(o0 - L, o1 - L, o2 - L) > 0 when L is inside
                        // (reversed when L is outside).
                        let sign = corner_det(t[lone], t[others[0]], t[others[1]], t[others[2]])
                            * if count == 1 { 1 } else { -1 };
                        mesh.triangles.push(if sign > 0 { [v0, v1, v2] } else { [v0, v2, v1] });
                    } else {
                        // Two inside (in0, in1), two outside (out0, out1).
                        let inn: Vec<usize> = (0..4).filter(|&a| m >> a & 1 == 1).collect();
                        let out: Vec<usize> = (0..4).filter(|&a| m >> a & 1 == 0).collect();
                        let mut e2 = |x: usize, y: usize| if x < y { ev(x, y) } else { ev(y, x) };
                        let e00 = e2(inn[0], out[0]);
                        let e01 = e2(inn[0], out[1]);
                        let e11 = e2(inn[1], out[1]);
                        let e10 = e2(inn[1], out[0]);
                        if corner_det(t[inn[0]], t[inn[1]], t[out[0]], t[out[1]]) > 0 {
                            mesh.triangles.push([e00, e01, e11]);
                            mesh.triangles.push([e00, e11, e10]);
                        } else {
                            mesh.triangles.push([e00, e11, e01]);
                            mesh.triangles.push([e00, e10, e11]);
                        }
                    }
                }
            }
        }
        // Slice k + 1 becomes slice 0.
        val.swap(0, 1);
        edge.swap(0, 1);
        edge[1].fill(-1);
    }
    mesh
}

/// A mesh from a Wavefront OBJ file: `v` positions, optional `vn` normals, `f` faces (polygons
/// fanned into triangles; `v`, `v/t`, `v//n`, `v/t/n` corners, negative indices counted from
/// the end). Normals missing from the file are the faces' areas summed at each vertex.
pub fn read_obj(text: &str) -> Result<IsoMesh, String> {
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut file_normals: Vec<[f32; 3]> = Vec::new();
    let mut corners: Vec<(u32, Option<u32>)> = Vec::new();
    let mut triangles = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let bad = |what: &str| format!("line {}: {what}: {line}", n + 1);
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") | Some("vn") => {
                let v: Vec<f32> = words
                    .take(3)
                    .map(|w| w.parse::<f32>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| bad("not a number"))?;
                let v: [f32; 3] = v.try_into().map_err(|_| bad("three numbers expected"))?;
                if line.starts_with("vn") {
                    file_normals.push(v);
                } else {
                    positions.push(v);
                }
            }
            Some("f") => {
                let index = |w: &str, count: usize| -> Result<u32, String> {
                    let i: i64 = w.parse().map_err(|_| bad("a bad index"))?;
                    let i = if i < 0 { count as i64 + i } else { i - 1 };
                    (0..count as i64).contains(&i).then_some(i as u32).ok_or_else(|| bad("an index out of range"))
                };
                let face: Vec<(u32, Option<u32>)> = words
                    .map(|w| {
                        let mut parts = w.split('/');
                        let v = index(parts.next().unwrap_or(""), positions.len())?;
                        let normal =
                            parts.nth(1).filter(|s| !s.is_empty()).map(|s| index(s, file_normals.len())).transpose()?;
                        Ok((v, normal))
                    })
                    .collect::<Result<_, String>>()?;
                if face.len() < 3 {
                    return Err(bad("a face of fewer than three corners"));
                }
                for k in 1..face.len() - 1 {
                    let base = corners.len() as u32;
                    corners.extend([face[0], face[k], face[k + 1]]);
                    triangles.push([base, base + 1, base + 2]);
                }
            }
            _ => {}
        }
    }
    if triangles.is_empty() {
        return Err("no faces (f lines)".into());
    }
    // One vertex per corner when the file gives normals per corner; else the positions shared.
    let with_normals = corners.iter().all(|c| c.1.is_some()) && !file_normals.is_empty();
    if with_normals {
        let positions2 = corners.iter().map(|c| positions[c.0 as usize]).collect();
        let normals = corners.iter().map(|c| file_normals[c.1.unwrap() as usize]).collect();
        return Ok(IsoMesh { positions: positions2, normals, triangles });
    }
    let triangles: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(|k| corners[k as usize].0)).collect();
    let mut normals = vec![[0f32; 3]; positions.len()];
    for t in &triangles {
        let [a, b, c] = t.map(|i| glam::Vec3::from(positions[i as usize]));
        let n = (b - a).cross(c - a);
        for &i in t {
            let s = glam::Vec3::from(normals[i as usize]) + n;
            normals[i as usize] = s.into();
        }
    }
    let normals = normals.into_iter().map(|n| glam::Vec3::from(n).normalize_or_zero().into()).collect();
    Ok(IsoMesh { positions, normals, triangles })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_sizes_are_the_anchors() {
        assert_eq!((cells_for(100_000), cells_for(1_000_000), cells_for(10_000_000)), (57, 181, 573));
        // About 30.5 N^2 triangles.
        let m = generate(20);
        let expect = 30.5 * 400.0;
        assert!((m.triangles.len() as f64 - expect).abs() < 0.25 * expect, "{} triangles", m.triangles.len());
        assert_eq!(m.positions.len(), m.normals.len());
        assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < m.positions.len()));
    }

    /// An ISOMESH1 file's bytes (the format of the anchors' meshgen.c).
    fn isomesh_bytes(m: &IsoMesh) -> Vec<u8> {
        let mut d = b"ISOMESH1".to_vec();
        d.extend((m.positions.len() as u32).to_le_bytes());
        d.extend((m.triangles.len() as u32).to_le_bytes());
        d.extend(m.positions.iter().chain(&m.normals).flatten().flat_map(|x| x.to_le_bytes()));
        d.extend(m.triangles.iter().flatten().flat_map(|x| x.to_le_bytes()));
        d
    }

    #[test]
    fn the_mesh_is_the_anchors_byte_for_byte() {
        // ../shared/anchors/meshgen 20 wrote 5638 vertices and 11340 triangles, whose file's
        // xxh3-128 is below: the same vertices, normals and triangles in the same order (and
        // for N = 181, the 1M mesh, compared whole when this was written).
        let m = generate(20);
        assert_eq!((m.positions.len(), m.triangles.len()), (5638, 11340));
        let bytes = isomesh_bytes(&m);
        assert_eq!(glray_core::hash::content_hash(&bytes), [6837677718711598325, -954245725134682441]);
    }

    #[test]
    fn obj_faces_are_fanned_and_missing_normals_made() {
        let obj = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
        let m = read_obj(obj).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(m.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]));
        let m = read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 -1\nf 1//1 2//1 -1//1\n").unwrap();
        assert_eq!((m.positions.len(), m.normals[2]), (3, [0.0, 0.0, -1.0]));
        assert!(read_obj("v 0 0 0\nf 1 2 3\n").unwrap_err().contains("line 2"));
        assert!(read_obj("v 0 0\n").unwrap_err().contains("three numbers"));
    }
}
