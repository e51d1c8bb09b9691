//! MJCF (`MuJoCo` XML) import via `roxmltree`, for the subset that describes articulated objects.
//!
//! Read: `<include file>` (relative to the including file, spliced in place, loops refused);
//! `<compiler angle eulerseq meshdir assetdir>` (angles default to **degrees**, as in `MuJoCo`);
//! `<default>` classes (nested, inherited) applied through `class` and the bodies' `childclass`
//! to geom, joint and mesh attributes; `<asset><mesh name file scale>` (or inline `vertex` /
//! `face`); nested `<body>` and `<frame>` with `pos` and one of `quat`, `axisangle`, `euler`,
//! `xyaxes`, `zaxis`; `<joint type="hinge|slide" pos axis range limited>`;
//! `<geom type="box|sphere|capsule|cylinder|mesh" size pos (orientation) fromto contype
//! conaffinity mesh>`. Unnamed bodies are called `body<id>` with `MuJoCo`'s depth-first body id
//! (the world body is 0), so names match what `MuJoCo` reports.
//!
//! Tolerated (warnings): ball and free joints, plane/ellipsoid/hfield geoms, missing or
//! unreadable mesh files, unknown classes. Unknown elements and attributes are ignored.
//! Errors: malformed XML, missing include files, include loops, and numbers that do not parse
//! or have the wrong count (the message names the file, line, element and attribute).
//!
//! Mesh files are looked up, first match wins, in: the model folder joined with `meshdir` (else
//! `assetdir`), the model folder, the folder of the file that declares the mesh joined with
//! `meshdir`, and that folder itself. `MuJoCo`'s own rule is the first; the others make include
//! files that reference meshes relative to themselves work too.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use super::mesh::TriMesh;
use super::model::{ArticulatedAsset, AssetGeom, AssetJoint, AssetLink, GeomRole};
use super::{AssetError, MeshCache};
use crate::kinematics::JointKind;
use crate::math::{Pose, Quat, Vec3};
use crate::primitive::PrimitiveKind;
use crate::report::Warning;

/// How deep includes may nest before the reader gives up.
const MAX_INCLUDE_DEPTH: usize = 32;

/// Reads an MJCF file (see the module docs for what is understood).
pub fn load_mjcf(path: &Path) -> Result<ArticulatedAsset, AssetError> {
    let root = load_tree(path, &mut Vec::new())?;
    Reader::new(path, &root)?.read(&root)
}

/// Reads MJCF text as if it were the file `path` (includes and meshes resolve from its folder).
pub fn parse_mjcf(text: &str, path: &Path) -> Result<ArticulatedAsset, AssetError> {
    let root = parse_tree(text, path, &mut vec![path.to_path_buf()])?;
    Reader::new(path, &root)?.read(&root)
}

// ---------------------------------------------------------------------------------------------
// The XML tree with includes spliced in; every element remembers where it was written.

#[derive(Clone, Debug)]
struct Elem {
    tag: String,
    attrs: Vec<(String, String)>,
    children: Vec<Elem>,
    file: Rc<PathBuf>,
    line: u32,
}

impl Elem {
    fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    fn children_named<'e>(&'e self, tag: &'e str) -> impl Iterator<Item = &'e Elem> + 'e {
        self.children.iter().filter(move |c| c.tag == tag)
    }
}

fn load_tree(path: &Path, stack: &mut Vec<PathBuf>) -> Result<Elem, AssetError> {
    if stack.iter().any(|p| p == path) {
        return Err(AssetError::Structure { path: path.to_path_buf(), message: "include loop: the file includes itself".into() });
    }
    if stack.len() >= MAX_INCLUDE_DEPTH {
        return Err(AssetError::Structure {
            path: path.to_path_buf(),
            message: format!("includes nested deeper than {MAX_INCLUDE_DEPTH}"),
        });
    }
    let text = super::read_text(path)?;
    stack.push(path.to_path_buf());
    let tree = parse_tree(&text, path, stack);
    stack.pop();
    tree
}

