"""TD-MPC2 (Hansen et al., 2024) on the world-model contract of :mod:`stable_worldmodel.wm.jepa`.

A latent world model trained on rewards, not goals: an encoder to a SimNorm latent ``z``, a
latent dynamics ``z' = d(z, a)``, a reward head ``R(z, a)`` and an ensemble of Q heads
(two-hot distributions over symlog bins), and a tanh-Gaussian policy prior ``pi(z)``. Plans
score candidates by their discounted predicted reward plus a terminal Q value; there is no
goal (``info["goal"]`` is ignored). Shapes: ``B`` envs, ``S`` candidates, ``T`` frames, ``H``
horizon, ``A`` action block (``frameskip`` env actions), ``L`` latent::

    encode(info)                    -> info + emb (B, T, L)           from pixels (B, T, C, h, w)
    predict(z, action)              -> next z (..., L), reward logits (..., num_bins)
    rollout(info, candidates)       -> info + predicted_emb (B, S, H + 1, L), predicted_reward (B, S, H)
    get_cost(info, candidates)      -> (B, S) = - predicted return (lower is better)
    get_action(info)                -> (B, A) from the policy prior (``horizon=k``: (B, k, A), a warm start)
    loss(batch)                     -> {"loss", "consistency_loss", "reward_loss", "value_loss", "pi_loss", "emb"}

``get_cost`` encodes the last context frame once per plan and keeps it in ``info["emb"]``.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import torch
import torch.nn.functional as F
from torch import nn

from ... import keys
from ...errors import ConfigError, SpaceError, UnknownNameError, did_you_mean
from ..encoders import ConvEncoder
from .module import (
    NormedLinear,
    RunningScale,
    SimNorm,
    gaussian_logprob,
    log_std,
    mlp,
    squash,
    two_hot,
    two_hot_inv,
    weight_init,
)

__all__ = ["TDMPC2", "EMB", "PREDICTED_EMB", "PREDICTED_REWARD", "WM_DEFAULTS"]

EMB, PREDICTED_EMB, PREDICTED_REWARD = "emb", "predicted_emb", "predicted_reward"
PIXEL_ENCODERS = ("tdmpc2", "conv")

#: ``cfg["wm"]`` keys and their defaults (upstream's names; ``encoder``, ``cnn_width``,
#: ``num_channels`` and ``q_dropout`` are ours: upstream always builds its 32-channel CNN; so is
#: ``bc_coef``, 0 for upstream's loss)
WM_DEFAULTS: dict[str, Any] = {
    "encoding": {keys.PIXELS: 512},
    "encoder": "tdmpc2",
    "num_channels": 32,
    "cnn_width": 16,
    "enc_dim": 256,
    "mlp_dim": 512,
    "num_bins": 101,
    "vmin": -10.0,
    "vmax": 10.0,
    "num_q": 5,
    "simnorm_dim": 8,
    "q_dropout": 0.01,
    "tau": 0.01,
    "rho": 0.5,
    "discount": 0.99,
    "entropy_coef": 1e-4,
    "consistency_coef": 20.0,
    "reward_coef": 0.1,
    "value_coef": 0.1,
    "horizon": 3,
    "uncertainty_penalty": 0.5,
    "bc_coef": 0.0,
}


def _plain(cfg: Any) -> dict:
    """A mapping, an OmegaConf config or an attribute object as a plain dict."""
    if isinstance(cfg, Mapping):
        return dict(cfg)
    if hasattr(cfg, "__dict__"):
        return {k: v for k, v in vars(cfg).items() if not k.startswith("_")}
    raise ConfigError(
        f"TDMPC2 requires cfg to be a mapping (upstream's cfg with a 'wm' section), got {type(cfg).__name__}"
    )


def _read_cfg(cfg: Any) -> dict:
    """Upstream's ``cfg`` (``image_size``, ``action_dim``, ``extra_dims``, ``num_pi_trajs``,
    ``wm: {...}``) with defaults filled in and checked."""
    top = _plain(cfg)
    wm = _plain(top.get("wm", {}))
    unknown = sorted(set(wm) - set(WM_DEFAULTS))
    if unknown:
        raise ConfigError(
            f"TDMPC2 has no cfg.wm key {unknown[0]!r}.{did_you_mean(unknown[0], WM_DEFAULTS)} "
            f"Keys: {', '.join(WM_DEFAULTS)}"
        )
    wm = {**WM_DEFAULTS, **wm, "encoding": _plain(wm.get("encoding", WM_DEFAULTS["encoding"]))}
    out = {
        "image_size": top.get("image_size", 64),
        "action_dim": top.get("action_dim"),
        "extra_dims": _plain(top.get("extra_dims") or {}),
        "num_pi_trajs": top.get("num_pi_trajs", 1),
        "wm": wm,
    }
    ints = {
        "action_dim": out["action_dim"],
        "num_pi_trajs": out["num_pi_trajs"],
        "image_size": out["image_size"],
        **{
            k: wm[k]
            for k in ("num_channels", "cnn_width", "enc_dim", "mlp_dim", "num_bins", "num_q", "simnorm_dim", "horizon")
        },
        **{f"encoding[{k!r}]": v for k, v in wm["encoding"].items()},
    }
    for name, value in ints.items():
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ConfigError(f"TDMPC2 requires cfg {name} to be a positive int, got {value!r}")
    if wm["encoder"] not in PIXEL_ENCODERS:
        hint = did_you_mean(str(wm["encoder"]), PIXEL_ENCODERS)
        raise ConfigError(f"TDMPC2 requires cfg.wm.encoder in {PIXEL_ENCODERS}, got {wm['encoder']!r}.{hint}")
    if wm["num_q"] < 2 or wm["num_bins"] < 2 or not wm["vmin"] < wm["vmax"]:
        raise ConfigError(
            "TDMPC2 requires num_q >= 2, num_bins >= 2 and vmin < vmax, "
            f"got {wm['num_q']}, {wm['num_bins']}, {wm['vmin']}, {wm['vmax']}"
        )
    latent = sum(wm["encoding"].values())
    if latent % wm["simnorm_dim"]:
        raise ConfigError(
            f"TDMPC2 requires a latent width (sum of cfg.wm.encoding {wm['encoding']}) divisible by "
            f"simnorm_dim={wm['simnorm_dim']}, got {latent}"
        )
    missing = [k for k in wm["encoding"] if k != keys.PIXELS and k not in out["extra_dims"]]
    if missing:
        raise ConfigError(f"TDMPC2 requires cfg.extra_dims for every non-pixel encoding, got none for {missing}")
    return out


def _upstream_cnn(channels: int) -> nn.Sequential:
    """Upstream's pixel CNN (64x64 -> 4x4 maps): four Mish convs, then Flatten."""
    c = channels
    return nn.Sequential(
        nn.Conv2d(3, c, 7, stride=2),
        nn.Mish(),
        nn.Conv2d(c, c, 5, stride=2),
        nn.Mish(),
        nn.Conv2d(c, c, 3, stride=2),
        nn.Mish(),
        nn.Conv2d(c, c, 3, stride=1),
        nn.Mish(),
        nn.Flatten(),
    )


