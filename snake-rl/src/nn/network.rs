//! The paper's actor-critic networks over one flat parameter buffer, laid out and named as
//! Stable-Baselines3's `ActorCriticPolicy` names its tensors, so that weights move between the two
//! one to one.
//!
//! - [`Arch::Small`] (PPO-small, SB3's default `MlpPolicy`): separate policy and value networks of
//!   two tanh layers of 64; `log_std`, `mlp_extractor.{policy,value}_net.{0,2}`, `action_net`,
//!   `value_net`.
//! - [`Arch::Large`] (PPO-large, the paper's `net_arch=[128, 128, dict(pi=[64, 64], vf=[64, 64])]`):
//!   a shared trunk of two tanh layers of 128 (`features_extractor.shared_net.{0,2}`, as snakesim's
//!   SB3 features extractor names it), then the same [64, 64] heads.
//! - [`Arch::Custom`]: any widths ([`NetArch`]: a trunk, then a policy and a value head of at least
//!   one layer each), named the same way.

use serde::{Deserialize, Serialize};

use super::activation::{tanh_backward_in_place, tanh_in_place};
use super::dense::Dense;

/// Most tanh layers of one part of a network (the shared trunk, the policy or the value head).
pub const MAX_LAYERS: usize = 8;
/// Widest tanh layer: four times the [256, 256] that locomotion PPO configs commonly reach for, and a
/// bound of three parts of 8 x 1024^2 weights, about 25M parameters or 400 MB with gradients and
/// Adam's two moments. At 4096 the same limits allowed 6.4 GB.
pub const MAX_WIDTH: usize = 1024;

/// The widths of a network's tanh layers, as SB3's `net_arch` gives them, with the paper's shared trunk
/// in front: `shared` feeds both heads (empty: none), then `pi` (the policy) and `vf` (the value
/// function) each have layers of their own. A key left out takes PPO-small's value.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NetArch {
    /// Layers shared by the policy and the value function (PPO-large: [128, 128]).
    pub shared: Vec<usize>,
    /// The policy's own layers ([64, 64]).
    pub pi: Vec<usize>,
    /// The value function's own layers ([64, 64]).
    pub vf: Vec<usize>,
}

impl Default for NetArch {
    fn default() -> Self {
        Arch::Small.net()
    }
}

impl NetArch {
    /// Checks every part's depth and widths; the error names the part (`arch.pi: ...`).
    pub fn check(&self) -> Result<(), String> {
        for (part, widths, least) in [
            ("shared", &self.shared, 0),
            ("pi", &self.pi, 1),
            ("vf", &self.vf, 1),
        ] {
            if widths.len() < least || widths.len() > MAX_LAYERS {
                return Err(format!(
                    "arch.{part}: must have {least} to {MAX_LAYERS} layers, got {}",
                    widths.len()
                ));
            }
            if let Some(w) = widths.iter().find(|w| !(1..=MAX_WIDTH).contains(*w)) {
                return Err(format!(
                    "arch.{part}: layer widths must be in [1, {MAX_WIDTH}], got {w}"
                ));
            }
        }
        Ok(())
    }
}

/// Which network: one of the paper's two by name, or any [`NetArch`] (a mapping in a configuration).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub enum Arch {
    /// Separate policy and value networks of [64, 64] (tanh).
    #[default]
    Small,
    /// A shared [128, 128] tanh trunk, then policy and value heads of [64, 64].
    Large,
    /// Any other widths (one equal to a named network is that network).
    Custom(NetArch),
}

const HEADS: &[usize] = &[64, 64];
const LARGE_TRUNK: &[usize] = &[128, 128];

impl Arch {
    /// The named architectures, in the order of their names in [`Arch::NAMES`].
    pub const ALL: [Arch; 2] = [Arch::Small, Arch::Large];
    /// The configuration names.
    pub const NAMES: [&'static str; 2] = ["small", "large"];

    /// The network of `net`: a named one where the widths are its widths.
    pub fn from_net(net: NetArch) -> Self {
        Arch::ALL
            .into_iter()
            .find(|a| {
                a.shared_widths() == net.shared
                    && a.pi_widths() == net.pi
                    && a.vf_widths() == net.vf
            })
            .unwrap_or(Arch::Custom(net))
    }

    /// The named network called `name` (`small` or `large`).
    pub fn named(name: &str) -> Option<Arch> {
        Arch::ALL.into_iter().find(|a| a.name() == Some(name))
    }

    /// The configuration name: `small`, `large`, or None for a custom network.
    pub fn name(&self) -> Option<&'static str> {
        match self {
            Arch::Small => Some("small"),
            Arch::Large => Some("large"),
            Arch::Custom(_) => None,
        }
    }

