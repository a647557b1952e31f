//! URDF robots, read as pybullet 3.2.7's `loadURDF` reads them.
//!
//! [`UrdfRobot::parse`] turns a URDF document into links in pybullet's order (depth first from the root,
//! children in the order their joints appear in the file), each with its collision shapes, `<inertial>`
//! block, pybullet's `<contact>` extension and the joint from its parent. [`crate::World::add_urdf`]
//! builds the multibody from it as pybullet's importer does. What pybullet's parser does with each
//! element, and where this one is stricter (it refuses what pybullet silently misreads), is in
//! docs/parity.md, "URDF robots".
//!
//! The XML is read with `roxmltree`; the `urdf-rs` crate was not used because it cannot tell a link
//! without `<inertial>` (pybullet: 1 kg) from one with mass 0, does not read `<contact>`, and reports no
//! line numbers.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use roxmltree::{Document, Node};

use crate::error::{invalid, Result};
use crate::limits::{MAX_ROBOT_LINKS, MAX_SHAPES_PER_LINK, MAX_URDF_BYTES};

/// A pose relative to a parent frame as a URDF `<origin xyz rpy>` gives it (pybullet turns the rpy
/// into a quaternion in the shim, with its own formula).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Origin {
    /// Translation, metres.
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (radians), if the attribute is present.
    pub rpy: Option<[f64; 3]>,
}

/// A collision shape of a link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Geometry {
    /// `<box size="x y z">`: full extents.
    Box([f64; 3]),
    /// `<sphere radius>`.
    Sphere(f64),
    /// `<cylinder radius length>` along z (pybullet makes a 64-vertex convex hull of it).
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Length along z, metres.
        length: f64,
    },
    /// `<capsule radius length>` along z; `length` is the cylinder part.
    Capsule {
        /// Radius, metres.
        radius: f64,
        /// Length of the cylinder part along z, metres.
        length: f64,
    },
}

/// One `<collision>` element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collision {
    /// Pose of the shape in the link frame.
    pub origin: Origin,
    /// The shape.
    pub geometry: Geometry,
}

/// A link's `<inertial>` block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertial {
    /// Pose of the centre of mass (and inertia axes) in the link frame.
    pub origin: Origin,
    /// Mass, kg.
    pub mass: f64,
    /// ixx, ixy, ixz, iyy, iyz, izz, kg m² (used with `URDF_USE_INERTIA_FROM_FILE` only).
    pub inertia: [f64; 6],
}

/// pybullet's `<contact>` extension of a link; `None` leaves Bullet's default.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactInfo {
    /// `<lateral_friction value>` (pybullet sets 0.5 when absent).
    pub lateral_friction: Option<f64>,
    /// `<rolling_friction value>`.
    pub rolling_friction: Option<f64>,
    /// `<spinning_friction value>`.
    pub spinning_friction: Option<f64>,
    /// `<restitution value>`.
    pub restitution: Option<f64>,
    /// `<inertia_scaling value>`: multiplies the link's inertia.
    pub inertia_scaling: Option<f64>,
    /// `<stiffness value>` of the contact (with `damping`, a spring contact).
    pub stiffness: Option<f64>,
    /// `<damping value>` of the contact.
    pub damping: Option<f64>,
    /// `<friction_anchor/>`.
    pub friction_anchor: bool,
}

/// Joint types pybullet's multibody importer builds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Hinge held inside `[lower, upper]` when `lower <= upper`.
    Revolute,
    /// Hinge without limits.
    Continuous,
    /// Slider along the axis, held inside `[lower, upper]` when `lower <= upper`.
    Prismatic,
    /// Rigid.
    Fixed,
}

impl JointKind {
    /// Whether pybullet gives the joint a motor (revolute, continuous and prismatic joints).
    pub fn is_movable(self) -> bool {
        !matches!(self, JointKind::Fixed)
    }
}

