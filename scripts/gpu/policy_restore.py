"""Where restoring a pack's exported policies goes, on this machine's default device:
`python scripts/gpu/policy_restore.py OUT.json RUN_DIR [RUN_DIR ...]` times train.core.policy's
load_policy_params over the runs (the first pass, then again), and its parts: the network's
initial parameters (the restore's target) and orbax's restore (a checkpointer each, one for all,
one for all into numpy). Writes the seconds of each to OUT.json with the device and date."""

import datetime
import functools
import json
import os
import sys
import time

t0 = time.time()
import jax  # noqa: E402
import numpy as np  # noqa: E402
import orbax.checkpoint as ocp  # noqa: E402
from flax import serialization  # noqa: E402

from train.core.networks import NetworkSpec  # noqa: E402
from train.core.policy import load_policy_info, load_policy_params  # noqa: E402


def main(out_path: str, runs: list[str]) -> dict:
  out = {"import_s": round(time.time() - t0, 3), "device": str(jax.devices()[0].device_kind), "runs": len(runs),
         "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
         "command": "python scripts/gpu/policy_restore.py " + " ".join(sys.argv[1:2]) + f" RUN_DIR x{len(runs)}"}
  dirs = [os.path.join(r, "policy") for r in runs]
  spec = NetworkSpec.from_json(load_policy_info(dirs[0])["network"])
  params = lambda d: os.path.join(os.path.abspath(d), "params")  # noqa: E731
  one = ocp.StandardCheckpointer()
  target = functools.cache(lambda: jax.tree_util.tree_map(np.asarray, serialization.to_state_dict(spec.init_policy_params())))
  for name, fn in (("load_policy_params, first pass", load_policy_params),
                   ("load_policy_params, again", load_policy_params),
                   ("init_policy_params", lambda d: jax.block_until_ready(spec.init_policy_params())),
                   ("restore, a checkpointer each", lambda d: jax.block_until_ready(ocp.StandardCheckpointer().restore(params(d)))),
                   ("restore, one checkpointer", lambda d: jax.block_until_ready(one.restore(params(d)))),
                   ("restore, one checkpointer, into numpy", lambda d: one.restore(params(d), target()))):
    t = time.time()
    for d in dirs:
      fn(d)
    out[f"{name} (s, all runs)"] = round(time.time() - t, 3)
    print(name, out[f"{name} (s, all runs)"], flush=True)
  with open(out_path, "w") as f:
    json.dump(out, f, indent=1)
  return out


if __name__ == "__main__":
  main(sys.argv[1], sys.argv[2:])
