//! Visual geometry: what a viewer draws for a body (URDF `<visual>`, MJCF geoms). No part of
//! the dynamics; kept on the [`Model`](crate::model::Model) so a loaded robot keeps its look
//! through copies and pickling. Mesh files are named here, never read: reading and
//! simplifying them is the viewer's business (Python, an optional extra).
use std::path::{Path, PathBuf};

use crate::support::args::Arg;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Placement, Vec3};

/// A shape in its own frame (the [`Visual::origin`] places that frame in the body frame).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Shape {
    /// Full side lengths, centred on the origin.
    Box {
        size: Vec3,
    },
    /// Along z, centred on the origin.
    Cylinder {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    /// Along z, centred; `length` between the centres of the two hemispherical caps.
    Capsule {
        radius: f64,
        length: f64,
    },
    /// Semi-axes along x, y, z.
    Ellipsoid {
        radii: Vec3,
    },
    /// A mesh file: `uri` as the model file wrote it, `path` where it was found (`None`: not
    /// found when the model was loaded), its vertices multiplied by `scale` axis by axis.
    Mesh {
        uri: String,
        path: Option<String>,
        scale: Vec3,
    },
}

impl Shape {
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "box",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Sphere { .. } => "sphere",
            Shape::Capsule { .. } => "capsule",
            Shape::Ellipsoid { .. } => "ellipsoid",
            Shape::Mesh { .. } => "mesh",
        }
    }
}

/// One piece of a body's visual geometry.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Visual {
    /// Index of the body in `model.bodies`.
    pub body: usize,
    /// The shape's frame in the body frame.
    pub origin: Placement,
    pub shape: Shape,
    /// Colour and opacity in 0..1 (`None`: the mesh's own colours, else a default).
    pub rgba: Option<[f64; 4]>,
}

impl Visual {
    /// Checks sizes (finite, > 0; a mesh's scale finite and non-zero), the colour (0..1), the
    /// rotation and the body index; errors name `arg`.
    pub fn check(&self, nbodies: usize, arg: &str) -> Result<()> {
        let bad = |what: &str, got: String| Err(Error::arg(arg, what, got));
        if self.body >= nbodies {
            return bad(
                &format!("a body index 0..{}", nbodies.saturating_sub(1)),
                format!("body {}", self.body),
            );
        }
        crate::model::checked_rotation(&self.origin.rotation, arg)?;
        crate::support::error::check_finite(arg, self.origin.translation.as_slice())?;
        let positive = |x: &[f64]| x.iter().all(|v| v.is_finite() && *v > 0.0);
        let ok = match &self.shape {
            Shape::Box { size } => positive(size.as_slice()),
            Shape::Cylinder { radius, length } => positive(&[*radius, *length]),
            Shape::Sphere { radius } => positive(&[*radius]),
            Shape::Capsule { radius, length } => {
                positive(&[*radius]) && length.is_finite() && *length >= 0.0
            }
            Shape::Ellipsoid { radii } => positive(radii.as_slice()),
            Shape::Mesh { scale, .. } => scale.iter().all(|v| v.is_finite() && *v != 0.0),
        };
        if !ok {
            return bad(
                "finite sizes > 0 (a mesh: a finite, non-zero scale)",
                format!("{:?}", self.shape),
            );
        }
        if let Some(c) = self.rgba {
            if !c.iter().all(|v| (0.0..=1.0).contains(v)) {
                return bad("rgba in [0, 1]", format!("{c:?}"));
            }
        }
        Ok(())
    }

    /// The visual as `Model.visuals` lists it (`model::args::visual` reads it back): `(key,
    /// value)` in order, `None` for a value it lacks (`rgba`, a mesh's `path`). The shape's
    /// frame as `rotation` (rows) and `translation`; sizes as the shape names them.
    pub fn fields(&self, body_name: &str) -> Vec<(&'static str, Option<toml::Value>)> {
        use toml::Value as V;
        let xyz = |x: &Vec3| V::from(x.as_slice().to_vec());
        let r = &self.origin.rotation;
        let rows: Vec<V> = (0..3)
            .map(|i| V::from(vec![r[(i, 0)], r[(i, 1)], r[(i, 2)]]))
            .collect();
        let mut out = vec![
            ("body", Some(V::Integer(self.body as i64))),
            ("body_name", Some(V::from(body_name))),
            ("kind", Some(V::from(self.shape.kind()))),
            ("rotation", Some(V::Array(rows))),
            ("translation", Some(xyz(&self.origin.translation))),
        ];
        match &self.shape {
            Shape::Box { size } => out.push(("size", Some(xyz(size)))),
            Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
                out.push(("radius", Some(V::Float(*radius))));
                out.push(("length", Some(V::Float(*length))));
            }
            Shape::Sphere { radius } => out.push(("radius", Some(V::Float(*radius)))),
            Shape::Ellipsoid { radii } => out.push(("radii", Some(xyz(radii)))),
            Shape::Mesh { uri, path, scale } => {
                out.push(("uri", Some(V::from(uri.as_str()))));
                out.push(("path", path.as_deref().map(V::from)));
                out.push(("scale", Some(xyz(scale))));
            }
        }
        out.push(("rgba", self.rgba.map(|c| V::from(c.to_vec()))));
        out
    }
}

