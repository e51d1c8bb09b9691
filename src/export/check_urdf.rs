//! `partscene check-urdf FILE...`: what `urdfdom`'s `check_urdf` and the simulators' loaders
//! refuse or silently mis-read, checked on any URDF (ours in CI, or one a user brings).
//!
//! Errors (the file is not a usable model): not XML/URDF; no link; duplicate link or joint names;
//! a joint naming a link that does not exist; a link that is the child of two joints; not exactly
//! one root (a forest, or a cycle); a movable joint with a zero or non-finite axis, or limits with
//! lower > upper; a non-root link whose mass is not positive and finite, or whose inertia is not
//! positive or breaks the triangle inequality (`ixx + iyy >= izz` and the like, which `PhysX` and
//! `MuJoCo` enforce); a box, cylinder, sphere or capsule of non-positive or non-finite size; a
//! non-finite origin. Warnings: an axis that is not of unit length (readers normalise it), a
//! revolute or prismatic joint with zero effort or velocity limit (many controllers then refuse to
//! move it), a mesh file that does not exist beside the URDF.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use urdf_rs as ur;

/// What `check_urdf` found in one file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UrdfCheck {
    pub errors: Vec<String>,
    pub warnings: Vec<String>,
    pub links: usize,
    pub joints: usize,
    pub root: Option<String>,
}

impl UrdfCheck {
    #[must_use]
    pub fn is_ok(&self) -> bool {
        self.errors.is_empty()
    }
}

