//! How the links connect: each joint's parent and child link, the root link, and the joints
//! in Pinocchio's order (depth first, the children of a link in byte order of their joints'
//! names). Every way the joints can fail to form one tree is an error naming the joints.
use std::collections::HashMap;

use super::parse::{Ctx, JointData, LinkData};
use crate::support::error::Result;

pub(super) struct Tree {
    /// The link that is no joint's child.
    pub root: usize,
    /// Joint indices, depth first.
    pub order: Vec<usize>,
    /// Parent and child link of each joint (by joint index).
    pub parent_link: Vec<usize>,
    pub child_link: Vec<usize>,
}

impl Tree {
    pub(super) fn new(ctx: &Ctx, links: &[LinkData], joints: &[JointData]) -> Result<Tree> {
        let link_index = index_links(ctx, links)?;
        let mut tree = Tree {
            root: 0,
            order: Vec::with_capacity(joints.len()),
            parent_link: Vec::with_capacity(joints.len()),
            child_link: Vec::with_capacity(joints.len()),
        };
        let parent_joint = tree.connect(ctx, &link_index, joints)?;
        tree.root = tree.find_root(ctx, links, joints, &parent_joint)?;
        tree.order_depth_first(links.len(), joints);
        if tree.order.len() != joints.len() {
            let mut reached = vec![false; links.len()];
            reached[tree.root] = true;
            for &j in &tree.order {
                reached[tree.child_link[j]] = true;
            }
            let off = (0..links.len()).find(|&l| !reached[l]).unwrap();
            return Err(ctx.err(
                "robot",
                format!(
                    "the joints {} form a cycle, detached from the root link '{}'",
                    tree.cycle_from(off, joints, &parent_joint),
                    links[tree.root].name
                ),
            ));
        }
        Ok(tree)
    }

    /// Resolves each joint's links; returns each link's parent joint.
    fn connect(
        &mut self,
        ctx: &Ctx,
        link_index: &HashMap<&str, usize>,
        joints: &[JointData],
    ) -> Result<Vec<Option<usize>>> {
        let mut joint_names: HashMap<&str, usize> = HashMap::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; link_index.len()];
        for (k, j) in joints.iter().enumerate() {
            let element = format!("joint '{}'", j.name);
            if let Some(&first) = joint_names.get(j.name.as_str()) {
                return Err(ctx.located(
                    element,
                    Some(j.line),
                    format!(
                        "defined twice (lines {} and {})",
                        joints[first].line, j.line
                    ),
                ));
            }
            joint_names.insert(&j.name, k);
            let link = |which: &str, name: &str| {
                link_index.get(name).copied().ok_or_else(|| {
                    ctx.on_line(
                        &element,
                        j.line,
                        format!("{which} link '{name}' is not defined"),
                    )
                })
            };
            let p = link("parent", &j.parent)?;
            let c = link("child", &j.child)?;
            if p == c {
                return Err(ctx.on_line(
                    element,
                    j.line,
                    format!(
                        "link '{}' is both parent and child: the joints form a cycle",
                        j.child
                    ),
                ));
            }
            if let Some(other) = parent_joint[c] {
                return Err(ctx.on_line(
                    element,
                    j.line,
                    format!(
                        "link '{}' already has a parent through joint '{}': a link may have only one parent",
                        j.child, joints[other].name
                    ),
                ));
            }
            parent_joint[c] = Some(k);
            self.parent_link.push(p);
            self.child_link.push(c);
        }
        Ok(parent_joint)
    }

    /// The one link without a parent joint.
    fn find_root(
        &self,
        ctx: &Ctx,
        links: &[LinkData],
        joints: &[JointData],
        parent_joint: &[Option<usize>],
    ) -> Result<usize> {
        let roots: Vec<usize> = (0..links.len())
            .filter(|&l| parent_joint[l].is_none())
            .collect();
        match roots.as_slice() {
            [] => Err(ctx.err(
                "robot",
                format!(
                    "no root link: every link is the child of a joint, so the joints form a cycle (joints {})",
                    self.cycle_from(0, joints, parent_joint)
                ),
            )),
            [r] => Ok(*r),
            many => {
                let names: Vec<String> = many
                    .iter()
                    .map(|&l| format!("'{}'", links[l].name))
                    .collect();
                Err(ctx.err(
                    "robot",
                    format!(
                        "several root links ({}): a URDF must be one tree; connect them with joints",
                        names.join(", ")
                    ),
                ))
            }
        }
    }

    /// Depth first from the root, children in joint-name order (Pinocchio's order). Joints
    /// on a cycle detached from the root are not reached.
    fn order_depth_first(&mut self, nlinks: usize, joints: &[JointData]) {
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); nlinks];
        for (j, &p) in self.parent_link.iter().enumerate() {
            children[p].push(j);
        }
        for c in children.iter_mut() {
            c.sort_by(|&a, &b| joints[a].name.as_bytes().cmp(joints[b].name.as_bytes()));
        }
        let mut stack: Vec<usize> = children[self.root].iter().rev().copied().collect();
        while let Some(j) = stack.pop() {
            self.order.push(j);
            stack.extend(children[self.child_link[j]].iter().rev().copied());
        }
    }

    /// The names of the joints of the cycle above link `start` (which is off the tree: each
    /// link has at most one parent, so walking up from it ends in a cycle).
    fn cycle_from(
        &self,
        start: usize,
        joints: &[JointData],
        parent_joint: &[Option<usize>],
    ) -> String {
        let mut seen = vec![false; parent_joint.len()];
        let mut l = start;
        while !seen[l] {
            seen[l] = true;
            l = self.parent_link[parent_joint[l].unwrap()];
        }
        let mut names = Vec::new();
        let first = l;
        loop {
            let j = parent_joint[l].unwrap();
            names.push(format!("'{}'", joints[j].name));
            l = self.parent_link[j];
            if l == first {
                break;
            }
        }
        names.reverse();
        names.join(", ")
    }
}

/// Link index by name; a name defined twice is an error.
fn index_links<'a>(ctx: &Ctx, links: &'a [LinkData]) -> Result<HashMap<&'a str, usize>> {
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (k, l) in links.iter().enumerate() {
        if let Some(&first) = link_index.get(l.name.as_str()) {
            return Err(ctx.located(
                format!("link '{}'", l.name),
                Some(l.line),
                format!("defined twice (lines {} and {})", links[first].line, l.line),
            ));
        }
        link_index.insert(&l.name, k);
    }
    Ok(link_index)
}