    /// Its widths.
    pub fn net(&self) -> NetArch {
        NetArch {
            shared: self.shared_widths().to_vec(),
            pi: self.pi_widths().to_vec(),
            vf: self.vf_widths().to_vec(),
        }
    }

    /// Widths of the shared trunk's tanh layers.
    pub fn shared_widths(&self) -> &[usize] {
        match self {
            Arch::Small => &[],
            Arch::Large => LARGE_TRUNK,
            Arch::Custom(n) => &n.shared,
        }
    }

    /// Widths of the policy head's tanh layers.
    pub fn pi_widths(&self) -> &[usize] {
        match self {
            Arch::Small | Arch::Large => HEADS,
            Arch::Custom(n) => &n.pi,
        }
    }

    /// Widths of the value head's tanh layers.
    pub fn vf_widths(&self) -> &[usize] {
        match self {
            Arch::Small | Arch::Large => HEADS,
            Arch::Custom(n) => &n.vf,
        }
    }

    /// Checks a custom network's widths (the named ones are fine).
    pub fn check(&self) -> Result<(), String> {
        match self {
            Arch::Custom(n) => n.check(),
            _ => Ok(()),
        }
    }

    /// As a model file's metadata holds it: the name, or the widths as a JSON mapping.
    pub fn to_meta(&self) -> String {
        match self {
            Arch::Custom(n) => serde_json::to_string(n).expect("widths serialise"),
            named => named.name().expect("a named network").to_owned(),
        }
    }
}

/// `small`, `large`, or the widths (`shared [32], pi [256, 256], vf [256, 256]`).
impl std::fmt::Display for Arch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(name) = self.name() {
            return f.write_str(name);
        }
        if !self.shared_widths().is_empty() {
            write!(f, "shared {:?}, ", self.shared_widths())?;
        }
        write!(f, "pi {:?}, vf {:?}", self.pi_widths(), self.vf_widths())
    }
}

/// A name, or (as [`Arch::to_meta`] writes it) the widths as a JSON mapping.
impl std::str::FromStr for Arch {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if let Some(a) = Arch::named(s) {
            return Ok(a);
        }
        if s.trim_start().starts_with('{') {
            let net: NetArch =
                serde_json::from_str(s).map_err(|e| format!("arch: bad widths {s} ({e})"))?;
            net.check()?;
            return Ok(Arch::from_net(net));
        }
        Err(format!(
            "unknown arch '{s}' (expected small, large or a mapping of widths {{shared, pi, vf}})"
        ))
    }
}

impl Serialize for Arch {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Arch::Custom(n) => n.serialize(s),
            named => s.serialize_str(named.name().expect("named")),
        }
    }
}

impl<'de> Deserialize<'de> for Arch {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Arch;

            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("small, large, or a mapping of layer widths {shared, pi, vf}")
            }

            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<Arch, E> {
                Arch::named(s).ok_or_else(|| E::unknown_variant(s, &Arch::NAMES))
            }

            fn visit_map<M: serde::de::MapAccess<'de>>(self, map: M) -> Result<Arch, M::Error> {
                let net = NetArch::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(Arch::from_net(net))
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// How a layer's weight is initialised (SB3's orthogonal init): the gain of its orthogonal matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Role {
    /// A hidden tanh layer (gain sqrt(2)).
    Hidden,
    /// The policy head's output, the action means (gain 0.01).
    ActionMean,
    /// The value head's output (gain 1).
    Value,
}

impl Role {
    /// SB3's `ortho_init` gain for this role.
    pub fn gain(self) -> f64 {
        match self {
            Role::Hidden => std::f64::consts::SQRT_2,
            Role::ActionMean => 0.01,
            Role::Value => 1.0,
        }
    }
}

