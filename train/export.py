"""`python -m train.export RUN_DIR --onnx FILE`: a run's policy as an ONNX model a robot can run.

The deterministic policy, observation normalization included, is converted by jax2onnx (the
[export] extra) to one graph: observation (B, n) float32 -> action (B, k) float32 in [-1, 1]. The
file carries the layout a robot's code needs as metadata (metadata_props, JSON values):
  mjx_tracks.observation  each entry's name and meaning with its unit, in order
  mjx_tracks.action       each dimension's name and what -1..1 maps onto (units)
  mjx_tracks.control      the control period (s) and the increments rule
  mjx_tracks.task / .run_id / .config   the task, the run, its whole config (train.run's run.json)
  mjx_tracks.parity       the check below
Before it is written, onnxruntime runs it on 1,000 observations drawn from the policy's own
normalizer statistics (mean + std x N(0, 1)); the largest absolute difference from the JAX policy
must be <= 1e-5 (--tolerance), else nothing is written and the command exits 1.
`python -m train.onnx_drive FILE` then runs it on the simulator, onnxruntime alone choosing actions.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile

import numpy as np

PARITY_OBSERVATIONS = 1000
TOLERANCE = 1e-5  # the largest |ONNX - JAX| allowed on any action entry
META = "mjx_tracks."  # prefix of the metadata keys


def policy_function(run_dir: str, checkpoint: str | None = None):
  """(fn, spec, params, step): fn(observations (B, n)) -> actions (B, k), deterministic, with the
  normalizer, the parameters closed over (constants of the graph)."""
  from train.core.policy import act_from_params, load_checkpoint_params, load_policy_info, load_policy_params  # noqa: PLC0415
  if checkpoint is None:
    spec, params = load_policy_params(os.path.join(run_dir, "policy"))
    step = load_policy_info(os.path.join(run_dir, "policy")).get("step")
  else:
    spec, params, step = load_checkpoint_params(run_dir, None if checkpoint == "latest" else int(checkpoint))
  act = act_from_params(spec)(params)
  return act, spec, params, step


def layout_metadata(cfg) -> dict[str, object]:
  """The observation and action layout of a task, for a robot's code (names, meanings, units)."""
  from mjx_tracks.envs.observations import PARTS, observation_entries  # noqa: PLC0415
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from mjx_tracks.sim.control import INCREMENT  # noqa: PLC0415
  env = TrackedRobotEnv(cfg)
  entries = observation_entries(cfg.observation.parts, env.part_sizes, cfg.observation.history)
  obs = [{"name": n, "meaning": PARTS[p].doc + (f", {j} control step{'s' * (j > 1)} back" if j else "")}
         for n, p, j in entries]
  c = env.controller
  lo, hi = c.v_range
  joint = (f"joint target change: -1..1 onto +-{INCREMENT:.4f} rad per control step" if c.increments
           else "joint target: -1..1 onto the joint's limits (rad)")
  meaning = {"v": f"forward speed: -1..1 onto [{lo}, {hi}] m/s",
             "w": f"yaw rate: -1..1 onto +-{c.max_yaw_rate} rad/s"}
  joints = env.robot.joint_names()
  act = [{"name": d, "meaning": meaning.get(d) or
          f"{joint}; joints {[joints[i] for i in np.atleast_1d(env.robot.joint_index(d))]}"} for d in c.dims]
  control = {"period_s": cfg.control.period, "mode": c.mode, "increments": c.increments,
             "note": "clip actions to [-1, 1]; beams and speeds as the simulator measures them (see each meaning)"}
  return {"observation": obs, "action": act, "control": control}


def parity_observations(params, n: int, seed: int = 0) -> np.ndarray:
  """(n, obs) float32 drawn from the policy's normalizer statistics: mean + std x N(0, 1)."""
  normalizer = params[0]
  mean, std = np.asarray(normalizer.mean, np.float32), np.asarray(normalizer.std, np.float32)
  rng = np.random.default_rng(seed)
  return (mean + std * rng.standard_normal((n, mean.shape[0]))).astype(np.float32)


def convert(fn, observation_size: int):
  """The ONNX ModelProto of fn: 'observation' (B, n) -> 'action' (B, k)."""
  from train.extras import require_extra  # noqa: PLC0415
  require_extra("export", "train.export")
  from jax2onnx import to_onnx  # noqa: PLC0415
  return to_onnx(fn, [("B", observation_size)], model_name="mjx_tracks_policy",
                 input_names=["observation"], output_names=["action"])


