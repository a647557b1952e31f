//! [`VecSnakeEnv`]: many independent [`SnakeEnv`]s stepped together, across threads, with
//! Stable-Baselines3-style automatic resets.

use crate::env::{EnvConfig, Info, ResetOptions, SnakeEnv};
use crate::error::{invalid, Error, Result};

/// One environment of the vector with its per-step scratch, so that stepping allocates nothing.
#[derive(Debug)]
struct Slot {
    env: SnakeEnv,
    /// The step's info (for a finished env: its final step's).
    info: Option<Info>,
    /// The final observation, valid when `finished`.
    final_obs: Vec<f32>,
    finished: bool,
    error: Option<Error>,
}

/// `M` independent [`SnakeEnv`]s of one configuration, stepped by one call.
///
/// Arrays are flat and env-major: actions are `M * N` values (env 0's N joints first), observations
/// `M * D`. Stepping runs the envs in parallel on a rayon thread pool (the global one, or a dedicated
/// one of [`VecSnakeEnv::with_threads`]); every env owns its Bullet world and its random number
/// generator, so the results are bit-identical to stepping the envs one by one, whatever the threads.
///
/// An env whose episode ends (terminated or truncated) is reset within the same
/// [`VecSnakeEnv::step`], continuing its own random stream: the observation written for it is the
/// first of its next episode, and the last observation and info of the finished episode are handed
/// back separately in [`FinalSteps`] (Gymnasium's same-step autoreset puts them in
/// `final_obs`/`final_info`, Stable-Baselines3 in `infos[i]["terminal_observation"]`).
///
/// ```
/// use snake_core::{EnvConfig, StepBuffers, VecSnakeEnv};
///
/// let mut envs = VecSnakeEnv::new(EnvConfig { max_episode_steps: 3, ..EnvConfig::snakebot_gym(4) }, 2)?;
/// let (m, n) = (envs.num_envs(), envs.action_dim());
/// let mut out = StepBuffers::for_envs(&envs);
/// envs.reset(Some(7), &mut out.obs)?;
/// let actions = vec![0.3f32; m * n];
/// for step in 1..=3 {
///     let finals = envs.step_into(&actions, &mut out)?;
///     assert_eq!(finals.len(), if step == 3 { 2 } else { 0 });
/// }
/// assert!(out.truncated.iter().all(|t| *t));
/// # Ok::<(), snake_core::Error>(())
/// ```
#[derive(Debug)]
pub struct VecSnakeEnv {
    slots: Vec<Slot>,
    config: EnvConfig,
    parallelism: Parallelism,
}

#[derive(Debug)]
enum Parallelism {
    /// rayon's global pool.
    Global,
    /// A dedicated pool, possibly shared with the caller (e.g. a trainer's).
    Pool(std::sync::Arc<rayon::ThreadPool>),
    /// No threads: one env after the other.
    Sequential,
}

/// The episodes that ended in the last [`VecSnakeEnv::step`].
#[derive(Debug, Clone, Copy)]
pub struct FinalSteps<'a> {
    slots: &'a [Slot],
}

/// The last step of an episode that ended (and was reset) in [`VecSnakeEnv::step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FinalStep<'a> {
    /// Index of the env.
    pub env: usize,
    /// The episode's last observation.
    pub observation: &'a [f32],
    /// The episode's last info.
    pub info: &'a Info,
}

impl<'a> FinalSteps<'a> {
    /// Number of episodes that ended.
    pub fn len(&self) -> usize {
        self.slots.iter().filter(|s| s.finished).count()
    }

    /// No episode ended.
    pub fn is_empty(&self) -> bool {
        !self.slots.iter().any(|s| s.finished)
    }

    /// The final step of env `env`, if its episode ended.
    pub fn get(&self, env: usize) -> Option<FinalStep<'a>> {
        let slot = self.slots.get(env)?;
        slot.finished.then(|| FinalStep {
            env,
            observation: &slot.final_obs,
            info: slot
                .info
                .as_ref()
                .expect("a finished env has its final info"),
        })
    }

    /// The final steps in env order.
    pub fn iter(&self) -> impl Iterator<Item = FinalStep<'a>> + 'a {
        let slots = self.slots;
        (0..slots.len()).filter_map(move |i| FinalSteps { slots }.get(i))
    }
}

