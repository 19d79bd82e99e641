"""A fingerprint of the simulator's behaviour: a 12-step batched rollout of one task per scene kind,
through the training wrappers (curriculum auto-reset included), hashed bit for bit.

  python -m mjx_tracks.tools.rollout_digest --write results/rollout_digest.json   # record
  python -m mjx_tracks.tools.rollout_digest --check results/rollout_digest.json   # compare (exit 1 if any differs)

Each task runs N_ENVS robots for N_STEPS control steps from a fixed key, with actions ~ U(-1, 1)
from that key, and episodes cut at EPISODE_STEPS steps so that the curriculum's reset runs inside
the rollout. The digest is the SHA-256 of every step's observation, reward, done flag, metrics,
positions (qpos) and scene (boxes, spawn, goal, parameters), as float32 bytes. A refactor that changes no behaviour keeps every digest. Digests are
compared on the platform they were recorded on (floating point differs between CPU and GPU). On
the CPU they also differ between hosts of other instruction sets (XLA compiles for the host's): the
file records the CPU's (`cpu_features`) and a check on another says so. Record on the machine at
hand before a change, check after it.
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import os
import sys

N_ENVS, N_STEPS, EPISODE_STEPS, SEED = 4, 12, 5, 0
# one task per scene kind: stairs up and down, every terrain kind, both navigation tasks
TASKS = ("asc-inc-cog", "des-inc-ang", "step-up", "step-down", "uplift", "rails", "waves", "blocks",
         "landing-up", "landing-down", "spiral-up", "spiral-down", "nav", "nav-obstacles")


def rollout_digest(task: str) -> str:
  """The SHA-256 (hex) of one task's 12-step batched rollout."""
  import jax  # noqa: PLC0415
  import numpy as np  # noqa: PLC0415

  from mjx_tracks.envs.config import load_config  # noqa: PLC0415
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from mjx_tracks.envs.wrappers import batched_env  # noqa: PLC0415

  env = batched_env(TrackedRobotEnv(load_config(task, [f"episode.max_steps={EPISODE_STEPS}"])))

  @jax.jit
  def run(key):
    k_reset, k_act = jax.random.split(key)
    state = env.reset(jax.random.split(k_reset, N_ENVS))

    def one(state, k):
      action = jax.random.uniform(k, (N_ENVS, env.action_size), minval=-1.0, maxval=1.0)
      state = env.step(state, action)
      es = state.pipeline_state
      return state, (state.obs, state.reward, state.done, state.metrics, es.data.qpos, es.scene)

    return jax.lax.scan(one, state, jax.random.split(k_act, N_STEPS))[1]

  trace = jax.device_get(run(jax.random.PRNGKey(SEED)))
  h = hashlib.sha256()
  for leaf in jax.tree_util.tree_leaves(trace):  # dict leaves in sorted-key order
    h.update(np.ascontiguousarray(np.asarray(leaf, np.float32)).tobytes())
  return h.hexdigest()


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  g = p.add_mutually_exclusive_group(required=True)
  g.add_argument("--write", metavar="JSON", help="record every task's digest in JSON (with --tasks: those "
                 "tasks' digests, the file's others kept where it was recorded on this platform and packages)")
  g.add_argument("--check", metavar="JSON", help="compare every task's digest with JSON's")
  p.add_argument("--tasks", nargs="+", default=TASKS, help="a subset of the tasks")
  args = p.parse_args(argv)
  unknown = [t for t in args.tasks if t not in TASKS]
  if unknown:  # before any compilation; tasks go space-separated
    p.error(f"--tasks: not among the recorded tasks: {', '.join(unknown)} (known: {' '.join(TASKS)})")
  import jax  # noqa: PLC0415
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  recorded = json.load(open(args.check)) if args.check else {}
  here = f"{jax.devices()[0].platform} ({jax.devices()[0].device_kind})"
  if args.check and recorded.get("device") != here:
    print(f"error: {args.check} was recorded on {recorded.get('device')}, this is {here}: the digests are bit "
          "for bit and differ between platforms; record one here with --write", file=sys.stderr)
    return 2
  versions, features = _versions(), cpu_features()
  if args.check and recorded.get("versions", {}) != versions:
    print(f"note: recorded with {recorded.get('versions', 'unknown packages')}, this is {versions}: the "
          "digests may differ for the packages alone (record one with --write before changing code)",
          file=sys.stderr)
  if args.check and (note := cpu_note(recorded, here, features)):
    print(note, file=sys.stderr)
  digests, differ = {}, []
  for task in args.tasks:
    digests[task] = rollout_digest(task)
    same = "" if not args.check else " same" if recorded["digests"].get(task) == digests[task] else " DIFFERS"
    differ += [task] if same == " DIFFERS" else []
    print(f"{task:15s} {digests[task][:16]}{same}", file=sys.stderr, flush=True)
  if args.write:
    kept = _kept_digests(args.write, here, versions) if set(args.tasks) != set(TASKS) else {}
    digests = {t: digests.get(t, kept.get(t)) for t in TASKS if t in digests or t in kept}
    record = {"what": __doc__.split("\n\n")[0], "command": "python -m mjx_tracks.tools.rollout_digest --write " + args.write,
              "device": here, "cpu_features": features, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(),
              "jax": jax.__version__, "versions": versions,
              "n_envs": N_ENVS, "n_steps": N_STEPS, "episode_steps": EPISODE_STEPS, "seed": SEED, "digests": digests}
    with open(args.write, "w") as f:
      json.dump(record, f, indent=1)
      f.write("\n")
  if differ:
    print(f"differ: {', '.join(differ)}", file=sys.stderr)
  return 1 if differ else 0


