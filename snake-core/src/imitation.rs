//! What a run's `init` can imitate (snake-rl's `init: {imitate: NAME, hold: ...}`), bound to the
//! env it drives: a joint-target wave ([`JointsSine`]: `sine`, `steered_sine`) or a gait-action hand
//! controller ([`HandController`]: `gait`, `steer`, the baselines), the latter holding a chosen
//! amplitude and frequency ([`HeldWave`]). Each acts in its env's own action space, so that a
//! policy can be fitted to its actions.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::controllers::{
    ControlledEnv, HandController, HeldWave, Imitable, JointsSine, GAIT_ACTION_LEN,
};
use crate::env::EnvConfig;
use crate::error::{invalid_at, Error, Result};
use crate::keys::by_name;

/// A controller a run can imitate, by its name (`init.imitate`): a joint-target wave or a
/// gait-action hand controller. Written in configurations as the name (`"steered_sine"`,
/// `"steer"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Imitated {
    /// A joint-target wave (the `joints` action mode).
    Joints(Imitable),
    /// A gait-action hand controller (the `gait` action mode with the goal vector observed).
    Hand(HandController),
}

impl Imitated {
    /// Every one, the joint-target waves first.
    pub fn all() -> impl Iterator<Item = Imitated> {
        Imitable::ALL
            .into_iter()
            .map(Imitated::Joints)
            .chain(HandController::ALL.into_iter().map(Imitated::Hand))
    }

    /// Its configuration name.
    pub fn name(self) -> &'static str {
        match self {
            Imitated::Joints(c) => c.name(),
            Imitated::Hand(c) => c.name(),
        }
    }

    /// The one called `name`; the error lists every name.
    pub fn from_name(name: &str) -> Result<Self> {
        by_name(
            &Self::all().collect::<Vec<_>>(),
            Self::name,
            name,
            "controller",
        )
    }
}

impl From<Imitable> for Imitated {
    fn from(c: Imitable) -> Self {
        Imitated::Joints(c)
    }
}

impl From<HandController> for Imitated {
    fn from(c: HandController) -> Self {
        Imitated::Hand(c)
    }
}

impl From<Imitated> for String {
    fn from(c: Imitated) -> String {
        c.name().to_string()
    }
}

impl TryFrom<String> for Imitated {
    /// The message alone: serde puts it after the key path.
    type Error = String;
    fn try_from(name: String) -> std::result::Result<Self, String> {
        Imitated::from_name(&name).map_err(|e| e.message())
    }
}

impl fmt::Display for Imitated {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An [`Imitated`] controller bound to `envs` envs of one env configuration: it writes every env's
/// action for its observation and is told when an env's episode ends.
#[derive(Debug, Clone)]
pub enum Demonstrator {
    /// A joint-target wave, a clock per env.
    Joints(JointsSine),
    /// A gait-action hand controller holding `hold`; it has no clock.
    Hand {
        /// The controller.
        controller: HandController,
        /// Where its env's observation holds the goal vector.
        on: ControlledEnv,
        /// The amplitude and frequency actions it holds.
        hold: HeldWave,
        /// Its float64 actions for every env before they are written as the policy's float32 ones.
        scratch: Vec<f64>,
    },
}

impl Demonstrator {
    /// `imitated` for `envs` envs of `config`, holding `hold` (a hand controller only; `None`: the
    /// middle of the ranges, as the baselines do), or an error saying why it cannot drive them: one
    /// about `hold` has the key `hold` (`hold.amplitude`), one about the env none.
    pub fn new(
        imitated: Imitated,
        hold: Option<HeldWave>,
        config: &EnvConfig,
        envs: usize,
    ) -> Result<Self> {
        match imitated {
            Imitated::Joints(kind) => {
                if hold.is_some() {
                    return Err(invalid_at(
                        "hold",
                        format!(
                            "{} sets joint targets: only the gait-action controllers ({}) hold an \
                             amplitude and a frequency",
                            kind.name(),
                            HandController::ALL.map(HandController::name).join(", ")
                        ),
                    ));
                }
                JointsSine::new(kind, config, envs).map(Demonstrator::Joints)
            }
            Imitated::Hand(controller) => {
                let hold = hold.unwrap_or_default();
                hold.validate().map_err(|e| match e {
                    Error::InvalidArgument(i) => Error::InvalidArgument(i.under("hold")),
                    e => e,
                })?;
                let on = ControlledEnv::of(config, "the gait-action controllers")?;
                Ok(Demonstrator::Hand {
                    controller,
                    on,
                    hold,
                    scratch: vec![0.0; envs * GAIT_ACTION_LEN],
                })
            }
        }
    }