fn finite3(v: [f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Checks a URDF file (mesh paths are resolved beside it).
#[must_use]
pub fn check_urdf_file(path: &Path) -> UrdfCheck {
    match std::fs::read_to_string(path) {
        Ok(text) => check_urdf_named(&text, path, path.parent()),
        Err(e) => UrdfCheck { errors: vec![format!("cannot read: {e}")], ..UrdfCheck::default() },
    }
}

/// Checks URDF text; `base` is the folder mesh file names are relative to (`None`: not checked).
#[must_use]
pub fn check_urdf(text: &str, base: Option<&Path>) -> UrdfCheck {
    check_urdf_named(text, Path::new("urdf"), base)
}

fn check_urdf_named(text: &str, path: &Path, base: Option<&Path>) -> UrdfCheck {
    let mut out = UrdfCheck::default();
    // Vectors written with commas (`xyz="0, 0, 1"`, seen in published assets) are read as the
    // asset importer reads them, and reported: urdfdom splits on spaces only.
    let text = match crate::assets::urdf::normalise_vector_commas(text, path) {
        Ok((normalised, 0)) => normalised,
        Ok((normalised, n)) => {
            out.warnings.push(format!("{n} vector attribute(s) written with commas (urdfdom and urdf-rs split on spaces only)"));
            normalised
        }
        Err(e) => {
            out.errors.push(format!("not XML: {e}"));
            return out;
        }
    };
    let robot = match ur::read_from_string(&text) {
        Ok(r) => r,
        Err(e) => {
            out.errors.push(format!("not a URDF: {e}"));
            return out;
        }
    };
    out.links = robot.links.len();
    out.joints = robot.joints.len();
    if robot.links.is_empty() {
        out.errors.push("no <link>".to_owned());
        return out;
    }
    check_names(&robot, &mut out);
    let root = check_tree(&robot, &mut out);
    out.root.clone_from(&root);
    for joint in &robot.joints {
        check_joint(joint, &mut out);
    }
    for link in &robot.links {
        check_link(link, root.as_deref() == Some(link.name.as_str()), base, &mut out);
    }
    out
}

fn check_names(robot: &ur::Robot, out: &mut UrdfCheck) {
    let mut seen = BTreeSet::new();
    for l in &robot.links {
        if !seen.insert(l.name.as_str()) {
            out.errors.push(format!("link {:?}: the name is used twice", l.name));
        }
    }
    let mut seen = BTreeSet::new();
    for j in &robot.joints {
        if !seen.insert(j.name.as_str()) {
            out.errors.push(format!("joint {:?}: the name is used twice", j.name));
        }
    }
}

/// The links form one tree; returns its root.
fn check_tree(robot: &ur::Robot, out: &mut UrdfCheck) -> Option<String> {
    let links: BTreeSet<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    let mut parent_of: BTreeMap<&str, &str> = BTreeMap::new();
    for j in &robot.joints {
        for (end, link) in [("parent", j.parent.link.as_str()), ("child", j.child.link.as_str())] {
            if !links.contains(link) {
                out.errors.push(format!("joint {:?}: {end} link {link:?} does not exist", j.name));
            }
        }
        if let Some(first) = parent_of.insert(j.child.link.as_str(), j.parent.link.as_str()) {
            out.errors.push(format!("link {:?}: child of two joints (parents {first:?} and {:?})", j.child.link, j.parent.link));
        }
    }
    let roots: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).filter(|l| !parent_of.contains_key(l)).collect();
    match roots.as_slice() {
        [root] => {
            // Every link reaches the root (no cycle hanging apart).
            for l in &links {
                let mut at = *l;
                let mut steps = 0;
                while let Some(&up) = parent_of.get(at) {
                    at = up;
                    steps += 1;
                    if steps > links.len() {
                        out.errors.push(format!("link {l:?}: its joints form a cycle"));
                        break;
                    }
                }
            }
            Some((*root).to_owned())
        }
        [] => {
            out.errors.push("no root link: the joints form a cycle".to_owned());
            None
        }
        many => {
            out.errors.push(format!("{} root links ({}): expected one tree", many.len(), many.join(", ")));
            None
        }
    }
}

fn check_joint(j: &ur::Joint, out: &mut UrdfCheck) {
    let name = &j.name;
    if !finite3(j.origin.xyz.0) || !finite3(j.origin.rpy.0) {
        out.errors.push(format!("joint {name:?}: non-finite origin"));
    }
    let movable = matches!(j.joint_type, ur::JointType::Revolute | ur::JointType::Continuous | ur::JointType::Prismatic);
    if !movable {
        return;
    }
    let axis = j.axis.xyz.0;
    let norm = axis.iter().map(|a| a * a).sum::<f64>().sqrt();
    if !norm.is_finite() || norm < 1e-9 {
        out.errors.push(format!("joint {name:?}: axis {axis:?} has no direction"));
    } else if (norm - 1.0).abs() > 1e-3 {
        out.warnings.push(format!("joint {name:?}: axis {axis:?} has length {norm:.4}, not 1 (readers normalise it)"));
    }
    if matches!(j.joint_type, ur::JointType::Revolute | ur::JointType::Prismatic) {
        let l = &j.limit;
        if !(l.lower.is_finite() && l.upper.is_finite()) || l.lower > l.upper {
            out.errors.push(format!("joint {name:?}: limits lower {} > upper {} (or not finite)", l.lower, l.upper));
        }
        if !(l.effort > 0.0 && l.velocity > 0.0) {
            out.warnings
                .push(format!("joint {name:?}: effort {} and velocity {} limits: a zero one stops many controllers", l.effort, l.velocity));
        }
    }
}

fn check_link(link: &ur::Link, is_root: bool, base: Option<&Path>, out: &mut UrdfCheck) {
    let name = &link.name;
    let i = &link.inertial;
    let mass = i.mass.value;
    let inertia = [i.inertia.ixx, i.inertia.iyy, i.inertia.izz];
    let massless = mass == 0.0 && inertia.iter().all(|v| *v == 0.0);
    // A root without <inertial> (a `world` link) is fixed to the world: no mass needed.
    if !(is_root && massless) {
        if !(mass.is_finite() && mass > 0.0) {
            out.errors.push(format!("link {name:?}: mass {mass} is not positive"));
        }
        let [a, b, c] = inertia;
        let off = [i.inertia.ixy, i.inertia.ixz, i.inertia.iyz];
        if !inertia.iter().chain(&off).all(|v| v.is_finite()) || inertia.iter().any(|v| *v <= 0.0) {
            out.errors.push(format!("link {name:?}: inertia diagonal {inertia:?} is not positive"));
        } else if off.iter().all(|v| *v == 0.0) {
            let tol = 1e-9 * (a + b + c);
            if a + b < c - tol || b + c < a - tol || a + c < b - tol {
                out.errors.push(format!("link {name:?}: inertia {inertia:?} breaks the triangle inequality (no rigid body has it)"));
            }
        }
    }
    let geometries = link
        .visual
        .iter()
        .map(|v| ("visual", &v.origin, &v.geometry))
        .chain(link.collision.iter().map(|c| ("collision", &c.origin, &c.geometry)));
    for (what, origin, g) in geometries {
        if !finite3(origin.xyz.0) || !finite3(origin.rpy.0) {
            out.errors.push(format!("link {name:?}: {what} origin is not finite"));
        }
        let sizes: Vec<f64> = match g {
            ur::Geometry::Box { size } => size.0.to_vec(),
            ur::Geometry::Cylinder { radius, length } | ur::Geometry::Capsule { radius, length } => vec![*radius, *length],
            ur::Geometry::Sphere { radius } => vec![*radius],
            ur::Geometry::Mesh { filename, .. } => {
                if let Some(base) = base {
                    let file = filename.strip_prefix("package://").or_else(|| filename.strip_prefix("file://")).unwrap_or(filename);
                    if !base.join(file).exists() && !Path::new(file).exists() {
                        out.warnings.push(format!("link {name:?}: {what} mesh {filename:?} not found beside the URDF"));
                    }
                }
                Vec::new()
            }
        };
        if sizes.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            out.errors.push(format!("link {name:?}: {what} geometry has size {sizes:?}; expected positive sizes"));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LINK: &str = r#"<inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
        <collision><geometry><box size="0.1 0.2 0.3"/></geometry></collision>"#;

    fn robot(body: &str) -> String {
        format!("<robot name=\"r\">{body}</robot>")
    }

    fn link(name: &str) -> String {
        format!("<link name=\"{name}\">{LINK}</link>")
    }

    fn joint(name: &str, kind: &str, parent: &str, child: &str, extra: &str) -> String {
        format!("<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/>{extra}</joint>")
    }

    /// Errors and warnings expected to contain these fragments (empty: none).
    fn check(urdf: &str, errors: &[&str], warnings: &[&str]) {
        let c = check_urdf(urdf, None);
        assert_eq!(c.errors.len(), errors.len(), "{:?}", c.errors);
        for (e, want) in c.errors.iter().zip(errors) {
            assert!(e.contains(want), "{e:?} should contain {want:?}");
        }
        assert_eq!(c.warnings.len(), warnings.len(), "{:?}", c.warnings);
        for (w, want) in c.warnings.iter().zip(warnings) {
            assert!(w.contains(want), "{w:?} should contain {want:?}");
        }
    }

    #[test]
    fn good_and_broken_urdfs() {
        let limit = r#"<axis xyz="0 0 1"/><limit lower="0" upper="1" effort="10" velocity="1"/>"#;
        let ok = robot(&format!(
            "<link name=\"world\"/>{}{}{}",
            link("a"),
            joint("fix", "fixed", "world", "a", ""),
            link("b") + &joint("j", "revolute", "a", "b", limit)
        ));
        check(&ok, &[], &[]);
        check("not xml", &["not XML"], &[]);
        check("<robot><link name=\"a\"><inertial><mass value=\"x\"/></inertial></link></robot>", &["not a URDF"], &[]);
        let commas = r#"<robot name="r"><link name="a"><visual><geometry><box size="1, 1, 1"/></geometry></visual></link></robot>"#;
        check(commas, &[], &["1 vector attribute(s) written with commas"]);
        check(&robot(&(link("a") + &link("a"))), &["used twice", "2 root links"], &[]);
        check(&robot(&(link("a") + &link("b"))), &["2 root links (a, b)"], &[]);
        check(&robot(&(link("a") + &joint("j", "fixed", "a", "c", ""))), &["child link \"c\" does not exist"], &[]);
        check(
            &robot(&(link("a") + &link("b") + &joint("j", "fixed", "a", "b", "") + &joint("k", "fixed", "b", "a", ""))),
            &["no root link"],
            &[],
        );
        let flipped = r#"<axis xyz="0 0 2"/><limit lower="1" upper="0" effort="0" velocity="1"/>"#;
        check(
            &robot(&(link("a") + &link("b") + &joint("j", "prismatic", "a", "b", flipped))),
            &["lower 1 > upper 0"],
            &["length 2.0000", "effort 0"],
        );
        check(
            &robot(&(link("a") + &link("b") + &joint("j", "continuous", "a", "b", r#"<axis xyz="0 0 0"/>"#))),
            &["has no direction"],
            &[],
        );
        let bad_inertia =
            r#"<link name="b"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>"#;
        check(&robot(&(link("a") + bad_inertia + &joint("j", "fixed", "a", "b", ""))), &["triangle inequality"], &[]);
        check(
            &robot(&(link("a") + "<link name=\"b\"/>" + &joint("j", "fixed", "a", "b", ""))),
            &["mass 0 is not positive", "not positive"],
            &[],
        );
        let flat = r#"<link name="a"><collision><geometry><cylinder radius="0" length="1"/></geometry></collision></link>"#;
        check(&robot(flat), &["geometry has size [0.0, 1.0]"], &[]);
    }
}
