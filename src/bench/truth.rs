//! An imported articulated asset as ground truth ([`GroundTruth`]): one object, one part per link
//! that has geometry, truth joints and contact edges from the asset's kinematic tree, stood upright
//! on a floor at z = 0.

use std::collections::BTreeMap;

use crate::assets::{ArticulatedAsset, AssetGeom, AssetJoint, AssetLink, GeomShape};
use crate::kinematics::{Joint, JointKind, Vocabulary};
use crate::math::{Pose, Quat, Vec3};
use crate::primitive::Primitive;
use crate::report::Warning;
use crate::scan::PartId;
use crate::truth::{GroundTruth, TRUTH_FORMAT, TruthMesh, TruthObject, TruthPart};

use super::BenchError;

/// Which asset axis points up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// +z up (URDF/ROS, `MuJoCo`).
    #[default]
    Z,
    /// +y up (glTF, habitat): rotated by +90° about x so that +y becomes +z.
    Y,
}

/// How to turn an asset into ground truth.
#[derive(Clone, Debug, Default)]
pub struct AssetTruthOptions {
    /// The object's category (`MANIFEST.tsv` `category`, else derived from the file name).
    pub category: String,
    pub up: UpAxis,
}

/// The ground truth of an asset, plus what was carried past (links merged into an ancestor,
/// several movable joints on one collapsed chain).
#[derive(Clone, Debug)]
pub struct AssetTruth {
    pub truth: GroundTruth,
    /// Part id → the asset link it came from.
    pub part_links: BTreeMap<PartId, String>,
    /// The transform applied to the asset (asset root frame → world: upright, on the floor).
    pub world_from_asset: Pose,
    pub warnings: Vec<Warning>,
}

/// The label a person would give a link, from its name, else from its parent joint's name: the
/// vocabulary word the name contains ([`Vocabulary::classify`]: `drawer_handle` → handle,
/// `drawercase_link` → case, `lightswitchbaseroot` → base, `drawer1_top` → drawer); the root part
/// defaults to "body", others to "part". Never derived from the joint type.
#[must_use]
pub fn coarse_label(link_name: &str, joint_name: Option<&str>, is_root: bool) -> String {
    let vocab = Vocabulary::builtin();
    let find = |name: &str| vocab.classify(name).map(|m| m.word);
    find(link_name).or_else(|| joint_name.and_then(find)).unwrap_or_else(|| if is_root { "body".into() } else { "part".into() })
}

/// A category from an asset's file name: the stem without `_obj`, `_standalone` and digits
/// (`kitchen_counter_obj.urdf` → `kitchen_counter`).
#[must_use]
pub fn category_from_file_name(path: &std::path::Path) -> String {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("object").to_ascii_lowercase();
    let stem = stem.trim_end_matches("_obj").trim_end_matches("_standalone");
    let stem = stem.trim_end_matches(|c: char| c.is_ascii_digit() || c == '_');
    if stem.is_empty() { "object".into() } else { stem.to_owned() }
}

/// A link with geometry (or a grip split off one), before placement.
struct Raw<'a> {
    link: &'a str,
    /// The file named the link ([`AssetLink::named`]): only then is its name a label.
    named: bool,
    shapes: Vec<Primitive>,
    meshes: Vec<TruthMesh>,
    /// A grip split off the link before it in `raws` ([`split_grip`]): labelled `handle`, fixed
    /// to that link's part.
    grip: bool,
}

/// Bounds are widened by this much (metres) when asking whether a geom lies inside a grip's
/// named geometry: collision boxes approximate a visual mesh and poke out of it by millimetres.
const GRIP_MARGIN_M: f32 = 0.003;