    /// The number of envs it drives.
    pub fn envs(&self) -> usize {
        match self {
            Demonstrator::Joints(c) => c.envs(),
            Demonstrator::Hand { scratch, .. } => scratch.len() / GAIT_ACTION_LEN,
        }
    }

    /// The length of an action it writes.
    pub fn action_dim(&self) -> usize {
        match self {
            Demonstrator::Joints(c) => c.action_dim(),
            Demonstrator::Hand { .. } => GAIT_ACTION_LEN,
        }
    }

    /// Tells it env `env`'s episode ended (a wave restarts its clock).
    pub fn reset(&mut self, env: usize) {
        if let Demonstrator::Joints(c) = self {
            c.reset(env);
        }
    }

    /// Writes every env's action for its observation (`obs`: `envs x observation_dim`) into
    /// `actions` (`envs x action_dim`); a wave advances by one env step.
    pub fn act(&mut self, obs: &[f32], actions: &mut [f32]) {
        match self {
            Demonstrator::Joints(c) => c.act(obs, actions),
            Demonstrator::Hand {
                controller,
                on,
                hold,
                scratch,
            } => {
                let envs = scratch.len() / GAIT_ACTION_LEN;
                controller.act_holding(on, obs, envs, scratch, *hold);
                for (a, s) in actions.iter_mut().zip(scratch.iter()) {
                    *a = *s as f32;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::{ActionMode, ObservationLayout};
    use crate::{Preset, ResetOptions, SnakeEnv};

    fn gait_goal_env() -> EnvConfig {
        EnvConfig {
            observation: ObservationLayout::Extended,
            action: crate::ActionConfig {
                mode: ActionMode::Gait,
                ..Default::default()
            },
            ..EnvConfig::goal_task(Preset::Paper, 5)
        }
    }

    #[test]
    fn names_round_trip_through_the_configuration() {
        let names: Vec<_> = Imitated::all().map(Imitated::name).collect();
        assert_eq!(names, ["sine", "steered_sine", "gait", "steer"]);
        for c in Imitated::all() {
            let json = serde_json::to_string(&c).unwrap();
            assert_eq!(json, format!("\"{}\"", c.name()));
            assert_eq!(serde_json::from_str::<Imitated>(&json).unwrap(), c);
        }
        let message = serde_json::from_str::<Imitated>("\"wiggle\"")
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("'wiggle'") && message.contains("sine, steered_sine, gait, steer"),
            "{message}"
        );
    }

    #[test]
    fn steer_holding_a_wave_is_the_baseline_with_those_actions() {
        let config = gait_goal_env();
        let hold = HeldWave {
            amplitude: 0.5,
            frequency: 1.0,
        };
        let mut d =
            Demonstrator::new(HandController::Steer.into(), Some(hold), &config, 1).unwrap();
        let mut env = SnakeEnv::new(config.clone()).unwrap();
        let (obs, _) = env.reset(Some(3), ResetOptions::default()).unwrap();
        let mut actions = [0.0f32; 3];
        d.act(&obs, &mut actions);
        // The baseline's own steering for this observation, and the held wave.
        let on = ControlledEnv::of(&config, "x").unwrap();
        let mut baseline = [0.0f64; 3];
        HandController::Steer.act(&on, &obs, 1, &mut baseline);
        assert_eq!(f64::from(actions[0]), baseline[0] as f32 as f64);
        assert_ne!(baseline[0], 0.0);
        assert_eq!(&actions[1..], &[0.5, 1.0]);
        assert_eq!(baseline[1..], [0.0, 0.0]);
    }

    #[test]
    fn a_controller_that_cannot_drive_the_env_says_why() {
        let gait = gait_goal_env();
        let hold = Some(HeldWave::default());
        let message = Demonstrator::new(Imitable::Sine.into(), hold, &gait, 1)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("only the gait-action controllers (gait, steer)"),
            "{message}"
        );
        let message =
            Demonstrator::new(HandController::Steer.into(), None, &EnvConfig::default(), 1)
                .unwrap_err()
                .to_string();
        assert!(message.contains("action mode 'gait'"), "{message}");
        for (amplitude, frequency, key) in [
            (1.5, 0.0, "amplitude"),
            (0.0, f64::NAN, "frequency"),
            (f64::NEG_INFINITY, 0.0, "amplitude"),
        ] {
            let hold = HeldWave {
                amplitude,
                frequency,
            };
            let message = Demonstrator::new(HandController::Gait.into(), Some(hold), &gait, 1)
                .unwrap_err()
                .to_string();
            assert!(
                message.contains(&format!("{key}: must be an action in [-1, 1]")),
                "{message}"
            );
        }
    }
}
