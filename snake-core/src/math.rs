//! Small numeric helpers that must round exactly as the reference does.

/// pybullet's `getQuaternionFromEuler((roll, pitch, yaw))`, with its operation order, as (x, y, z, w).
pub fn quaternion_from_euler(roll: f64, pitch: f64, yaw: f64) -> [f64; 4] {
    let (phi, the, psi) = (roll / 2.0, pitch / 2.0, yaw / 2.0);
    let q = [
        phi.sin() * the.cos() * psi.cos() - phi.cos() * the.sin() * psi.sin(),
        phi.cos() * the.sin() * psi.cos() + phi.sin() * the.cos() * psi.sin(),
        phi.cos() * the.cos() * psi.sin() - phi.sin() * the.sin() * psi.cos(),
        phi.cos() * the.cos() * psi.cos() + phi.sin() * the.sin() * psi.sin(),
    ];
    let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    [q[0] / len, q[1] / len, q[2] / len, q[3] / len]
}

/// A start pose on the ground plane: base position and heading.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StartPose {
    /// Base centre x, metres.
    pub x: f64,
    /// Base centre y, metres.
    pub y: f64,
    /// Base centre z, metres (the cube half extent rests it on the plane).
    pub z: f64,
    /// Heading about z, radians (0: the tail extends along +y and the snake moves towards -y).
    pub yaw: f64,
}

impl StartPose {
    /// The base resting on the plane at the origin, heading 0, for cubes of `half_extent`.
    pub fn resting(half_extent: f64) -> Self {
        StartPose {
            x: 0.0,
            y: 0.0,
            z: half_extent,
            yaw: 0.0,
        }
    }

    /// The orientation as pybullet's `getQuaternionFromEuler((0, 0, yaw))` gives it.
    pub fn orientation(&self) -> [f64; 4] {
        quaternion_from_euler(0.0, 0.0, self.yaw)
    }

    /// Checks that every value is finite.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::limits::{check_position, check_range, MAX_START_HEIGHT, MAX_YAW};
        if ![self.x, self.y, self.z, self.yaw]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(crate::error::invalid(format!(
                "start pose must be finite, got {self:?}"
            )));
        }
        check_position("start", self.x, self.y)?;
        check_range("start z", self.z, 0.0, MAX_START_HEIGHT)?;
        check_range("start yaw", self.yaw, -MAX_YAW, MAX_YAW)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_rotation_is_exact() {
        assert_eq!(quaternion_from_euler(0.0, 0.0, 0.0), [0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn yaw_quarter_turn() {
        let q = quaternion_from_euler(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q[2] - h).abs() < 1e-15 && (q[3] - h).abs() < 1e-15);
        assert_eq!((q[0], q[1]), (0.0, 0.0));
    }
}