/// The visuals a caller gives for a model of `nbodies` bodies (`Model.set_visuals`): each
/// read as [`crate::model::args::visual`] reads one, and checked; errors name `visuals[k]`.
pub fn parse_visuals<A: Arg>(
    items: &[A],
    nbodies: usize,
) -> std::result::Result<Vec<Visual>, A::Err> {
    let one = |(k, d): (usize, &A)| {
        let arg = format!("visuals[{k}]");
        let v = crate::model::args::visual(d, &arg)?;
        v.check(nbodies, &arg)?;
        Ok(v)
    };
    items.iter().enumerate().map(one).collect()
}

/// Where a mesh `uri` of a model file in `base_dir` is, as Pinocchio resolves it:
/// `package://pkg/rest` in each of `package_dirs` (as `dir/pkg/rest`, or `dir/rest` when the
/// directory is named `pkg`), then in the file's directory and each of its ancestors the same
/// way; `file://` and absolute paths as they are; other relative paths against `base_dir`.
/// `None` when no candidate is a file.
pub fn resolve_mesh(
    uri: &str,
    base_dir: Option<&Path>,
    package_dirs: &[PathBuf],
) -> Option<PathBuf> {
    let is_file = |p: &Path| p.is_file().then(|| p.to_path_buf());
    let scheme = ["package://", "model://"]
        .iter()
        .find_map(|s| uri.strip_prefix(s));
    if let Some(rest) = scheme {
        // Talos writes `package:///example-robot-data/...`: leading slashes mean nothing here.
        let rest = rest.trim_start_matches('/');
        let (pkg, inner) = rest.split_once('/').unwrap_or((rest, ""));
        let ancestors = base_dir.into_iter().flat_map(Path::ancestors);
        return package_dirs
            .iter()
            .map(PathBuf::as_path)
            .chain(ancestors)
            .find_map(|dir| {
                is_file(&dir.join(rest)).or_else(|| {
                    (dir.file_name().is_some_and(|n| n == pkg) && !inner.is_empty())
                        .then(|| is_file(&dir.join(inner)))
                        .flatten()
                })
            });
    }
    let plain = uri.strip_prefix("file://").unwrap_or(uri);
    let p = Path::new(plain);
    if p.is_absolute() {
        return is_file(p);
    }
    base_dir.and_then(|d| is_file(&d.join(p)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_uris_resolve_in_package_dirs_and_ancestors() {
        let tmp = std::env::temp_dir().join(format!("pmd_visual_{}", std::process::id()));
        let mesh = tmp.join("share/my_robot/meshes/a.stl");
        std::fs::create_dir_all(mesh.parent().unwrap()).unwrap();
        std::fs::write(&mesh, b"solid a\nendsolid a\n").unwrap();
        let urdf_dir = tmp.join("share/my_robot/urdf");
        std::fs::create_dir_all(&urdf_dir).unwrap();
        let found = |uri: &str, dirs: &[PathBuf]| resolve_mesh(uri, Some(&urdf_dir), dirs);
        // An ancestor holding the package (share/), and the package directory itself.
        assert_eq!(
            found("package://my_robot/meshes/a.stl", &[]),
            Some(mesh.clone())
        );
        assert_eq!(
            found("package:///my_robot/meshes/a.stl", &[]),
            Some(mesh.clone())
        );
        assert_eq!(
            found("../meshes/a.stl", &[]),
            Some(urdf_dir.join("../meshes/a.stl"))
        );
        let abs = format!("file://{}", mesh.display());
        assert_eq!(found(&abs, &[]), Some(mesh.clone()));
        assert_eq!(found("package://other/meshes/a.stl", &[]), None);
        // package_dirs: a parent of packages, or the package directory.
        let elsewhere = Path::new("/nonexistent");
        let dirs = [tmp.join("share")];
        assert_eq!(
            resolve_mesh("package://my_robot/meshes/a.stl", Some(elsewhere), &dirs),
            Some(mesh.clone())
        );
        let dirs = [tmp.join("share/my_robot")];
        assert_eq!(
            resolve_mesh("package://my_robot/meshes/a.stl", Some(elsewhere), &dirs),
            Some(mesh.clone())
        );
        assert_eq!(found("package://my_robot/meshes/missing.stl", &[]), None);
        std::fs::remove_dir_all(&tmp).unwrap();
    }

    #[test]
    fn bad_visuals_are_refused_by_name() {
        let v = Visual {
            body: 0,
            origin: Placement::identity(),
            shape: Shape::Box {
                size: Vec3::new(1.0, 0.0, 1.0),
            },
            rgba: None,
        };
        let e = v.check(1, "visuals[0]").unwrap_err().to_string();
        assert!(e.contains("visuals[0]") && e.contains("sizes"), "{e}");
        let v = Visual {
            shape: Shape::Sphere { radius: 0.1 },
            rgba: Some([0.5, 0.5, 2.0, 1.0]),
            ..v
        };
        assert!(v.check(1, "v").unwrap_err().to_string().contains("rgba"));
        let v = Visual { rgba: None, ..v };
        assert!(v.check(1, "v").is_ok());
        assert!(v.check(0, "v").unwrap_err().to_string().contains("body"));
    }
}
