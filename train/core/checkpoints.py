"""Run checkpoints (orbax) of the whole training state, and the exported policy.

RUN/checkpoints/<step>/ holds three items:
- `state`: every leaf of the learner's state (parameters, optimizer moments, observation
  normalizer, the batch of environments with the curriculum and penalty normalizer in it, RNG
  keys, SAC's whole replay buffer), in tree order, their bytes one after the other in one array
  `state_bytes` (orbax's cost is per array: a SAC state's 240 leaves took ~3x as long to write;
  checkpoints written before 2026-11-29 hold one `leaf_NNNNN` array per leaf, and read back too);
- `params`: the (normalizer, policy) parameters, what evaluation and export need;
- `meta` (JSON): step, algorithm, network spec, the leaves' tree paths and shapes, curriculum.
Orbax writes each step into a temporary directory and renames it when complete, so a run killed
mid-save leaves the previous checkpoint readable; a damaged one is skipped for the one before it.
RUN/policy/ is the export: (normalizer, policy) plus policy.json, loadable by `train.core.policy`.
"""

from __future__ import annotations

import os
import sys
from typing import Any, Callable

import jax
import numpy as np
import orbax.checkpoint as ocp
from flax import serialization

from mjx_tracks import atomic
from train.core.networks import NetworkSpec

KEEP = 3  # checkpoints kept
CHECKPOINT_EVERY_S = 60.0  # s of wall time between timed checkpoints (any backend)


class CheckpointError(Exception):
  """No readable checkpoint, or one that does not fit the run."""


class DamagedCheckpoint(CheckpointError):
  """A checkpoint whose parts disagree (its state's bytes and the layout in its metadata): damaged,
  not another run's; a resume falls back to the one before it."""


def _plain(tree):
  return jax.tree_util.tree_map(np.asarray, serialization.to_state_dict(tree))


def _solo() -> ocp.options.MultiprocessingOptions:
  """Orbax acting for this process alone: under jax.distributed only process 0 writes (what it
  writes is gathered from all processes first) and every process reads on its own, without barriers."""
  me = jax.process_index()
  return ocp.options.MultiprocessingOptions(primary_host=me, active_processes={me})


def checkpoint_dir(run_dir: str) -> str:
  """RUN/checkpoints: where a run's checkpoints live."""
  return os.path.join(os.path.abspath(run_dir), "checkpoints")


def saved_steps(run_dir: str) -> list[int]:
  """Steps of the run's complete checkpoints, ascending, read from disk without creating anything
  (orbax names a finished step's directory by the number alone)."""
  path = checkpoint_dir(run_dir)
  return sorted(int(d) for d in os.listdir(path) if d.isdigit()) if os.path.isdir(path) else []


def trained_to(run_dir: str, total: int | None) -> bool:
  """Whether the run's newest checkpoint reaches `total` steps (a resume would train no further)."""
  steps = saved_steps(run_dir)
  return bool(steps) and total is not None and steps[-1] >= total


PACKED = "state_bytes"  # the state item's one array: every leaf's bytes in tree order


def flatten_state(state) -> tuple[dict[str, np.ndarray], list[dict]]:
  """Host state -> ({PACKED: every leaf's bytes, one after the other}, [{path, shape, dtype}]) in
  tree order ({} for a state without any element: orbax writes no empty array)."""
  leaves = [(p, np.asarray(x)) for p, x in jax.tree_util.tree_flatten_with_path(state)[0]]
  layout = [{"path": jax.tree_util.keystr(p), "shape": list(x.shape), "dtype": str(x.dtype)} for p, x in leaves]
  parts = [x.reshape(-1).view(np.uint8) for _, x in leaves if x.size]  # reshape: a contiguous copy where not
  return ({PACKED: np.concatenate(parts)} if parts else {}), layout


def leaf_arrays(arrays: dict, layout: list[dict]) -> dict[str, np.ndarray]:
  """A checkpoint's state item -> {leaf_NNNNN: array} (the layout's leaves with any element; from
  PACKED, or as checkpoints before 2026-11-29 hold them)."""
  if PACKED not in arrays:
    return {k: np.asarray(v) for k, v in arrays.items()}
  data, out, at = np.asarray(arrays[PACKED], np.uint8), {}, 0
  sizes = [int(np.prod(leaf["shape"], dtype=np.int64)) * np.dtype(leaf["dtype"]).itemsize for leaf in layout]
  if sum(sizes) != data.size:
    raise DamagedCheckpoint(f"the checkpoint's state holds {data.size:,} bytes, its layout {sum(sizes):,}")
  for i, (leaf, size) in enumerate(zip(layout, sizes)):
    if size:
      out[f"leaf_{i:05d}"] = data[at:at + size].view(leaf["dtype"]).reshape(leaf["shape"])
    at += size
  return out


def unflatten_state(arrays: dict, layout: list[dict], target):
  """The inverse of flatten_state onto `target`'s tree (e.g. from jax.eval_shape); a checkpoint of
  another shape of run raises CheckpointError naming the first leaf that differs."""
  arrays = leaf_arrays(arrays, layout)
  leaves, treedef = jax.tree_util.tree_flatten_with_path(target)
  if len(leaves) != len(layout):
    raise CheckpointError(f"the checkpoint holds {len(layout)} arrays, this run's state {len(leaves)}")
  out = []
  for i, ((path, want), saved) in enumerate(zip(leaves, layout)):
    name = f"leaf_{i:05d}"
    x = np.asarray(arrays[name]) if name in arrays else np.zeros(saved["shape"], saved["dtype"])
    if jax.tree_util.keystr(path) != saved["path"] or list(x.shape) != list(want.shape):
      raise CheckpointError(f"checkpoint leaf {saved['path']} {list(x.shape)} does not fit this run's "
                            f"{jax.tree_util.keystr(path)} {list(want.shape)}")
    out.append(x.astype(want.dtype))
  return jax.tree_util.tree_unflatten(treedef, out)


