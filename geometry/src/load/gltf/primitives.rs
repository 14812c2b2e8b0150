//! Accessors (glTF 2.0 §3.6.2) and the triangle primitives they make (§3.7.2): every range checked
//! against its buffer view and buffer before the elements are read.

use std::path::Path;

use ::gltf::json;
use glam::{DMat4, Vec3};
use json::accessor::{ComponentType, Type};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

use super::buffers::Buffers;
use super::nodes::{placed_element, placement};
use super::{GltfPrimitive, attribute, item};
use crate::InputError;
use crate::load::{normal, position};
use crate::mesh::TriangleMesh;

/// What an accessor is read as, and the component and accessor types that allows.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Use {
    Position,
    Normal,
    Indices,
}

impl Use {
    fn name(self) -> &'static str {
        match self {
            Use::Position => "POSITION",
            Use::Normal => "NORMAL",
            Use::Indices => "indices",
        }
    }

    /// glTF 2.0 §3.7.2.1: POSITION and NORMAL are FLOAT VEC3; indices are an unsigned SCALAR.
    fn allows(self, component: ComponentType) -> bool {
        match self {
            Use::Position | Use::Normal => component == ComponentType::F32,
            Use::Indices => matches!(
                component,
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32
            ),
        }
    }

    fn accessor_type(self) -> Type {
        match self {
            Use::Position | Use::Normal => Type::Vec3,
            Use::Indices => Type::Scalar,
        }
    }

    fn expected(self) -> &'static str {
        match self {
            Use::Position | Use::Normal => "FLOAT (5126) VEC3",
            Use::Indices => {
                "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT (5121, 5123, 5125) SCALAR"
            }
        }
    }
}

/// A primitive mode's name in the specification.
fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

/// A component type's name in the specification.
fn component_name(component: ComponentType) -> &'static str {
    match component {
        ComponentType::I8 => "BYTE",
        ComponentType::U8 => "UNSIGNED_BYTE",
        ComponentType::I16 => "SHORT",
        ComponentType::U16 => "UNSIGNED_SHORT",
        ComponentType::U32 => "UNSIGNED_INT",
        ComponentType::F32 => "FLOAT",
    }
}

/// Where an accessor's elements lie in its buffer, checked against the buffer's `byteLength`
/// (which the loaded buffer is checked against).
struct Layout {
    accessor: usize,
    buffer: usize,
    /// First byte of element 0 in the buffer.
    start: usize,
    stride: usize,
    /// Bytes of one element.
    element: usize,
    count: usize,
    component: ComponentType,
}

/// Reads placed primitives.
pub(super) struct Reader<'a, 'r> {
    root: &'a json::Root,
    path: &'a Path,
    buffers: Buffers<'a, 'r>,
}

impl<'a, 'r> Reader<'a, 'r> {
    /// A reader of `root`'s primitives from `buffers`.
    pub(super) fn new(root: &'a json::Root, path: &'a Path, buffers: Buffers<'a, 'r>) -> Self {
        Reader {
            root,
            path,
            buffers,
        }
    }

