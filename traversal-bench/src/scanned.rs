//! A procedural stand-in for a scanned mesh: a bunny-like blob (body, head, two ears, tail,
//! smooth unions) with two octaves of surface noise, polygonised by marching tetrahedra. Like a
//! range-scan reconstruction it is closed and irregular (slivers, widely varying triangle sizes);
//! no mesh file needs to be committed.

use std::collections::HashMap;

use geometry::TriangleMesh;
use glam::{Vec3, vec3};

/// Lattice value noise in `[−1, 1]`, smooth (quintic fade) between integer points.
fn value_noise(p: Vec3) -> f32 {
    let hash = |x: i32, y: i32, z: i32| {
        let mut h = (x as u32).wrapping_mul(0x8da6_b343)
            ^ (y as u32).wrapping_mul(0xd816_3841)
            ^ (z as u32).wrapping_mul(0xcb1a_b31f);
        h ^= h >> 13;
        h = h.wrapping_mul(0x5bd1_e995);
        h ^= h >> 15;
        h as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    let base = p.floor();
    let f = p - base;
    let fade = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let (x, y, z) = (base.x as i32, base.y as i32, base.z as i32);
    let mut sum = 0.0;
    for corner in 0..8 {
        let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, corner >> 2);
        let w = |d: i32, t: f32| if d == 1 { t } else { 1.0 - t };
        sum += w(dx, fade.x) * w(dy, fade.y) * w(dz, fade.z) * hash(x + dx, y + dy, z + dz);
    }
    sum
}

/// Approximate signed distance to an ellipsoid (exact on the axes).
fn ellipsoid(p: Vec3, centre: Vec3, radii: Vec3) -> f32 {
    (((p - centre) / radii).length() - 1.0) * radii.min_element()
}

/// Smooth union (exponential smooth minimum with blend width `k`).
fn smooth_union(a: f32, b: f32, k: f32) -> f32 {
    -k * ((-a / k).exp() + (-b / k).exp()).ln()
}

/// The implicit surface: negative inside.
fn field(p: Vec3) -> f32 {
    let body = ellipsoid(p, vec3(0.0, 0.0, 0.0), vec3(0.5, 0.38, 0.36));
    let head = ellipsoid(p, vec3(0.42, 0.28, 0.0), vec3(0.22, 0.2, 0.19));
    let ear = |z: f32| {
        // Ears lean back: shear the point before the ellipsoid test.
        let q = p - vec3(0.38, 0.46, z);
        let q = vec3(q.x + 0.35 * q.y, q.y, q.z);
        ellipsoid(q, vec3(0.0, 0.2, 0.0), vec3(0.06, 0.24, 0.035))
    };
    let tail = ellipsoid(p, vec3(-0.52, 0.08, 0.0), vec3(0.1, 0.1, 0.1));
    let shape = [head, ear(0.09), ear(-0.09), tail]
        .into_iter()
        .fold(body, |a, b| smooth_union(a, b, 0.04));
    shape + 0.012 * value_noise(p * 14.0) + 0.003 * value_noise(p * 61.0)
}

