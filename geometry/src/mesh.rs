//! Indexed triangle meshes: the common currency of procedural shapes, loaded files and the BVH.

use glam::{Affine3A, Vec3};

/// An indexed triangle mesh. Winding defines the geometric normal `(v1 − v0) × (v2 − v0)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    /// Per-vertex shading normals (unit length), one per position, or `None` for flat shading.
    pub normals: Option<Vec<Vec3>>,
}

impl TriangleMesh {
    /// The mesh under the affine map `xf`; normals go through the inverse transpose and are
    /// renormalised. A mirroring transform (negative determinant) flips the winding so that
    /// geometric normals keep pointing the same way relative to the surface.
    pub fn transformed(&self, xf: &Affine3A) -> TriangleMesh {
        let positions = self
            .positions
            .iter()
            .map(|&p| xf.transform_point3(p))
            .collect();
        let normal_matrix = xf.matrix3.inverse().transpose();
        let normals = self.normals.as_ref().map(|normals| {
            normals
                .iter()
                .map(|&n| (normal_matrix * n).normalize_or_zero())
                .collect()
        });
        let indices = if xf.matrix3.determinant() < 0.0 {
            self.indices.iter().map(|&[a, b, c]| [a, c, b]).collect()
        } else {
            self.indices.clone()
        };
        TriangleMesh {
            positions,
            indices,
            normals,
        }
    }

    /// The meshes as one: their vertices in order, each one's triangles re-indexed; shading
    /// normals only if every mesh has them. The meshes have at most `u32::MAX` vertices together
    /// (the loaders' limits keep them far below).
    pub fn merged<'a, I>(meshes: I) -> TriangleMesh
    where
        I: IntoIterator<Item = &'a TriangleMesh>,
        I::IntoIter: Clone,
    {
        let meshes = meshes.into_iter();
        let with_normals = meshes.clone().all(|m| m.normals.is_some());
        let mut merged = TriangleMesh {
            normals: with_normals.then(Vec::new),
            ..TriangleMesh::default()
        };
        for mesh in meshes {
            let offset = u32::try_from(merged.positions.len()).expect("at most u32::MAX vertices");
            merged.positions.extend_from_slice(&mesh.positions);
            merged
                .indices
                .extend(mesh.indices.iter().map(|t| t.map(|i| i + offset)));
            if let (Some(all), Some(normals)) = (&mut merged.normals, &mesh.normals) {
                all.extend_from_slice(normals);
            }
        }
        merged
    }

    /// Removes triangles with zero area or a non-finite vertex; returns how many were removed.
    pub fn drop_degenerate(&mut self) -> usize {
        let before = self.indices.len();
        let positions = &self.positions;
        self.indices.retain(|&[a, b, c]| {
            let [p0, p1, p2] = [a, b, c].map(|i| positions[i as usize]);
            let n = (p1 - p0).cross(p2 - p0);
            p0.is_finite() && p1.is_finite() && p2.is_finite() && n.is_finite() && n != Vec3::ZERO
        });
        before - self.indices.len()
    }

