//! Media beyond pybullet's rigid world (issues 59 and 60): a granular medium (resistive force theory) and
//! water (Kelasidi et al.'s link-by-link hydrodynamics), given in a world file's `media` list. Each medium
//! fills a region; in it, every link of a robot gets the medium's forces and torques at every physics
//! step, applied through `World::apply_external_force`/`apply_external_torque` before the step. A world
//! without media builds and steps exactly as before: bit for bit with pybullet, at the same cost (the
//! bodies hold no [`MediaState`] then, and their step is the one call it always was).
//!
//! Layout: `region` (where a medium is), `geometry` (what a medium sees of a link: shapes and surface
//! elements), `ground` (the rigid ground giving way under a granular medium), `probe` (Li et al.'s
//! plate experiment, `snake-cli probe`), `granular` (the granular medium, issue 59), `water` (water,
//! issue 60); this file holds
//! the types every medium shares ([`LinkState`], [`Wrench`], [`LinkMemory`]) and the per-step
//! application ([`MediaState::apply`]). docs/media.md has the laws and their validation.

pub mod geometry;
pub mod granular;
pub mod ground;
pub mod probe;
pub mod region;
pub mod water;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::world::{BodyId, Pose, World};

pub use geometry::{Element, LinkGeometry, Primitive, Shape};
pub use region::{Region, RegionFile};

/// One entry of a world file's `media` list, as written: `{medium: granular, ...}` or
/// `{medium: water, ...}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "medium", rename_all = "lowercase", deny_unknown_fields)]
pub enum MediumFile {
    /// Dry granular media (sand, glass beads, ...), resistive force theory.
    Granular(granular::GranularFile),
    /// Water.
    Water(water::WaterFile),
}

/// A medium checked and ready to act.
#[derive(Debug, Clone, PartialEq)]
pub enum Medium {
    /// See [`granular::Granular`].
    Granular(granular::Granular),
    /// See [`water::Water`].
    Water(water::Water),
}

impl MediumFile {
    /// Checks every value once; `what` names the entry in messages (e.g. `media[0]`).
    pub fn resolve(&self, what: &str) -> Result<Medium> {
        Ok(match self {
            MediumFile::Granular(g) => Medium::Granular(g.resolve(what)?),
            MediumFile::Water(w) => Medium::Water(w.resolve(what)?),
        })
    }
}

impl Medium {
    /// Where the medium is.
    pub fn region(&self) -> &Region {
        match self {
            Medium::Granular(g) => &g.region,
            Medium::Water(w) => &w.region,
        }
    }

    /// The surface element size the medium cuts links into, metres (`None`: it reads shapes only).
    pub fn element_size(&self) -> Option<f64> {
        match self {
            Medium::Granular(g) => Some(g.element),
            Medium::Water(_) => None,
        }
    }
}

/// A link's state as a medium reads it: its centre-of-mass pose and its velocities, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkState {
    /// Centre-of-mass pose.
    pub pose: Pose,
    /// Linear velocity of the centre of mass, m/s.
    pub linear: Vector3<f64>,
    /// Angular velocity, rad/s.
    pub angular: Vector3<f64>,
}

impl LinkState {
    /// Velocity of a point fixed to the link, given by its offset from the centre of mass (world frame).
    pub fn velocity_at(&self, offset: &Vector3<f64>) -> Vector3<f64> {
        self.linear + self.angular.cross(offset)
    }
}

/// A force and a torque on a link, world frame; the torque is about the link's centre of mass.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wrench {
    /// Force, N.
    pub force: Vector3<f64>,
    /// Torque about the centre of mass, N m.
    pub torque: Vector3<f64>,
}

impl std::ops::AddAssign for Wrench {
    fn add_assign(&mut self, other: Wrench) {
        self.force += other.force;
        self.torque += other.torque;
    }
}

/// How close to another link's shape a surface element may lie and still count as inside it, metres:
/// the faces where two segments meet touch to rounding, and a joint's gap is under a millimetre.
pub const INNER_TOLERANCE: f64 = 1.0e-3;

/// What a medium keeps of one link between physics steps (one per medium and link, starting empty).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LinkMemory {
    /// Per surface element, a vector the medium keeps (the granular medium: each element's elastic
    /// displacement, world frame, metres); empty until the medium first fills it.
    pub elements: Vec<Vector3<f64>>,
    /// The link's previous linear velocity relative to the medium, when the medium keeps one.
    pub previous_linear: Option<Vector3<f64>>,
    /// The link's previous angular velocity relative to the medium, when the medium keeps one.
    pub previous_angular: Option<Vector3<f64>>,
}

/// A body's media at run time: the media, each link's geometry, each medium's memory of each link.
/// Built only for worlds with media; [`MediaState::apply`] runs once before every physics step.
#[derive(Debug, Clone)]
pub struct MediaState {
    media: Vec<Medium>,
    links: Vec<LinkGeometry>,
    /// `memory[m][k]`: medium `m`'s memory of link `k` (0 the base).
    memory: Vec<Vec<LinkMemory>>,
    dt: f64,
}

