"""`python -m train.run --library brax`: the same task and preset trained by Brax's own `ppo.train` /
`sac.train` (the reference for parity with this project's loop); recorded like any run (run.json,
the database's rows, policy/), so that `train.evaluate` and studies use it alike. No checkpoints,
resume, probes or early stop: Brax's train() has none.

    python -m train.run --library brax --task asc-inc-cog --preset gpu --steps 2000000 --seed 0
"""

from __future__ import annotations

import time

from train.core.plan import RunPlan


def brax_kwargs(plan: RunPlan, spec) -> dict:
  """Brax train() arguments from the plan's preset (the hyperparameters train.run uses)."""
  p = plan.preset
  common = dict(num_timesteps=plan.total_steps, episode_length=plan.cfg.episode.max_steps,
                num_envs=plan.num_envs, learning_rate=p.learning_rate, discounting=p.discounting,
                reward_scaling=p.reward_scaling, normalize_observations=True, network_factory=spec.factory(),
                num_evals=p.num_evals, num_eval_envs=p.num_eval_envs, seed=plan.seed)
  if plan.algo == "ppo":
    return dict(common, unroll_length=p.unroll_length, batch_size=p.batch_size, num_minibatches=p.num_minibatches,
                num_updates_per_batch=p.num_updates_per_batch, entropy_cost=p.entropy_cost,
                gae_lambda=p.gae_lambda, clipping_epsilon=p.clipping_epsilon, max_grad_norm=p.max_grad_norm,
                run_evals=p.run_evals)
  return dict(common, batch_size=p.batch_size, tau=p.tau, grad_updates_per_step=p.grad_updates_per_step,
              min_replay_size=p.min_replay_size, max_replay_size=p.max_replay_size)


def brax_train(plan: RunPlan, progress=lambda step, metrics: None):
  """(network spec, (normalizer, policy)) trained by Brax's train() for the plan."""
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from mjx_tracks.envs.wrappers import wrap_for_training  # noqa: PLC0415
  from train.core import brax_compat  # noqa: PLC0415
  from train.core.build import network_spec  # noqa: PLC0415
  from train.evaluation import scene_config  # noqa: PLC0415
  brax_compat.install()
  core = TrackedRobotEnv(plan.cfg)
  eval_core = TrackedRobotEnv(scene_config(plan.cfg, "uniform"))
  spec = network_spec(plan, core)
  if plan.algo == "ppo":
    from brax.training.agents.ppo import train as trainer  # noqa: PLC0415
  else:
    from brax.training.agents.sac import train as trainer  # noqa: PLC0415
  _, params, _ = trainer.train(environment=core, eval_env=eval_core, wrap_env_fn=wrap_for_training("i"),
                               progress_fn=progress, **brax_kwargs(plan, spec))
  return spec, (params[0], params[1])


def train_run(plan: RunPlan) -> dict:
  """Trains the plan with Brax's train(), printing its evaluations, and exports the policy; returns
  the run's final figures (step, wall_s) for its records."""
  t0 = time.time()
  show = lambda step, m: print(f"{step:>11,} steps, {time.time() - t0:,.0f} s: " + ", ".join(
      f"{k} {float(v):.3f}" for k, v in m.items() if k.endswith(("episode_reward", "sum_reward"))), flush=True)
  spec, (normalizer, policy) = brax_train(plan, show)
  from train.core.checkpoints import export_policy  # noqa: PLC0415
  info = {"task": plan.task, "algo": plan.algo, "step": plan.total_steps, "run_id": plan.run_id,
          "config": plan.cfg.to_dict(), "trainer": "brax", "train_wall_s": time.time() - t0}
  export_policy(plan.out_dir, normalizer, policy, spec, info)
  return {"reason": "done", "step": plan.total_steps, "wall_s": time.time() - t0}