/// One named tensor of the parameter buffer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tensor {
    /// SB3's `state_dict` name.
    pub name: String,
    /// Its shape (PyTorch's: `[outputs, inputs]` for a weight).
    pub shape: Vec<usize>,
    /// Offset in the flat buffer.
    pub offset: usize,
}

impl Tensor {
    /// Number of values.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether it holds no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The network's structure: where each layer lives in the flat parameter buffer.
#[derive(Debug, Clone, PartialEq)]
pub struct ActorCritic {
    arch: Arch,
    obs_dim: usize,
    act_dim: usize,
    shared: Vec<Dense>,
    pi: Vec<Dense>,
    vf: Vec<Dense>,
    action: Dense,
    value: Dense,
    log_std: usize,
    len: usize,
}

/// A chain of tanh layers starting at `offset`; returns the layers and the offset past them.
fn chain(mut offset: usize, mut width: usize, widths: &[usize]) -> (Vec<Dense>, usize, usize) {
    let mut layers = Vec::with_capacity(widths.len());
    for &w in widths {
        let d = Dense::at(offset, width, w);
        offset = d.end();
        width = w;
        layers.push(d);
    }
    (layers, offset, width)
}

impl ActorCritic {
    /// The network `arch` for observations of `obs_dim` values and `act_dim` actions. Its widths must
    /// pass [`Arch::check`] (the policy and value heads have at least one layer each).
    pub fn new(arch: Arch, obs_dim: usize, act_dim: usize) -> Self {
        // log_std first, as SB3's state_dict lists it.
        let log_std = 0;
        // Buffer order: log_std, trunk, policy layers, action head, value layers, value head. The
        // policy's parameters (with log_std) come before the value network's, so that PPO-small's two
        // networks own two contiguous ranges that two threads can update at once (see `Branch`).
        let (shared, offset, trunk) = chain(act_dim, obs_dim, arch.shared_widths());
        let (pi, offset, pi_width) = chain(offset, trunk, arch.pi_widths());
        let action = Dense::at(offset, pi_width, act_dim);
        let (vf, offset, vf_width) = chain(action.end(), trunk, arch.vf_widths());
        let value = Dense::at(offset, vf_width, 1);
        ActorCritic {
            arch,
            obs_dim,
            act_dim,
            shared,
            pi,
            vf,
            action,
            value,
            log_std,
            len: value.end(),
        }
    }

    /// The architecture.
    pub fn arch(&self) -> &Arch {
        &self.arch
    }

    /// Observation length.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Action length.
    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// Number of parameters (the flat buffer's length).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the network has no parameters (never).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Offset of the `act_dim` log standard deviations.
    pub fn log_std_offset(&self) -> usize {
        self.log_std
    }

    /// Every dense layer with its initialisation role.
    pub fn layers(&self) -> Vec<(Dense, Role)> {
        let hidden = self.shared.iter().chain(&self.pi).chain(&self.vf);
        hidden
            .map(|d| (*d, Role::Hidden))
            .chain([(self.action, Role::ActionMean), (self.value, Role::Value)])
            .collect()
    }

    /// Without a shared trunk (PPO-small), the offset where the value network's parameters begin:
    /// the policy (log_std, policy layers, action head) owns `[0, split)`, the value network
    /// `[split, len)`.
    pub fn branch_split(&self) -> Option<usize> {
        self.shared
            .is_empty()
            .then(|| self.vf.first().map_or(self.value.weight, |d| d.weight))
    }

    /// PPO-small's policy network alone, over the parameter range `[0, split)`.
    pub fn policy_branch(&self) -> Option<Branch> {
        self.branch_split().map(|_| Branch {
            layers: self.pi.clone(),
            out: self.action,
        })
    }

    /// PPO-small's value network alone, over the parameter range `[split, len)` (offsets relative to
    /// `split`).
    pub fn value_branch(&self) -> Option<Branch> {
        let split = self.branch_split()?;
        let rebase = |d: &Dense| Dense {
            weight: d.weight - split,
            bias: d.bias - split,
            ..*d
        };
        Some(Branch {
            layers: self.vf.iter().map(rebase).collect(),
            out: rebase(&self.value),
        })
    }

