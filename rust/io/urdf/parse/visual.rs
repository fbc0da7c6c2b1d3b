//! `<visual>` and `<material>`: the geometry a viewer draws. A visual that cannot be read
//! is dropped with a warning naming the link and line (it never refuses the dynamics model),
//! as a mesh file that cannot be found is (`super::super::visuals`).
use roxmltree::Node;

use super::{child, Ctx};
use crate::model::visual::Shape;
use crate::support::spatial::{Placement, Vec3};

/// A `<visual>` as read: its mesh `path` is resolved once the tree is built.
#[derive(Debug, Clone)]
pub(in crate::io::urdf) struct VisualData {
    pub origin: Placement,
    pub shape: Shape,
    /// Its own `<material><color rgba>`, else the name of a robot-level `<material>`.
    pub rgba: Option<[f64; 4]>,
    pub material: Option<String>,
}

/// `<material name><color rgba>`: the name and colour (either may be absent).
pub(super) fn material(
    ctx: &Ctx,
    element: &str,
    node: Node,
) -> Result<(Option<String>, Option<[f64; 4]>), String> {
    let name = node.attribute("name").map(str::to_string);
    let Some(c) = child(node, "color") else {
        return Ok((name, None));
    };
    let Some(s) = c.attribute("rgba") else {
        return Ok((name, None));
    };
    let v: Vec<f64> = s
        .split_whitespace()
        .filter_map(|p| p.parse::<f64>().ok())
        .collect();
    if v.len() != 4 || s.split_whitespace().count() != 4 {
        return Err(ctx
            .at(
                element,
                c,
                format!("<color rgba>: expected four numbers, got '{s}'"),
            )
            .to_string());
    }
    // Files write 255-based colours or values a little out of range: clamp, as viewers do.
    Ok((name, Some([0, 1, 2, 3].map(|k| v[k].clamp(0.0, 1.0)))))
}

/// One `<visual>` of `element` (`link 'x'`); `Err` is the warning for a dropped visual.
pub(super) fn visual(ctx: &Ctx, element: &str, node: Node) -> Result<VisualData, String> {
    let origin = ctx
        .origin(element, child(node, "origin"))
        .map_err(|e| e.to_string())?;
    let geometry = child(node, "geometry").ok_or_else(|| {
        ctx.at(element, node, "<visual> has no <geometry>")
            .to_string()
    })?;
    let shape_node = geometry
        .children()
        .find(|c| c.is_element())
        .ok_or_else(|| ctx.at(element, geometry, "<geometry> is empty").to_string())?;
    let shape = shape(ctx, element, shape_node).map_err(|e| e.to_string())?;
    let (material, rgba) = match child(node, "material") {
        Some(m) => material(ctx, element, m)?,
        None => (None, None),
    };
    Ok(VisualData {
        origin,
        shape,
        rgba,
        material,
    })
}

fn shape(ctx: &Ctx, element: &str, node: Node) -> crate::support::error::Result<Shape> {
    let tag = node.tag_name().name();
    let positive = |attr: &str| -> crate::support::error::Result<f64> {
        let x = ctx.required(element, node, attr)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(ctx.at(
                element,
                node,
                format!("<{tag} {attr}>: expected a number > 0, got {x}"),
            ))
        }
    };
    Ok(match tag {
        "box" => {
            let size = ctx
                .triple(element, node, "size")?
                .ok_or_else(|| ctx.at(element, node, "<box> is missing the 'size' attribute"))?;
            if size.iter().any(|x| *x <= 0.0) {
                return Err(ctx.at(element, node, "<box size>: expected three numbers > 0"));
            }
            Shape::Box { size }
        }
        "cylinder" => Shape::Cylinder {
            radius: positive("radius")?,
            length: positive("length")?,
        },
        "capsule" => Shape::Capsule {
            radius: positive("radius")?,
            length: positive("length")?,
        },
        "sphere" => Shape::Sphere {
            radius: positive("radius")?,
        },
        "mesh" => {
            let uri = node.attribute("filename").ok_or_else(|| {
                ctx.at(element, node, "<mesh> is missing the 'filename' attribute")
            })?;
            let scale = ctx
                .triple(element, node, "scale")?
                .unwrap_or_else(|| Vec3::new(1.0, 1.0, 1.0));
            if scale.iter().any(|x| *x == 0.0) {
                return Err(ctx.at(element, node, "<mesh scale>: expected non-zero numbers"));
            }
            Shape::Mesh {
                uri: uri.to_string(),
                path: None,
                scale,
            }
        }
        other => {
            return Err(ctx.at(
                element,
                node,
                format!(
                    "unknown geometry <{other}> (expected box, cylinder, sphere, capsule or mesh)"
                ),
            ))
        }
    })
}
