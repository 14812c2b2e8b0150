//! Procedural shapes. All are closed, consistently wound meshes with outward geometric normals,
//! except [`quad`] (one single-sided face). Resolution parameters must be at least the stated
//! minimum (the scene loader validates them; these functions assert it).

use std::collections::HashMap;
use std::f64::consts::TAU;

use glam::{DVec3, Vec3};
use restir::rng::StreamKey;

use super::mesh::TriangleMesh;

/// `purpose` of the stream that draws the bumpy sphere's noise tables.
const NOISE_PURPOSE: u32 = 0x5EED_0B0F;

/// A UV sphere centred at the origin with poles on ±y: `segments ≥ 3` around, `rings ≥ 2` from
/// pole to pole. Shading normals are the exact sphere normals.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> TriangleMesh {
    assert!(
        segments >= 3 && rings >= 2,
        "uv_sphere needs segments ≥ 3, rings ≥ 2"
    );
    let mut normals = vec![Vec3::Y];
    for ring in 1..rings {
        let theta = std::f64::consts::PI * ring as f64 / rings as f64;
        for s in 0..segments {
            let phi = TAU * s as f64 / segments as f64;
            normals.push(
                DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
                .as_vec3(),
            );
        }
    }
    normals.push(Vec3::NEG_Y);
    let south = normals.len() as u32 - 1;
    let at = |ring: u32, s: u32| 1 + (ring - 1) * segments + s % segments;
    let mut indices = Vec::new();
    for s in 0..segments {
        indices.push([0, at(1, s + 1), at(1, s)]);
        indices.push([south, at(rings - 1, s), at(rings - 1, s + 1)]);
        for ring in 1..rings - 1 {
            let (a, b, c, d) = (
                at(ring, s),
                at(ring, s + 1),
                at(ring + 1, s + 1),
                at(ring + 1, s),
            );
            indices.push([a, b, c]);
            indices.push([a, c, d]);
        }
    }
    TriangleMesh {
        positions: normals.iter().map(|&n| radius * n).collect(),
        indices,
        normals: Some(normals),
    }
}

/// An icosphere: an icosahedron with each face split into `4^subdivisions` triangles, projected
/// onto the sphere (`20 · 4^subdivisions` triangles). Shading normals are the sphere normals.
pub fn icosphere(radius: f32, subdivisions: u32) -> TriangleMesh {
    let (directions, indices) = unit_icosphere(subdivisions);
    TriangleMesh {
        positions: directions.iter().map(|&n| radius * n).collect(),
        indices,
        normals: Some(directions),
    }
}

/// Unit-sphere directions and outward-wound faces of a subdivided icosahedron.
fn unit_icosphere(subdivisions: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut directions: Vec<DVec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .map(|(x, y, z)| DVec3::new(x, y, z).normalize())
    .to_vec();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, directions: &mut Vec<DVec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                directions.push((directions[a as usize] + directions[b as usize]).normalize());
                directions.len() as u32 - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut directions);
                let bc = midpoint(b, c, &mut directions);
                let ca = midpoint(c, a, &mut directions);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (directions.iter().map(|d| d.as_vec3()).collect(), faces)
}

/// An axis-aligned box centred at the origin (8 shared vertices, flat shading: no normals).
pub fn cuboid(half_extents: Vec3) -> TriangleMesh {
    let positions = (0..8)
        .map(|i| {
            let sign = |bit: u32| if i & bit != 0 { 1.0 } else { -1.0 };
            half_extents * Vec3::new(sign(1), sign(2), sign(4))
        })
        .collect();
    // Vertex i has x from bit 0, y from bit 1, z from bit 2; quads wound counter-clockwise seen
    // from outside.
    let quads = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    let indices = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    TriangleMesh {
        positions,
        indices,
        normals: None,
    }
}

/// A thin box centred at the origin: `size_x × thickness × size_z`, thickness along y.
pub fn slab(size_x: f32, size_z: f32, thickness: f32) -> TriangleMesh {
    cuboid(0.5 * Vec3::new(size_x, thickness, size_z))
}