class RunCheckpoints:
  """The checkpoint manager of one run directory."""

  def __init__(self, run_dir: str, keep: int = KEEP):
    self.dir = checkpoint_dir(run_dir)
    os.makedirs(self.dir, exist_ok=True)
    self.mgr = ocp.CheckpointManager(self.dir, options=ocp.CheckpointManagerOptions(
        max_to_keep=keep, create=False, multiprocessing_options=_solo()))

  def save(self, step: int, state, policy, meta: dict[str, Any], wait: bool = True) -> bool:
    """Saves a step (host state tree, (normalizer, policy), JSON meta); a step already on disk is
    kept as it is (returns False). wait=False: orbax writes it in the background (the arrays must
    not change until then) and the step is on disk once `wait()` returns; a save waits for the
    one before it first."""
    if step in self.mgr.all_steps():
      return False
    arrays, layout = flatten_state(state)
    self.mgr.save(step, args=ocp.args.Composite(
        state=ocp.args.StandardSave(arrays), params=ocp.args.StandardSave(_plain(policy)),
        meta=ocp.args.JsonSave(dict(meta, step=step, layout=layout))), force=True)
    if wait:
      self.wait()
    return True

  def wait(self) -> None:
    """Returns once the save in flight (if any) is complete on disk; raises what it failed with."""
    self.mgr.wait_until_finished()

  def writing(self) -> bool:
    """Whether a save is still being written (True where this orbax cannot tell)."""
    in_progress = getattr(self.mgr, "is_saving_in_progress", None)
    return True if in_progress is None else bool(in_progress())

  def latest_step(self) -> int | None:
    return self.mgr.latest_step()

  def restore(self, step: int | None = None) -> tuple[dict, dict]:
    """(raw (normalizer, policy) state dict, meta) of a step (default: latest)."""
    step = self.latest_step() if step is None else step
    if step is None:
      raise FileNotFoundError(f"no checkpoint in {self.dir}")
    out = self.mgr.restore(step, args=ocp.args.Composite(params=ocp.args.StandardRestore(),
                                                          meta=ocp.args.JsonRestore()))
    return out["params"], out["meta"]

  def arrays(self, step: int) -> dict[str, np.ndarray]:
    """The raw `leaf_NNNNN` arrays of a step's state (e.g. to compare two runs)."""
    out = self.mgr.restore(step, args=ocp.args.Composite(state=ocp.args.StandardRestore(),
                                                          meta=ocp.args.JsonRestore()))
    return leaf_arrays(jax.device_get(out["state"]), out["meta"]["layout"])

  def restore_state(self, step: int, target) -> tuple[Any, dict]:
    """(host state shaped like target, meta) of a step."""
    out = self.mgr.restore(step, args=ocp.args.Composite(state=ocp.args.StandardRestore(),
                                                          meta=ocp.args.JsonRestore()))
    meta = out["meta"]
    return unflatten_state(jax.device_get(out["state"]), meta["layout"], target), meta

  def restore_latest_good(self, target, say: Callable[[str], None] = lambda m: print(m, file=sys.stderr)):
    """(state, meta) of the newest checkpoint that reads back whole; each damaged one newer than
    it is reported in one line and skipped. Raises CheckpointError when none is readable."""
    steps = sorted(self.mgr.all_steps(), reverse=True)
    for i, step in enumerate(steps):
      try:
        return self.restore_state(step, target)
      except CheckpointError as e:
        if not isinstance(e, DamagedCheckpoint):
          raise  # another run's checkpoint: no older one fits either
        say(unreadable_warning(self.dir, steps, i, e))
      except Exception as e:  # orbax / tensorstore raise many types for damaged files
        say(unreadable_warning(self.dir, steps, i, e))
    raise CheckpointError(f"no readable checkpoint in {self.dir}")


def unreadable_warning(folder: str, steps: list[int], i: int, error: Exception) -> str:
  """The one line that reports the damaged checkpoint steps[i] (steps newest first) and what a
  resume falls back to."""
  reason = str(error).strip().splitlines()[0][:160] if str(error).strip() else type(error).__name__
  fallback = f"falling back to checkpoint {steps[i + 1]:,}" if i + 1 < len(steps) else "no older one"
  return f"warning: checkpoint {steps[i]:,} in {folder} is unreadable ({reason}); {fallback}"


def policy_params(raw: dict, spec: NetworkSpec):
  """(normalizer, policy) parameters from a checkpoint's raw `params` state dict."""
  return serialization.from_state_dict(spec.policy_params_target(), {"0": raw["0"], "1": raw["1"]})


def export_policy(out_dir: str, normalizer, policy, spec: NetworkSpec, info: dict[str, Any],
                  folder: str = "policy") -> str:
  """Writes RUN/<folder>/ (parameters, then policy.json, each replaced whole); returns the directory."""
  path = os.path.join(os.path.abspath(out_dir), folder)
  ckpt = ocp.StandardCheckpointer(multiprocessing_options=_solo())
  ckpt.save(os.path.join(path, "params"), _plain((normalizer, policy)), force=True)
  ckpt.wait_until_finished()
  atomic.write_json(os.path.join(path, "policy.json"), {"network": spec.to_json(), **info})
  return path
