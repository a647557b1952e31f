//! How a viewer draws a collision shape: shared by robots (their links' shapes) and world files
//! (their obstacles), so that neither module needs the other for it.

use serde::Serialize;

/// One collision shape as a viewer draws it, in its link's centre-of-mass frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShapeDrawing {
    /// box, sphere, cylinder or capsule (cylinders and capsules along their z axis).
    pub kind: &'static str,
    /// Box: full extents; sphere: radius, 0, 0; cylinder and capsule: radius, length, 0.
    pub size: [f64; 3],
    /// Centre and orientation: x, y, z, qx, qy, qz, qw.
    pub pose: [f64; 7],
}