/// A single-sided `size_x × size_z` rectangle at y = 0 centred at the origin, normal +y. Not
/// closed: a ray from below hits its back face.
pub fn quad(size_x: f32, size_z: f32) -> TriangleMesh {
    let (x, z) = (0.5 * size_x, 0.5 * size_z);
    TriangleMesh {
        positions: vec![
            Vec3::new(-x, 0.0, -z),
            Vec3::new(x, 0.0, -z),
            Vec3::new(x, 0.0, z),
            Vec3::new(-x, 0.0, z),
        ],
        indices: vec![[0, 2, 1], [0, 3, 2]],
        normals: Some(vec![Vec3::Y; 4]),
    }
}

/// A torus around the y axis: tube of radius `minor` around a circle of radius `major` in the
/// xz plane; `segments ≥ 3` along the ring, `sides ≥ 3` around the tube.
pub fn torus(major: f32, minor: f32, segments: u32, sides: u32) -> TriangleMesh {
    let major = major as f64;
    tube(
        |u| {
            (
                major * DVec3::new(u.cos(), 0.0, u.sin()),
                DVec3::new(-u.sin(), 0.0, u.cos()),
            )
        },
        TAU,
        minor,
        segments,
        sides,
    )
}

/// A (p, q) torus knot of overall radius `radius` with a tube of radius `tube`:
/// `C(u) = radius/2 · ((2 + cos(qu/p)) cos u, (2 + cos(qu/p)) sin u, sin(qu/p))`, `u ∈ [0, 2πp)`.
/// `segments ≥ 3` along the knot, `sides ≥ 3` around the tube. The tube must be thin enough not
/// to self-intersect (e.g. p = 2, q = 3, tube ≤ 0.15 · radius), and p, q coprime (otherwise the
/// curve runs over itself gcd(p, q) times and the mesh overlaps itself).
pub fn torus_knot(
    p: u32,
    q: u32,
    radius: f32,
    tube_radius: f32,
    segments: u32,
    sides: u32,
) -> TriangleMesh {
    assert!(p >= 1 && q >= 1, "torus_knot needs p, q ≥ 1");
    let (w, half) = (q as f64 / p as f64, 0.5 * radius as f64);
    let curve = |u: f64| {
        let (r, dr) = (2.0 + (w * u).cos(), -w * (w * u).sin());
        let position = half * DVec3::new(r * u.cos(), r * u.sin(), (w * u).sin());
        let tangent = half
            * DVec3::new(
                dr * u.cos() - r * u.sin(),
                dr * u.sin() + r * u.cos(),
                w * (w * u).cos(),
            );
        (position, tangent)
    };
    tube(curve, TAU * p as f64, tube_radius, segments, sides)
}

/// A tube of radius `radius` around the closed curve `curve(u) = (point, tangent)`,
/// `u ∈ [0, period)`. The frame is `N` = the part of the point orthogonal to the tangent,
/// `B = T × N`; it is a function of `u` alone, so the seam closes exactly.
fn tube(
    curve: impl Fn(f64) -> (DVec3, DVec3),
    period: f64,
    radius: f32,
    segments: u32,
    sides: u32,
) -> TriangleMesh {
    assert!(
        segments >= 3 && sides >= 3,
        "tubes need segments ≥ 3, sides ≥ 3"
    );
    let mut positions = Vec::with_capacity((segments * sides) as usize);
    let mut normals = Vec::with_capacity(positions.capacity());
    for i in 0..segments {
        let (point, tangent) = curve(period * i as f64 / segments as f64);
        let t = tangent.normalize();
        let n = (point - point.dot(t) * t).normalize();
        let b = t.cross(n);
        for j in 0..sides {
            let v = TAU * j as f64 / sides as f64;
            let normal = v.cos() * n + v.sin() * b;
            positions.push((point + radius as f64 * normal).as_vec3());
            normals.push(normal.as_vec3());
        }
    }
    let at = |i: u32, j: u32| (i % segments) * sides + j % sides;
    // With (T, N, B) right-handed, ∂/∂v × ∂/∂u points along the outward normal.
    let indices = (0..segments)
        .flat_map(|i| (0..sides).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            [[a, b, c], [a, c, d]]
        })
        .collect();
    TriangleMesh {
        positions,
        indices,
        normals: Some(normals),
    }
}

