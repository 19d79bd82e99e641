"""GPU smoke test: device, versions of jax / mujoco / mjx / brax, and a batched MJX step."""

import importlib.metadata as md
import json
import os
import sys
import time

import jax
import jax.numpy as jnp
import mujoco
from mujoco import mjx

XML = """<mujoco><worldbody><geom type="plane" size="0 0 1"/>
<body pos="0 0 .5"><freejoint/><geom type="capsule" size=".05 .1"/></body></worldbody></mujoco>"""


def main() -> int:
  info = {"devices": [str(d) for d in jax.devices()], "backend": jax.default_backend(),
          "python": sys.version.split()[0]}
  for pkg in ("jax", "jaxlib", "mujoco", "mujoco-mjx", "brax", "gymnasium", "flax", "orbax-checkpoint"):
    try:
      info[pkg] = md.version(pkg)
    except md.PackageNotFoundError:
      info[pkg] = "missing"
  m = mjx.put_model(mujoco.MjModel.from_xml_string(XML), impl="jax")
  batch = 1024
  d = jax.vmap(lambda z: mjx.make_data(m, impl="jax").replace(qpos=mjx.make_data(m, impl="jax").qpos.at[2].set(z)))(
      jnp.linspace(0.3, 1.0, batch))
  step = jax.jit(jax.vmap(lambda d: mjx.step(m, d)))
  t = time.time()
  d = jax.block_until_ready(step(d))
  info["compile_s"] = round(time.time() - t, 2)
  t = time.time()
  for _ in range(100):
    d = step(d)
  jax.block_until_ready(d)
  info["batch"] = batch
  info["steps_per_s"] = round(100 * batch / (time.time() - t))
  info["finite"] = bool(jnp.isfinite(d.qpos).all())
  print(json.dumps(info, indent=1))
  out = os.environ.get("OUT")
  if out:
    with open(os.path.join(out, "gpu_smoke.json"), "w") as f:
      json.dump(info, f, indent=1)
  return 0 if info["finite"] else 1


if __name__ == "__main__":
  sys.exit(main())
