//! Procedural `shape`s of `[[objects]]` (`geometry::shapes`), checked against the limits
//! before they are tessellated.

use geometry::{TriangleMesh, shapes};
use glam::Vec3;

use super::Ctx;
use crate::InputError;
use crate::limits::MAX_SHAPE_TRIANGLES;
use crate::scene::format::ShapeDesc;

impl Ctx<'_> {
    /// The mesh of `shape`, centred at the origin; errors at `field`.
    pub(super) fn shape(&self, shape: &ShapeDesc, field: &str) -> Result<TriangleMesh, InputError> {
        let pos = |member: &str, x: f32| self.positive(&format!("{field}.{member}"), x);
        let at_least = |member: &str, x: u32, min: u32| {
            if x >= min {
                Ok(x)
            } else {
                Err(self.err(
                    format!("{field}.{member}"),
                    x.to_string(),
                    format!("must be ≥ {min}"),
                ))
            }
        };
        let budget = |triangles: u64| {
            if triangles <= MAX_SHAPE_TRIANGLES {
                Ok(())
            } else {
                Err(self.err(
                    field,
                    format!("{triangles} triangles"),
                    format!("more than {MAX_SHAPE_TRIANGLES} triangles"),
                ))
            }
        };
        Ok(match *shape {
            ShapeDesc::Sphere {
                radius,
                segments,
                rings,
            } => {
                let (s, r) = (
                    at_least("segments", segments.unwrap_or(64), 3)?,
                    at_least("rings", rings.unwrap_or(32), 2)?,
                );
                budget(2 * s as u64 * r as u64)?;
                shapes::uv_sphere(pos("radius", radius)?, s, r)
            }
            ShapeDesc::Box { size } => {
                let size = Vec3::from_array(size);
                if !(size.is_finite() && size.cmpgt(Vec3::ZERO).all()) {
                    return Err(self.err(
                        format!("{field}.size"),
                        format!("{size}"),
                        "each extent must be finite and > 0",
                    ));
                }
                shapes::cuboid(0.5 * size)
            }
            ShapeDesc::Slab { size, thickness } => shapes::slab(
                pos("size[0]", size[0])?,
                pos("size[1]", size[1])?,
                pos("thickness", thickness)?,
            ),
            ShapeDesc::Quad { size } => {
                shapes::quad(pos("size[0]", size[0])?, pos("size[1]", size[1])?)
            }
            ShapeDesc::Torus {
                major_radius,
                minor_radius,
                segments,
                sides,
            } => {
                let (s, k) = (
                    at_least("segments", segments.unwrap_or(96), 3)?,
                    at_least("sides", sides.unwrap_or(32), 3)?,
                );
                budget(2 * s as u64 * k as u64)?;
                shapes::torus(
                    pos("major_radius", major_radius)?,
                    pos("minor_radius", minor_radius)?,
                    s,
                    k,
                )
            }
            ShapeDesc::TorusKnot {
                p,
                q,
                radius,
                tube_radius,
                segments,
                sides,
            } => {
                let (s, k) = (
                    at_least("segments", segments.unwrap_or(384), 3)?,
                    at_least("sides", sides.unwrap_or(24), 3)?,
                );
                budget(2 * s as u64 * k as u64)?;
                let (p, q) = (at_least("p", p, 1)?, at_least("q", q, 1)?);
                shapes::torus_knot(
                    p,
                    q,
                    pos("radius", radius)?,
                    pos("tube_radius", tube_radius)?,
                    s,
                    k,
                )
            }
            ShapeDesc::BumpySphere {
                radius,
                amplitude,
                frequency,
                seed,
                subdivisions,
            } => {
                let subdivisions = subdivisions.unwrap_or(5);
                budget(20u64.saturating_mul(4u64.saturating_pow(subdivisions)))?;
                if !(amplitude.is_finite() && amplitude >= 0.0 && amplitude < radius) {
                    return Err(self.err(
                        format!("{field}.amplitude"),
                        amplitude.to_string(),
                        "must be finite, ≥ 0 and < radius",
                    ));
                }
                shapes::bumpy_sphere(
                    pos("radius", radius)?,
                    amplitude,
                    pos("frequency", frequency)?,
                    seed.unwrap_or(0),
                    subdivisions,
                )
            }
        })
    }
}