/// An icosphere (`20 · 4^subdivisions` triangles) displaced along its normals by
/// `amplitude · noise(frequency · n)`, where `noise` is 3D Perlin gradient noise (Perlin 2002,
/// values in about [−1, 1]) with permutation and gradients drawn from the stream keyed by `seed`.
/// Shading normals are area-weighted face normals.
pub fn bumpy_sphere(
    radius: f32,
    amplitude: f32,
    frequency: f32,
    seed: u64,
    subdivisions: u32,
) -> TriangleMesh {
    let noise = PerlinNoise::new(seed);
    let (directions, indices) = unit_icosphere(subdivisions);
    let positions = directions
        .iter()
        .map(|&n| n * (radius + amplitude * noise.sample(frequency * n)))
        .collect();
    TriangleMesh {
        positions,
        indices,
        normals: None,
    }
    .with_smooth_normals()
}

/// Improved Perlin noise (Perlin 2002) with a seeded permutation table.
struct PerlinNoise {
    permutation: [u8; 512],
}

impl PerlinNoise {
    fn new(seed: u64) -> PerlinNoise {
        let mut rng = StreamKey::new(0, 0, 0, NOISE_PURPOSE).stream(seed);
        let mut table: [u8; 256] = std::array::from_fn(|i| i as u8);
        for i in (1..256).rev() {
            let j = ((rng.next_u32() as u64 * (i as u64 + 1)) >> 32) as usize;
            table.swap(i, j);
        }
        PerlinNoise {
            permutation: std::array::from_fn(|i| table[i % 256]),
        }
    }

    fn sample(&self, p: Vec3) -> f32 {
        let cell = p.floor();
        let f = p - cell;
        let [x, y, z] = cell.to_array().map(|c| (c as i32 & 255) as usize);
        let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let (u, v, w) = (fade(f.x), fade(f.y), fade(f.z));
        let perm = &self.permutation;
        let hash = |i: usize, j: usize, k: usize| {
            perm[perm[perm[x + i] as usize + y + j] as usize + z + k]
        };
        let corner = |i: usize, j: usize, k: usize| {
            gradient(hash(i, j, k), f - Vec3::new(i as f32, j as f32, k as f32))
        };
        let lerp = |t: f32, a: f32, b: f32| a + t * (b - a);
        lerp(
            w,
            lerp(
                v,
                lerp(u, corner(0, 0, 0), corner(1, 0, 0)),
                lerp(u, corner(0, 1, 0), corner(1, 1, 0)),
            ),
            lerp(
                v,
                lerp(u, corner(0, 0, 1), corner(1, 0, 1)),
                lerp(u, corner(0, 1, 1), corner(1, 1, 1)),
            ),
        )
    }
}