def _require(info: dict, key: str, who: str) -> torch.Tensor:
    if key not in info:
        raise UnknownNameError(f"{who} requires info[{key!r}], got keys {sorted(info)}")
    return info[key]


class TDMPC2(nn.Module):
    """``TDMPC2(cfg, extra_encoders=None)``: upstream 0.1.1's constructor and submodules
    (``cnn`` + ``pixel_encoder``, ``extra_encoders``, ``sim_norm``, ``dynamics``, ``reward``,
    ``pi``, ``qs``, ``target_qs``, ``scale``), so its ``state_dict`` keys match.

    ``cfg`` is a mapping (see :data:`WM_DEFAULTS`; :class:`~stable_worldmodel.wm.tdmpc2.config.TDMPC2Config`
    renders it): ``image_size``, ``action_dim`` (the action block), ``extra_dims`` (width of each
    non-pixel input), ``num_pi_trajs`` and ``wm.encoding`` (input -> latent width; the latent
    ``L`` is their sum). ``wm.encoder="conv"`` replaces upstream's CNN with a
    :class:`~stable_worldmodel.wm.encoders.ConvEncoder` (in ``cnn``; any image size >= 8).
    Actions are normalized blocks in ``[-1, 1]`` for the policy; rewards and values are
    expected in ``symexp([vmin, vmax])``.
    """

    #: the term of :meth:`loss` the trainer's validation reports (``val/loss``)
    validation_loss = "model_loss"

    def __init__(self, cfg: Any, extra_encoders: nn.ModuleDict | Mapping[str, nn.Module] | None = None):
        super().__init__()
        self.cfg = c = _read_cfg(cfg)
        wm = c["wm"]
        self.action_dim, self.num_bins, self.vmin, self.vmax = (
            c["action_dim"],
            wm["num_bins"],
            float(wm["vmin"]),
            float(wm["vmax"]),
        )
        self.scale = RunningScale(wm["tau"])
        encoding = wm["encoding"]
        self.use_pixels = keys.PIXELS in encoding
        if self.use_pixels:
            width = encoding[keys.PIXELS]
            if wm["encoder"] == "conv":
                self.cnn: nn.Module = ConvEncoder(image_size=c["image_size"], width=wm["cnn_width"], hidden_size=width)
                self.pixel_encoder: nn.Module = nn.Identity()
            else:
                self.cnn = _upstream_cnn(wm["num_channels"])
                side = c["image_size"]
                for kernel, stride in ((7, 2), (5, 2), (3, 2), (3, 1)):
                    side = (side - kernel) // stride + 1
                if side < 1:
                    raise ConfigError(
                        f"TDMPC2's upstream CNN requires image_size >= 35, got {c['image_size']}; "
                        "use cfg.wm.encoder='conv'"
                    )
                self.pixel_encoder = nn.Linear(wm["num_channels"] * side * side, width)
        if extra_encoders is None:
            extra_encoders = {
                k: nn.Sequential(
                    NormedLinear(c["extra_dims"][k], wm["enc_dim"]), nn.Linear(wm["enc_dim"], d), nn.LayerNorm(d)
                )
                for k, d in encoding.items()
                if k != keys.PIXELS
            }
        self.extra_encoders = (
            extra_encoders if isinstance(extra_encoders, nn.ModuleDict) else nn.ModuleDict(dict(extra_encoders))
        )
        self.latent_dim = sum(encoding.values())
        za = self.latent_dim + self.action_dim
        self.sim_norm = SimNorm(wm["simnorm_dim"])
        self.dynamics = mlp(za, wm["mlp_dim"], self.latent_dim, act=SimNorm(wm["simnorm_dim"]))
        self.reward = mlp(za, wm["mlp_dim"], self.num_bins)
        self.pi = mlp(self.latent_dim, wm["mlp_dim"], 2 * self.action_dim)
        self.qs = nn.ModuleList(
            mlp(za, wm["mlp_dim"], self.num_bins, dropout=wm["q_dropout"]) for _ in range(wm["num_q"])
        )
        self.apply(weight_init)
        for head in (self.reward, *self.qs):
            nn.init.zeros_(head[-1].weight)  # predict the middle bin (0) at first
        self.target_qs = copy.deepcopy(self.qs).requires_grad_(False)

    # -- sizes ---------------------------------------------------------------------------------
    @property
    def history_size(self) -> int:
        """Frames the model looks at: the last one."""
        return 1

    def _dtype(self) -> torch.dtype:
        return self.pi[0].weight.dtype

    # -- encode / predict ------------------------------------------------------------------------
    def encode_obs(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """``{pixels: (..., C, h, w), <key>: (..., d)}`` -> SimNorm latents ``(..., L)``."""
        parts = []
        if self.use_pixels:
            pixels = obs[keys.PIXELS].to(self._dtype())
            lead = pixels.shape[:-3]
            feat = self.cnn(pixels.reshape(-1, *pixels.shape[-3:]))
            if not torch.is_tensor(feat):  # a ConvEncoder: one token
                feat = feat.last_hidden_state[:, 0]
            parts.append(self.pixel_encoder(feat).reshape(*lead, -1))
        for key, encoder in self.extra_encoders.items():
            value = obs[key].to(self._dtype())
            parts.append(encoder(value.reshape(-1, value.shape[-1])).reshape(*value.shape[:-1], -1))
        return self.sim_norm(torch.cat(parts, dim=-1))

    def _inputs(self, info: dict, who: str) -> dict[str, torch.Tensor]:
        names = ([keys.PIXELS] if self.use_pixels else []) + list(self.extra_encoders)
        return {k: _require(info, k, who) for k in names}

    def encode(self, info: dict) -> dict:
        """Add ``emb: (B, T, L)`` from ``pixels: (B, T, C, h, w)`` (and the extra inputs). Returns the same dict."""
        info[EMB] = self.encode_obs(self._inputs(info, f"{type(self).__name__}.encode"))
        return info

    def forward(self, z: torch.Tensor, action: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """One latent step: ``z (..., L)``, ``action (..., A)`` -> next ``z (..., L)``,
        reward logits ``(..., num_bins)``."""
        if action.shape[-1] != self.action_dim:
            raise SpaceError(
                f"TDMPC2 requires action blocks of {self.action_dim} numbers, got shape {tuple(action.shape)}"
            )
        za = torch.cat([z, action.to(z.dtype)], dim=-1)
        return self.dynamics(za), self.reward(za)

    predict = forward

    def q_values(self, z: torch.Tensor, action: torch.Tensor, target: bool = False) -> torch.Tensor:
        """Every Q head's value ``(num_q, ...)`` of ``(z, action)`` (the EMA heads when ``target``)."""
        za = torch.cat([z, action], dim=-1)
        return torch.stack([two_hot_inv(q(za), self.vmin, self.vmax) for q in (self.target_qs if target else self.qs)])

    # -- the policy prior -----------------------------------------------------------------------
    def sample_pi(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Policy prior at ``z (..., L)``: (tanh mean, tanh sample, log-density ``(..., 1)``), each ``(..., A)``."""
        mean, raw_std = self.pi(z).chunk(2, dim=-1)
        std_log = log_std(raw_std)
        eps = torch.randn_like(mean)
        return squash(mean, mean + eps * std_log.exp(), gaussian_logprob(eps, std_log))

    def policy_rollout(self, z: torch.Tensor, horizon: int, num_trajs: int = 1) -> torch.Tensor:
        """Upstream's ``rollout(z, horizon, num_trajs)``: sample the prior along the latent
        dynamics for ``horizon`` steps, ``num_trajs`` times; the mean ``(B, horizon, A)``."""
        trajs = []
        for _ in range(num_trajs):
            cur, steps = z, []
            for _ in range(horizon):
                action = self.sample_pi(cur)[1]
                steps.append(action)
                cur = self.dynamics(torch.cat([cur, action], dim=-1))
            trajs.append(torch.stack(steps, dim=1))
        return torch.stack(trajs).mean(0)

    def get_action(
        self, info: dict, horizon: int | None = None, prefix_actions: torch.Tensor | None = None
    ) -> torch.Tensor:
        """Action block ``(B, A)`` of the policy prior at the last frame of ``info["pixels"]``
        (``(B, T, C, h, w)`` or ``(B, C, h, w)``): a sample (averaged over ``num_pi_trajs``).
        With ``horizon=k``: ``(B, k, A)`` along the latent dynamics (a warm start for a solver's
        ``init_action``), after ``prefix_actions (B, t, A)`` when given (upstream's signature)."""
        who = f"{type(self).__name__}.get_action"
        if horizon is not None and (isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 1):
            raise ConfigError(f"{who} requires horizon to be a positive int or None, got {horizon!r}")
        obs = self._inputs(info, who)
        if self.use_pixels and obs[keys.PIXELS].ndim == 5:
            obs = {k: v[:, -1] for k, v in obs.items()}
        z = self.encode_obs(obs)
        if z.ndim != 2:
            raise SpaceError(
                f"{who} requires info[{keys.PIXELS!r}] of shape (B, T, C, h, w) or (B, C, h, w), "
                f"got {tuple(obs[keys.PIXELS].shape)}"
            )
        if prefix_actions is not None:
            for t in range(prefix_actions.shape[1]):
                z = self.forward(z, prefix_actions[:, t].to(z.device))[0]
        actions = self.policy_rollout(z, horizon or 1, self.cfg["num_pi_trajs"])
        return actions[:, 0] if horizon is None else actions

    # -- planning ---------------------------------------------------------------------------------
    def _start(self, info: dict, b: int, s: int | None) -> torch.Tensor:
        """Latent ``(B, L)`` of the last context frame, cached in ``info["emb"]``."""
        if EMB in info:
            z = info[EMB]
        else:
            obs = self._inputs(info, f"{type(self).__name__}.get_cost")
            for k, v in obs.items():
                feat = 3 if k == keys.PIXELS else 1  # (C, h, w) or (d,)
                if s is not None and v.ndim == 3 + feat:
                    v = v[:, 0]  # (B, S, T, ...): the S copies of an env's info are views of one tensor
                obs[k] = v[:, -1] if v.ndim == 2 + feat else v  # (B, T, ...): the last frame
            z = self.encode_obs(obs)
            info[EMB] = z.unsqueeze(1).expand(b, s, -1) if s is not None else z
        return z[:, 0] if z.ndim == 3 else z

    def rollout(self, info: Any, action_sequence: torch.Tensor, num_trajs: int = 1) -> Any:
        """Roll the latent dynamics out over ``action_sequence (B, S, H, A)`` (or ``(B, H, A)``)
        from the last frame of ``info["pixels"] (B, S, T, C, h, w)`` (or ``info["emb"]``). Adds
        ``predicted_emb (B, S, H + 1, L)`` (the start latent first) and ``predicted_reward (B, S, H)``.
        Called as ``rollout(z, horizon, num_trajs)`` (a tensor first), it is upstream's policy rollout
        (:meth:`policy_rollout`)."""
        if torch.is_tensor(info):
            return self.policy_rollout(info, int(action_sequence), num_trajs)
        squeeze = action_sequence.ndim == 3
        cand = action_sequence.unsqueeze(1) if squeeze else action_sequence
        if cand.ndim != 4:
            raise SpaceError(
                f"{type(self).__name__}.rollout requires actions (B, S, H, A) or (B, H, A), "
                f"got {tuple(action_sequence.shape)}"
            )
        b, s, h, _ = cand.shape
        z = self._start(info, b, None if squeeze else s)
        z = z.unsqueeze(1).expand(b, s, -1).reshape(b * s, -1)
        acts = cand.reshape(b * s, h, -1).to(z.dtype)
        latents, rewards = [z], []
        for t in range(h):
            z, logits = self.forward(z, acts[:, t])
            latents.append(z)
            rewards.append(two_hot_inv(logits, self.vmin, self.vmax))
        emb = torch.stack(latents, dim=1).reshape(b, s, h + 1, -1)
        reward = torch.stack(rewards, dim=1).reshape(b, s, h)
        info[PREDICTED_EMB], info[PREDICTED_REWARD] = (emb[:, 0], reward[:, 0]) if squeeze else (emb, reward)
        return info

    def get_cost(self, info: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        """Minus the predicted return of ``action_candidates (B, S, H, A)``: ``(B, S)`` (``(B,)``
        for ``(B, H, A)``). The return is ``sum_t discount^t r_t`` plus ``discount^H`` times the
        Q ensemble's mean at the last latent and the prior's mean action, less
        ``uncertainty_penalty * |mean| * std`` of the ensemble (a conservative value)."""
        wm = self.cfg["wm"]
        self.rollout(info, action_candidates)
        reward, last = info[PREDICTED_REWARD], info[PREDICTED_EMB][..., -1, :]
        h = reward.shape[-1]
        discounts = wm["discount"] ** torch.arange(h + 1, device=reward.device, dtype=reward.dtype)
        action = torch.tanh(self.pi(last).chunk(2, dim=-1)[0])
        q = self.q_values(last, action)
        value = q.mean(0) - wm["uncertainty_penalty"] * q.mean(0).abs() * q.std(0)
        return -((reward * discounts[:h]).sum(-1) + discounts[h] * value)

    # -- training ----------------------------------------------------------------------------------
    def _two_hot_ce(self, logits: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
        """Cross-entropy ``(...)`` of ``logits (..., num_bins)`` against the two-hot of scalars ``target (...)``."""
        return -(two_hot(target, self.num_bins, self.vmin, self.vmax) * F.log_softmax(logits, dim=-1)).sum(-1)

    def loss(self, batch: dict) -> dict:
        """TD-MPC2's loss on ``batch``: ``pixels (B, T, C, h, w)``, normalized ``action (B, T, A)``
        and ``reward (B, T)`` (``reward[:, t]``: what ``action[:, t]`` earned; the last is unused),
        over the ``H = T - 1`` transitions, step ``t`` weighted by ``rho**t``:

        - ``consistency_loss``: MSE of the latents rolled out from frame 0 to the encoded frames;
        - ``reward_loss``: two-hot cross-entropy of the reward head;
        - ``value_loss``: two-hot cross-entropy of every Q head against ``r + discount * min`` of
          two random EMA heads at the next encoded frame and a prior action (averaged over heads);
        - ``pi_loss``: ``-(Q / scale + entropy_coef * entropy)`` of the prior on detached latents
          (Q: the mean of two random heads, which this term does not train), plus, with
          ``bc_coef > 0``, ``bc_coef`` times the squared distance of the prior's mean action to the
          batch's (TD3+BC's remedy for offline data: the prior, whose actions the value targets and
          the planner's terminal value use, stays where the data has actions).

        ``loss = consistency_coef * consistency + reward_coef * reward + value_coef * value + pi``;
        ``model_loss`` is ``loss`` without ``pi`` (the world model's part, which the trainer
        validates: ``pi`` is ``-Q`` and falls as the values grow, so ``loss`` need not).
        In training mode it also updates the Q scale and moves ``target_qs`` by ``tau`` towards ``qs``.
        """
        who = f"{type(self).__name__}.loss"
        wm = self.cfg["wm"]
        action = torch.nan_to_num(_require(batch, keys.ACTION, who), 0.0)
        reward = _require(batch, keys.REWARD, who)
        obs = self._inputs(batch, who)
        t_all = action.shape[1]
        if t_all < 2 or reward.shape[:2] != action.shape[:2]:
            raise ConfigError(
                f"{who} requires at least 2 frames and reward (B, T) matching action (B, T, A), got action "
                f"{tuple(action.shape)} and reward {tuple(reward.shape)}"
            )
        reward = torch.nan_to_num(reward.reshape(*reward.shape[:2], -1)[..., 0], 0.0)
        horizon = t_all - 1
        emb = self.encode_obs(obs)  # (B, T, L)
        target_z = emb[:, 1:].detach()
        with torch.no_grad():
            next_action = self.sample_pi(target_z)[1]
            pick = torch.randperm(wm["num_q"], device=emb.device)[:2]
            next_q = self.q_values(target_z, next_action, target=True)[pick].min(0).values
            td_target = reward[:, :horizon] + wm["discount"] * next_q  # (B, H)
        # only the dynamics run step by step; the reward and Q heads then score every step's (z, action) at once
        z, inputs = emb[:, 0], []
        consistency = 0.0
        for t in range(horizon):
            za = torch.cat([z, action[:, t].to(z.dtype)], dim=-1)
            inputs.append(za)
            z = self.dynamics(za)
            consistency = consistency + wm["rho"] ** t * F.mse_loss(z, target_z[:, t])
        za = torch.stack(inputs, dim=1)  # (B, H, L + A)
        steps = torch.arange(horizon, device=za.device)

        def weighted(logits: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
            per_step = self._two_hot_ce(logits, target).mean(0)  # (H,), float32 also under bf16 autocast
            return (per_step * wm["rho"] ** steps.to(per_step.dtype)).sum()

        reward_loss = weighted(self.reward(za), reward[:, :horizon])
        value_loss = sum(weighted(q(za), td_target) for q in self.qs)
        pi_loss = self._pi_loss(za[..., : emb.shape[-1]].detach(), action[:, :horizon])
        consistency, reward_loss = consistency / horizon, reward_loss / horizon
        value_loss = value_loss / (horizon * wm["num_q"])
        total = (
            wm["consistency_coef"] * consistency
            + wm["reward_coef"] * reward_loss
            + wm["value_coef"] * value_loss
            + pi_loss
        )
        if self.training:
            with torch.no_grad():
                for p, p_target in zip(self.qs.parameters(), self.target_qs.parameters(), strict=False):
                    p_target.lerp_(p, wm["tau"])
        model_loss = total - pi_loss
        return {
            "loss": total,
            "model_loss": model_loss,
            "consistency_loss": consistency,
            "reward_loss": reward_loss,
            "value_loss": value_loss,
            "pi_loss": pi_loss,
            "emb": emb,
        }

    def _pi_loss(self, zs: torch.Tensor, data_action: torch.Tensor) -> torch.Tensor:
        """Policy term on detached latents ``zs (B, H, L)``; the Q heads get no gradient from it.
        With ``bc_coef > 0`` it also pulls the prior's mean action towards the dataset's
        ``data_action (B, H, A)`` (clipped to [-1, 1], the prior's range)."""
        wm = self.cfg["wm"]
        mean_action, action, log_prob = self.sample_pi(zs)
        entropy = -log_prob[..., 0] * self.action_dim
        self.qs.requires_grad_(False)
        try:
            q = self.q_values(zs, action)
        finally:
            self.qs.requires_grad_(True)
        pick = torch.randperm(wm["num_q"], device=zs.device)[:2]
        q = q[pick].mean(0)  # (B, H)
        if self.training:
            self.scale.update(q[:, 0])
        weights = wm["rho"] ** torch.arange(zs.shape[1], device=zs.device, dtype=zs.dtype)
        per_step = -(wm["entropy_coef"] * entropy + self.scale(q))  # (B, H)
        if wm["bc_coef"]:
            target = data_action.to(mean_action.dtype).clamp(-1.0, 1.0)
            per_step = per_step + wm["bc_coef"] * (mean_action - target).square().mean(-1)
        return (per_step.mean(0) * weights).mean()