/// Prefixes an error's message with the env index.
fn in_env(env: usize, error: Error) -> Error {
    match error {
        Error::InvalidArgument(m) => {
            Error::InvalidArgument(crate::error::Invalid::new(format!("env {env}: {m}")))
        }
        Error::NonFinite(m) => Error::NonFinite(format!("env {env}: {m}")),
        Error::Engine { code, message } => Error::Engine {
            code,
            message: format!("env {env}: {message}"),
        },
    }
}

fn check_len(what: &str, len: usize, expected: usize) -> Result<()> {
    if len == expected {
        Ok(())
    } else {
        Err(invalid(format!(
            "{what} must have {expected} values, got {len}"
        )))
    }
}

/// What [`VecSnakeEnv::step`] writes for every env, allocated once for a batch: each env's
/// observation (`obs`, `num_envs * observation_dim` values, env after env), reward, and whether its
/// episode terminated or was truncated on this step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepBuffers {
    /// Observations, env after env (the next episode's first one where an episode ended).
    pub obs: Vec<f32>,
    /// Rewards.
    pub rewards: Vec<f64>,
    /// The episode reached the goal (Gymnasium's `terminated`).
    pub terminated: Vec<bool>,
    /// The episode hit its step limit (Gymnasium's `truncated`).
    pub truncated: Vec<bool>,
}

impl StepBuffers {
    /// Buffers for `num_envs` envs of `observation_dim` observations each.
    pub fn new(num_envs: usize, observation_dim: usize) -> Self {
        StepBuffers {
            obs: vec![0.0; num_envs * observation_dim],
            rewards: vec![0.0; num_envs],
            terminated: vec![false; num_envs],
            truncated: vec![false; num_envs],
        }
    }

    /// Buffers for `envs`' batch.
    pub fn for_envs(envs: &VecSnakeEnv) -> Self {
        Self::new(envs.num_envs(), envs.observation_dim())
    }

    /// Env `i`'s episode ended on this step (terminated or truncated).
    pub fn done(&self, i: usize) -> bool {
        self.terminated[i] || self.truncated[i]
    }
}

impl VecSnakeEnv {
    /// `num_envs` (at least 1) envs of `config`, stepped on rayon's global thread pool.
    pub fn new(config: EnvConfig, num_envs: usize) -> Result<Self> {
        let max = crate::limits::MAX_ENVS as f64;
        crate::limits::check_range("num_envs", num_envs as f64, 1.0, max)?;
        // One configuration, checked once: every env is built from it as it is.
        config.validate()?;
        let d = config.observation_dim();
        let slots = (0..num_envs)
            .map(|_| Slot {
                env: SnakeEnv::from_valid(config.clone()),
                info: None,
                final_obs: vec![0.0; d],
                finished: false,
                error: None,
            })
            .collect();
        Ok(VecSnakeEnv {
            slots,
            config,
            parallelism: Parallelism::Global,
        })
    }

