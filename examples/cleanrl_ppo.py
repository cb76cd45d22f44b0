"""Single-file PPO for BoxToss in the style of CleanRL's ``ppo_continuous_action.py``, on the native
batched env (``gymnasium.make_vec("BoxToss-v0", num_envs=N)``) with our observation normaliser.

    PYTHONPATH=. python examples/cleanrl_ppo.py                      # 300k throws, the project's PPO settings
    PYTHONPATH=. python examples/cleanrl_ppo.py --total-timesteps 65536 --num-steps 8 --num-minibatches 4 \
        --learning-rate 1e-3                                         # fewer throws, smaller updates

The defaults are the project's SB3 settings (``agents/hyperparams/ppo.yml``).

It depends only on box_toss_env, gymnasium, numpy and torch. Differences from CleanRL's script, all
because every BoxToss episode is ONE throw:

- The native env resets in the step an episode ends (``AutoresetMode.SAME_STEP``), so every step is
  a throw (with Gymnasium's ``NEXT_STEP`` every other step would be an empty reset step). Gymnasium's
  ``NormalizeObservation``/``TransformObservation`` refuse SAME_STEP; we use
  ``box_toss_env.wrappers.normalize.NormalizeObservation`` (it also normalises ``info["final_obs"]``).
- Every step terminates, so GAE reduces to ``advantage = reward - value`` (the next value is always
  masked by ``done``); the loop is kept as in CleanRL, gamma and lambda change nothing.
- A narrow initial policy (log std -2.5, std 0.08 of the action range): with std 1 the throws scatter
  over metres and the gradient is noise. No reward normalisation, no clipping of observations.

At the end the deterministic policy (the mean action) throws once at each of ``--eval-targets`` fixed
targets (env i seeded with ``eval_seed + i``) and the script prints ``success rate: ...``.
"""

from __future__ import annotations

import argparse
import dataclasses
import random
import time

import gymnasium as gym
import numpy as np
import torch
import torch.nn as nn
import torch.optim as optim
from torch.distributions.normal import Normal

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from box_toss_env.wrappers.normalize import NormalizeObservation


@dataclasses.dataclass
class Args:
    seed: int = 0
    """seed of the experiment (torch, numpy, the envs)"""
    env_id: str = "BoxToss-v0"
    total_timesteps: int = 300_000
    """throws in total (every step of every env is one throw)"""
    learning_rate: float = 5e-4
    anneal_lr: bool = True
    """decay the learning rate linearly to 0"""
    num_envs: int = 32
    num_steps: int = 64
    """steps per env per rollout: an update every num_envs * num_steps = 2,048 throws"""
    gamma: float = 0.0
    gae_lambda: float = 1.0
    num_minibatches: int = 16
    """minibatches of batch_size / num_minibatches = 128 throws"""
    update_epochs: int = 10
    norm_adv: bool = True
    clip_coef: float = 0.2
    clip_vloss: bool = False
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    target_kl: float | None = None
    log_std_init: float = -2.5
    hidden: int = 128
    env_threads: int = 1
    """engine threads of the batched env (the network runs in between, so 1 is fastest on 2 cores)"""
    torch_threads: int = 1
    eval_targets: int = 1024
    eval_seed: int = 10_000
    log_every: int = 10
    """print progress every this many updates (0: never)"""


