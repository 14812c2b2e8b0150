//! The node hierarchy (glTF 2.0 §3.5): parents checked (one at most, no cycle, a bounded depth),
//! the default scene's roots, each node's transform from the root, and the totals that the placed
//! primitives would reach.

use std::path::Path;

use ::gltf::json;
use glam::{Affine3A, DMat3, DMat4, DQuat, DVec3, DVec4};
use json::mesh::Semantic;

use super::{attribute, item};
use crate::InputError;
use crate::limits::{
    MAX_GLTF_NODE_DEPTH, MAX_GLTF_PRIMITIVES, MAX_MESH_TRIANGLES, MAX_MESH_VERTICES,
};

/// Each node's parent and its position among the parent's children, once checked: a node has at
/// most one parent, there is no cycle, and no node lies deeper than [`MAX_GLTF_NODE_DEPTH`]
/// (glTF 2.0 §3.5.2: the hierarchy is a set of disjoint strict trees).
pub(super) fn hierarchy(
    root: &json::Root,
    path: &Path,
) -> Result<Vec<Option<(usize, usize)>>, InputError> {
    let mut parents = vec![None; root.nodes.len()];
    for (j, node) in root.nodes.iter().enumerate() {
        for (k, child) in node.children.iter().flatten().enumerate() {
            let c = child.value();
            let field = || format!("nodes[{j}].children[{k}]");
            let slot = item(&parents, c, path, field)?;
            if let Some((p, pk)) = *slot {
                return Err(InputError::new(
                    path,
                    field(),
                    c.to_string(),
                    format!(
                        "node {c} is already a child of nodes[{p}] (children[{pk}]): a node has at \
                         most one parent (glTF 2.0 §3.5.2)"
                    ),
                ));
            }
            parents[c] = Some((j, k));
        }
    }
    check_depths(&parents, path)?;
    Ok(parents)
}

/// Marks a node on the chain being climbed in [`check_depths`].
const ON_CHAIN: u32 = u32::MAX;