/// Splits the geometry of a link into (rest, grip) when the file names part of it as a grip:
/// geoms whose names ([`crate::assets::AssetGeom::names`]: geom, mesh, material) carry a handle
/// word (handle, pull, grip, bar), and the link's preferred geoms that lie inside such a geom's
/// bounds (collision boxes approximating a visual handle mesh). A part-segmented scan segments a
/// handle as its own semantic part, whichever body the asset author put it in (LIBERO's
/// `wooden_cabinet_top_handle_vis` mesh lives in the drawer body `cabinet_top`). Links that are
/// grips themselves, and links whose geometry would be all grip, are not split (`None`).
fn split_grip<'g>(link: &'g AssetLink, preferred: &[&'g AssetGeom]) -> Option<(Vec<&'g AssetGeom>, Vec<&'g AssetGeom>)> {
    let vocab = Vocabulary::builtin();
    if vocab.is_grip(&coarse_label(if link.named { &link.name } else { "" }, None, false)) {
        return None;
    }
    let named_grip = |g: &AssetGeom| g.names.iter().any(|n| vocab.is_grip(n));
    let regions: Vec<(Vec3, Vec3)> = link
        .geoms
        .iter()
        .filter(|g| named_grip(g))
        .filter_map(AssetGeom::aabb)
        .map(|(lo, hi)| (lo - Vec3::splat(GRIP_MARGIN_M), hi + Vec3::splat(GRIP_MARGIN_M)))
        .collect();
    if regions.is_empty() {
        return None;
    }
    let inside =
        |g: &AssetGeom| g.aabb().is_some_and(|(lo, hi)| regions.iter().any(|(rlo, rhi)| lo.cmpge(*rlo).all() && hi.cmple(*rhi).all()));
    let (grip, rest): (Vec<&AssetGeom>, Vec<&AssetGeom>) = preferred.iter().partition(|g| named_grip(g) || inside(g));
    (!grip.is_empty() && !rest.is_empty()).then_some((rest, grip))
}

/// Primitives and meshes of geoms.
fn solids_of(geoms: &[&AssetGeom]) -> (Vec<Primitive>, Vec<TruthMesh>) {
    let mut shapes = Vec::new();
    let mut meshes = Vec::new();
    for g in geoms {
        match &g.shape {
            GeomShape::Primitive(p) => shapes.push(*p),
            GeomShape::Mesh { vertices, triangles } if !triangles.is_empty() => {
                meshes.push(TruthMesh { vertices: vertices.clone(), triangles: triangles.clone() });
            }
            GeomShape::Mesh { .. } => {}
        }
    }
    (shapes, meshes)
}

