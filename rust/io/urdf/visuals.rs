//! The `<visual>`s of the links put on the model's bodies, their mesh files looked for as
//! Pinocchio does ([`crate::model::visual::resolve_mesh`]): one warning names every mesh not found.
use std::path::{Path, PathBuf};

use super::parse::RobotData;
use crate::model::visual::{resolve_mesh, Shape, Visual};
use crate::model::Model;

/// Where meshes are looked for besides `package_dirs`: `ROS_PACKAGE_PATH` (as Pinocchio).
fn ros_package_path() -> Vec<PathBuf> {
    std::env::var_os("ROS_PACKAGE_PATH")
        .map(|p| std::env::split_paths(&p).collect())
        .unwrap_or_default()
}

/// Adds each link's visuals to `model` (colour: the visual's own, else its named robot-level
/// material) and names the model; returns the warning about meshes not found, if any.
pub(super) fn attach(
    robot: &RobotData,
    model: &mut Model,
    file: &str,
    base_dir: Option<&Path>,
    package_dirs: &[PathBuf],
) -> Option<String> {
    let dirs: Vec<PathBuf> = package_dirs
        .iter()
        .cloned()
        .chain(ros_package_path())
        .collect();
    let mut missing: Vec<String> = Vec::new();
    model.name = robot.name.clone();
    for link in &robot.links {
        let Some(body) = model.body_index(&link.name) else {
            continue;
        };
        for v in &link.visuals {
            let mut shape = v.shape.clone();
            if let Shape::Mesh { uri, path, .. } = &mut shape {
                *path =
                    resolve_mesh(uri, base_dir, &dirs).map(|p| p.to_string_lossy().into_owned());
                if path.is_none() && !missing.contains(uri) {
                    missing.push(uri.clone());
                }
            }
            let rgba = v.rgba.or_else(|| {
                v.material
                    .as_ref()
                    .and_then(|m| robot.materials.get(m).copied())
            });
            model.visuals.push(Visual {
                body,
                origin: v.origin,
                shape,
                rgba,
            });
        }
    }
    if missing.is_empty() {
        return None;
    }
    const SHOWN: usize = 8;
    let mut names: Vec<String> = missing
        .iter()
        .take(SHOWN)
        .map(|u| format!("'{u}'"))
        .collect();
    if missing.len() > SHOWN {
        names.push(format!("and {} more", missing.len() - SHOWN));
    }
    let searched = match base_dir {
        Some(d) => format!("the directory {} and its ancestors", d.display()),
        None => "no directory (the URDF was given as text)".to_string(),
    };
    Some(format!(
        "{file}: {} mesh file(s) not found, their bodies are drawn with simple shapes: {} (looked in package_dirs {:?}, ROS_PACKAGE_PATH and {searched}; pass package_dirs=[...] to Model.from_urdf)",
        missing.len(),
        names.join(", "),
        package_dirs
    ))
}
