"""Persistent-cache keys by content (mjx_tracks.jax_private.key_programs_by_content, switched on by
compile_cache.enable): a program whose equal functions were traced as one shared function or as
several gets one key; programs that differ anywhere, however deep in their calls, get different
ones. JAX's own hash is the oracle of what the hook changes. Also fails where a JAX upgrade moves the
private function it hooks."""

import inspect

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks import jax_private


_key = jax_private.computation_key  # the computation's part of the cache key: by content, or JAX's own


def _module(outer, x=jax.ShapeDtypeStruct((4,), jnp.float32)):
  return jax.jit(outer).lower(x).compiler_ir("stablehlo")


def _scaled(k: float):
  """A jitted function of its own (its own trace, its own private function in a caller's MLIR)."""
  @jax.jit
  def scaled(x):
    return jnp.sin(x) * k + 1.0
  return scaled


def test_the_hook_is_installed_on_the_private_api_it_expects():
  from jax._src import cache_key
  assert jax_private._key_api() is not None
  assert jax_private.keys_by_content()  # tests/conftest.py's compile_cache.enable()
  assert "_hash_computation(" in inspect.getsource(cache_key.get)


def test_equal_functions_shared_or_traced_apart_give_one_key_and_jax_s_own_hash_two():
  first, second = _scaled(2.0), _scaled(2.0)
  shared = _module(lambda x: first(first(x)))  # one private function, called twice
  apart = _module(lambda x: first(second(x)))  # two equal private functions
  assert str(shared).count("func.func private") == 1 and str(apart).count("func.func private") == 2
  assert _key(shared, by_content=False) != _key(apart, by_content=False)
  assert _key(shared) == _key(apart)
  x = jnp.linspace(0.0, 1.0, 4)
  assert jnp.array_equal(jax.jit(lambda x: first(first(x)))(x), jax.jit(lambda x: first(second(x)))(x))


def test_programs_that_differ_in_a_function_called_deep_down_get_different_keys():
  def nested(leaf):
    mid = jax.jit(lambda x: leaf(x) - 0.5)
    return _module(lambda x: mid(x) * 3.0)
  base = nested(_scaled(2.0))
  assert _key(base) == _key(nested(_scaled(2.0)))
  assert _key(base) != _key(nested(_scaled(2.5)))  # a constant two calls down
  assert _key(base) != _key(_module(lambda x: jax.jit(lambda x: _scaled(2.0)(x) - 0.5)(x) * 3.0,
                                    jax.ShapeDtypeStruct((5,), jnp.float32)))  # another shape
  big = np.arange(5_000, dtype=np.float32)
  other = big.copy()
  other[-1] += 1.0  # the last of 5,000 constants (printed in full, not elided)
  assert _key(_module(lambda x: x * jnp.asarray(big)[-4:])) != _key(_module(lambda x: x * jnp.asarray(other)[-4:]))


def test_program_content_replaces_calls_by_their_callees_hashes_and_refuses_other_text():
  def module(names, leaf_body):
    a, b = names
    return "\n".join([
        "module @jit_f {", "  func.func public @main(%arg0: tensor<f32>) -> tensor<f32> {",
        f"    %0 = call @{a}(%arg0) : (tensor<f32>) -> tensor<f32>", "    return %0 : tensor<f32>", "  }",
        f"  func.func private @{a}(%arg0: tensor<f32>) -> tensor<f32> {{",
        f"    %0 = call @{b}(%arg0) : (tensor<f32>) -> tensor<f32>", "    return %0 : tensor<f32>", "  }",
        f"  func.func private @{b}(%arg0: tensor<f32>) -> tensor<f32> {{", f"    {leaf_body}",
        "    return %0 : tensor<f32>", "  }", "}"])
  add = "%0 = stablehlo.add %arg0, %arg0 : tensor<f32>"
  one = jax_private.program_content(module(("mid_3", "leaf_7"), add))
  assert one == jax_private.program_content(module(("mid_9", "leaf_1"), add))
  assert one != jax_private.program_content(module(("mid_3", "leaf_7"), add.replace("add", "multiply")))
  assert b"leaf" not in one and b"mid" not in one
  with pytest.raises(ValueError, match="main"):
    jax_private.program_content("module @m {\n}")
