//! The fitted robot file (`snakesim calibrate --out`): the robot file with [`Overrides`] written in,
//! so that it builds the robot the fitted simulation ran (`run_targets` with those overrides), bit for
//! bit. [`Overrides::apply_to_file`] is [`Overrides::apply_to_spec`]'s mapping on the file's keys,
//! per-link and per-joint values included; the tests check that the two build the same robot.

use std::path::Path;

use crate::error::{invalid_at, Result};
use crate::limits::MAX_URDF_BYTES;
use crate::{RobotFile, RobotSpec};

use super::Overrides;

/// Keys a robot file cannot hold, each with where such a value lives instead: the fitted file names
/// them in a comment and calibrate's JSON lists them (`_core.NOT_IN_ROBOT_FILE`).
pub const NOT_IN_ROBOT_FILE: [(&str, &str); 3] = [
    ("ground_friction", "a world file's ground_friction"),
    ("lateral_friction", "no robot-file key"),
    ("mass_scale", "no robot-file key"),
];

impl Overrides {
    /// Writes the robot-file keys into `file` as [`Overrides::apply_to_spec`] writes them into the
    /// spec it builds: the gains and the velocity limit under `motors` (each joint's own limit
    /// removed), the anisotropic friction's axes into the robot's value and into every link's own, the
    /// skin friction's coefficients likewise. The ground friction, the links' lateral friction and the
    /// mass factor have no robot-file key (see [`fitted_robot_file`]).
    pub fn apply_to_file(&self, file: &mut RobotFile) -> Result<()> {
        self.validate()?;
        if let Some(kp) = self.kp {
            file.motors.kp = kp;
        }
        if let Some(kd) = self.kd {
            file.motors.kd = kd;
        }
        if let Some(v) = self.max_velocity {
            file.motors.max_velocity = Some(v);
            file.joints.values_mut().for_each(|j| j.max_velocity = None);
            file.joints.retain(|_, j| j.max_velocity.is_some());
        }
        let axes = [self.anisotropic_x, self.anisotropic_y, self.anisotropic_z];
        let merge = |a: Option<[f64; 3]>| {
            let mut v = a.unwrap_or([1.0; 3]);
            for (slot, given) in v.iter_mut().zip(axes) {
                if let Some(g) = given {
                    *slot = g;
                }
            }
            v
        };
        if axes.iter().any(Option::is_some) {
            file.anisotropic_friction = Some(merge(file.anisotropic_friction));
            for link in file.links.values_mut() {
                if let Some(a) = link.anisotropic_friction {
                    link.anisotropic_friction = Some(merge(Some(a)));
                }
            }
        }
        let skin = [self.skin_forward, self.skin_backward, self.skin_transverse];
        if skin.iter().any(Option::is_some) {
            let links = file
                .links
                .values_mut()
                .filter_map(|l| l.skin_friction.as_mut());
            let all: Vec<_> = file.skin_friction.iter_mut().chain(links).collect();
            if all.is_empty() {
                return Err(invalid_at(
                    "skin_friction",
                    "the robot file sets no skin_friction to fit",
                ));
            }
            for s in all {
                s.forward = self.skin_forward.unwrap_or(s.forward);
                s.backward = self.skin_backward.unwrap_or(s.backward);
                s.transverse = self.skin_transverse.unwrap_or(s.transverse);
            }
        }
        // Water's coefficients (issue 60): the robot's `water` and every link's that names one.
        if let Some(fit) = self.water_file() {
            file.water = Some(file.water.map_or(fit, |own| fit.merged_over(&own)));
            for link in file.links.values_mut() {
                if let Some(own) = link.water {
                    link.water = Some(fit.merged_over(&own));
                }
            }
        }
        Ok(())
    }

    fn not_in_robot_file(&self) -> [(&'static str, &'static str, Option<f64>); 3] {
        let values = [self.ground_friction, self.lateral_friction, self.mass_scale];
        let mut out = [("", "", None); 3];
        for (slot, ((key, where_), v)) in out.iter_mut().zip(NOT_IN_ROBOT_FILE.iter().zip(values)) {
            *slot = (*key, *where_, v);
        }
        out
    }
}