def onnx_policy(model: bytes | str):
  """act(observations (B, n) float32) -> actions (B, k) by onnxruntime on the CPU, from an exported
  model's bytes or file."""
  import onnxruntime as ort  # noqa: PLC0415
  session = ort.InferenceSession(model, providers=["CPUExecutionProvider"])
  return lambda observations: session.run(["action"], {"observation": observations})[0]


def export(run_dir: str, path: str, checkpoint: str | None = None, tolerance: float = TOLERANCE) -> dict:
  """Writes the ONNX policy of a run to path (after the parity check); returns the parity figures.
  ValueError when the check fails (nothing written)."""
  import onnx  # noqa: PLC0415

  from mjx_tracks.envs.config import from_dict  # noqa: PLC0415
  from train.core.run_record import read_run_record  # noqa: PLC0415
  meta = read_run_record(run_dir)
  cfg = from_dict(meta["config"])
  fn, spec, params, step = policy_function(run_dir, checkpoint)
  model = convert(fn, spec.observation_size)
  obs = parity_observations(params, PARITY_OBSERVATIONS)
  diff = float(np.max(np.abs(onnx_policy(model.SerializeToString())(obs) - np.asarray(fn(obs)))))
  parity = {"observations": PARITY_OBSERVATIONS, "max_abs_difference": diff, "tolerance": tolerance,
            "drawn_from": "the policy's normalizer: mean + std x N(0, 1), seed 0"}
  if not diff <= tolerance:
    raise ValueError(f"ONNX and JAX policies differ by {diff:.3g} > {tolerance:g} on {PARITY_OBSERVATIONS} observations; "
                     "nothing written")
  layout = layout_metadata(cfg)
  props = {"observation": layout["observation"], "action": layout["action"], "control": layout["control"],
           "task": meta["task"], "run_id": meta["run_id"], "policy_step": step, "config": meta["config"],
           "parity": parity}
  onnx.helper.set_model_props(model, {META + k: json.dumps(v) for k, v in props.items()})
  fd, tmp = tempfile.mkstemp(suffix=".onnx.tmp", dir=os.path.dirname(os.path.abspath(path)))
  os.close(fd)
  try:
    onnx.save(model, tmp)
    os.replace(tmp, path)  # a reader never sees half a file
  finally:
    if os.path.exists(tmp):
      os.unlink(tmp)
  return parity


def read_metadata(path: str) -> dict:
  """The mjx_tracks metadata of an exported ONNX file, JSON values decoded."""
  import onnx  # noqa: PLC0415
  model = onnx.load(path, load_external_data=False)
  return {p.key[len(META):]: json.loads(p.value) for p in model.metadata_props if p.key.startswith(META)}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.export", description=__doc__.splitlines()[0])
  p.add_argument("run_dir", help="a run folder (train.run --out)")
  p.add_argument("--onnx", required=True, metavar="FILE", help="where the ONNX model goes")
  p.add_argument("--checkpoint", nargs="?", const="latest", metavar="STEP",
                 help="export a training checkpoint (default the latest) instead of RUN_DIR/policy")
  p.add_argument("--tolerance", type=float, default=TOLERANCE, help="largest |ONNX - JAX| allowed (default 1e-5)")
  args = p.parse_args(argv)
  if args.checkpoint not in (None, "latest") and not args.checkpoint.isdigit():
    print(f"error: --checkpoint takes a step number, got {args.checkpoint!r}", file=sys.stderr)
    return 2
  from mjx_tracks.envs.config import ConfigError  # noqa: PLC0415
  try:
    parity = export(args.run_dir, args.onnx, args.checkpoint, args.tolerance)
  except (ConfigError, FileNotFoundError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  except ValueError as e:
    print(f"error: {e}", file=sys.stderr)
    return 1
  except Exception as e:  # noqa: BLE001  (the converter's own errors: a primitive it cannot convert)
    print(f"error: the ONNX conversion failed, nothing written: {type(e).__name__}: {str(e).splitlines()[0][:300]}",
          file=sys.stderr)
    return 1
  print(f"{args.onnx}: parity on {parity['observations']} observations, max |ONNX - JAX| = "
        f"{parity['max_abs_difference']:.2e} (tolerance {parity['tolerance']:g})")
  print(f"next: python -m train.onnx_drive {args.onnx} --trials 20   # onnxruntime drives the simulator")
  return 0


if __name__ == "__main__":
  sys.exit(main())