def _kept_digests(path: str, here: str, versions: dict) -> dict[str, str]:
  """The digests recorded in `path` (none where it is absent); exits 2 where it was recorded on
  another platform or packages, whose digests cannot stand beside this one's."""
  if not os.path.exists(path):
    return {}
  old = json.load(open(path))
  if old.get("device") != here or old.get("versions") != versions:
    print(f"error: {path} was recorded on {old.get('device')} with {old.get('versions')}, this is {here} with "
          f"{versions}: record every task (--write without --tasks)", file=sys.stderr)
    sys.exit(2)
  return old["digests"]


def cpu_features(cpuinfo: str = "/proc/cpuinfo") -> list[str]:
  """The host CPU's vector instruction sets that XLA's CPU code generation may use (the first
  processor's `flags` in `cpuinfo`: avx*, fma, f16c, amx*; on Arm its `Features`: asimd*, sve*, sme,
  sme2; not x86's smep, a protection flag), sorted; [] where the file is absent."""
  try:
    text = open(cpuinfo).read()
  except OSError:
    return []
  flags = next((line.split(":", 1)[1].split() for line in text.splitlines()
                if line.startswith(("flags", "Features"))), [])
  return sorted(f for f in set(flags) if f.startswith(("avx", "amx", "asimd", "sve")) or f in ("fma", "f16c", "sme", "sme2"))


def cpu_note(recorded: dict, here: str, features: list[str]) -> str | None:
  """A note where a CPU digest file was recorded on a CPU of other instruction sets (or of unknown ones)."""
  if not here.startswith("cpu") or recorded.get("cpu_features") == features:
    return None
  return (f"note: recorded on a CPU with instruction sets {recorded.get('cpu_features', '(not recorded)')}, this one "
          f"has {features}: XLA compiles for the host's, so the digests may differ for the CPU alone (record one "
          "here with --write before changing code)")


def _versions() -> dict[str, str]:
  """The packages whose numerics a digest depends on."""
  from importlib import metadata  # noqa: PLC0415
  return {name: metadata.version(name) for name in ("jax", "jaxlib", "mujoco", "mujoco-mjx")}


if __name__ == "__main__":
  sys.exit(main())