    /// The primitives of node `n`'s mesh, if it has one, placed by `world`.
    pub(super) fn place(
        &mut self,
        n: usize,
        world: &DMat4,
        out: &mut Vec<GltfPrimitive>,
    ) -> Result<(), InputError> {
        let Some(m) = self.root.nodes.get(n).and_then(|node| node.mesh) else {
            return Ok(());
        };
        let m = m.value();
        let mesh = item(&self.root.meshes, m, self.path, || {
            format!("nodes[{n}].mesh")
        })?;
        let transform = placement(world, n, self.path)?;
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let element = placed_element(n, m, p);
            let placed = self.primitive(m, p, primitive)?.transformed(&transform);
            for (k, &v) in placed.positions.iter().enumerate() {
                position(v.to_array()).map_err(|(value, reason)| {
                    InputError::new(self.path, format!("{element} (vertex {k})"), value, reason)
                })?;
            }
            out.push(GltfPrimitive {
                mesh: placed,
                material: primitive.material.map(|i| i.value()),
                element,
            });
        }
        Ok(())
    }

    /// Primitive `p` of mesh `m` in the mesh's own space.
    fn primitive(
        &mut self,
        m: usize,
        p: usize,
        primitive: &json::mesh::Primitive,
    ) -> Result<TriangleMesh, InputError> {
        let at = |field: &str| format!("meshes[{m}].primitives[{p}].{field}");
        match primitive.mode {
            Checked::Valid(Mode::Triangles) => {}
            Checked::Valid(mode) => {
                return Err(InputError::new(
                    self.path,
                    at("mode"),
                    format!("{} ({})", mode.as_gl_enum(), mode_name(mode)),
                    "only TRIANGLES (4) primitives are read",
                ));
            }
            Checked::Invalid => {
                return Err(InputError::new(
                    self.path,
                    at("mode"),
                    "(invalid)",
                    "not a primitive mode",
                ));
            }
        }
        let position = attribute(primitive, Semantic::Positions).ok_or_else(|| {
            InputError::new(
                self.path,
                at("attributes"),
                "(no POSITION)",
                "a primitive needs POSITION",
            )
        })?;
        let positions = self.layout(position, Use::Position)?;
        let normals = attribute(primitive, Semantic::Normals)
            .map(|a| self.layout(a, Use::Normal))
            .transpose()?;
        if let Some(normals) = &normals
            && normals.count != positions.count
        {
            return Err(InputError::new(
                self.path,
                format!("accessors[{}].count", normals.accessor),
                normals.count.to_string(),
                format!(
                    "NORMAL has a count other than POSITION's {}",
                    positions.count
                ),
            ));
        }
        let indices = primitive
            .indices
            .map(|a| self.layout(a.value(), Use::Indices))
            .transpose()?;
        let corners = indices.as_ref().unwrap_or(&positions);
        if corners.count % 3 != 0 {
            return Err(InputError::new(
                self.path,
                format!("accessors[{}].count", corners.accessor),
                corners.count.to_string(),
                "TRIANGLES need a multiple of 3 corners",
            ));
        }
        for layout in [Some(&positions), normals.as_ref(), indices.as_ref()]
            .into_iter()
            .flatten()
        {
            self.buffers.load(layout.buffer)?;
        }
        Ok(TriangleMesh {
            positions: self.vectors(&positions, true)?,
            normals: normals.map(|n| self.vectors(&n, false)).transpose()?,
            indices: match &indices {
                Some(layout) => self.indices(layout, positions.count)?,
                None => (0..positions.count as u32 / 3)
                    .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                    .collect(),
            },
        })
    }

    /// Where accessor `a`'s elements lie, checked for `usage` and against its view and buffer
    /// (glTF 2.0 §3.6.2).
    fn layout(&self, a: usize, usage: Use) -> Result<Layout, InputError> {
        let path = self.path;
        let at = |field: &str| format!("accessors[{a}].{field}");
        let err = |field: String, value: String, reason: String| {
            Err(InputError::new(path, field, value, reason))
        };
        let accessor = item(&self.root.accessors, a, path, || format!("accessors[{a}]"))?;
        if accessor.sparse.is_some() {
            return err(
                at("sparse"),
                "(present)".into(),
                format!("sparse accessors are not read ({})", usage.name()),
            );
        }
        let (Checked::Valid(component), Checked::Valid(kind)) =
            (accessor.component_type, accessor.type_)
        else {
            return err(
                at("componentType"),
                "(invalid)".into(),
                "not a valid component or accessor type".into(),
            );
        };
        let component = component.0;
        let wrong = format!("{} must be {}", usage.name(), usage.expected());
        if !usage.allows(component) {
            return err(
                at("componentType"),
                format!("{} ({})", component.as_gl_enum(), component_name(component)),
                wrong,
            );
        }
        if kind != usage.accessor_type() {
            return err(at("type"), format!("{kind:?}").to_uppercase(), wrong);
        }
        if accessor.normalized {
            return err(
                at("normalized"),
                "true".into(),
                format!("{} must not be normalized", usage.name()),
            );
        }
        let Some(v) = accessor.buffer_view.map(|v| v.value()) else {
            return err(
                at("bufferView"),
                "(absent)".into(),
                "an accessor without a buffer view (all zeros) is not read".into(),
            );
        };
        let view = item(&self.root.buffer_views, v, path, || at("bufferView"))?;
        let b = view.buffer.value();
        let buffer = item(&self.root.buffers, b, path, || {
            format!("bufferViews[{v}].buffer")
        })?;
        let view_start = view.byte_offset.map_or(0, |o| o.0);
        let view_length = view.byte_length.0;
        let view_end = view_start.checked_add(view_length);
        if view_end.is_none_or(|end| end > buffer.byte_length.0) {
            return err(
                format!("bufferViews[{v}].byteLength"),
                view_length.to_string(),
                format!(
                    "from byteOffset {view_start}, the view passes the end of buffers[{b}] \
                     ({} bytes)",
                    buffer.byte_length.0
                ),
            );
        }
        let element = (component.size() * kind.multiplicity()) as u64;
        let stride = view.byte_stride.map_or(element, |s| s.0 as u64);
        if stride < element {
            return err(
                format!("bufferViews[{v}].byteStride"),
                stride.to_string(),
                format!("smaller than one element of accessors[{a}] ({element} bytes)"),
            );
        }
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let count = accessor.count.0;
        // Bytes the elements span: offset + stride·(count − 1) + element.
        let span = match count {
            0 => Some(0),
            _ => stride
                .checked_mul(count - 1)
                .and_then(|s| s.checked_add(element))
                .and_then(|s| s.checked_add(offset)),
        };
        if count > 0 && offset.saturating_add(element) > view_length {
            return err(
                at("byteOffset"),
                offset.to_string(),
                format!("past the end of bufferViews[{v}] ({view_length} bytes)"),
            );
        }
        if span.is_none_or(|span| span > view_length) {
            return err(
                at("count"),
                count.to_string(),
                format!(
                    "{count} elements of {element} bytes, {stride} apart from byte {offset}, pass \
                     the end of bufferViews[{v}] ({view_length} bytes)"
                ),
            );
        }
        // Within the buffer's byteLength, itself within the bytes a loaded buffer has.
        Ok(Layout {
            accessor: a,
            buffer: b,
            start: (view_start + offset) as usize,
            stride: stride as usize,
            element: element as usize,
            count: count as usize,
            component,
        })
    }

    /// The bytes of each element of `layout`, in order.
    fn elements(&self, layout: &Layout) -> Result<impl Iterator<Item = &[u8]>, InputError> {
        let span = match layout.count {
            0 => 0,
            n => layout.stride * (n - 1) + layout.element,
        };
        let bytes = self.buffers.bytes(layout.buffer);
        let region = bytes
            .get(layout.start..layout.start + span)
            .ok_or_else(|| {
                InputError::new(
                    self.path,
                    format!("accessors[{}]", layout.accessor),
                    format!("bytes {}..{}", layout.start, layout.start + span),
                    format!("past the end of buffers[{}]", layout.buffer),
                )
            })?;
        let element = layout.element;
        // Every chunk but the last has `stride` ≥ `element` bytes, the last exactly `element`.
        Ok(region.chunks(layout.stride).map(move |c| &c[..element]))
    }

    /// FLOAT VEC3 elements, finite (positions are range-checked once placed).
    fn vectors(&self, layout: &Layout, is_position: bool) -> Result<Vec<Vec3>, InputError> {
        let mut out = Vec::with_capacity(layout.count);
        for (k, e) in self.elements(layout)?.enumerate() {
            let xyz: [f32; 3] = std::array::from_fn(|i| {
                f32::from_le_bytes([e[4 * i], e[4 * i + 1], e[4 * i + 2], e[4 * i + 3]])
            });
            let v = Vec3::from(xyz);
            let fault = if is_position {
                (!v.is_finite()).then(|| {
                    (
                        format!("{xyz:?}"),
                        "a vertex position must be finite".to_string(),
                    )
                })
            } else {
                normal(xyz).err()
            };
            if let Some((value, reason)) = fault {
                return Err(InputError::new(
                    self.path,
                    format!("accessors[{}] (vertex {k})", layout.accessor),
                    value,
                    reason,
                ));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// Triangles from unsigned indices, each below `vertices`.
    fn indices(&self, layout: &Layout, vertices: usize) -> Result<Vec<[u32; 3]>, InputError> {
        let mut triangles = Vec::with_capacity(layout.count / 3);
        let mut corner = [0u32; 3];
        for (k, e) in self.elements(layout)?.enumerate() {
            let i = match layout.component {
                ComponentType::U8 => e[0] as u32,
                ComponentType::U16 => u16::from_le_bytes([e[0], e[1]]) as u32,
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            };
            if i as usize >= vertices {
                return Err(InputError::new(
                    self.path,
                    format!("accessors[{}] (index {k})", layout.accessor),
                    i.to_string(),
                    format!("at or past the vertex count {vertices}"),
                ));
            }
            corner[k % 3] = i;
            if k % 3 == 2 {
                triangles.push(corner);
            }
        }
        Ok(triangles)
    }
}
