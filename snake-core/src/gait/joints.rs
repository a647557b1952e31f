//! Which joints a gait bends sideways and which up and down, read from the joint axes at rest.
//!
//! A gait of the library ([`super::serpenoid`]) writes a lateral (yaw) wave and a vertical (pitch)
//! wave; a robot file does not say which joint is which, so the roles come from the URDF's geometry:
//! with every joint at 0 and the root link level (the start pose only turns it about z, which changes
//! no role), each joint's axis is carried into the world frame through the `<origin rpy>` of every joint
//! above it and its own, and
//!
//! - an axis within [`AXIS_TOLERANCE_DEG`] of world z is a **yaw** joint (it bends the body sideways);
//! - an axis within that tolerance of horizontal *and* across the body (within the tolerance of
//!   perpendicular to the joint's offset from its parent, the direction the chain runs there) is a
//!   **pitch** joint (it lifts and lowers the body);
//! - any other actuated revolute or continuous joint (tilted axes, a roll joint along the body) is
//!   **other** and holds target 0;
//! - a joint without a motor (URDF effort 0, such as a passive wheel of wheeled-8) or a prismatic joint
//!   is **passive**: target 0, which for effort 0 leaves it free (as `sine` does today).
//!
//! The yaw and pitch joints, in pybullet's joint order, are the gait's modules `n = 0, 1, ...` (Tesch et
//! al. 2009 number modules along the body; on an alternating yaw-pitch snake the yaw joints are the even
//! modules and the pitch joints the odd ones).

use nalgebra::{Rotation3, Vector3};

use crate::urdf::{JointKind, UrdfRobot};

/// How far (degrees) an axis may lean from vertical, or from horizontal-and-across, and keep its role.
pub const AXIS_TOLERANCE_DEG: f64 = 20.0;

/// What a gait does with one movable joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JointRole {
    /// Axis along world z at rest: the lateral wave.
    Yaw,
    /// Axis horizontal and across the body at rest: the vertical wave.
    Pitch,
    /// Actuated, but neither: target 0.
    Other,
    /// No motor (effort 0) or prismatic: target 0.
    Passive,
}

/// The role of each movable joint, in pybullet's joint order, with each yaw or pitch joint's module
/// number.
#[derive(Debug, Clone, PartialEq)]
pub struct JointRoles {
    /// One role per movable joint.
    pub roles: Vec<JointRole>,
    /// Module number of each movable joint (its place among the yaw and pitch joints); `None` for the
    /// others.
    pub modules: Vec<Option<usize>>,
}

impl JointRoles {
    /// From roles in joint order.
    pub fn new(roles: Vec<JointRole>) -> Self {
        let mut next = 0;
        let modules = roles
            .iter()
            .map(|r| match r {
                JointRole::Yaw | JointRole::Pitch => {
                    next += 1;
                    Some(next - 1)
                }
                _ => None,
            })
            .collect();
        JointRoles { roles, modules }
    }

    /// The built-in snake: `joints` yaw joints.
    pub fn all_yaw(joints: usize) -> Self {
        Self::new(vec![JointRole::Yaw; joints])
    }

    /// A URDF robot's roles (see the module docs).
    pub fn of_urdf(urdf: &UrdfRobot) -> Self {
        // World orientation of each link's frame at rest, root first (links come parent first).
        let mut frames: Vec<Rotation3<f64>> = Vec::with_capacity(urdf.links.len());
        let mut roles = Vec::new();
        let tol = AXIS_TOLERANCE_DEG.to_radians();
        for link in &urdf.links {
            let parent = link
                .parent
                .and_then(|p| frames.get(p).copied())
                .unwrap_or_else(Rotation3::identity);
            let Some(joint) = &link.joint else {
                frames.push(parent);
                continue;
            };
            let [r, p, y] = joint.origin.rpy.unwrap_or([0.0; 3]);
            let frame = parent * Rotation3::from_euler_angles(r, p, y);
            frames.push(frame);
            if !joint.kind.is_movable() {
                continue;
            }
            let role = if joint.effort <= 0.0 || joint.kind == JointKind::Prismatic {
                JointRole::Passive
            } else {
                let axis = frame * Vector3::from(joint.axis);
                let along = parent * Vector3::from(joint.origin.xyz);
                classify(axis, along, tol)
            };
            roles.push(role);
        }
        Self::new(roles)
    }

    /// Number of joints of `role`.
    pub fn count(&self, role: JointRole) -> usize {
        self.roles.iter().filter(|r| **r == role).count()
    }
}

/// The role of an actuated hinge with world `axis`, whose chain runs along `along` there.
fn classify(axis: Vector3<f64>, along: Vector3<f64>, tol: f64) -> JointRole {
    let Some(a) = axis.try_normalize(1e-12) else {
        return JointRole::Other;
    };
    if a.z.abs() >= tol.cos() {
        return JointRole::Yaw;
    }
    if a.z.abs() > tol.sin() {
        return JointRole::Other;
    }
    // Horizontal: across the body (pitch) or along it (roll). A joint at its parent's origin gives no
    // direction; it is taken as across.
    match along.try_normalize(1e-12) {
        Some(b) if a.dot(&b).abs() > tol.sin() => JointRole::Other,
        _ => JointRole::Pitch,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_are_classified() {
        let y = Vector3::new(0.0, 1.0, 0.0);
        assert_eq!(classify(Vector3::z(), y, 0.35), JointRole::Yaw);
        assert_eq!(classify(-Vector3::z(), y, 0.35), JointRole::Yaw);
        assert_eq!(classify(Vector3::x(), y, 0.35), JointRole::Pitch);
        assert_eq!(classify(Vector3::y(), y, 0.35), JointRole::Other);
        assert_eq!(
            classify(Vector3::new(1.0, 0.0, 1.0), y, 0.35),
            JointRole::Other
        );
        assert_eq!(
            classify(Vector3::x(), Vector3::zeros(), 0.35),
            JointRole::Pitch
        );
    }

    #[test]
    fn modules_number_the_yaw_and_pitch_joints() {
        use JointRole::*;
        let r = JointRoles::new(vec![Passive, Yaw, Passive, Pitch, Other, Yaw]);
        assert_eq!(r.modules, vec![None, Some(0), None, Some(1), None, Some(2)]);
    }
}
