"""mjx_tracks.tools.rollout_digest: what `--write --tasks` keeps of a recorded file; unknown tasks refused."""

import json

import pytest

from mjx_tracks.tools.rollout_digest import _kept_digests

HERE, VERSIONS = "cpu (cpu)", {"jax": "1", "jaxlib": "1", "mujoco": "2", "mujoco-mjx": "3"}


def test_a_subset_keeps_the_other_digests_of_a_file_recorded_here(tmp_path):
  path = tmp_path / "d.json"
  assert _kept_digests(str(path), HERE, VERSIONS) == {}  # no file yet: nothing to keep
  path.write_text(json.dumps({"device": HERE, "versions": VERSIONS, "digests": {"nav": "ab"}}))
  assert _kept_digests(str(path), HERE, VERSIONS) == {"nav": "ab"}


@pytest.mark.parametrize("device, versions", [("gpu (H100)", VERSIONS), (HERE, {**VERSIONS, "jax": "2"})])
def test_a_subset_refuses_a_file_recorded_elsewhere(tmp_path, capsys, device, versions):
  path = tmp_path / "d.json"
  path.write_text(json.dumps({"device": device, "versions": versions, "digests": {"nav": "ab"}}))
  with pytest.raises(SystemExit) as e:
    _kept_digests(str(path), HERE, VERSIONS)
  assert e.value.code == 2 and "record every task" in capsys.readouterr().err


def test_an_unknown_task_is_refused_in_one_line_before_anything_compiles(capsys):
  from mjx_tracks.tools.rollout_digest import main
  with pytest.raises(SystemExit) as e:
    main(["--check", "unused.json", "--tasks", "asc-inc-cog,nav"])  # a comma list: one unknown name
  assert e.value.code == 2 and "not among the recorded tasks: asc-inc-cog,nav" in capsys.readouterr().err
