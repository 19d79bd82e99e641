"""`python -m train.bench contacts`: the scene each task is surveyed on, and bad inputs refused in
one line before anything compiles (the survey's counting is the collision watch's own test:
dist - includemargin < 0, tests/test_collisions.py; its figures: results/bench/contacts-*.json)."""

from mjx_tracks.envs.config import load_config
from train.bench import __main__ as bench
from train.bench.contacts import default_scene


def test_each_task_is_surveyed_on_its_hardest_scene_or_uniform_where_it_has_none():
  assert default_scene(load_config("asc-inc-cog")) == "hardest"
  assert default_scene(load_config("waves")) == "hardest"
  assert default_scene(load_config("nav")) == "uniform"  # navigation areas have no hardest end


def test_bad_inputs_fail_in_one_line(capsys):
  out = ["--out", "/nonexistent/x.json"]
  for args, said in ((["--trials", "3"], "--trials must be even"),
                     (["--set", "episode.max_steps=5"], "physics settings only"),
                     (["--tasks", "no-such-task"], "no-such-task")):
    assert bench.main(["contacts", *args, *out]) == 2
    assert said in capsys.readouterr().err