/// Dot product of `d` with one of the 12 cube-edge gradients selected by `hash` (Perlin 2002).
fn gradient(hash: u8, d: Vec3) -> f32 {
    let h = hash & 15;
    let a = if h < 8 { d.x } else { d.y };
    let b = if h < 4 {
        d.y
    } else if h == 12 || h == 14 {
        d.x
    } else {
        d.z
    };
    (if h & 1 == 0 { a } else { -a }) + (if h & 2 == 0 { b } else { -b })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Every directed edge occurs once and its reverse once: closed, 2-manifold along edges,
    /// consistently wound.
    fn check_closed(mesh: &TriangleMesh) -> Result<(), String> {
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for &[a, b, c] in &mesh.indices {
            for edge in [(a, b), (b, c), (c, a)] {
                *directed.entry(edge).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            let reverse = directed.get(&(b, a)).copied().unwrap_or(0);
            if count != 1 || reverse != 1 {
                return Err(format!(
                    "edge ({a}, {b}) occurs {count}×, reverse {reverse}×"
                ));
            }
        }
        Ok(())
    }

    /// Closed, positive volume (so outward), and shading normals on the geometric side.
    fn check_outward(mesh: &TriangleMesh) -> Result<(), String> {
        check_closed(mesh)?;
        let volume = mesh.signed_volume();
        if volume <= 0.0 {
            return Err(format!("signed volume {volume}"));
        }
        if let Some(normals) = &mesh.normals {
            for (i, t) in mesh.indices.iter().enumerate() {
                let [p0, p1, p2] = mesh.triangle(i);
                let face = (p1 - p0).cross(p2 - p0);
                let shading = t.iter().map(|&v| normals[v as usize]).sum::<Vec3>();
                if face.dot(shading) <= 0.0 {
                    return Err(format!("triangle {i}: shading normal opposes the winding"));
                }
            }
        }
        Ok(())
    }

    fn relative_error(value: f64, exact: f64) -> f64 {
        (value - exact).abs() / exact
    }

    #[test]
    fn shapes_are_closed_and_outward() {
        let shapes = [
            ("uv_sphere", uv_sphere(1.3, 24, 12)),
            ("icosphere", icosphere(0.7, 3)),
            ("cuboid", cuboid(Vec3::new(0.5, 1.0, 2.0))),
            ("slab", slab(2.0, 3.0, 0.1)),
            ("torus", torus(1.0, 0.25, 32, 12)),
            ("torus_knot", torus_knot(2, 3, 1.0, 0.12, 128, 10)),
            ("torus_knot 3,5", torus_knot(3, 5, 1.0, 0.08, 256, 8)),
            ("bumpy_sphere", bumpy_sphere(1.0, 0.15, 2.5, 9, 3)),
        ];
        for (name, mesh) in &shapes {
            assert!(
                check_outward(mesh).is_ok(),
                "{name}: {:?}",
                check_outward(mesh)
            );
            let mut copy = mesh.clone();
            assert_eq!(copy.drop_degenerate(), 0, "{name} has degenerate triangles");
        }
    }

    #[test]
    fn closedness_check_detects_defects() {
        // Negative controls for the checks used above.
        assert!(
            check_closed(&quad(1.0, 1.0)).is_err(),
            "a quad has boundary edges"
        );
        let mut flipped = icosphere(1.0, 2);
        flipped.indices[7].swap(1, 2);
        assert!(check_closed(&flipped).is_err(), "one flipped triangle");
        let inside_out = TriangleMesh {
            indices: cuboid(Vec3::ONE)
                .indices
                .iter()
                .map(|&[a, b, c]| [a, c, b])
                .collect(),
            ..cuboid(Vec3::ONE)
        };
        assert!(
            check_closed(&inside_out).is_ok() && check_outward(&inside_out).is_err(),
            "inward winding"
        );
        let mut bad_normals = uv_sphere(1.0, 8, 4);
        bad_normals
            .normals
            .as_mut()
            .unwrap()
            .iter_mut()
            .for_each(|n| *n = -*n);
        assert!(
            check_outward(&bad_normals).is_err(),
            "inward shading normals"
        );
    }

    #[test]
    fn quad_faces_up() {
        let mesh = quad(2.0, 3.0);
        assert!((mesh.area() - 6.0).abs() < 1e-12);
        for i in 0..2 {
            let [p0, p1, p2] = mesh.triangle(i);
            assert_eq!((p1 - p0).cross(p2 - p0).normalize(), Vec3::Y);
        }
        assert_eq!(
            mesh.bounds(),
            (Vec3::new(-1.0, 0.0, -1.5), Vec3::new(1.0, 0.0, 1.5))
        );
    }

    #[test]
    fn areas_and_volumes_converge_to_analytic_values() {
        // Inscribed tessellations err by O(h²) in the angular spacing h: the error must fall by
        // about 4× per halving of h, and the fine one must be within h² (constant 1).
        let (r, big_r) = (0.3, 1.0);
        type Make = Box<dyn Fn(u32) -> TriangleMesh>;
        // (name, mesh at resolution n, exact area, exact volume, angular spacing · n)
        let cases: [(&str, Make, f64, f64, f64); 4] = [
            (
                "uv_sphere",
                Box::new(|n| uv_sphere(1.0, 2 * n, n)),
                4.0 * PI,
                4.0 * PI / 3.0,
                PI,
            ),
            (
                "icosphere",
                Box::new(|n| icosphere(1.0, n.trailing_zeros())),
                4.0 * PI,
                4.0 * PI / 3.0,
                1.1,
            ),
            (
                "torus",
                Box::new(move |n| torus(big_r as f32, r as f32, 2 * n, n)),
                4.0 * PI * PI * big_r * r,
                2.0 * PI * PI * big_r * r * r,
                2.0 * PI,
            ),
            (
                "cuboid",
                Box::new(|_| cuboid(Vec3::new(0.5, 1.0, 1.5))),
                22.0,
                6.0,
                0.0,
            ),
        ];
        for (name, make, area, volume, angle_scale) in &cases {
            let errors = [16u32, 32].map(|n| {
                let mesh = make(n);
                let h = angle_scale / n as f64;
                (
                    relative_error(mesh.area(), *area),
                    relative_error(mesh.signed_volume(), *volume),
                    h * h,
                )
            });
            let (area_err, volume_err, h2) = errors[1];
            assert!(
                area_err <= h2 + 1e-6 && volume_err <= h2 + 1e-6,
                "{name}: {errors:?}"
            );
            if *angle_scale > 0.0 {
                assert!(
                    errors[0].0 > 3.0 * area_err && errors[0].1 > 3.0 * volume_err,
                    "{name}: {errors:?}"
                );
            }
        }
    }

    #[test]
    fn torus_knot_tube_matches_pappus() {
        // A tube of radius r around a curve of length L (r below the curvature radius, no
        // self-overlap) has area 2πrL and volume πr²L; L by the trapezoid rule in f64.
        let (p, q, radius, tube_radius) = (2u32, 3u32, 1.0f64, 0.1f64);
        let (w, half) = (q as f64 / p as f64, 0.5 * radius);
        let speed = |u: f64| {
            let (r, dr) = (2.0 + (w * u).cos(), -w * (w * u).sin());
            half * DVec3::new(
                dr * u.cos() - r * u.sin(),
                dr * u.sin() + r * u.cos(),
                w * (w * u).cos(),
            )
            .length()
        };
        let steps = 200_000;
        let du = TAU * p as f64 / steps as f64;
        let length: f64 = (0..steps).map(|i| speed(i as f64 * du) * du).sum();
        let mesh = torus_knot(p, q, radius as f32, tube_radius as f32, 1024, 64);
        let area_err = relative_error(mesh.area(), TAU * tube_radius * length);
        let volume_err = relative_error(
            mesh.signed_volume(),
            PI * tube_radius * tube_radius * length,
        );
        // Around the tube h = 2π/64 dominates: h² ≈ 1e-2; along it 2π·2/1024.
        let h2 = (TAU / 64.0).powi(2);
        assert!(
            area_err < h2 && volume_err < h2,
            "area {area_err}, volume {volume_err}, h² {h2}"
        );
    }

    #[test]
    fn bumpy_sphere_is_deterministic_and_displaced() {
        let (radius, amplitude) = (1.0f32, 0.2f32);
        let a = bumpy_sphere(radius, amplitude, 3.0, 11, 3);
        assert_eq!(
            a,
            bumpy_sphere(radius, amplitude, 3.0, 11, 3),
            "same seed, same mesh"
        );
        assert_ne!(
            a.positions,
            bumpy_sphere(radius, amplitude, 3.0, 12, 3).positions,
            "seed matters"
        );
        let radii: Vec<f32> = a.positions.iter().map(|p| p.length()).collect();
        let (lo, hi) = radii
            .iter()
            .fold((f32::MAX, 0.0f32), |(lo, hi), &r| (lo.min(r), hi.max(r)));
        // Improved Perlin noise lies in [−1, 1]; the bumps must use a good part of that range.
        assert!(
            lo >= radius - amplitude && hi <= radius + amplitude,
            "radii in [{lo}, {hi}]"
        );
        assert!(
            hi - lo > amplitude,
            "radii in [{lo}, {hi}]: barely displaced"
        );
        // Continuous: the largest radius jump along an edge shrinks with the edge length
        // (each subdivision halves it), as it could not for a noise with jumps.
        let worst_step = |mesh: &TriangleMesh| {
            mesh.indices
                .iter()
                .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                .map(|(i, j)| {
                    (mesh.positions[i as usize].length() - mesh.positions[j as usize].length())
                        .abs()
                })
                .fold(0.0f32, f32::max)
        };
        let coarse = worst_step(&a);
        let fine = worst_step(&bumpy_sphere(radius, amplitude, 3.0, 11, 5));
        assert!(
            fine < 0.4 * coarse,
            "largest radius jump along an edge: {coarse} → {fine} after 2 subdivisions"
        );
    }
}
