"""`python -m train.brax_reference`: the same task and preset trained by Brax's own `ppo.train` /
`sac.train` (the reference for parity with train.run's loop); writes run.json and policy/, so that
`python -m train.evaluate` evaluates it like any run. No checkpoints, resume or database.

    python -m train.brax_reference --task asc-inc-cog --preset gpu --steps 2000000 --seed 0 --out runs/brax-s0
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from mjx_tracks.envs.config import ConfigError
from train.plan import RunError, RunPlan, plan_run, write_run_json


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
  from train import brax_compat  # noqa: PLC0415
  from train.build import network_spec  # noqa: PLC0415
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


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.brax_reference", description=__doc__.splitlines()[0])
  for name in ("--task", "--algo", "--preset", "--out"):
    p.add_argument(name)
  for name in ("--num-envs", "--steps", "--seed"):
    p.add_argument(name, type=int)
  p.add_argument("--set", action="append", default=[])
  p.add_argument("--hp", action="append", default=[])
  args = p.parse_args(argv)
  args.resume, args.early_stop, args.probe_every = None, None, 0
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  try:
    plan = plan_run(args)
  except (RunError, ConfigError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  write_run_json(plan)
  t0 = time.time()
  show = lambda step, m: print(f"{step:>11,} steps, {time.time() - t0:,.0f} s: " + ", ".join(
      f"{k} {float(v):.3f}" for k, v in m.items() if k.endswith(("episode_reward", "sum_reward"))), flush=True)
  spec, (normalizer, policy) = brax_train(plan, show)
  from train.checkpoints import export_policy  # noqa: PLC0415
  info = {"task": plan.task, "algo": plan.algo, "step": plan.total_steps, "run_id": plan.run_id,
          "config": plan.cfg.to_dict(), "trainer": "brax", "train_wall_s": time.time() - t0}
  print(json.dumps({"policy": export_policy(plan.out_dir, normalizer, policy, spec, info), **info}, default=str)[:400])
  return 0


if __name__ == "__main__":
  sys.exit(main())