    /// The named tensors, in buffer order, with SB3's `state_dict` names.
    pub fn tensors(&self) -> Vec<Tensor> {
        let mut out = vec![Tensor {
            name: "log_std".into(),
            shape: vec![self.act_dim],
            offset: self.log_std,
        }];
        let mut push = |prefix: String, d: &Dense| {
            out.push(Tensor {
                name: format!("{prefix}.weight"),
                shape: vec![d.outputs, d.inputs],
                offset: d.weight,
            });
            out.push(Tensor {
                name: format!("{prefix}.bias"),
                shape: vec![d.outputs],
                offset: d.bias,
            });
        };
        // nn.Sequential(Linear, Tanh, Linear, Tanh): the linear layers are entries 0, 2, ...
        for (k, d) in self.shared.iter().enumerate() {
            push(format!("features_extractor.shared_net.{}", 2 * k), d);
        }
        for (k, d) in self.pi.iter().enumerate() {
            push(format!("mlp_extractor.policy_net.{}", 2 * k), d);
        }
        for (k, d) in self.vf.iter().enumerate() {
            push(format!("mlp_extractor.value_net.{}", 2 * k), d);
        }
        push("action_net".into(), &self.action);
        push("value_net".into(), &self.value);
        out
    }

    /// Buffers for a forward and backward pass of up to `rows` rows.
    pub fn workspace(&self, rows: usize) -> Workspace {
        let mut ws = Workspace::default();
        ws.ensure(self, rows);
        ws
    }

    fn widest(&self) -> usize {
        self.shared
            .iter()
            .chain(&self.pi)
            .chain(&self.vf)
            .map(|d| d.outputs.max(d.inputs))
            .chain([self.obs_dim, self.act_dim])
            .max()
            .unwrap_or(1)
    }

    /// Action means and values of `rows` observations (`rows x obs_dim`); results in `ws.mean`
    /// (`rows x act_dim`) and `ws.value` (`rows`), hidden activations kept for [`Self::backward`].
    pub fn forward(&self, params: &[f32], obs: &[f32], rows: usize, ws: &mut Workspace) {
        debug_assert_eq!(params.len(), self.len);
        ws.ensure(self, rows);
        ws.rows = rows;
        let trunk = tanh_chain(&self.shared, &mut ws.shared, params, obs, rows);
        let pi = tanh_chain(&self.pi, &mut ws.pi, params, trunk, rows);
        self.action.forward(params, pi, rows, &mut ws.mean);
        let vf = tanh_chain(&self.vf, &mut ws.vf, params, trunk, rows);
        self.value.forward(params, vf, rows, &mut ws.value);
    }

    /// Values only (the value network), into `ws.value`.
    pub fn forward_value(&self, params: &[f32], obs: &[f32], rows: usize, ws: &mut Workspace) {
        ws.ensure(self, rows);
        ws.rows = rows;
        let trunk = tanh_chain(&self.shared, &mut ws.shared, params, obs, rows);
        let vf = tanh_chain(&self.vf, &mut ws.vf, params, trunk, rows);
        self.value.forward(params, vf, rows, &mut ws.value);
    }