/// Converts an asset at rest into ground truth (object id 1, part ids 1.. in link order).
///
/// Links without geometry are merged into their nearest ancestor with geometry; a part's joint is
/// the movable joint on the chain up to its parent part (the one nearest the part when the chain
/// has several, with a warning), else fixed. Parts with no ancestor part hang off the largest of
/// them. Geometry the file names as a grip inside a link that is not itself a grip becomes its
/// own `handle` part, fixed to the link's part ([`split_grip`]). The asset is rotated so `up`
/// becomes +z and moved so it stands centred on z = 0.
pub fn asset_truth(asset: &ArticulatedAsset, options: &AssetTruthOptions) -> Result<AssetTruth, BenchError> {
    let mut warnings = Vec::new();
    let rotation = match options.up {
        UpAxis::Z => Quat::IDENTITY,
        UpAxis::Y => Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
    };
    // Parts: links with preferred geometry, in link order.
    let mut raws: Vec<Raw> = Vec::new();
    for link in &asset.links {
        let geoms = link.preferred_geoms();
        let (rest, grip) = split_grip(link, &geoms).unwrap_or((geoms, Vec::new()));
        let (shapes, meshes) = solids_of(&rest);
        if !shapes.is_empty() || !meshes.is_empty() {
            raws.push(Raw { link: &link.name, named: link.named, shapes, meshes, grip: false });
            let (shapes, meshes) = solids_of(&grip);
            if !shapes.is_empty() || !meshes.is_empty() {
                raws.push(Raw { link: &link.name, named: link.named, shapes, meshes, grip: true });
            }
        }
    }
    if raws.is_empty() {
        return Err(BenchError::NoGeometry { asset: asset.name.clone() });
    }
    // Placement: rotate, then centre on x, y and put the lowest point on z = 0.
    let rot_pose = Pose::from_parts(Vec3::ZERO, rotation);
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for r in &raws {
        for s in &r.shapes {
            let (a, b) = Primitive::new(s.kind, s.size, rot_pose * s.world_from_primitive).aabb();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        for v in r.meshes.iter().flat_map(|m| m.vertices.iter()) {
            let v = rotation * *v;
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let shift = Vec3::new(-0.5 * (lo.x + hi.x), -0.5 * (lo.y + hi.y), -lo.z);
    let world_from_asset = Pose::from_parts(shift, rotation);

    let part_of: BTreeMap<&str, PartId> =
        raws.iter().enumerate().filter(|(_, r)| !r.grip).map(|(i, r)| (r.link, i as PartId + 1)).collect();
    let parent_joint: BTreeMap<&str, &AssetJoint> = asset.joints.iter().map(|j| (j.child.as_str(), j)).collect();
    // Walk up from each part to its nearest ancestor part, collecting the joints on the way.
    let chain_of = |link: &str| -> (Option<PartId>, Vec<&AssetJoint>) {
        let mut chain = Vec::new();
        let mut cur = link;
        for _ in 0..=asset.joints.len() {
            let Some(j) = parent_joint.get(cur) else { return (None, chain) };
            chain.push(*j);
            if let Some(&p) = part_of.get(j.parent.as_str()) {
                return (Some(p), chain);
            }
            cur = j.parent.as_str();
        }
        (None, chain)
    };
    let volume = |r: &Raw| -> f32 {
        let bounds = r.shapes.iter().map(Primitive::aabb).chain(r.meshes.iter().filter_map(TruthMesh::aabb));
        bounds.reduce(|(a, b), (c, d)| (a.min(c), b.max(d))).map_or(0.0, |(a, b)| (b - a).max(Vec3::ZERO).element_product())
    };
    // A grip hangs off its link's part with no joint in between.
    let chains: Vec<(Option<PartId>, Vec<&AssetJoint>)> =
        raws.iter().map(|r| if r.grip { (part_of.get(r.link).copied(), Vec::new()) } else { chain_of(r.link) }).collect();
    let main_root = raws
        .iter()
        .zip(&chains)
        .enumerate()
        .filter(|(_, (_, (p, _)))| p.is_none())
        .max_by(|(ia, (a, _)), (ib, (b, _))| volume(a).total_cmp(&volume(b)).then(ib.cmp(ia)))
        .map_or(1, |(i, _)| i as PartId + 1);

    let mut parts = Vec::with_capacity(raws.len());
    let mut joints = Vec::new();
    let mut part_links = BTreeMap::new();
    for (i, (raw, (parent, chain))) in raws.iter().zip(&chains).enumerate() {
        let id = i as PartId + 1;
        let is_root = id == main_root;
        let joint_name = chain.first().map(|j| j.name.as_str());
        let label = if raw.grip { "handle".to_owned() } else { coarse_label(if raw.named { raw.link } else { "" }, joint_name, is_root) };
        let shapes = raw.shapes.iter().map(|s| Primitive::new(s.kind, s.size, world_from_asset * s.world_from_primitive)).collect();
        let meshes = raw
            .meshes
            .iter()
            .map(|m| TruthMesh {
                vertices: m.vertices.iter().map(|v| world_from_asset.transform_point(*v)).collect(),
                triangles: m.triangles.clone(),
            })
            .collect();
        parts.push(TruthPart { id, label, shapes, meshes });
        part_links.insert(id, if raw.grip { format!("{} (handle geoms)", raw.link) } else { raw.link.to_owned() });
        if is_root {
            continue;
        }
        let parent = parent.unwrap_or(main_root);
        let movable: Vec<&&AssetJoint> = chain.iter().filter(|j| j.kind.is_movable()).collect();
        if movable.len() > 1 {
            warnings.push(Warning::new(
                "bench",
                format!("link {}", raw.link),
                format!("{} movable joints between it and its parent part; kept `{}`", movable.len(), movable[0].name),
            ));
        }
        let joint = if let Some(j) = movable.first() {
            let (lower, upper) = finite_limits(j.kind, j.lower, j.upper);
            Joint {
                parent,
                child: id,
                kind: j.kind,
                axis_world: (rotation * j.axis_world).normalize_or(Vec3::X),
                origin_world: world_from_asset.transform_point(j.origin_world),
                lower,
                upper,
            }
        } else {
            let origin = asset.link(raw.link).map_or(Vec3::ZERO, |l| l.world_from_link.translation);
            Joint {
                parent,
                child: id,
                kind: JointKind::Fixed,
                axis_world: Vec3::X,
                origin_world: world_from_asset.transform_point(origin),
                lower: 0.0,
                upper: 0.0,
            }
        };
        joints.push(joint);
    }
    let contact_edges = joints.iter().map(|j| [j.parent.min(j.child), j.parent.max(j.child)]).collect();
    let object = TruthObject { id: 1, category: options.category.clone(), supported_by: None, parts, joints, contact_edges };
    let truth = GroundTruth { format: TRUTH_FORMAT.into(), objects: vec![object], floor_z: 0.0 };
    Ok(AssetTruth { truth, part_links, world_from_asset, warnings })
}

/// Limits as finite numbers (JSON has no infinity): an unlimited revolute joint turns ±π, an
/// unlimited prismatic one slides ±1 m.
fn finite_limits(kind: JointKind, lower: f32, upper: f32) -> (f32, f32) {
    let bound = if kind == JointKind::Revolute { std::f32::consts::PI } else { 1.0 };
    let fix = |v: f32, default: f32| if v.is_finite() { v } else { default };
    (fix(lower, -bound), fix(upper, bound))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assets::{AssetGeom, AssetLink, GeomRole};
    use crate::primitive::PrimitiveKind;

    fn link(name: &str, boxes: &[(Vec3, Vec3)]) -> AssetLink {
        AssetLink {
            name: name.into(),
            named: true,
            world_from_link: Pose::IDENTITY,
            geoms: boxes
                .iter()
                .map(|(c, s)| AssetGeom::primitive(PrimitiveKind::Cuboid, *s, Pose::from_translation(*c), GeomRole::Collision))
                .collect(),
        }
    }

    fn joint(name: &str, kind: JointKind, parent: &str, child: &str, axis: Vec3, origin: Vec3) -> AssetJoint {
        AssetJoint {
            name: name.into(),
            kind,
            parent: parent.into(),
            child: child.into(),
            axis_world: axis,
            origin_world: origin,
            lower: 0.0,
            upper: f32::INFINITY,
        }
    }

    #[test]
    fn labels_come_from_names_not_joint_types() {
        assert_eq!(coarse_label("microdoorroot", None, false), "door");
        assert_eq!(coarse_label("drawer_link", None, false), "drawer");
        assert_eq!(coarse_label("drawer1_top", None, false), "drawer");
        assert_eq!(coarse_label("top_door", None, false), "door");
        assert_eq!(coarse_label("lightswitchbaseroot", None, false), "base");
        assert_eq!(coarse_label("knob 1", None, false), "knob");
        assert_eq!(coarse_label("slide_link", None, false), "slide");
        assert_eq!(coarse_label("ovenroot", None, true), "oven");
        assert_eq!(coarse_label("drawercase_link", None, false), "case");
        assert_eq!(coarse_label("thing", None, true), "body");
        assert_eq!(coarse_label("thing", Some("right_hinge"), false), "part");
        // A joint named after both ends: the part it leads to (vocabulary priority) names the child.
        assert_eq!(coarse_label("thing", Some("base__drawer"), false), "drawer");
        assert_eq!(category_from_file_name(std::path::Path::new("a/kitchen_counter_obj.urdf")), "kitchen_counter");
        assert_eq!(category_from_file_name(std::path::Path::new("door1_obj.urdf")), "door");
    }

    #[test]
    fn y_up_asset_stands_on_the_floor_and_empty_links_collapse() {
        // world (no geometry) → body (a 1 × 2 × 0.5 box, 2 m along y = up) → carrier (no geometry,
        // revolute about y) → door (geometry, welded to the carrier).
        let asset = ArticulatedAsset {
            name: "cab".into(),
            links: vec![
                link("world", &[]),
                link("body", &[(Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 2.0, 0.5))]),
                link("carrier", &[]),
                link("door_panel", &[(Vec3::new(0.0, 1.0, 0.3), Vec3::new(1.0, 2.0, 0.05))]),
            ],
            joints: vec![
                joint("fix", JointKind::Fixed, "world", "body", Vec3::X, Vec3::ZERO),
                joint("hinge", JointKind::Revolute, "body", "carrier", Vec3::Y, Vec3::new(0.5, 0.0, 0.3)),
                joint("weld", JointKind::Fixed, "carrier", "door_panel", Vec3::X, Vec3::ZERO),
            ],
            warnings: vec![],
        };
        let out = asset_truth(&asset, &AssetTruthOptions { category: "cabinet".into(), up: UpAxis::Y }).expect("truth");
        let o = &out.truth.objects[0];
        assert_eq!(o.parts.len(), 2);
        assert_eq!((o.parts[0].label.as_str(), o.parts[1].label.as_str()), ("body", "door"));
        let (lo, hi) = o.aabb().expect("bounds");
        assert!(lo.z.abs() < 1e-5 && (hi.z - 2.0).abs() < 1e-5, "{lo} {hi}");
        assert!((lo.x + hi.x).abs() < 1e-5 && (lo.y + hi.y).abs() < 1e-5);
        assert_eq!(o.joints.len(), 1);
        let j = o.joints[0];
        assert_eq!((j.parent, j.child, j.kind), (1, 2, JointKind::Revolute));
        assert!((j.axis_world - Vec3::Z).length() < 1e-5, "{}", j.axis_world);
        assert!(j.upper.is_finite());
        assert_eq!(o.contact_edges, vec![[1, 2]]);
        assert!(o.parts[1].shapes[0].center().z > 0.9);
    }

    #[test]
    fn handle_geoms_inside_a_drawer_body_become_a_handle_part() {
        // LIBERO's wooden cabinet: the drawer body `cabinet_top` holds its box geoms and a handle
        // (a visual mesh named `…_handle_vis`, material `…_handle`, approximated by unnamed
        // collision boxes). The handle becomes its own part, fixed to the drawer; the drawer keeps
        // its slide joint and its name-derived label.
        let mut drawer = link("cabinet_top", &[(Vec3::new(0.0, -0.2, 0.5), Vec3::new(0.6, 0.02, 0.2))]);
        let handle_boxes =
            [(Vec3::new(0.0, -0.24, 0.5), Vec3::new(0.1, 0.01, 0.01)), (Vec3::new(0.04, -0.22, 0.5), Vec3::new(0.01, 0.03, 0.01))];
        drawer.geoms.extend(link("x", &handle_boxes).geoms);
        let mesh = [Vec3::new(-0.05, -0.245, 0.49), Vec3::new(0.05, -0.245, 0.49), Vec3::new(0.05, -0.205, 0.51)];
        drawer.geoms.push(
            AssetGeom::mesh(&mesh, vec![[0, 1, 2]], Pose::IDENTITY, GeomRole::Visual)
                .named(["wooden_cabinet_top_handle_vis", "wooden_cabinet_top_handle"]),
        );
        let asset = ArticulatedAsset {
            name: "wooden_cabinet".into(),
            links: vec![link("base", &[(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.7, 0.4, 1.0))]), drawer],
            joints: vec![joint("top_level", JointKind::Prismatic, "base", "cabinet_top", Vec3::Y, Vec3::ZERO)],
            warnings: vec![],
        };
        let out = asset_truth(&asset, &AssetTruthOptions::default()).expect("truth");
        let o = &out.truth.objects[0];
        let labels: Vec<&str> = o.parts.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["base", "top", "handle"]);
        assert_eq!((o.parts[1].shapes.len(), o.parts[2].shapes.len()), (1, 2), "both handle boxes lie inside the handle mesh");
        let kinds: Vec<(PartId, PartId, JointKind)> = o.joints.iter().map(|j| (j.parent, j.child, j.kind)).collect();
        assert_eq!(kinds, [(1, 2, JointKind::Prismatic), (2, 3, JointKind::Fixed)]);
        assert_eq!(out.part_links.get(&3).map(String::as_str), Some("cabinet_top (handle geoms)"));
        // A link that is a handle itself is not split.
        let mut grip = link("door_handle", &handle_boxes);
        grip.geoms.push(AssetGeom::mesh(&mesh, vec![[0, 1, 2]], Pose::IDENTITY, GeomRole::Visual).named(["handle_vis"]));
        let preferred = grip.preferred_geoms();
        assert!(split_grip(&grip, &preferred).is_none());
    }

    #[test]
    fn an_unnamed_sliding_sash_is_labelled_from_its_joint_not_the_readers_name() {
        // Meta-World's window: the sash body has no name, so the MJCF reader calls it `body2`,
        // which holds the base word `body`; the sash was made fixed. Its joint's name speaks.
        let xml = r#"<mujoco><worldbody>
            <body name="frame"><geom type="box" size="0.2 0.03 0.25" pos="0 0 0.25"/>
              <body pos="0 -0.03 0.05"><joint name="window_slide" type="slide" axis="0 0 1" range="0 0.2"/>
                <geom type="box" size="0.15 0.012 0.1" pos="0 0 0.1"/></body>
            </body></worldbody></mujoco>"#;
        let asset = crate::assets::mjcf::parse_mjcf(xml, std::path::Path::new("window.xml")).expect("parses");
        let made_up: Vec<&str> = asset.links.iter().filter(|l| !l.named).map(|l| l.name.as_str()).collect();
        assert_eq!(made_up.len(), 2, "the world and the sash: {made_up:?}");
        assert!(made_up.contains(&"world") && made_up.iter().any(|n| n.starts_with("body")), "{made_up:?}");
        let out = asset_truth(&asset, &AssetTruthOptions::default()).expect("truth");
        let labels: Vec<&str> = out.truth.objects[0].parts.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["frame", "slide"], "labelled from `window_slide`");
    }

    #[test]
    fn asset_without_geometry_is_an_error() {
        let asset = ArticulatedAsset { name: "empty".into(), links: vec![link("a", &[])], joints: vec![], warnings: vec![] };
        assert!(matches!(asset_truth(&asset, &AssetTruthOptions::default()), Err(BenchError::NoGeometry { .. })));
    }
}