def parse_args() -> Args:
    """``--kebab-case`` options from the ``Args`` fields (CleanRL uses tyro; argparse needs nothing)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for field in dataclasses.fields(Args):
        flag = "--" + field.name.replace("_", "-")
        if field.type == "bool":
            parser.add_argument(
                flag, type=lambda s: s.lower() in ("1", "true", "yes"), default=field.default, metavar="BOOL"
            )
        elif field.type == "float | None":
            parser.add_argument(flag, type=float, default=field.default)
        else:
            parser.add_argument(flag, type=type(field.default), default=field.default)
    return Args(**vars(parser.parse_args()))


def layer_init(layer: nn.Linear, std: float = np.sqrt(2), bias_const: float = 0.0) -> nn.Linear:
    torch.nn.init.orthogonal_(layer.weight, std)
    torch.nn.init.constant_(layer.bias, bias_const)
    return layer


class Agent(nn.Module):
    def __init__(self, obs_dim: int, act_dim: int, hidden: int, log_std_init: float):
        super().__init__()
        self.critic = nn.Sequential(
            layer_init(nn.Linear(obs_dim, hidden)),
            nn.Tanh(),
            layer_init(nn.Linear(hidden, hidden)),
            nn.Tanh(),
            layer_init(nn.Linear(hidden, 1), std=1.0),
        )
        self.actor_mean = nn.Sequential(
            layer_init(nn.Linear(obs_dim, hidden)),
            nn.Tanh(),
            layer_init(nn.Linear(hidden, hidden)),
            nn.Tanh(),
            layer_init(nn.Linear(hidden, act_dim), std=0.01),
        )
        self.actor_logstd = nn.Parameter(torch.full((1, act_dim), log_std_init))

    def get_value(self, x):
        return self.critic(x)

    def get_action_and_value(self, x, action=None):
        action_mean = self.actor_mean(x)
        action_std = torch.exp(self.actor_logstd.expand_as(action_mean))
        probs = Normal(action_mean, action_std)
        if action is None:
            action = probs.sample()
        return action, probs.log_prob(action).sum(1), probs.entropy().sum(1), self.critic(x)


def evaluate(agent: Agent, train_envs: NormalizeObservation, args: Args) -> dict[str, float]:
    """Throw once at each of ``eval_targets`` fixed targets with the mean action; the observation
    statistics are the training ones, frozen."""
    envs = NormalizeObservation(
        gym.make_vec(
            args.env_id, num_envs=args.eval_targets, vectorization_mode="vector_entry_point", threads=args.env_threads
        )
    )
    envs.obs_rms = train_envs.obs_rms
    envs.update_running_mean = False
    obs, _ = envs.reset(seed=args.eval_seed)
    with torch.no_grad():
        action = agent.actor_mean(torch.as_tensor(obs)).numpy()
    _, _, _, _, info = envs.step(np.clip(action, -1.0, 1.0))
    envs.close()
    final = info["final_info"]
    return {"success": float(np.mean(final["success"])), "distance": float(np.mean(final["distance"]))}


def main(args: Args) -> dict[str, float]:
    batch_size = args.num_envs * args.num_steps
    minibatch_size = batch_size // args.num_minibatches
    num_iterations = max(1, args.total_timesteps // batch_size)
    random.seed(args.seed)
    rng = np.random.default_rng(args.seed)
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.torch_threads)

    envs = gym.make_vec(
        args.env_id, num_envs=args.num_envs, vectorization_mode="vector_entry_point", threads=args.env_threads
    )
    envs = NormalizeObservation(envs)
    obs_dim = envs.single_observation_space.shape[0]
    act_dim = envs.single_action_space.shape[0]
    agent = Agent(obs_dim, act_dim, args.hidden, args.log_std_init)
    optimizer = optim.Adam(agent.parameters(), lr=args.learning_rate, eps=1e-5)

    obs = torch.zeros((args.num_steps, args.num_envs, obs_dim))
    actions = torch.zeros((args.num_steps, args.num_envs, act_dim))
    logprobs = torch.zeros((args.num_steps, args.num_envs))
    rewards = torch.zeros((args.num_steps, args.num_envs))
    dones = torch.zeros((args.num_steps, args.num_envs))
    values = torch.zeros((args.num_steps, args.num_envs))
    successes = np.zeros((args.num_steps, args.num_envs))

    start = time.time()
    global_step = 0
    next_obs, _ = envs.reset(seed=args.seed)
    next_obs = torch.as_tensor(next_obs)
    next_done = torch.zeros(args.num_envs)

    for iteration in range(1, num_iterations + 1):
        if args.anneal_lr:
            optimizer.param_groups[0]["lr"] = (1.0 - (iteration - 1.0) / num_iterations) * args.learning_rate

        for step in range(args.num_steps):
            global_step += args.num_envs
            obs[step] = next_obs
            dones[step] = next_done
            with torch.no_grad():
                action, logprob, _, value = agent.get_action_and_value(next_obs)
            values[step] = value.flatten()
            actions[step] = action
            logprobs[step] = logprob
            next_obs, reward, terminations, truncations, info = envs.step(action.numpy())
            rewards[step] = torch.as_tensor(reward, dtype=torch.float32)
            next_obs = torch.as_tensor(next_obs)
            next_done = torch.as_tensor(np.logical_or(terminations, truncations), dtype=torch.float32)
            successes[step] = info["final_info"]["success"]

        # GAE as in CleanRL. Here every step ends its episode, so the bootstrap term is always masked
        # and advantages = rewards - values. (CleanRL's dones[t + 1] marks that obs[t + 1] starts a new
        # episode; with SAME_STEP autoreset that is next_done of step t, as in NEXT_STEP's layout.)
        with torch.no_grad():
            next_value = agent.get_value(next_obs).reshape(1, -1)
            advantages = torch.zeros_like(rewards)
            lastgaelam = 0
            for t in reversed(range(args.num_steps)):
                if t == args.num_steps - 1:
                    nextnonterminal = 1.0 - next_done
                    nextvalues = next_value
                else:
                    nextnonterminal = 1.0 - dones[t + 1]
                    nextvalues = values[t + 1]
                delta = rewards[t] + args.gamma * nextvalues * nextnonterminal - values[t]
                advantages[t] = lastgaelam = delta + args.gamma * args.gae_lambda * nextnonterminal * lastgaelam
            returns = advantages + values

        b_obs = obs.reshape((-1, obs_dim))
        b_logprobs = logprobs.reshape(-1)
        b_actions = actions.reshape((-1, act_dim))
        b_advantages = advantages.reshape(-1)
        b_returns = returns.reshape(-1)
        b_values = values.reshape(-1)

        b_inds = np.arange(batch_size)
        clipfracs = []
        for _epoch in range(args.update_epochs):
            rng.shuffle(b_inds)
            for begin in range(0, batch_size, minibatch_size):
                mb_inds = b_inds[begin : begin + minibatch_size]
                _, newlogprob, entropy, newvalue = agent.get_action_and_value(b_obs[mb_inds], b_actions[mb_inds])
                logratio = newlogprob - b_logprobs[mb_inds]
                ratio = logratio.exp()
                with torch.no_grad():
                    approx_kl = ((ratio - 1) - logratio).mean()
                    clipfracs += [((ratio - 1.0).abs() > args.clip_coef).float().mean().item()]

                mb_advantages = b_advantages[mb_inds]
                if args.norm_adv:
                    mb_advantages = (mb_advantages - mb_advantages.mean()) / (mb_advantages.std() + 1e-8)
                pg_loss1 = -mb_advantages * ratio
                pg_loss2 = -mb_advantages * torch.clamp(ratio, 1 - args.clip_coef, 1 + args.clip_coef)
                pg_loss = torch.max(pg_loss1, pg_loss2).mean()

                newvalue = newvalue.view(-1)
                if args.clip_vloss:
                    v_loss_unclipped = (newvalue - b_returns[mb_inds]) ** 2
                    v_clipped = b_values[mb_inds] + torch.clamp(
                        newvalue - b_values[mb_inds], -args.clip_coef, args.clip_coef
                    )
                    v_loss = 0.5 * torch.max(v_loss_unclipped, (v_clipped - b_returns[mb_inds]) ** 2).mean()
                else:
                    v_loss = 0.5 * ((newvalue - b_returns[mb_inds]) ** 2).mean()
                entropy_loss = entropy.mean()
                loss = pg_loss - args.ent_coef * entropy_loss + v_loss * args.vf_coef

                optimizer.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), args.max_grad_norm)
                optimizer.step()
            if args.target_kl is not None and approx_kl > args.target_kl:
                break

        if args.log_every and (iteration % args.log_every == 0 or iteration == num_iterations):
            print(
                f"throws {global_step:>8,}  rollout success {successes.mean():6.1%}  "
                f"mean reward {rewards.mean().item():7.3f}  std {agent.actor_logstd.exp().mean().item():.3f}  "
                f"clipfrac {np.mean(clipfracs):.3f}  {global_step / (time.time() - start):,.0f} throws/s",
                flush=True,
            )

    envs.close()
    result = evaluate(agent, envs, args)
    print(f"trained on {global_step:,} throws in {time.time() - start:.1f} s")
    print(
        f"deterministic policy on {args.eval_targets} fixed targets (seeds {args.eval_seed}...): "
        f"mean distance {result['distance']:.3f} m"
    )
    print(f"success rate: {result['success']:.4f}")
    return result


if __name__ == "__main__":
    main(parse_args())
