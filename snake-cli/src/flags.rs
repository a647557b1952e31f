//! The command line's typed values: clap value parsers shared by the subcommands (`run`, `bench`),
//! each turning one flag's text into its checked value.

use snake_core::{SkinFriction, StartPose};

fn parse_numbers<const N: usize>(text: &str, what: &str) -> Result<[f64; N], String> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{text}' is not {what} ({N} numbers separated by commas)"))?;
    values
        .try_into()
        .map_err(|v: Vec<f64>| format!("'{text}' has {} values; expected {what}", v.len()))
}

pub(crate) fn parse_gait_param(text: &str) -> Result<(String, f64), String> {
    snake_core::gait::parse_param(text).map_err(|e| e.to_string())
}

pub(crate) fn parse_start(text: &str) -> Result<StartPose, String> {
    let [x, y, z, yaw] = parse_numbers::<4>(text, "X,Y,Z,YAW")?;
    let pose = StartPose { x, y, z, yaw };
    pose.validate().map_err(|e| e.to_string())?;
    Ok(pose)
}

pub(crate) fn parse_friction(text: &str) -> Result<[f64; 3], String> {
    let a = parse_numbers::<3>(text, "X,Y,Z")?;
    if a.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(a)
    } else {
        Err(format!(
            "'{text}': anisotropic friction must be finite and >= 0"
        ))
    }
}

/// `--skin-friction F,B,T` as the typed value, checked here once (clap's value parser): what the
/// commands hand on is a valid [`SkinFriction`] (along the body's default axis; `--skin-axis` sets
/// it).
pub(crate) fn parse_skin(text: &str) -> Result<SkinFriction, String> {
    let [f, b, t] = parse_numbers::<3>(text, "F,B,T")?;
    let skin = SkinFriction::new(f, b, t);
    skin.validate(&format!("--skin-friction '{text}'"))
        .map_err(|e| e.message())?;
    Ok(skin)
}