/// The bunny-like mesh polygonised on a `cells³` grid over `[−0.8, 0.8]³` (about 1.3 units long,
/// outward winding); `cells = 104` gives about 100k triangles.
pub fn scanned_like(cells: u32) -> TriangleMesh {
    let (lo, size) = (Vec3::splat(-0.8), 1.6);
    let n = cells + 1;
    let h = size / cells as f32;
    let point = |i: u32, j: u32, k: u32| lo + h * vec3(i as f32, j as f32, k as f32);
    let index = |i: u32, j: u32, k: u32| (k * n + j) * n + i;
    // Values exactly 0 count as outside, so every crossing edge has endpoints of opposite sign.
    let values: Vec<f32> = (0..n * n * n)
        .map(|id| {
            let (i, j, k) = (id % n, id / n % n, id / (n * n));
            field(point(i, j, k))
        })
        .collect();
    let position = |id: u32| point(id % n, id / n % n, id / (n * n));
    let mut mesh = TriangleMesh::default();
    let mut edge_vertex: HashMap<(u32, u32), u32> = HashMap::new();
    let mut vertex_on = |a: u32, b: u32, mesh: &mut TriangleMesh| -> u32 {
        let key = (a.min(b), a.max(b));
        *edge_vertex.entry(key).or_insert_with(|| {
            let (fa, fb) = (values[key.0 as usize], values[key.1 as usize]);
            let t = fa / (fa - fb);
            mesh.positions
                .push(position(key.0).lerp(position(key.1), t));
            mesh.positions.len() as u32 - 1
        })
    };
    // Kuhn decomposition: six tetrahedra along the cube diagonal 0 → 7, consistent across
    // neighbouring cubes, so the surface is closed.
    const TETS: [[usize; 4]; 6] = [
        [0, 1, 3, 7],
        [0, 1, 5, 7],
        [0, 2, 3, 7],
        [0, 2, 6, 7],
        [0, 4, 5, 7],
        [0, 4, 6, 7],
    ];
    for k in 0..cells {
        for j in 0..cells {
            for i in 0..cells {
                let corner = |c: usize| {
                    index(
                        i + (c & 1) as u32,
                        j + ((c >> 1) & 1) as u32,
                        k + (c >> 2) as u32,
                    )
                };
                for tet in TETS {
                    let ids = tet.map(corner);
                    let inside: Vec<u32> = ids
                        .iter()
                        .copied()
                        .filter(|&v| values[v as usize] < 0.0)
                        .collect();
                    let outside: Vec<u32> = ids
                        .iter()
                        .copied()
                        .filter(|&v| values[v as usize] >= 0.0)
                        .collect();
                    let polygon: Vec<(u32, u32)> = match (inside.len(), outside.len()) {
                        (1, 3) => outside.iter().map(|&o| (inside[0], o)).collect(),
                        (3, 1) => inside.iter().map(|&i| (i, outside[0])).collect(),
                        (2, 2) => vec![
                            (inside[0], outside[0]),
                            (inside[0], outside[1]),
                            (inside[1], outside[1]),
                            (inside[1], outside[0]),
                        ],
                        _ => continue,
                    };
                    let outward = position(polygon[0].1) - position(polygon[0].0);
                    let verts: Vec<u32> = polygon
                        .iter()
                        .map(|&(a, b)| vertex_on(a, b, &mut mesh))
                        .collect();
                    for fan in 1..verts.len() - 1 {
                        let mut tri = [verts[0], verts[fan], verts[fan + 1]];
                        let [p0, p1, p2] = tri.map(|v| mesh.positions[v as usize]);
                        if (p1 - p0).cross(p2 - p0).dot(outward) < 0.0 {
                            tri.swap(1, 2);
                        }
                        mesh.indices.push(tri);
                    }
                }
            }
        }
    }
    mesh.drop_degenerate();
    mesh.with_smooth_normals()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_outward_and_about_100k_triangles() {
        let mesh = scanned_like(104);
        let count = mesh.triangle_count();
        assert!((80_000..140_000).contains(&count), "{count} triangles");
        // Closed with outward winding: the divergence theorem gives a positive volume close to
        // the blob's (body ellipsoid 4/3·π·0.5·0.38·0.36 ≈ 0.287 plus head, ears and tail).
        let volume = mesh.signed_volume();
        assert!((0.3..0.45).contains(&volume), "volume {volume}");
        // Closed: every edge is shared by exactly two triangles, in opposite directions.
        let mut edges = HashMap::new();
        for t in &mesh.indices {
            for e in 0..3 {
                *edges.entry((t[e], t[(e + 1) % 3])).or_insert(0) += 1;
            }
        }
        let open = edges
            .iter()
            .filter(|&(&(a, b), &c)| c != 1 || edges.get(&(b, a)) != Some(&1))
            .count();
        // Dropped degenerate triangles may leave a few edges unmatched.
        assert!(
            open * 1000 < edges.len(),
            "{open} of {} edges unmatched",
            edges.len()
        );
        // Irregular like a scan: triangle areas spread over orders of magnitude.
        let mut areas: Vec<f32> = (0..count)
            .map(|i| {
                let [a, b, c] = mesh.triangle(i);
                (b - a).cross(c - a).length()
            })
            .collect();
        areas.sort_by(f32::total_cmp);
        assert!(areas[count * 9 / 10] > 10.0 * areas[count / 10]);
    }
}