fn parse_tree(text: &str, path: &Path, stack: &mut Vec<PathBuf>) -> Result<Elem, AssetError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| AssetError::Xml { path: path.to_path_buf(), message: e.to_string() })?;
    let file = Rc::new(path.to_path_buf());
    convert(&doc, doc.root_element(), &file, stack)
}

fn convert(doc: &roxmltree::Document, node: roxmltree::Node, file: &Rc<PathBuf>, stack: &mut Vec<PathBuf>) -> Result<Elem, AssetError> {
    let mut children = Vec::new();
    for child in node.children().filter(roxmltree::Node::is_element) {
        if child.tag_name().name() == "include" {
            let line = doc.text_pos_at(child.range().start).row;
            let Some(name) = child.attribute("file") else {
                return Err(bad(file, line, "include", "file", "", "a file name"));
            };
            let dir = file.parent().unwrap_or(Path::new("."));
            let included = load_tree(&dir.join(name), stack)?;
            children.extend(included.children);
        } else {
            children.push(convert(doc, child, file, stack)?);
        }
    }
    Ok(Elem {
        tag: node.tag_name().name().to_owned(),
        attrs: node.attributes().map(|a| (a.name().to_owned(), a.value().to_owned())).collect(),
        children,
        file: Rc::clone(file),
        line: doc.text_pos_at(node.range().start).row,
    })
}

fn bad(file: &Path, line: u32, element: &str, attribute: &str, value: &str, expected: &str) -> AssetError {
    AssetError::BadAttribute {
        path: file.to_path_buf(),
        line,
        element: element.to_owned(),
        attribute: attribute.to_owned(),
        value: value.to_owned(),
        expected: expected.to_owned(),
    }
}

// ---------------------------------------------------------------------------------------------
// Attributes after default classes: each value remembers the element it was written on.

#[derive(Clone, Debug)]
struct AttrVal {
    value: String,
    file: Rc<PathBuf>,
    line: u32,
    element: String,
}

/// Attribute name → value, for one element kind.
type AttrMap = BTreeMap<String, AttrVal>;
/// Element kind (geom, joint, mesh, ...) → defaulted attributes.
type ClassAttrs = BTreeMap<String, AttrMap>;

fn own_attrs(e: &Elem) -> AttrMap {
    e.attrs
        .iter()
        .map(|(k, v)| (k.clone(), AttrVal { value: v.clone(), file: Rc::clone(&e.file), line: e.line, element: e.tag.clone() }))
        .collect()
}

fn text<'a>(attrs: &'a AttrMap, name: &str) -> Option<&'a str> {
    attrs.get(name).map(|a| a.value.as_str())
}

/// All numbers of an attribute (whitespace-separated); `Ok(None)` when absent.
fn numbers(attrs: &AttrMap, name: &str) -> Result<Option<Vec<f64>>, AssetError> {
    let Some(a) = attrs.get(name) else { return Ok(None) };
    let mut out = Vec::new();
    for token in a.value.split(|c: char| c.is_whitespace() || c == ',').filter(|t| !t.is_empty()) {
        match token.parse::<f64>() {
            Ok(x) if x.is_finite() => out.push(x),
            _ => return Err(bad(&a.file, a.line, &a.element, name, &a.value, "finite numbers")),
        }
    }
    Ok(Some(out))
}

/// Exactly `n` numbers; `Ok(None)` when absent.
fn fixed<const N: usize>(attrs: &AttrMap, name: &str) -> Result<Option<[f64; N]>, AssetError> {
    let Some(values) = numbers(attrs, name)? else { return Ok(None) };
    let a = &attrs[name];
    <[f64; N]>::try_from(values.as_slice()).map(Some).map_err(|_| bad(&a.file, a.line, &a.element, name, &a.value, &format!("{N} numbers")))
}

fn v3(x: [f64; 3]) -> Vec3 {
    Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32)
}

// ---------------------------------------------------------------------------------------------

#[derive(Clone, Debug)]
struct Compiler {
    degrees: bool,
    eulerseq: String,
    meshdir: Option<String>,
    assetdir: Option<String>,
}

struct MeshAsset {
    /// Resolved file, or the inline mesh.
    source: Result<MeshSource, String>,
    scale: Vec3,
}

enum MeshSource {
    File(PathBuf),
    Inline(TriMesh),
}