impl MediaState {
    /// The media acting on a body whose links (the base first) have these masses and shapes, stepped
    /// every `dt` seconds. `None` when there are no media: nothing runs then.
    pub fn new(media: &[Medium], links: Vec<(f64, Vec<Shape>)>, dt: f64) -> Result<Option<Self>> {
        if media.is_empty() {
            return Ok(None);
        }
        // The smallest element any medium asks for; water reads shapes only.
        let element = media
            .iter()
            .filter_map(Medium::element_size)
            .min_by(f64::total_cmp);
        let links = links
            .into_iter()
            .map(|(mass, shapes)| {
                LinkGeometry::new(mass, shapes, element, "the world file's media: element")
            })
            .collect::<Result<Vec<_>>>()?;
        let memory = vec![vec![LinkMemory::default(); links.len()]; media.len()];
        Ok(Some(MediaState {
            media: media.to_vec(),
            links,
            memory,
            dt,
        }))
    }

    /// The media acting on `body` of `world`, whose links (the base first) have these collision shapes
    /// (each link's shapes in the URDF's order; their poses are read from the world, in the link's
    /// centre-of-mass frame, and the masses too). `None` when there are no media.
    pub fn for_body(
        media: &[Medium],
        world: &World,
        body: BodyId,
        shapes: &[Vec<Primitive>],
    ) -> Result<Option<Self>> {
        if media.is_empty() {
            return Ok(None);
        }
        let mut links = Vec::with_capacity(shapes.len());
        for (k, primitives) in shapes.iter().enumerate() {
            let link = k.checked_sub(1);
            let poses = world.shape_poses(body, link)?;
            let mass = world.dynamics_info(body, link)?.mass;
            let placed = primitives
                .iter()
                .zip(poses)
                .map(|(&primitive, pose)| Shape { primitive, pose })
                .collect();
            links.push((mass, placed));
        }
        let mut state = Self::new(media, links, world.time_step())?;
        if let Some(s) = &mut state {
            // The faces where links meet are inside the body: no medium acts on them.
            let poses: Vec<Pose> = Self::states(world, body)?
                .into_iter()
                .map(|l| l.pose)
                .collect();
            geometry::hide_inner_elements(&mut s.links, &poses, INNER_TOLERANCE);
            for per_medium in &mut s.memory {
                for m in per_medium.iter_mut() {
                    m.elements.clear();
                }
            }
        }
        Ok(state)
    }

    /// Sets each link's water coefficients (a robot file's `water` keys, checked; the base first).
    pub fn set_water_coefficients(&mut self, per_link: &[Option<water::CoefficientsFile>]) {
        for (link, c) in self.links.iter_mut().zip(per_link) {
            link.water = *c;
        }
    }

    /// Sets the current of every water medium (m/s, world frame: randomized physics' drawn current);
    /// false when there is none.
    pub fn set_water_current(&mut self, current: Vector3<f64>) -> bool {
        let mut any = false;
        for medium in &mut self.media {
            if let Medium::Water(w) = medium {
                w.current = current;
                any = true;
            }
        }
        any
    }

    /// The links' geometry, the base first.
    pub fn links(&self) -> &[LinkGeometry] {
        &self.links
    }

    /// Forgets every medium's memory of every link (a body reset to a new state).
    pub fn reset(&mut self) {
        for per_medium in &mut self.memory {
            for m in per_medium.iter_mut() {
                *m = LinkMemory::default();
            }
        }
    }

    /// Every link's state (the base first), as the media read it.
    pub fn states(world: &World, body: BodyId) -> Result<Vec<LinkState>> {
        let base = world.base_state(body)?;
        let poses = world.link_poses(body)?;
        let velocities = world.link_velocities(body)?;
        let mut states = Vec::with_capacity(poses.len() + 1);
        states.push(LinkState {
            pose: base.pose,
            linear: base.linear_velocity,
            angular: base.angular_velocity,
        });
        for (pose, v) in poses.into_iter().zip(velocities) {
            states.push(LinkState {
                pose,
                linear: v.linear,
                angular: v.angular,
            });
        }
        Ok(states)
    }

    /// Every link's wrench from every medium for these states (the base first), under `gravity` (the
    /// world's, m/s^2: what buoyancy works against).
    pub fn wrenches(&mut self, states: &[LinkState], gravity: Vector3<f64>) -> Vec<Wrench> {
        let mut out = vec![Wrench::default(); self.links.len()];
        for (medium, memory) in self.media.iter().zip(&mut self.memory) {
            for (k, ((link, state), mem)) in self.links.iter().zip(states).zip(memory).enumerate() {
                out[k] += match medium {
                    Medium::Granular(g) => g.wrench(link, state, self.dt, mem),
                    Medium::Water(w) => w.wrench(link, state, self.dt, gravity, mem),
                };
            }
        }
        out
    }

    /// Applies every link's wrench for the next physics step (forces at the centre of mass).
    pub fn apply(&mut self, world: &mut World, body: BodyId) -> Result<()> {
        let states = Self::states(world, body)?;
        let wrenches = self.wrenches(&states, world.gravity());
        for (k, (w, state)) in wrenches.iter().zip(&states).enumerate() {
            if w.force == Vector3::zeros() && w.torque == Vector3::zeros() {
                continue;
            }
            let link = k.checked_sub(1);
            world.apply_external_force(body, link, w.force, state.pose.position)?;
            world.apply_external_torque(body, link, w.torque)?;
        }
        Ok(())
    }
}