/// The joint from a link's parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// The joint's name (a targets CSV names joints by it).
    pub name: String,
    /// Its type.
    pub kind: JointKind,
    /// Joint frame in the parent link's frame.
    pub origin: Origin,
    /// Axis in the joint frame (not normalised, as pybullet leaves it).
    pub axis: [f64; 3],
    /// `<limit lower>` (0 when absent).
    pub lower: f64,
    /// `<limit upper>` (-1 when absent: no limit).
    pub upper: f64,
    /// `<limit effort>`: the motor force of `setJointMotorControlArray` (0 when absent).
    pub effort: f64,
    /// `<limit velocity>` (read, and unused by pybullet's motors).
    pub velocity: f64,
    /// `<dynamics damping>`: viscous damping applied before each step.
    pub damping: f64,
    /// `<dynamics friction>` (read, and unused by Bullet).
    pub friction: f64,
}

/// One link with the joint from its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// The link's name.
    pub name: String,
    /// Index of the parent in [`UrdfRobot::links`]; `None` for the root.
    pub parent: Option<usize>,
    /// The `<inertial>` block; `None` gives pybullet's default (1 kg, inertia diagonal 1, identity frame).
    pub inertial: Option<Inertial>,
    /// Collision shapes in file order.
    pub collisions: Vec<Collision>,
    /// The last `<collision group>` and `<collision mask>` attributes, as pybullet takes them.
    pub collision_group: Option<i32>,
    /// See `collision_group`.
    pub collision_mask: Option<i32>,
    /// The `<contact>` extension.
    pub contact: ContactInfo,
    /// The joint from the parent; `None` for the root.
    pub joint: Option<Joint>,
}

/// A URDF robot in pybullet's link order: `links[0]` is the root (pybullet's base, link -1), link `k`
/// is pybullet's joint / link `k - 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfRobot {
    /// `<robot name>`.
    pub name: String,
    /// The file it was read from (for messages), if any.
    pub source: Option<PathBuf>,
    /// Links, root first, depth first.
    pub links: Vec<Link>,
}

/// Where link inertias come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InertiaSource {
    /// pybullet's default: computed from the collision shapes and the mass.
    #[default]
    Shapes,
    /// `URDF_USE_INERTIA_FROM_FILE`: the `<inertia>` values.
    File,
}

impl std::str::FromStr for InertiaSource {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "shapes" => Ok(InertiaSource::Shapes),
            "file" => Ok(InertiaSource::File),
            _ => Err(invalid(format!(
                "unknown inertia source '{s}' (expected shapes or file)"
            ))),
        }
    }
}

impl std::fmt::Display for InertiaSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            InertiaSource::Shapes => "shapes",
            InertiaSource::File => "file",
        })
    }
}

