"""Content keys of the persistent cache (mjx_tracks.jax_private.key_programs_by_content) on this
machine's JAX: the private function they hook as it is here, JAX's own key and the content key of
one program whose equal functions were traced shared or apart (and of one with another constant),
and how long each key takes for asc-inc-cog's env step (8 robots). Writes OUT/cache-key.json with
device, command and date.
Usage: python scripts/gpu/cache_key_check.py OUT"""

from __future__ import annotations

import datetime
import inspect
import json
import os
import shlex
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def _scaled(k: float):
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  @jax.jit
  def scaled(x):
    return jnp.sin(x) * k + 1.0
  return scaled


def main() -> None:
  if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
    sys.exit(__doc__)
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415
  from jax._src import cache_key  # noqa: PLC0415

  import mjx_tracks  # noqa: PLC0415
  from mjx_tracks import compile_cache, jax_private  # noqa: PLC0415
  from mjx_tracks.envs.wrappers import batched_env  # noqa: PLC0415
  compile_cache.enable()
  key = jax_private.computation_key

  x = jax.ShapeDtypeStruct((4,), jnp.float32)
  first, second = _scaled(2.0), _scaled(2.0)
  shared = jax.jit(lambda x: first(first(x))).lower(x).compiler_ir("stablehlo")
  apart = jax.jit(lambda x: first(second(x))).lower(x).compiler_ir("stablehlo")
  other = jax.jit(lambda x: first(_scaled(2.5)(x))).lower(x).compiler_ir("stablehlo")
  core = mjx_tracks.load("asc-inc-cog")
  env = batched_env(core)
  s = jax.eval_shape(lambda k: env.reset_with(k, env.initial_stats()), jax.random.split(jax.random.PRNGKey(0), 8))
  step = jax.jit(env.step).lower(s, jax.ShapeDtypeStruct((8, core.action_size), jnp.float32)).compiler_ir("stablehlo")
  seconds = {}
  for name, content in (("content", True), ("jax_own", False)):
    t0 = time.perf_counter()
    key(step, content)
    seconds[name] = round(time.perf_counter() - t0, 3)
  result = {
      "device": f"{jax.devices()[0].device_kind} x {jax.device_count()}, JAX {jax.__version__}",
      "command": "python scripts/gpu/cache_key_check.py " + shlex.join(sys.argv[1:]),
      "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
      "hooked_signature": str(inspect.signature(cache_key._hash_computation.__wrapped__)),  # noqa: SLF001
      "hook_installed": jax_private.keys_by_content(),
      "jax_own_key_shared_equals_apart": key(shared, False) == key(apart, False),
      "content_key_shared_equals_apart": key(shared) == key(apart),
      "content_key_shared_equals_other_constant": key(shared) == key(other),
      "env_step_key_seconds": seconds}
  print(json.dumps(result, indent=1))
  os.makedirs(sys.argv[1], exist_ok=True)
  json.dump(result, open(os.path.join(sys.argv[1], "cache-key.json"), "w"), indent=1)


if __name__ == "__main__":
  main()