    /// Steps on a dedicated pool of `threads` threads instead (1: one env after the other on the
    /// caller's thread, without rayon).
    pub fn with_threads(mut self, threads: usize) -> Result<Self> {
        self.parallelism = match threads {
            0 => return Err(invalid("threads must be at least 1, got 0")),
            1 => Parallelism::Sequential,
            _ => Parallelism::Pool(std::sync::Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .thread_name(|i| format!("snakesim-env-{i}"))
                    .build()
                    .map_err(|e| invalid(format!("could not start {threads} threads: {e}")))?,
            )),
        };
        Ok(self)
    }

    /// Steps on `pool`, which the caller may use for its own work between steps (a trainer's
    /// updates), so that one set of threads serves both.
    pub fn with_pool(mut self, pool: std::sync::Arc<rayon::ThreadPool>) -> Self {
        self.parallelism = Parallelism::Pool(pool);
        self
    }

    /// Number of envs `M`.
    pub fn num_envs(&self) -> usize {
        self.slots.len()
    }

    /// Action length of one env `N` (its joints, or 3 in the gait action mode).
    pub fn action_dim(&self) -> usize {
        self.config.action_dim()
    }

    /// Observation length of one env `D`.
    pub fn observation_dim(&self) -> usize {
        self.config.observation_dim()
    }

    /// The configuration every env shares.
    pub fn config(&self) -> &EnvConfig {
        &self.config
    }

    /// Changes every env's reward weights from the next step on (see [`SnakeEnv::set_reward`]).
    pub fn set_reward(&mut self, reward: crate::RewardConfig) -> Result<()> {
        reward.validate()?;
        self.config.reward = reward;
        for slot in &mut self.slots {
            slot.env.set_reward(reward)?;
        }
        Ok(())
    }

    /// The envs, for inspection.
    pub fn envs(&self) -> impl Iterator<Item = &SnakeEnv> {
        self.slots.iter().map(|s| &s.env)
    }

    /// The info of env `env`'s last reset or step (for an env that finished in the last step: the
    /// info of that final step).
    pub fn info(&self, env: usize) -> Option<&Info> {
        self.slots.get(env)?.info.as_ref()
    }

    /// Resets every env: env `i` gets the seed `seed + i` (wrapping), or continues its stream with
    /// `None`. Writes the `M * D` first observations into `obs_out`.
    pub fn reset(&mut self, seed: Option<u64>, obs_out: &mut [f32]) -> Result<()> {
        self.reset_with(|i| seed.map(|s| s.wrapping_add(i as u64)), obs_out)
    }

    /// Resets every env with a seed of its own: env `i` gets `seeds[i]`, or continues its stream
    /// where that is `None` (Gymnasium's vector envs take a list of seeds so). `seeds` holds `M`
    /// values; writes the `M * D` first observations into `obs_out`.
    pub fn reset_each(&mut self, seeds: &[Option<u64>], obs_out: &mut [f32]) -> Result<()> {
        check_len("seeds", seeds.len(), self.num_envs())?;
        self.reset_with(|i| seeds[i], obs_out)
    }

    /// Resets every env, env `i` with the seed `seed_of(i)`.
    fn reset_with(
        &mut self,
        seed_of: impl Fn(usize) -> Option<u64> + Sync,
        obs_out: &mut [f32],
    ) -> Result<()> {
        let d = self.observation_dim();
        check_len("obs_out", obs_out.len(), self.num_envs() * d)?;
        let job = |i: usize, slot: &mut Slot, obs: &mut [f32]| {
            slot.finished = false;
            let seed = seed_of(i);
            match slot.env.reset_into(seed, ResetOptions::default(), obs) {
                Ok(info) => slot.info = Some(info),
                Err(e) => slot.error = Some(e),
            }
        };
        match &self.parallelism {
            Parallelism::Sequential => {
                for (i, (slot, obs)) in self.slots.iter_mut().zip(obs_out.chunks_mut(d)).enumerate()
                {
                    job(i, slot, obs);
                }
            }
            parallel => {
                let slots = &mut self.slots;
                let mut run = || {
                    use rayon::prelude::*;
                    slots
                        .par_iter_mut()
                        .zip(obs_out.par_chunks_mut(d))
                        .enumerate()
                        .for_each(|(i, (slot, obs))| job(i, slot, obs));
                };
                match parallel {
                    Parallelism::Pool(pool) => pool.install(run),
                    _ => run(),
                }
            }
        }
        self.first_error()
    }

    /// Resets env `env` alone (after an error, or to choose its start or goal), writing its first
    /// observation (`D` values) into `obs_out`.
    pub fn reset_env(
        &mut self,
        env: usize,
        seed: Option<u64>,
        options: ResetOptions,
        obs_out: &mut [f32],
    ) -> Result<Info> {
        let n = self.num_envs();
        let slot = self
            .slots
            .get_mut(env)
            .ok_or_else(|| invalid(format!("env must be below {n}, got {env}")))?;
        slot.finished = false;
        let info = slot
            .env
            .reset_into(seed, options, obs_out)
            .map_err(|e| in_env(env, e))?;
        slot.info = Some(info);
        Ok(info)
    }

    /// [`VecSnakeEnv::step`] into `out`.
    pub fn step_into<A: Copy + Into<f64> + Sync>(
        &mut self,
        actions: &[A],
        out: &mut StepBuffers,
    ) -> Result<FinalSteps<'_>> {
        self.step(
            actions,
            &mut out.obs,
            &mut out.rewards,
            &mut out.terminated,
            &mut out.truncated,
        )
    }

    /// Steps every env with its `N` actions from `actions` (`M * N` values, `f32` or `f64`), writing
    /// the `M * D` observations, `M` rewards and `M` termination and truncation flags. Envs whose
    /// episode ended are reset at once (their observation is the next episode's first); their final
    /// observations and infos are returned.
    ///
    /// Invalid actions or buffers fail before any env moves. If an env fails while stepping (it blew
    /// up), every other env has still stepped; the error names the first failed env, which then
    /// needs [`VecSnakeEnv::reset_env`].
    pub fn step<A: Copy + Into<f64> + Sync>(
        &mut self,
        actions: &[A],
        obs_out: &mut [f32],
        rewards_out: &mut [f64],
        terminated_out: &mut [bool],
        truncated_out: &mut [bool],
    ) -> Result<FinalSteps<'_>> {
        let (m, n, d) = (self.num_envs(), self.action_dim(), self.observation_dim());
        check_len("actions", actions.len(), m * n)?;
        check_len("obs_out", obs_out.len(), m * d)?;
        check_len("rewards_out", rewards_out.len(), m)?;
        check_len("terminated_out", terminated_out.len(), m)?;
        check_len("truncated_out", truncated_out.len(), m)?;
        if let Some(k) = actions.iter().position(|a| !(*a).into().is_finite()) {
            let a: f64 = actions[k].into();
            return Err(invalid(format!(
                "env {}: action[{}] must be finite, got {a}",
                k / n,
                k % n
            )));
        }
        if let Some(i) = self.slots.iter().position(|s| s.env.needs_reset()) {
            return Err(invalid(format!("env {i}: step() needs reset() first")));
        }
        let job = |slot: &mut Slot,
                   action: &[A],
                   obs: &mut [f32],
                   out: (&mut f64, &mut bool, &mut bool)| {
            slot.finished = false;
            let result = slot.env.step_into(action, obs).and_then(|step| {
                *out.0 = step.reward;
                *out.1 = step.terminated;
                *out.2 = step.truncated;
                slot.info = Some(step.info);
                if step.terminated || step.truncated {
                    slot.final_obs.copy_from_slice(obs);
                    slot.finished = true;
                    slot.env.reset_into(None, ResetOptions::default(), obs)?;
                }
                Ok(())
            });
            slot.error = result.err();
        };
        match &self.parallelism {
            Parallelism::Sequential => {
                let outs = rewards_out
                    .iter_mut()
                    .zip(terminated_out.iter_mut())
                    .zip(truncated_out.iter_mut());
                for (((slot, action), obs), ((r, te), tr)) in self
                    .slots
                    .iter_mut()
                    .zip(actions.chunks(n))
                    .zip(obs_out.chunks_mut(d))
                    .zip(outs)
                {
                    job(slot, action, obs, (r, te, tr));
                }
            }
            parallel => {
                let slots = &mut self.slots;
                let mut run = || {
                    use rayon::prelude::*;
                    let outs = rewards_out
                        .par_iter_mut()
                        .zip(terminated_out.par_iter_mut())
                        .zip(truncated_out.par_iter_mut());
                    slots
                        .par_iter_mut()
                        .zip(actions.par_chunks(n))
                        .zip(obs_out.par_chunks_mut(d))
                        .zip(outs)
                        .with_max_len(1)
                        .for_each(|(((slot, action), obs), ((r, te), tr))| {
                            job(slot, action, obs, (r, te, tr))
                        });
                };
                match parallel {
                    Parallelism::Pool(pool) => pool.install(run),
                    _ => run(),
                }
            }
        }
        self.first_error()?;
        Ok(FinalSteps { slots: &self.slots })
    }

    /// The first env's error of the last parallel call, if any (every slot's error is cleared).
    fn first_error(&mut self) -> Result<()> {
        let mut first = None;
        for (i, slot) in self.slots.iter_mut().enumerate() {
            if let Some(e) = slot.error.take() {
                first.get_or_insert(in_env(i, e));
            }
        }
        first.map_or(Ok(()), Err)
    }
}