impl UrdfRobot {
    /// Reads and parses a URDF file; mesh files are looked up relative to it.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::files::read_text(path, MAX_URDF_BYTES, "URDF")?;
        Self::parse_file(&text, path)
    }

    /// Parses the text of the URDF file at `path` (read already, or recorded): as [`UrdfRobot::load`].
    pub(crate) fn parse_file(text: &str, path: &Path) -> Result<Self> {
        let mut robot = Self::parse_in(text, &path.display().to_string(), path.parent())?;
        robot.source = Some(path.to_path_buf());
        Ok(robot)
    }

    /// Parses URDF text; `name` labels messages. Mesh references cannot be resolved without a
    /// directory and are refused.
    pub fn parse(text: &str, name: &str) -> Result<Self> {
        Self::parse_in(text, name, None)
    }

    fn parse_in(text: &str, file: &str, dir: Option<&Path>) -> Result<Self> {
        if text.len() as u64 > MAX_URDF_BYTES {
            return Err(invalid(format!(
                "{file}: more than the {MAX_URDF_BYTES} bytes a robot file may have"
            )));
        }
        crate::files::check_xml_shape(text, file)?;
        let doc = Document::parse(text).map_err(|e| invalid(format!("{file}: not XML: {e}")))?;
        let p = Parser {
            file,
            doc: &doc,
            dir,
        };
        p.robot()
    }

    /// Indices (pybullet joint indices, = link index - 1) of the movable joints, in order.
    pub fn movable_joints(&self) -> Vec<usize> {
        self.links
            .iter()
            .enumerate()
            .skip(1)
            .filter(|(_, l)| l.joint.as_ref().is_some_and(|j| j.kind.is_movable()))
            .map(|(k, _)| k - 1)
            .collect()
    }

    /// The joint of pybullet joint index `j` (link `j + 1`).
    pub fn joint(&self, j: usize) -> Option<&Joint> {
        self.links.get(j + 1).and_then(|l| l.joint.as_ref())
    }

    /// Checks that every link Bullet will move gets an inertia it can take: the root (when it has mass)
    /// and every link on a revolute or continuous joint need positive principal moments. With
    /// [`InertiaSource::File`] they are the `<inertia>` tensor's (pybullet sets a tensor that breaks the
    /// triangle inequality to zero); with [`InertiaSource::Shapes`] a link with mass needs a collision
    /// shape (an empty compound has zero inertia).
    pub fn check_inertia(&self, source: InertiaSource) -> Result<()> {
        for (k, link) in self.links.iter().enumerate() {
            let rotating = match &link.joint {
                None => link.inertial.is_none_or(|i| i.mass > 0.0),
                Some(j) => matches!(j.kind, JointKind::Revolute | JointKind::Continuous),
            };
            if !rotating {
                continue;
            }
            let problem = match source {
                InertiaSource::Shapes if link.collisions.is_empty() => Some(
                    "has mass but no collision shape, so its inertia from the shapes is zero \
                          (give it a shape, or use the file's inertia)"
                        .to_owned(),
                ),
                InertiaSource::Shapes => None,
                InertiaSource::File => {
                    let i = link
                        .inertial
                        .map_or([1.0, 0.0, 0.0, 1.0, 0.0, 1.0], |i| i.inertia);
                    let m = nalgebra::Matrix3::new(
                        i[0], i[1], i[2], i[1], i[3], i[4], i[2], i[4], i[5],
                    );
                    let e = nalgebra::SymmetricEigen::new(m).eigenvalues;
                    let (a, b, c) = (e[0], e[1], e[2]);
                    let bad =
                        !(a > 0.0 && b > 0.0 && c > 0.0) || a > b + c || b > a + c || c > a + b;
                    bad.then(|| {
                        format!(
                            "<inertia> has principal moments ({a:e}, {b:e}, {c:e}): each must be \
                             positive and at most the sum of the other two"
                        )
                    })
                }
            };
            if let Some(problem) = problem {
                let what = if k == 0 { "root link" } else { "link" };
                return Err(invalid(format!(
                    "{}: <link name=\"{}\"> ({what}): {problem}",
                    self.shown(),
                    link.name
                )));
            }
        }
        Ok(())
    }

    /// Name of the file (or of the text) for messages.
    pub fn shown(&self) -> String {
        self.source
            .as_ref()
            .map_or_else(|| self.name.clone(), |p| p.display().to_string())
    }
}

struct Parser<'a, 'input> {
    file: &'a str,
    doc: &'a Document<'input>,
    dir: Option<&'a Path>,
}

fn tag(node: Node) -> String {
    match node.attribute("name") {
        Some(name) => format!("<{} name=\"{name}\">", node.tag_name().name()),
        None => format!("<{}>", node.tag_name().name()),
    }
}

fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == name)
}

impl<'a, 'input> Parser<'a, 'input> {
    /// "FILE:LINE: <element name=..>: problem".
    fn err(&self, node: Node, problem: impl std::fmt::Display) -> crate::Error {
        let line = self.doc.text_pos_at(node.range().start).row;
        invalid(format!("{}:{line}: {}: {problem}", self.file, tag(node)))
    }

    fn attr<'n>(&self, node: Node<'n, 'input>, name: &str) -> Result<&'n str> {
        node.attribute(name)
            .ok_or_else(|| self.err(node, format!("missing attribute {name}")))
    }

