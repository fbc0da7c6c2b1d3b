//! An SRDF's reference poses (`<group_state>`: "standing", "half_sitting", …) as
//! configurations of a model loaded from the URDF beside it, as Pinocchio's
//! `loadReferenceConfigurations` reads them: each pose starts from the neutral configuration
//! and sets the joints it names (by their URDF names; a free flyer's value is
//! `x y z qx qy qz qw`). Joints the model does not have (welded or absent) are skipped and
//! listed; a value of the wrong length is an error naming the pose and the joint.
use std::path::Path;

use crate::model::Model;
use crate::support::error::{Error, FileKind, Location, Result};

/// One reference pose: its name and configuration (q, normalised).
#[derive(Debug, Clone, PartialEq)]
pub struct ReferencePose {
    pub name: String,
    pub q: Vec<f64>,
}

/// The poses of the SRDF file `path` for `model`, in file order, and the names of the joints
/// they set that the model does not move (skipped).
pub fn load_reference_poses(
    model: &Model,
    path: &Path,
) -> Result<(Vec<ReferencePose>, Vec<String>)> {
    let text = crate::support::files::read_text_named(path, FileKind::Urdf, "SRDF")?;
    reference_poses(model, &text, &crate::support::files::display_path(path))
}

/// [`load_reference_poses`], the joints skipped said in one warning (`None`: none skipped).
pub fn reference_poses_warned(
    model: &Model,
    path: &Path,
) -> Result<(Vec<ReferencePose>, Option<String>)> {
    let (poses, skipped) = load_reference_poses(model, path)?;
    let warning = (!skipped.is_empty()).then(|| {
        let file = crate::support::files::display_path(path);
        format!(
            "{file}: joints the model does not move, skipped: {}",
            skipped.join(", ")
        )
    });
    Ok((poses, warning))
}

/// [`load_reference_poses`] of SRDF text; `file` names it in errors.
pub fn reference_poses(
    model: &Model,
    text: &str,
    file: &str,
) -> Result<(Vec<ReferencePose>, Vec<String>)> {
    let err = |key: String, message: String| {
        Error::file(
            FileKind::Urdf,
            Location::new(file.to_string(), key),
            message,
        )
    };
    let doc = roxmltree::Document::parse(text)
        .map_err(|e| err(String::new(), format!("not an SRDF (XML) file: {e}")))?;
    let names = model.joint_names();
    let mut skipped: Vec<String> = Vec::new();
    let mut poses = Vec::new();
    for state in doc.descendants().filter(|n| n.has_tag_name("group_state")) {
        let pose = state.attribute("name").unwrap_or("").to_string();
        let mut q = model.neutral();
        for joint in state.children().filter(|n| n.has_tag_name("joint")) {
            let name = joint.attribute("name").unwrap_or("");
            let key = format!("group_state '{pose}' joint '{name}'");
            let Some(link) = names.iter().position(|n| n == name) else {
                if !skipped.iter().any(|s| s == name) {
                    skipped.push(name.to_string());
                }
                continue;
            };
            let values: Vec<f64> = joint
                .attribute("value")
                .unwrap_or("")
                .split_whitespace()
                .map(|x| x.parse::<f64>())
                .collect::<std::result::Result<_, _>>()
                .map_err(|e| err(key.clone(), format!("value: expected numbers ({e})")))?;
            let l = &model.links[link];
            let nq = l.joint.nq();
            if values.len() != nq || values.iter().any(|x| !x.is_finite()) {
                return Err(err(
                    key,
                    format!(
                        "value: expected {nq} finite number(s) for this joint, got {:?}",
                        joint.attribute("value").unwrap_or("")
                    ),
                ));
            }
            q[l.q_index..l.q_index + nq].copy_from_slice(&values);
        }
        model.check_state(&q, None).map_err(|e| {
            e.in_file(
                FileKind::Urdf,
                Location::new(file, format!("group_state '{pose}'")),
            )
        })?;
        model.normalize(&mut q);
        poses.push(ReferencePose { name: pose, q });
    }
    Ok((poses, skipped))
}