/// The robot `robot` (a robot file, or a URDF alone) with `overrides` written in, as the YAML text of
/// a robot file whose `urdf:` is `urdf` (the URDF's path as the fitted file's folder sees it). Keys a
/// robot file cannot hold are comments. The robot is read first ([`RobotSpec::load`]: every check
/// and limit of a robot file), then its file's keys are kept as they are, every one of them.
pub fn fitted_robot_file(robot: &Path, overrides: &Overrides, urdf: &str) -> Result<String> {
    RobotSpec::load(robot)?;
    let shown = robot.display().to_string();
    let is_urdf = robot.extension().and_then(|e| e.to_str()) == Some("urdf");
    let mut file: RobotFile = if is_urdf {
        crate::files::from_yaml("urdf: robot.urdf", &shown, "a robot file")?
    } else {
        let text = crate::files::read_text(robot, MAX_URDF_BYTES, "robot file")?;
        crate::files::from_yaml(&text, &shown, "a robot file")?
    };
    overrides.apply_to_file(&mut file)?;
    file.urdf = urdf.into();
    let mut value =
        serde_norway::to_value(&file).map_err(|e| invalid_at("robot file", e.to_string()))?;
    if let serde_norway::Value::Mapping(map) = &mut value {
        // Keys left at their default are left out, as a person writes a robot file.
        map.retain(|_, v| match v {
            serde_norway::Value::Null => false,
            serde_norway::Value::Mapping(m) => !m.is_empty(),
            _ => true,
        });
    }
    let body =
        serde_norway::to_string(&value).map_err(|e| invalid_at("robot file", e.to_string()))?;
    let name = robot
        .file_name()
        .map_or(shown.clone(), |n| n.to_string_lossy().into_owned());
    let mut text =
        format!("# {name} with values fitted by snakesim calibrate (docs/calibration.md).\n");
    for (key, where_, v) in overrides.not_in_robot_file() {
        if let Some(v) = v {
            text += &format!("# fitted {key}: {v:?} ({where_}; not applied by this file)\n");
        }
    }
    Ok(text + &body)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::WorldSpec;

    /// A robot file around yaw-pitch-16's URDF with robot-wide, per-link and per-joint values.
    const ROBOT: &str = "urdf: URDF\nstart: [0, 0, 0.0254, 0]\nmotors: {kp: 0.1, kd: 1.0}\n\
        anisotropic_friction: [1, 0.8, 0.8]\nlinks:\n  module0: {anisotropic_friction: [1, 0.5, 0.5]}\n\
        joints:\n  yaw0: {max_velocity: 2.0}\ngait: {segment_length: 0.0635, wave_length: 0.8, amplitude: 0.6}\n";
    const SKIN: &str = "urdf: URDF\nskin_friction: {forward: 0.1, backward: 0.2, transverse: 0.3}\n\
        links:\n  module0: {skin_friction: {forward: 0.4, backward: 0.5, transverse: 0.6, axis: y}}\n";

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/yaw-pitch-16.urdf");
        let path = dir.join(name);
        std::fs::write(&path, text.replace("URDF", &urdf.display().to_string())).unwrap();
        path
    }

    /// The spec the fitted file builds is the spec the simulation builds with the overrides applied.
    fn same_robot(robot: &Path, overrides: &Overrides) {
        let dir = robot.parent().unwrap();
        let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/yaw-pitch-16.urdf");
        let text = fitted_robot_file(robot, overrides, &urdf.display().to_string()).unwrap();
        let fitted = dir.join("fitted.yaml");
        std::fs::write(&fitted, &text).unwrap();
        let mut expected = RobotSpec::load(robot).unwrap();
        overrides
            .apply_to_spec(&mut expected, &mut WorldSpec::default())
            .unwrap();
        let mut got = RobotSpec::load(&fitted).unwrap();
        got.source = expected.source.clone();
        assert_eq!(got, expected, "{text}");
    }

    #[test]
    fn the_fitted_file_builds_the_fitted_robot_per_link_values_included() {
        let dir = tempfile::tempdir().unwrap();
        let robot = write(dir.path(), "robot.yaml", ROBOT);
        let overrides = Overrides {
            kp: Some(0.23),
            kd: Some(0.65),
            max_velocity: Some(2.3),
            anisotropic_y: Some(0.31),
            ground_friction: Some(0.82),
            mass_scale: Some(1.1),
            ..Overrides::default()
        };
        same_robot(&robot, &overrides);
        let text = fitted_robot_file(&robot, &overrides, "u.urdf").unwrap();
        assert!(text.contains("# fitted ground_friction: 0.82 (a world file's ground_friction"));
        assert!(text.contains("# fitted mass_scale: 1.1"), "{text}");
        assert!(
            text.contains("urdf: u.urdf") && text.contains("segment_length"),
            "{text}"
        );
        // Only the head's own axes: x and z kept, y fitted.
        let spec = {
            let mut s = RobotSpec::load(&robot).unwrap();
            overrides
                .apply_to_spec(&mut s, &mut WorldSpec::default())
                .unwrap();
            s
        };
        assert_eq!(spec.anisotropic_friction[0], Some([1.0, 0.31, 0.5]));
        assert_eq!(spec.anisotropic_friction[1], Some([1.0, 0.31, 0.8]));
        // One key at a time, and none.
        for o in [
            Overrides::default(),
            Overrides {
                anisotropic_x: Some(0.7),
                ..Overrides::default()
            },
            Overrides {
                max_velocity: Some(4.0),
                ..Overrides::default()
            },
        ] {
            same_robot(&robot, &o);
        }
    }

    #[test]
    fn skin_friction_is_fitted_on_every_link_that_has_it() {
        let dir = tempfile::tempdir().unwrap();
        let robot = write(dir.path(), "skin.yaml", SKIN);
        let overrides = Overrides {
            skin_backward: Some(0.25),
            ..Overrides::default()
        };
        same_robot(&robot, &overrides);
        let plain = write(dir.path(), "plain.yaml", "urdf: URDF\n");
        let e = fitted_robot_file(&plain, &overrides, "u.urdf").unwrap_err();
        assert!(
            e.to_string().contains("sets no skin_friction to fit"),
            "{e}"
        );
    }

    #[test]
    fn a_urdf_alone_gets_a_robot_file() {
        let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/yaw-pitch-16.urdf");
        let overrides = Overrides {
            kp: Some(0.3),
            ..Overrides::default()
        };
        let text = fitted_robot_file(&urdf, &overrides, "yaw-pitch-16.urdf").unwrap();
        assert!(
            text.contains("urdf: yaw-pitch-16.urdf") && text.contains("kp: 0.3"),
            "{text}"
        );
    }
}
