"""SAC end to end on the CPU (its own file, so that pytest-xdist can run it beside the PPO tests)."""

import os

import numpy as np

from helpers import TINY, run_id
from train import db as dbmod
from train import run
from train.core.checkpoints import RunCheckpoints

SAC_TINY = ["--task", "des-inc-ang", "--algo", "sac", "--preset", "cpu", *TINY]


def test_sac_trains_exports_and_resumes_bit_for_bit_with_its_replay_buffer(tmp_path):
  from train.core.policy import load_policy
  whole, part = str(tmp_path / "whole"), str(tmp_path / "part")
  database = str(tmp_path / "db.sqlite")
  assert run.main([*SAC_TINY, "--steps", "256", "--out", whole, "--db", database]) == 0
  act = load_policy(os.path.join(whole, "policy"))
  assert np.asarray(act(np.zeros((2, 12), np.float32))).shape == (2, 5)  # the tiny task: 6 entries x 2 steps
  assert dbmod.ExperimentDB(database).run(run_id(whole))["status"] == "done"
  # the same run in two sessions: 128 steps (the buffer is past min_replay_size), then resumed to 256
  assert run.main([*SAC_TINY, "--steps", "128", "--out", part, "--db", database]) == 0
  assert run.main(["--resume", part, "--steps", "256", "--db", database]) == 0
  a, b = RunCheckpoints(whole).arrays(256), RunCheckpoints(part).arrays(256)
  _, meta = RunCheckpoints(whole).restore(256)
  assert any(".buffer.data" in leaf["path"] for leaf in meta["layout"])
  for k in a:
    np.testing.assert_array_equal(b[k], a[k], err_msg=k)


def test_the_temperature_loss_is_brax_s_at_brax_s_target_and_moves_with_the_target():
  import jax
  import jax.numpy as jnp
  from brax.training.agents.sac import losses, networks
  from brax.training.acme import running_statistics, specs
  from brax.training.types import Transition

  from train.core.algos.sac import make_alpha_loss
  obs_size, act_size, n = 7, 5, 64
  nets = networks.make_sac_networks(obs_size, act_size, hidden_layer_sizes=(16,))
  policy = nets.policy_network.init(jax.random.PRNGKey(0))
  norm = running_statistics.init_state(specs.Array((obs_size,), jnp.float32))
  obs = jax.random.normal(jax.random.PRNGKey(1), (n, obs_size))
  t = Transition(obs, jnp.zeros((n, act_size)), jnp.zeros(n), jnp.ones(n), obs)
  key, log_alpha = jax.random.PRNGKey(2), jnp.float32(-0.7)
  brax_alpha_loss = losses.make_losses(nets, 1.0, 0.99, act_size)[0]  # the oracle: brax's own, at -0.5 x 5
  ours = make_alpha_loss(nets, -0.5 * act_size)
  np.testing.assert_allclose(ours(log_alpha, policy, norm, t, key), brax_alpha_loss(log_alpha, policy, norm, t, key),
                             rtol=1e-6)
  # the loss is alpha x mean(-log pi - target): lowering the target by 2.5 nats adds alpha x 2.5
  sb3 = make_alpha_loss(nets, -1.0 * act_size)
  np.testing.assert_allclose(sb3(log_alpha, policy, norm, t, key) - ours(log_alpha, policy, norm, t, key),
                             np.exp(-0.7) * 2.5, rtol=1e-5)