struct Reader {
    path: PathBuf,
    compiler: Compiler,
    classes: BTreeMap<String, ClassAttrs>,
    meshes: BTreeMap<String, MeshAsset>,
    mesh_cache: MeshCache,
    asset: ArticulatedAsset,
    body_count: usize,
}

impl Reader {
    fn new(path: &Path, root: &Elem) -> Result<Self, AssetError> {
        let mut compiler = Compiler { degrees: true, eulerseq: "xyz".into(), meshdir: None, assetdir: None };
        for c in root.children_named("compiler") {
            if let Some(angle) = c.attr("angle") {
                compiler.degrees = match angle {
                    "degree" => true,
                    "radian" => false,
                    other => return Err(bad(&c.file, c.line, "compiler", "angle", other, "\"degree\" or \"radian\"")),
                };
            }
            if let Some(seq) = c.attr("eulerseq") {
                if seq.len() != 3 || !seq.chars().all(|ch| "xyzXYZ".contains(ch)) {
                    return Err(bad(&c.file, c.line, "compiler", "eulerseq", seq, "three of x, y, z, X, Y, Z"));
                }
                seq.clone_into(&mut compiler.eulerseq);
            }
            if let Some(dir) = c.attr("meshdir") {
                compiler.meshdir = Some(dir.to_owned());
            }
            if let Some(dir) = c.attr("assetdir") {
                compiler.assetdir = Some(dir.to_owned());
            }
        }
        let name = root
            .attr("model")
            .map(str::to_owned)
            .or_else(|| path.file_stem().and_then(|s| s.to_str()).map(str::to_owned))
            .unwrap_or_else(|| "mjcf".to_owned());
        let mut reader = Self {
            path: path.to_path_buf(),
            compiler,
            classes: BTreeMap::new(),
            meshes: BTreeMap::new(),
            mesh_cache: MeshCache::default(),
            asset: ArticulatedAsset { name, ..ArticulatedAsset::default() },
            body_count: 0,
        };
        reader.classes.insert("main".into(), ClassAttrs::new());
        for d in root.children_named("default") {
            let class = d.attr("class").unwrap_or("main").to_owned();
            let parent = reader.classes.get("main").cloned().unwrap_or_default();
            reader.collect_defaults(d, class, &parent);
        }
        for a in root.children_named("asset") {
            for m in a.children_named("mesh") {
                reader.declare_mesh(m)?;
            }
        }
        Ok(reader)
    }

    fn warn(&mut self, subject: impl Into<String>, message: impl Into<String>) {
        self.asset.warnings.push(Warning::new("assets", subject, message));
    }

    fn collect_defaults(&mut self, d: &Elem, class: String, parent: &ClassAttrs) {
        let mut attrs = self.classes.get(&class).cloned().unwrap_or_else(|| parent.clone());
        for child in d.children.iter().filter(|c| c.tag != "default") {
            attrs.entry(child.tag.clone()).or_default().extend(own_attrs(child));
        }
        self.classes.insert(class, attrs.clone());
        for nested in d.children_named("default") {
            let Some(name) = nested.attr("class") else {
                self.warn(format!("{}:{}", nested.file.display(), nested.line), "nested <default> without a class; ignored");
                continue;
            };
            self.collect_defaults(nested, name.to_owned(), &attrs);
        }
    }

    /// An element's attributes over its class defaults (`class`, else the inherited childclass).
    fn resolved(&mut self, e: &Elem, childclass: Option<&str>) -> AttrMap {
        let class = e.attr("class").or(childclass).unwrap_or("main");
        let defaults = if let Some(c) = self.classes.get(class) {
            c.get(&e.tag).cloned().unwrap_or_default()
        } else {
            let subject = format!("{}:{}", e.file.display(), e.line);
            self.warn(subject, format!("<{}> uses unknown class {class:?}; main defaults used", e.tag));
            self.classes.get("main").and_then(|c| c.get(&e.tag)).cloned().unwrap_or_default()
        };
        let mut attrs = defaults;
        attrs.extend(own_attrs(e));
        attrs.remove("class");
        attrs
    }