    /// Gradients of every weight and bias (not `log_std`, which the loss owns) from dL/d(mean)
    /// (`ws.d_mean`, `rows x act_dim`) and dL/d(value) (`ws.d_value`), after [`Self::forward`] on
    /// the same `obs`. Overwrites those entries of `grads`.
    pub fn backward(&self, params: &[f32], obs: &[f32], ws: &mut Workspace, grads: &mut [f32]) {
        let rows = ws.rows;
        let Workspace {
            shared,
            pi,
            vf,
            d_mean,
            d_value,
            d_a,
            d_b,
            d_trunk,
            ..
        } = ws;
        let trunk: &[f32] = shared.last().map_or(obs, |v| v.as_slice());
        let has_trunk = !self.shared.is_empty();

        let heads = [
            (&self.pi, &*pi, self.action, &*d_mean),
            (&self.vf, &*vf, self.value, &*d_value),
        ];
        for (k, (layers, acts, out, d_out)) in heads.into_iter().enumerate() {
            let head = Head {
                layers,
                acts,
                out,
                input: trunk,
                rows,
            };
            head.backward(params, d_out, grads, d_a, d_b, has_trunk);
            if has_trunk {
                // d_a now holds dL/d(trunk) from this head; the trunk gets the sum of both heads'.
                let n = rows * self.shared.last().map_or(0, |d| d.outputs);
                if k == 0 {
                    d_trunk[..n].copy_from_slice(&d_a[..n]);
                } else {
                    for (t, g) in d_trunk[..n].iter_mut().zip(&d_a[..n]) {
                        *t += g;
                    }
                }
            }
        }
        if has_trunk {
            let n = rows * self.shared.last().map_or(0, |d| d.outputs);
            d_a[..n].copy_from_slice(&d_trunk[..n]);
            for i in (0..self.shared.len()).rev() {
                let d = self.shared[i];
                tanh_backward_in_place(&mut d_a[..rows * d.outputs], &shared[i]);
                if i > 0 {
                    d.backward(params, &shared[i - 1], d_a, rows, grads, Some(d_b));
                    std::mem::swap(d_a, d_b);
                } else {
                    d.backward(params, obs, d_a, rows, grads, None);
                }
            }
        }
    }
}

/// One head's backward pass: its output layer, then its tanh layers from the last to the first.
struct Head<'a> {
    layers: &'a [Dense],
    acts: &'a [Vec<f32>],
    out: Dense,
    input: &'a [f32],
    rows: usize,
}

impl Head<'_> {
    /// Writes the head's parameter gradients into `grads` from dL/d(output) `d_out`; with
    /// `input_gradient`, leaves dL/d(input) in `d_a` (`d_b` is scratch).
    fn backward(
        &self,
        params: &[f32],
        d_out: &[f32],
        grads: &mut [f32],
        d_a: &mut Vec<f32>,
        d_b: &mut Vec<f32>,
        input_gradient: bool,
    ) {
        let rows = self.rows;
        let last = self.acts.last().expect("heads have layers");
        self.out
            .backward(params, last, d_out, rows, grads, Some(d_a.as_mut_slice()));
        for i in (0..self.layers.len()).rev() {
            let d = self.layers[i];
            tanh_backward_in_place(&mut d_a[..rows * d.outputs], &self.acts[i]);
            let input = if i == 0 {
                self.input
            } else {
                &self.acts[i - 1]
            };
            if i > 0 || input_gradient {
                d.backward(params, input, d_a, rows, grads, Some(d_b.as_mut_slice()));
                std::mem::swap(d_a, d_b);
            } else {
                d.backward(params, input, d_a, rows, grads, None);
            }
        }
    }
}

/// One of PPO-small's two networks on its own (tanh layers and an output layer), over a parameter
/// range of its own: see [`ActorCritic::policy_branch`] and [`ActorCritic::value_branch`].
#[derive(Debug, Clone, PartialEq)]
pub struct Branch {
    layers: Vec<Dense>,
    out: Dense,
}

/// Buffers of a [`Branch`]'s forward and backward passes.
#[derive(Debug, Clone, Default)]
pub struct BranchWorkspace {
    rows: usize,
    acts: Vec<Vec<f32>>,
    /// The branch's output of the last forward pass (`rows x outputs`).
    pub out: Vec<f32>,
    /// dL/d(output), filled by the loss before [`Branch::backward`].
    pub d_out: Vec<f32>,
    d_a: Vec<f32>,
    d_b: Vec<f32>,
}

impl Branch {
    /// Width of the branch's output.
    pub fn outputs(&self) -> usize {
        self.out.outputs
    }

    fn ensure(&self, ws: &mut BranchWorkspace, rows: usize) {
        if ws.acts.len() == self.layers.len()
            && ws.out.len() >= rows * self.out.outputs
            && ws.rows >= rows
        {
            return;
        }
        ws.rows = rows.max(ws.rows);
        let rows = ws.rows;
        ws.acts = self
            .layers
            .iter()
            .map(|d| vec![0.0; rows * d.outputs])
            .collect();
        ws.out = vec![0.0; rows * self.out.outputs];
        ws.d_out = vec![0.0; rows * self.out.outputs];
        let widest = self
            .layers
            .iter()
            .map(|d| d.inputs.max(d.outputs))
            .max()
            .unwrap_or(1);
        ws.d_a = vec![0.0; rows * widest];
        ws.d_b = vec![0.0; rows * widest];
    }