/// Every node's depth (1 for a root) is at most [`MAX_GLTF_NODE_DEPTH`], and climbing the parents
/// from any node ends at a root (no cycle).
fn check_depths(parents: &[Option<(usize, usize)>], path: &Path) -> Result<(), InputError> {
    // 0: not known yet; ON_CHAIN: on the chain climbed now.
    let mut depth = vec![0u32; parents.len()];
    let mut chain = Vec::new();
    for start in 0..parents.len() {
        let mut node = start;
        let mut base = loop {
            match depth[node] {
                0 => {}
                ON_CHAIN => {
                    let below = chain.last().copied().unwrap_or(node);
                    let k = parents[below].map_or(0, |(_, k)| k);
                    return Err(InputError::new(
                        path,
                        format!("nodes[{node}].children[{k}]"),
                        below.to_string(),
                        format!(
                            "closes a cycle: node {below} is its own ancestor (glTF 2.0 §3.5.2)"
                        ),
                    ));
                }
                known => break known,
            }
            depth[node] = ON_CHAIN;
            chain.push(node);
            match parents[node] {
                Some((parent, _)) => node = parent,
                None => break 0,
            }
        };
        while let Some(n) = chain.pop() {
            base += 1;
            depth[n] = base;
            if base > MAX_GLTF_NODE_DEPTH {
                return Err(InputError::new(
                    path,
                    format!("nodes[{n}]"),
                    format!("depth {base}"),
                    format!(
                        "nested deeper than the limit of {MAX_GLTF_NODE_DEPTH} nodes from its root"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The root nodes of the default scene (`scene`, else scene 0); without scenes, every node that is
/// no node's child.
pub(super) fn scene_roots(
    root: &json::Root,
    parents: &[Option<(usize, usize)>],
    path: &Path,
) -> Result<Vec<usize>, InputError> {
    let chosen = root
        .scene
        .map(|s| s.value())
        .or((!root.scenes.is_empty()).then_some(0));
    let Some(s) = chosen else {
        return Ok((0..parents.len())
            .filter(|&n| parents[n].is_none())
            .collect());
    };
    let scene = item(&root.scenes, s, path, || "scene".into())?;
    let mut listed = vec![false; parents.len()];
    for (k, node) in scene.nodes.iter().enumerate() {
        let n = node.value();
        let field = || format!("scenes[{s}].nodes[{k}]");
        let reason = match item(parents, n, path, field)? {
            Some((p, _)) => format!("a child of nodes[{p}]: a scene lists root nodes only"),
            None if listed[n] => "listed twice".to_string(),
            None => {
                listed[n] = true;
                continue;
            }
        };
        return Err(InputError::new(
            path,
            field(),
            n.to_string(),
            format!("{reason} (glTF 2.0 §3.5.2)"),
        ));
    }
    Ok(scene.nodes.iter().map(|n| n.value()).collect())
}

/// Every node under `roots` with its transform from the scene's root, depth first in file order.
/// The hierarchy is a checked forest, so each node comes once.
pub(super) fn placements(
    root: &json::Root,
    roots: &[usize],
    path: &Path,
) -> Result<Vec<(usize, DMat4)>, InputError> {
    let mut placed = Vec::new();
    let mut stack: Vec<(usize, DMat4)> =
        roots.iter().rev().map(|&n| (n, DMat4::IDENTITY)).collect();
    while let Some((n, parent)) = stack.pop() {
        let node = item(&root.nodes, n, path, || format!("nodes[{n}]"))?;
        let world = parent * local_transform(node, n, path)?;
        placed.push((n, world));
        for child in node.children.iter().flatten().rev() {
            stack.push((child.value(), world));
        }
    }
    Ok(placed)
}

/// A node's `matrix`, or T·R·S (glTF 2.0 §3.5.3), checked.
fn local_transform(node: &json::Node, n: usize, path: &Path) -> Result<DMat4, InputError> {
    let at = |field: &str| format!("nodes[{n}].{field}");
    let err = |field: &str, value: String, reason: &str| {
        Err(InputError::new(path, at(field), value, reason))
    };
    let has_trs = node.translation.is_some() || node.rotation.is_some() || node.scale.is_some();
    if let Some(m) = node.matrix {
        let matrix = DMat4::from_cols_array(&m.map(f64::from));
        let shown = format!("{m:?}");
        if has_trs {
            return err(
                "matrix",
                shown,
                "a node has a matrix or translation/rotation/scale, not both (glTF 2.0 §3.5.3)",
            );
        }
        if !matrix.is_finite() {
            return err("matrix", shown, "not finite");
        }
        if matrix.row(3) != DVec4::W {
            return err(
                "matrix",
                shown,
                "not affine: the last row (elements 3, 7, 11, 15, column-major) must be 0, 0, 0, 1",
            );
        }
        if DMat3::from_mat4(matrix).determinant() == 0.0 {
            return err("matrix", shown, "singular (determinant 0)");
        }
        return Ok(matrix);
    }
    let translation = DVec3::from(node.translation.unwrap_or([0.0; 3]).map(f64::from));
    if !translation.is_finite() {
        return err("translation", format!("{translation}"), "not finite");
    }
    let [x, y, z, w] = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |r| r.0);
    let rotation = DQuat::from_xyzw(x.into(), y.into(), z.into(), w.into());
    if !(rotation.is_finite() && (rotation.length() - 1.0).abs() <= 1e-3) {
        return err(
            "rotation",
            format!("{:?}", [x, y, z, w]),
            "a rotation is a unit quaternion (x, y, z, w)",
        );
    }
    let scale = DVec3::from(node.scale.unwrap_or([1.0; 3]).map(f64::from));
    if !(scale.is_finite() && scale.abs().min_element() > 0.0) {
        return err(
            "scale",
            format!("{scale}"),
            "a scale is finite and non-zero (a zero scale is singular)",
        );
    }
    Ok(DMat4::from_scale_rotation_translation(
        scale,
        rotation.normalize(),
        translation,
    ))
}

/// A node's transform from the scene's root in `f32`, usable for positions and normals.
pub(super) fn placement(world: &DMat4, n: usize, path: &Path) -> Result<Affine3A, InputError> {
    let affine = Affine3A::from_mat4(world.as_mat4());
    let det = affine.matrix3.determinant();
    if affine.is_finite() && det.is_normal() && affine.matrix3.inverse().is_finite() {
        Ok(affine)
    } else {
        Err(InputError::new(
            path,
            format!("nodes[{n}]"),
            format!("determinant {det:e}"),
            "the transform from the scene's root to this node is not finite or singular in f32",
        ))
    }
}

/// The element that places primitive `p` of mesh `m` by node `n`.
pub(super) fn placed_element(n: usize, m: usize, p: usize) -> String {
    format!("nodes[{n}].mesh → meshes[{m}].primitives[{p}]")
}

/// The placed primitives, and their vertices and triangles together, instances included, are
/// within the limits: checked on the accessors' counts before anything is read.
pub(super) fn check_totals(
    root: &json::Root,
    placements: &[(usize, DMat4)],
    path: &Path,
) -> Result<(), InputError> {
    let (mut primitives, mut vertices, mut triangles) = (0u64, 0u64, 0u64);
    for &(n, _) in placements {
        let Some(m) = root.nodes.get(n).and_then(|node| node.mesh) else {
            continue;
        };
        let m = m.value();
        let mesh = item(&root.meshes, m, path, || format!("nodes[{n}].mesh"))?;
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let count = |a: usize| root.accessors.get(a).map_or(0, |a| a.count.0);
            let vertex_count = attribute(primitive, Semantic::Positions).map_or(0, count);
            let corners = primitive.indices.map_or(vertex_count, |a| count(a.value()));
            primitives += 1;
            vertices = vertices.saturating_add(vertex_count);
            triangles = triangles.saturating_add(corners / 3);
            let over = [
                (primitives, MAX_GLTF_PRIMITIVES, "primitives"),
                (vertices, MAX_MESH_VERTICES, "vertices"),
                (triangles, MAX_MESH_TRIANGLES, "triangles"),
            ]
            .into_iter()
            .find(|(total, limit, _)| total > limit);
            if let Some((total, limit, what)) = over {
                return Err(InputError::new(
                    path,
                    placed_element(n, m, p),
                    format!("{total} {what} so far"),
                    format!(
                        "the placed primitives (instances included) exceed the limit of {limit} \
                         {what}"
                    ),
                ));
            }
        }
    }
    Ok(())
}