    /// Axis-aligned bounds `(min, max)` of the referenced vertices; `(+∞, −∞)` when empty.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.indices
            .iter()
            .flatten()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| {
                let p = self.positions[i as usize];
                (lo.min(p), hi.max(p))
            })
    }

    /// The bounds of all of `meshes` together; `(+∞, −∞)` when they are empty.
    pub fn bounds_of(meshes: &[TriangleMesh]) -> (Vec3, Vec3) {
        meshes
            .iter()
            .map(TriangleMesh::bounds)
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| {
                (lo.min(a), hi.max(b))
            })
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three vertex positions of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.indices[i].map(|v| self.positions[v as usize])
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.indices.len())
            .map(|i| {
                let [p0, p1, p2] = self.triangle(i).map(|p| p.as_dvec3());
                0.5 * (p1 - p0).cross(p2 - p0).length()
            })
            .sum()
    }

    /// Signed enclosed volume (divergence theorem); positive for a closed, outward-wound mesh.
    pub fn signed_volume(&self) -> f64 {
        (0..self.indices.len())
            .map(|i| {
                let [p0, p1, p2] = self.triangle(i).map(|p| p.as_dvec3());
                p0.dot(p1.cross(p2)) / 6.0
            })
            .sum()
    }

    /// Replaces the shading normals by area-weighted averages of the adjacent face normals.
    pub fn with_smooth_normals(mut self) -> TriangleMesh {
        let mut sums = vec![Vec3::ZERO; self.positions.len()];
        for &[a, b, c] in &self.indices {
            let [p0, p1, p2] = [a, b, c].map(|i| self.positions[i as usize]);
            // |(p1 − p0) × (p2 − p0)| = 2·area, so the unnormalised cross product is area-weighted.
            let n = (p1 - p0).cross(p2 - p0);
            for i in [a, b, c] {
                sums[i as usize] += n;
            }
        }
        self.normals = Some(sums.into_iter().map(Vec3::normalize_or_zero).collect());
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, vec3};

    fn two_triangles() -> TriangleMesh {
        TriangleMesh {
            positions: vec![
                vec3(0.0, 0.0, 0.0),
                vec3(1.0, 0.0, 0.0),
                vec3(0.0, 1.0, 0.0),
                vec3(2.0, 0.0, 0.0),
            ],
            indices: vec![[0, 1, 2], [0, 1, 3]],
            normals: Some(vec![Vec3::Z; 4]),
        }
    }

    #[test]
    fn drop_degenerate_counts_collinear_and_nan_triangles() {
        let mut mesh = two_triangles();
        mesh.positions.push(vec3(f32::NAN, 0.0, 0.0));
        mesh.indices.push([0, 2, 4]);
        mesh.indices.push([1, 1, 2]);
        assert_eq!(
            mesh.drop_degenerate(),
            3,
            "collinear, NaN and repeated-vertex triangles"
        );
        assert_eq!(mesh.indices, vec![[0, 1, 2]]);
        assert_eq!(mesh.drop_degenerate(), 0);
    }

    #[test]
    fn transform_maps_normals_by_inverse_transpose() {
        let mut mesh = two_triangles();
        mesh.drop_degenerate();
        // A shear: the normal of the z = 0 plane maps by the inverse transpose, not the matrix.
        let xf = Affine3A::from_cols_array(&[
            1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0,
        ]) * Affine3A::from_quat(Quat::from_rotation_x(0.3));
        let moved = mesh.transformed(&xf);
        let [p0, p1, p2] = moved.triangle(0);
        let face = (p1 - p0).cross(p2 - p0).normalize();
        let n = moved.normals.as_ref().unwrap()[0];
        assert!(
            (face - n).length() < 1e-5,
            "face {face} vs transformed normal {n}"
        );
        let naive = (xf.matrix3 * Vec3::Z).normalize();
        assert!(
            (face - naive).length() > 1e-2,
            "negative control: the plain matrix is wrong here"
        );
    }

    #[test]
    fn merging_offsets_indices_and_keeps_normals_only_if_all_have_them() {
        let mesh = two_triangles();
        let merged = TriangleMesh::merged(&[mesh.clone(), mesh.clone()]);
        assert_eq!(merged.positions.len(), 8);
        assert_eq!(merged.indices[2..], [[4, 5, 6], [4, 5, 7]]);
        assert_eq!(merged.normals.as_ref().map(Vec::len), Some(8));
        let flat = TriangleMesh {
            normals: None,
            ..mesh.clone()
        };
        assert_eq!(TriangleMesh::merged([&mesh, &flat]).normals, None);
        let none: [&TriangleMesh; 0] = [];
        assert_eq!(TriangleMesh::merged(none).triangle_count(), 0);
    }

    #[test]
    fn mirroring_keeps_outward_winding() {
        let mesh = crate::shapes::cuboid(vec3(1.0, 2.0, 3.0));
        let mirrored = mesh.transformed(&Affine3A::from_scale(vec3(-1.0, 1.0, 1.0)));
        assert!((mirrored.signed_volume() - 48.0).abs() < 1e-9);
        assert_eq!(
            mirrored.bounds(),
            (vec3(-1.0, -2.0, -3.0), vec3(1.0, 2.0, 3.0))
        );
    }
}