    fn declare_mesh(&mut self, m: &Elem) -> Result<(), AssetError> {
        let attrs = self.resolved(m, None);
        let file = text(&attrs, "file").map(str::to_owned);
        let name = text(&attrs, "name")
            .map(str::to_owned)
            .or_else(|| file.as_deref().and_then(|f| Path::new(f).file_stem()).and_then(|s| s.to_str()).map(str::to_owned));
        let Some(name) = name else {
            self.warn(format!("{}:{}", m.file.display(), m.line), "<mesh> without name or file; ignored");
            return Ok(());
        };
        let scale = fixed::<3>(&attrs, "scale")?.map_or(Vec3::ONE, v3);
        let source = if let Some(file) = file {
            self.resolve_mesh_file(&m.file, &file).map(MeshSource::File).ok_or_else(|| format!("mesh file {file:?} not found"))
        } else if let (Some(vertex), Some(face)) = (numbers(&attrs, "vertex")?, numbers(&attrs, "face")?) {
            let vertices: Vec<Vec3> = vertex.chunks_exact(3).map(|c| v3([c[0], c[1], c[2]])).collect();
            let n = vertices.len();
            let triangles: Vec<[u32; 3]> = face.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]).collect();
            if face.iter().any(|&i| i < 0.0 || i.fract() != 0.0 || i as usize >= n) {
                Err(format!("inline mesh {name:?} has face indices outside its {n} vertices"))
            } else {
                Ok(MeshSource::Inline(TriMesh { vertices, triangles }))
            }
        } else {
            Err(format!("mesh {name:?} has neither a file nor vertex and face data"))
        };
        self.meshes.insert(name, MeshAsset { source, scale });
        Ok(())
    }

    fn resolve_mesh_file(&self, declared_in: &Path, file: &str) -> Option<PathBuf> {
        let file_path = Path::new(file);
        if file_path.is_absolute() {
            return file_path.is_file().then(|| file_path.to_path_buf());
        }
        let model_dir = self.path.parent().unwrap_or(Path::new("."));
        let decl_dir = declared_in.parent().unwrap_or(Path::new("."));
        let dir = self.compiler.meshdir.as_deref().or(self.compiler.assetdir.as_deref());
        let mut candidates = Vec::new();
        if let Some(d) = dir {
            candidates.push(model_dir.join(d).join(file));
        }
        candidates.push(model_dir.join(file));
        if let Some(d) = dir {
            candidates.push(decl_dir.join(d).join(file));
        }
        candidates.push(decl_dir.join(file));
        candidates.into_iter().find(|p| p.is_file())
    }

    fn read(mut self, root: &Elem) -> Result<ArticulatedAsset, AssetError> {
        self.asset.links.push(AssetLink { name: "world".into(), named: false, world_from_link: Pose::IDENTITY, geoms: Vec::new() });
        self.body_count = 1;
        for wb in root.children_named("worldbody") {
            self.walk(wb, 0, Pose::IDENTITY, None, true)?;
        }
        Ok(self.asset)
    }

    /// Reads the children of a body (or frame) whose link is `link` and whose frame is `world_from_frame`.
    fn walk(&mut self, e: &Elem, link: usize, world_from_frame: Pose, childclass: Option<&str>, is_world: bool) -> Result<(), AssetError> {
        for child in &e.children {
            match child.tag.as_str() {
                "geom" => {
                    let attrs = self.resolved(child, childclass);
                    if let Some(geom) = self.geom(child, &attrs, world_from_frame)? {
                        self.asset.links[link].geoms.push(geom);
                    }
                }
                "body" => self.body(child, link, world_from_frame, childclass)?,
                "frame" => {
                    let attrs = own_attrs(child);
                    let world_from_inner = world_from_frame * self.local_pose(&attrs)?;
                    let inner_class = child.attr("childclass").or(childclass);
                    self.walk(child, link, world_from_inner, inner_class, is_world)?;
                }
                "joint" | "freejoint" if is_world => {
                    let subject = format!("{}:{}", child.file.display(), child.line);
                    self.warn(subject, "joint in the world body; ignored");
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn body(&mut self, b: &Elem, parent: usize, world_from_parent: Pose, inherited_class: Option<&str>) -> Result<(), AssetError> {
        let id = self.body_count;
        self.body_count += 1;
        let named = b.attr("name").is_some();
        let name = b.attr("name").map_or_else(|| format!("body{id}"), str::to_owned);
        let world_from_body = world_from_parent * self.local_pose(&own_attrs(b))?;
        let childclass = b.attr("childclass").or(inherited_class);
        let index = self.asset.links.len();
        self.asset.links.push(AssetLink { name: name.clone(), named, world_from_link: world_from_body, geoms: Vec::new() });
        let parent_name = self.asset.links[parent].name.clone();

        let mut joints = Vec::new();
        self.collect_joints(b, world_from_body, childclass, &name, &parent_name, &mut joints)?;
        if joints.is_empty() {
            joints.push(AssetJoint {
                name: format!("{name}_fixed"),
                kind: JointKind::Fixed,
                parent: parent_name,
                child: name.clone(),
                axis_world: Vec3::X,
                origin_world: world_from_body.translation,
                lower: 0.0,
                upper: 0.0,
            });
        } else if joints.len() > 1 {
            self.warn(
                format!("body {name}"),
                format!("{} joints in one body; each is reported with the same parent and child", joints.len()),
            );
        }
        self.asset.joints.extend(joints);
        self.walk(b, index, world_from_body, childclass, false)
    }

    /// The joints written in a body (directly or inside its frames), in document order.
    fn collect_joints(
        &mut self,
        e: &Elem,
        world_from_frame: Pose,
        childclass: Option<&str>,
        body: &str,
        parent: &str,
        out: &mut Vec<AssetJoint>,
    ) -> Result<(), AssetError> {
        for child in &e.children {
            match child.tag.as_str() {
                "joint" => {
                    let attrs = self.resolved(child, childclass);
                    if let Some(j) = self.joint(&attrs, world_from_frame, body, parent, out.len())? {
                        out.push(j);
                    }
                }
                "freejoint" => self.warn(format!("body {body}"), "free joint ignored (the body is kept welded at its rest pose)"),
                "frame" => {
                    let world_from_inner = world_from_frame * self.local_pose(&own_attrs(child))?;
                    let inner_class = child.attr("childclass").or(childclass);
                    self.collect_joints(child, world_from_inner, inner_class, body, parent, out)?;
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn joint(
        &mut self,
        attrs: &AttrMap,
        world_from_body: Pose,
        body: &str,
        parent: &str,
        k: usize,
    ) -> Result<Option<AssetJoint>, AssetError> {
        let name = text(attrs, "name").map_or_else(|| format!("{body}_joint{k}"), str::to_owned);
        let kind = match text(attrs, "type").unwrap_or("hinge") {
            "hinge" => JointKind::Revolute,
            "slide" => JointKind::Prismatic,
            other => {
                self.warn(format!("joint {name}"), format!("{other} joints are not supported; ignored"));
                return Ok(None);
            }
        };
        let pos = fixed::<3>(attrs, "pos")?.map_or(Vec3::ZERO, v3);
        let axis_local = fixed::<3>(attrs, "axis")?.map_or(Vec3::Z, v3);
        let axis_local = if axis_local.length() < 1e-9 {
            self.warn(format!("joint {name}"), "zero axis; +Z used");
            Vec3::Z
        } else {
            axis_local.normalize()
        };
        let range = fixed::<2>(attrs, "range")?;
        let limited = match text(attrs, "limited").unwrap_or("auto") {
            "true" => true,
            "false" => false,
            "auto" => range.is_some(),
            other => {
                let a = &attrs["limited"];
                return Err(bad(&a.file, a.line, &a.element, "limited", other, "true, false or auto"));
            }
        };
        let (lower, upper) = match (limited, range) {
            (false, _) => (f32::NEG_INFINITY, f32::INFINITY),
            (true, None) => {
                self.warn(format!("joint {name}"), "limited without a range; range 0 0 used");
                (0.0, 0.0)
            }
            (true, Some([lo, hi])) => {
                let unit = if kind == JointKind::Revolute && self.compiler.degrees { std::f64::consts::PI / 180.0 } else { 1.0 };
                ((lo * unit) as f32, (hi * unit) as f32)
            }
        };
        Ok(Some(AssetJoint {
            name,
            kind,
            parent: parent.to_owned(),
            child: body.to_owned(),
            axis_world: (world_from_body.rotation * axis_local).normalize(),
            origin_world: world_from_body.transform_point(pos),
            lower,
            upper,
        }))
    }

    fn geom(&mut self, e: &Elem, attrs: &AttrMap, world_from_body: Pose) -> Result<Option<AssetGeom>, AssetError> {
        let subject = format!("{}:{}", e.file.display(), e.line);
        let contype = int_attr(attrs, "contype")?.unwrap_or(1);
        let conaffinity = int_attr(attrs, "conaffinity")?.unwrap_or(1);
        let role = if contype == 0 && conaffinity == 0 { GeomRole::Visual } else { GeomRole::Collision };
        let kind = text(attrs, "type").unwrap_or("sphere").to_owned();
        let size = numbers(attrs, "size")?.unwrap_or_default();
        let size_at = |i: usize| -> Result<f32, AssetError> {
            size.get(i).map(|&x| x as f32).ok_or_else(|| match attrs.get("size") {
                Some(a) => bad(&a.file, a.line, &a.element, "size", &a.value, &format!("at least {} numbers for a {kind}", i + 1)),
                None => bad(&e.file, e.line, &e.tag, "size", "", &format!("a size for a {kind}")),
            })
        };
        let fromto = fixed::<6>(attrs, "fromto")?;
        // fromto: the segment gives centre, z axis and length (capsule, cylinder, box, ellipsoid).
        let (local, segment_length) = match fromto {
            Some(ft) if matches!(kind.as_str(), "capsule" | "cylinder" | "box" | "ellipsoid") => {
                let a = v3([ft[0], ft[1], ft[2]]);
                let b = v3([ft[3], ft[4], ft[5]]);
                let d = b - a;
                if d.length() < 1e-9 {
                    let a = &attrs["fromto"];
                    return Err(bad(&a.file, a.line, &a.element, "fromto", &a.value, "two distinct points"));
                }
                (Pose::from_parts(0.5 * (a + b), Quat::from_rotation_arc(Vec3::Z, d.normalize())), Some(d.length()))
            }
            _ => (self.local_pose(attrs)?, None),
        };
        let world_from_geom = world_from_body * local;
        let geom = match kind.as_str() {
            "box" => {
                let half_z = match segment_length {
                    Some(l) => 0.5 * l,
                    None => size_at(2)?,
                };
                AssetGeom::primitive(PrimitiveKind::Cuboid, 2.0 * Vec3::new(size_at(0)?, size_at(1)?, half_z), world_from_geom, role)
            }
            "sphere" => AssetGeom::primitive(PrimitiveKind::Sphere, Vec3::splat(2.0 * size_at(0)?), world_from_geom, role),
            "cylinder" | "capsule" => {
                let r = size_at(0)?;
                let straight = match segment_length {
                    Some(l) => l,
                    None => 2.0 * size_at(1)?,
                };
                let (prim, total) =
                    if kind == "cylinder" { (PrimitiveKind::Cylinder, straight) } else { (PrimitiveKind::Capsule, straight + 2.0 * r) };
                AssetGeom::primitive(prim, Vec3::new(2.0 * r, 2.0 * r, total), world_from_geom, role)
            }
            "mesh" => {
                let Some(mesh_name) = text(attrs, "mesh").map(str::to_owned) else {
                    self.warn(subject, "mesh geom without a mesh attribute; skipped");
                    return Ok(None);
                };
                let loaded = match self.meshes.get(&mesh_name) {
                    None => Err(format!("mesh geom names unknown mesh {mesh_name:?}; skipped")),
                    Some(MeshAsset { source: Err(why), .. }) => Err(format!("{why}; geom skipped")),
                    Some(MeshAsset { source: Ok(MeshSource::Inline(m)), scale }) => Ok(m.clone().scaled(*scale)),
                    Some(MeshAsset { source: Ok(MeshSource::File(path)), scale }) => {
                        let (path, scale) = (path.clone(), *scale);
                        self.mesh_cache.get(&path).map(|m| m.clone().scaled(scale)).map_err(|why| format!("{why}; geom skipped"))
                    }
                };
                match loaded {
                    Ok(mesh) => AssetGeom::mesh(&mesh.vertices, mesh.triangles, world_from_geom, role),
                    Err(why) => {
                        self.warn(subject, why);
                        return Ok(None);
                    }
                }
            }
            other => {
                self.warn(subject, format!("{other} geoms are not imported; skipped"));
                return Ok(None);
            }
        };
        let names = ["name", "mesh", "material"].into_iter().filter_map(|a| text(attrs, a));
        Ok(Some(geom.named(names)))
    }

    /// `pos` and the orientation (`quat`, `axisangle`, `euler`, `xyaxes`, `zaxis`) of an element.
    fn local_pose(&self, attrs: &AttrMap) -> Result<Pose, AssetError> {
        let pos = fixed::<3>(attrs, "pos")?.map_or(Vec3::ZERO, v3);
        Ok(Pose::from_parts(pos, self.orientation(attrs)?))
    }

    fn orientation(&self, attrs: &AttrMap) -> Result<Quat, AssetError> {
        let unit = if self.compiler.degrees { std::f64::consts::PI / 180.0 } else { 1.0 };
        let fail = |name: &str, expected: &str| {
            let a = &attrs[name];
            bad(&a.file, a.line, &a.element, name, &a.value, expected)
        };
        if let Some([w, x, y, z]) = fixed::<4>(attrs, "quat")? {
            let q = glam::DQuat::from_xyzw(x, y, z, w);
            if q.length() < 1e-12 {
                return Err(fail("quat", "a non-zero quaternion (w x y z)"));
            }
            return Ok(q.normalize().as_quat());
        }
        if let Some([x, y, z, a]) = fixed::<4>(attrs, "axisangle")? {
            let axis = glam::DVec3::new(x, y, z);
            if axis.length() < 1e-12 {
                return Err(fail("axisangle", "a non-zero axis and an angle"));
            }
            return Ok(glam::DQuat::from_axis_angle(axis.normalize(), a * unit).as_quat());
        }
        if let Some(angles) = fixed::<3>(attrs, "euler")? {
            let mut q = glam::DQuat::IDENTITY;
            for (ch, angle) in self.compiler.eulerseq.chars().zip(angles) {
                let axis = match ch.to_ascii_lowercase() {
                    'x' => glam::DVec3::X,
                    'y' => glam::DVec3::Y,
                    _ => glam::DVec3::Z,
                };
                let r = glam::DQuat::from_axis_angle(axis, angle * unit);
                // Lower case: axes of the moving frame (intrinsic); upper case: parent axes.
                q = if ch.is_ascii_lowercase() { q * r } else { r * q };
            }
            return Ok(q.normalize().as_quat());
        }
        if let Some(v) = fixed::<6>(attrs, "xyaxes")? {
            let x = glam::DVec3::new(v[0], v[1], v[2]);
            let y = glam::DVec3::new(v[3], v[4], v[5]);
            let x = x.try_normalize().ok_or_else(|| fail("xyaxes", "two independent axes"))?;
            let y = (y - x * x.dot(y)).try_normalize().ok_or_else(|| fail("xyaxes", "two independent axes"))?;
            let z = x.cross(y);
            return Ok(glam::DQuat::from_mat3(&glam::DMat3::from_cols(x, y, z)).normalize().as_quat());
        }
        if let Some(v) = fixed::<3>(attrs, "zaxis")? {
            let z = glam::DVec3::new(v[0], v[1], v[2]).try_normalize().ok_or_else(|| fail("zaxis", "a non-zero axis"))?;
            return Ok(glam::DQuat::from_rotation_arc(glam::DVec3::Z, z).as_quat());
        }
        Ok(Quat::IDENTITY)
    }
}

fn int_attr(attrs: &AttrMap, name: &str) -> Result<Option<i64>, AssetError> {
    let Some(a) = attrs.get(name) else { return Ok(None) };
    a.value.trim().parse::<i64>().map(Some).map_err(|_| bad(&a.file, a.line, &a.element, name, &a.value, "an integer"))
}