    fn number(&self, node: Node, name: &str, text: &str) -> Result<f64> {
        match text.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err(node, format!("{name}=\"{text}\" is not a finite number"))),
        }
    }

    fn num_attr(&self, node: Node, name: &str) -> Result<f64> {
        let text = self.attr(node, name)?;
        self.number(node, name, text)
    }

    fn opt_num(&self, node: Node, name: &str) -> Result<Option<f64>> {
        node.attribute(name)
            .map(|t| self.number(node, name, t))
            .transpose()
    }

    fn vec3(&self, node: Node, name: &str, text: &str) -> Result<[f64; 3]> {
        let parts: Vec<&str> = text.split_whitespace().collect();
        if parts.len() != 3 {
            return Err(self.err(node, format!("{name}=\"{text}\" must be three numbers")));
        }
        let mut v = [0.0; 3];
        for (slot, part) in v.iter_mut().zip(parts) {
            *slot = self.number(node, name, part)?;
        }
        Ok(v)
    }

    fn origin(&self, parent: Node) -> Result<Origin> {
        let Some(o) = child(parent, "origin") else {
            return Ok(Origin::default());
        };
        let xyz = match o.attribute("xyz") {
            Some(t) => self.vec3(o, "xyz", t)?,
            None => [0.0; 3],
        };
        let rpy = o
            .attribute("rpy")
            .map(|t| self.vec3(o, "rpy", t))
            .transpose()?;
        Ok(Origin { xyz, rpy })
    }

    fn positive(&self, node: Node, name: &str) -> Result<f64> {
        let v = self.num_attr(node, name)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(node, format!("{name} must be positive, got {v}")))
        }
    }

    fn robot(&self) -> Result<UrdfRobot> {
        let root = self.doc.root_element();
        if root.tag_name().name() != "robot" {
            return Err(self.err(root, "expected a <robot> element"));
        }
        let name = self.attr(root, "name")?.to_owned();
        let mut links = Vec::new();
        let mut by_name: HashMap<String, usize> = HashMap::new();
        for node in root
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "link")
        {
            let link = self.link(node)?;
            if by_name.insert(link.name.clone(), links.len()).is_some() {
                return Err(self.err(node, "a second link of this name"));
            }
            links.push((node, link));
            if links.len() > MAX_ROBOT_LINKS {
                return Err(self.err(node, format!("more than {MAX_ROBOT_LINKS} links")));
            }
        }
        if links.is_empty() {
            return Err(self.err(root, "no <link>"));
        }
        // Joints in file order: each gives its child a parent and becomes the parent's next child.
        let mut parent_of: Vec<Option<(usize, Joint, Node)>> = vec![None; links.len()];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
        let mut joint_names: HashMap<String, ()> = HashMap::new();
        for node in root
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "joint")
        {
            let joint = self.joint(node)?;
            if joint_names.insert(joint.name.clone(), ()).is_some() {
                return Err(self.err(node, "a second joint of this name"));
            }
            let link_of = |element: &str| -> Result<usize> {
                let e = child(node, element)
                    .ok_or_else(|| self.err(node, format!("missing <{element} link=...>")))?;
                let n = self.attr(e, "link")?;
                by_name
                    .get(n)
                    .copied()
                    .ok_or_else(|| self.err(node, format!("{element} link '{n}' does not exist")))
            };
            let parent = link_of("parent")?;
            let child_index = link_of("child")?;
            if parent == child_index {
                return Err(self.err(node, "a link cannot be its own parent (a cycle)"));
            }
            if parent_of[child_index].is_some() {
                return Err(self.err(
                    node,
                    format!(
                        "link '{}' already has a parent joint",
                        links[child_index].1.name
                    ),
                ));
            }
            parent_of[child_index] = Some((parent, joint, node));
            children[parent].push(child_index);
        }
        let roots: Vec<usize> = (0..links.len())
            .filter(|&i| parent_of[i].is_none())
            .collect();
        let root_index = match roots[..] {
            [r] => r,
            [] => return Err(self.err(root, "no root link: the joints form a cycle")),
            _ => {
                let names: Vec<&str> = roots.iter().map(|&r| links[r].1.name.as_str()).collect();
                return Err(self.err(
                    root,
                    format!(
                        "two or more root links ({}): a robot has one",
                        names.join(", ")
                    ),
                ));
            }
        };
        // Depth first from the root, children in joint order (ConvertURDF2BulletInternal's recursion).
        let mut order = Vec::with_capacity(links.len());
        let mut stack = vec![root_index];
        while let Some(i) = stack.pop() {
            order.push(i);
            stack.extend(children[i].iter().rev());
        }
        if order.len() != links.len() {
            let lost = (0..links.len())
                .find(|i| !order.contains(i))
                .expect("a link outside the tree");
            return Err(self.err(
                links[lost].0,
                "is on a cycle of joints, not in the tree below the root",
            ));
        }
        let mut new_index = vec![0; links.len()];
        for (k, &i) in order.iter().enumerate() {
            new_index[i] = k;
        }
        let mut out = Vec::with_capacity(links.len());
        for &i in &order {
            let mut link = links[i].1.clone();
            if let Some((parent, joint, node)) = parent_of[i].take() {
                link.parent = Some(new_index[parent]);
                if let Some(inertial) = &link.inertial {
                    if inertial.mass <= 0.0 {
                        return Err(self.err(
                            links[i].0,
                            format!(
                                "mass {} kg: only the root link may have mass 0 (a fixed base)",
                                inertial.mass
                            ),
                        ));
                    }
                }
                let _ = node;
                link.joint = Some(joint);
            }
            out.push(link);
        }
        Ok(UrdfRobot {
            name,
            source: None,
            links: out,
        })
    }

    fn link(&self, node: Node) -> Result<Link> {
        let name = self.attr(node, "name")?.to_owned();
        let contact = match child(node, "contact") {
            Some(c) => self.contact(c)?,
            None => ContactInfo::default(),
        };
        let inertial = match child(node, "inertial") {
            Some(i) => Some(self.inertial(i)?),
            None => None,
        };
        // pybullet parses visuals too: a visual mesh it cannot find fails the whole load.
        for v in node
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "visual")
        {
            if let Some(mesh) = child(v, "geometry").and_then(|g| child(g, "mesh")) {
                self.find_mesh(mesh)?;
            }
        }
        let mut collisions = Vec::new();
        let (mut group, mut mask) = (None, None);
        for c in node
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "collision")
        {
            collisions.push(Collision {
                origin: self.origin(c)?,
                geometry: self.geometry(c)?,
            });
            if let Some(g) = c.attribute("group") {
                group = Some(
                    g.trim()
                        .parse::<i32>()
                        .map_err(|_| self.err(c, format!("group=\"{g}\" is not an integer")))?,
                );
            }
            if let Some(m) = c.attribute("mask") {
                mask = Some(
                    m.trim()
                        .parse::<i32>()
                        .map_err(|_| self.err(c, format!("mask=\"{m}\" is not an integer")))?,
                );
            }
            if collisions.len() > MAX_SHAPES_PER_LINK {
                return Err(self.err(
                    node,
                    format!("more than {MAX_SHAPES_PER_LINK} collision shapes"),
                ));
            }
        }
        Ok(Link {
            name,
            parent: None,
            inertial,
            collisions,
            collision_group: group,
            collision_mask: mask,
            contact,
            joint: None,
        })
    }

    fn inertial(&self, node: Node) -> Result<Inertial> {
        let origin = self.origin(node)?;
        let mass_node =
            child(node, "mass").ok_or_else(|| self.err(node, "missing <mass value=...>"))?;
        let mass = self.num_attr(mass_node, "value")?;
        if mass < 0.0 {
            return Err(self.err(mass_node, format!("negative mass {mass}")));
        }
        let i = child(node, "inertia").ok_or_else(|| self.err(node, "missing <inertia>"))?;
        let all = ["ixy", "ixz", "iyz"]
            .iter()
            .all(|k| i.attribute(*k).is_some());
        let off = |k: &str| -> Result<f64> {
            if all {
                self.num_attr(i, k)
            } else {
                Ok(0.0)
            }
        };
        let inertia = [
            self.num_attr(i, "ixx")?,
            off("ixy")?,
            off("ixz")?,
            self.num_attr(i, "iyy")?,
            off("iyz")?,
            self.num_attr(i, "izz")?,
        ];
        for (k, v) in [
            ("ixx", inertia[0]),
            ("iyy", inertia[3]),
            ("izz", inertia[5]),
        ] {
            if v < 0.0 {
                return Err(self.err(i, format!("negative {k} {v}")));
            }
        }
        Ok(Inertial {
            origin,
            mass,
            inertia,
        })
    }

    fn find_mesh(&self, mesh: Node) -> Result<PathBuf> {
        let name = self.attr(mesh, "filename")?;
        let relative = name.strip_prefix("file://").unwrap_or(name);
        let path = match self.dir {
            Some(dir) => dir.join(relative),
            None => PathBuf::from(relative),
        };
        if self.dir.is_none() || !path.is_file() {
            return Err(self.err(mesh, format!("mesh file '{name}' not found")));
        }
        Ok(path)
    }

    fn geometry(&self, collision: Node) -> Result<Geometry> {
        let g = child(collision, "geometry")
            .ok_or_else(|| self.err(collision, "missing <geometry>"))?;
        let shape = g
            .children()
            .find(|c| c.is_element())
            .ok_or_else(|| self.err(g, "no shape inside"))?;
        match shape.tag_name().name() {
            "box" => {
                let size = self.vec3(shape, "size", self.attr(shape, "size")?)?;
                if size.iter().any(|s| *s <= 0.0) {
                    return Err(self.err(shape, "size must be positive"));
                }
                Ok(Geometry::Box(size))
            }
            "sphere" => Ok(Geometry::Sphere(self.positive(shape, "radius")?)),
            "cylinder" => Ok(Geometry::Cylinder {
                radius: self.positive(shape, "radius")?,
                length: self.positive(shape, "length")?,
            }),
            "capsule" => Ok(Geometry::Capsule {
                radius: self.positive(shape, "radius")?,
                length: self.positive(shape, "length")?,
            }),
            "mesh" => {
                self.find_mesh(shape)?;
                Err(self.err(
                    shape,
                    "mesh collision shapes are not supported (boxes, spheres, cylinders and capsules are)",
                ))
            }
            other => Err(self.err(
                shape,
                format!(
                    "unsupported geometry <{other}> (boxes, spheres, cylinders and capsules are)"
                ),
            )),
        }
    }

    fn contact(&self, node: Node) -> Result<ContactInfo> {
        let value = |name: &str| -> Result<Option<f64>> {
            match child(node, name) {
                Some(e) => Ok(Some(self.num_attr(e, "value")?)),
                None => Ok(None),
            }
        };
        let c = ContactInfo {
            lateral_friction: value("lateral_friction")?,
            rolling_friction: value("rolling_friction")?,
            spinning_friction: value("spinning_friction")?,
            restitution: value("restitution")?,
            inertia_scaling: value("inertia_scaling")?,
            stiffness: value("stiffness")?,
            damping: value("damping")?,
            friction_anchor: child(node, "friction_anchor").is_some(),
        };
        for (name, v) in [
            ("lateral_friction", c.lateral_friction),
            ("rolling_friction", c.rolling_friction),
            ("spinning_friction", c.spinning_friction),
            ("restitution", c.restitution),
            ("stiffness", c.stiffness),
            ("damping", c.damping),
        ] {
            if v.is_some_and(|v| v < 0.0) {
                return Err(self.err(node, format!("{name} must be >= 0")));
            }
        }
        if c.inertia_scaling.is_some_and(|v| v <= 0.0) {
            return Err(self.err(node, "inertia_scaling must be positive"));
        }
        Ok(c)
    }

    fn joint(&self, node: Node) -> Result<Joint> {
        let name = self.attr(node, "name")?.to_owned();
        let kind = match self.attr(node, "type")? {
            "revolute" => JointKind::Revolute,
            "continuous" => JointKind::Continuous,
            "prismatic" => JointKind::Prismatic,
            "fixed" => JointKind::Fixed,
            other => {
                return Err(self.err(
                    node,
                    format!(
                        "joint type '{other}' is not supported (revolute, continuous, prismatic and fixed are)"
                    ),
                ))
            }
        };
        let origin = self.origin(node)?;
        let mut axis = [1.0, 0.0, 0.0];
        if kind.is_movable() {
            if let Some(a) = child(node, "axis") {
                if let Some(t) = a.attribute("xyz") {
                    axis = self.vec3(a, "xyz", t)?;
                }
                if axis.iter().all(|v| *v == 0.0) {
                    return Err(self.err(a, "the axis must not be zero"));
                }
            }
        }
        let (mut lower, mut upper, mut effort, mut velocity) = (0.0, -1.0, 0.0, 0.0);
        match child(node, "limit") {
            Some(l) => {
                lower = self.opt_num(l, "lower")?.unwrap_or(lower);
                upper = self.opt_num(l, "upper")?.unwrap_or(upper);
                effort = self.opt_num(l, "effort")?.unwrap_or(effort);
                velocity = self.opt_num(l, "velocity")?.unwrap_or(velocity);
                if effort < 0.0 {
                    return Err(self.err(l, format!("negative effort {effort}")));
                }
            }
            None if matches!(kind, JointKind::Revolute | JointKind::Prismatic) => {
                return Err(self.err(node, "a revolute or prismatic joint needs a <limit>"));
            }
            None => {}
        }
        let (mut damping, mut friction) = (0.0, 0.0);
        if let Some(d) = child(node, "dynamics") {
            if d.attribute("damping").is_none() && d.attribute("friction").is_none() {
                return Err(self.err(d, "needs damping or friction"));
            }
            damping = self.opt_num(d, "damping")?.unwrap_or(0.0);
            friction = self.opt_num(d, "friction")?.unwrap_or(0.0);
            if damping < 0.0 || friction < 0.0 {
                return Err(self.err(d, "damping and friction must be >= 0"));
            }
        }
        Ok(Joint {
            name,
            kind,
            origin,
            axis,
            lower,
            upper,
            effort,
            velocity,
            damping,
            friction,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO: &str = r#"<robot name="r">
      <link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1"/></inertial>
        <collision><geometry><box size="1 1 1"/></geometry></collision></link>
      <link name="c"/>
      <link name="b"/>
      <joint name="j2" type="fixed"><parent link="a"/><child link="b"/></joint>
      <joint name="j1" type="continuous"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/></joint>
    </robot>"#;

    #[test]
    fn links_come_depth_first_in_joint_order() {
        let r = UrdfRobot::parse(TWO, "two").unwrap();
        let names: Vec<&str> = r.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["a", "b", "c"]);
        assert_eq!(r.links[2].parent, Some(1));
        assert_eq!(r.movable_joints(), vec![1]);
        assert!(r.links[1].inertial.is_none());
    }

    fn err(text: &str) -> String {
        UrdfRobot::parse(text, "bad.urdf").unwrap_err().to_string()
    }

    #[test]
    fn bad_input_is_one_line_naming_file_and_element() {
        let cases = [
            ("<robot", "not XML"),
            ("<robot name='r'/>", "no <link>"),
            (
                "<robot name='r'><link name='a'/><link name='b'/></robot>",
                "two or more root links",
            ),
            (
                "<robot name='r'><link name='a'/><joint name='j' type='fixed'><parent link='a'/><child link='x'/></joint></robot>",
                "child link 'x' does not exist",
            ),
            (
                "<robot name='r'><link name='r0'/><link name='a'/><link name='b'/>\
                 <joint name='j' type='fixed'><parent link='a'/><child link='b'/></joint>\
                 <joint name='k' type='fixed'><parent link='b'/><child link='a'/></joint></robot>",
                "cycle",
            ),
            (
                "<robot name='r'><link name='a'><inertial><mass value='-1'/><inertia ixx='1' iyy='1' izz='1'/></inertial></link></robot>",
                "negative mass",
            ),
            (
                "<robot name='r'><link name='a'><collision><geometry><mesh filename='m.stl'/></geometry></collision></link></robot>",
                "mesh file 'm.stl' not found",
            ),
            (
                "<robot name='r'><link name='a'><collision><geometry><box size='1 1'/></geometry></collision></link></robot>",
                "three numbers",
            ),
        ];
        for (text, expected) in cases {
            let e = err(text);
            assert!(e.contains(expected), "{e}");
            assert!(e.contains("bad.urdf"), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