    /// The branch's outputs for `rows` observations, into `ws.out`.
    pub fn forward(&self, params: &[f32], obs: &[f32], rows: usize, ws: &mut BranchWorkspace) {
        self.ensure(ws, rows);
        let last = tanh_chain(&self.layers, &mut ws.acts, params, obs, rows);
        self.out.forward(params, last, rows, &mut ws.out);
    }

    /// The branch's parameter gradients from `ws.d_out`, after [`Branch::forward`] on `obs`.
    pub fn backward(
        &self,
        params: &[f32],
        obs: &[f32],
        rows: usize,
        ws: &mut BranchWorkspace,
        grads: &mut [f32],
    ) {
        let BranchWorkspace {
            acts,
            d_out,
            d_a,
            d_b,
            ..
        } = ws;
        let head = Head {
            layers: &self.layers,
            acts,
            out: self.out,
            input: obs,
            rows,
        };
        head.backward(params, d_out, grads, d_a, d_b, false);
    }
}

/// Runs `rows` rows of `input` through a chain of dense + tanh layers, each writing its output into
/// its buffer in `outputs`; returns the last output (`input` itself for an empty chain).
fn tanh_chain<'a>(
    layers: &[Dense],
    outputs: &'a mut [Vec<f32>],
    params: &[f32],
    input: &'a [f32],
    rows: usize,
) -> &'a [f32] {
    let mut input = input;
    for (d, out) in layers.iter().zip(outputs.iter_mut()) {
        d.forward(params, input, rows, out);
        tanh_in_place(&mut out[..rows * d.outputs]);
        input = out;
    }
    input
}

/// Buffers of one forward/backward pass; grows to the rows asked for and is reused.
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    rows: usize,
    capacity: usize,
    shared: Vec<Vec<f32>>,
    pi: Vec<Vec<f32>>,
    vf: Vec<Vec<f32>>,
    /// Action means of the last forward pass (`rows x act_dim`).
    pub mean: Vec<f32>,
    /// Values of the last forward pass (`rows`).
    pub value: Vec<f32>,
    /// dL/d(mean), filled by the loss before [`ActorCritic::backward`].
    pub d_mean: Vec<f32>,
    /// dL/d(value), filled by the loss before [`ActorCritic::backward`].
    pub d_value: Vec<f32>,
    d_a: Vec<f32>,
    d_b: Vec<f32>,
    d_trunk: Vec<f32>,
}

impl Workspace {
    fn ensure(&mut self, net: &ActorCritic, rows: usize) {
        let fits = |v: &Vec<Vec<f32>>, layers: &[Dense]| {
            v.len() == layers.len()
                && v.iter()
                    .zip(layers)
                    .all(|(b, d)| b.len() >= rows * d.outputs)
        };
        if rows <= self.capacity
            && fits(&self.shared, &net.shared)
            && fits(&self.pi, &net.pi)
            && fits(&self.vf, &net.vf)
            && self.mean.len() >= rows * net.act_dim
        {
            return;
        }
        let rows = rows.max(self.capacity);
        let alloc = |layers: &[Dense]| -> Vec<Vec<f32>> {
            layers.iter().map(|d| vec![0.0; rows * d.outputs]).collect()
        };
        self.shared = alloc(&net.shared);
        self.pi = alloc(&net.pi);
        self.vf = alloc(&net.vf);
        self.mean = vec![0.0; rows * net.act_dim];
        self.value = vec![0.0; rows];
        self.d_mean = vec![0.0; rows * net.act_dim];
        self.d_value = vec![0.0; rows];
        let wide = rows * net.widest();
        self.d_a = vec![0.0; wide];
        self.d_b = vec![0.0; wide];
        self.d_trunk = vec![0.0; wide];
        self.capacity = rows;
    }

    /// Rows of the last forward pass.
    pub fn rows(&self) -> usize {
        self.rows
    }
}
