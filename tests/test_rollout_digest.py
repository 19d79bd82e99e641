"""mjx_tracks.tools.rollout_digest: what `--write --tasks` keeps of a recorded file; unknown tasks refused."""

import json

import pytest

from mjx_tracks.tools.rollout_digest import _kept_digests, cpu_features, cpu_note

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


def test_the_cpus_vector_instruction_sets_are_read_from_cpuinfo_and_a_check_on_another_cpu_says_so(tmp_path):
  info = tmp_path / "cpuinfo"
  info.write_text("processor\t: 0\nflags\t\t: fpu sse4_2 avx2 fma avx avx512f f16c amx_tile smep\n\n"
                  "processor\t: 1\nflags\t\t: fpu avx\n")
  assert cpu_features(str(info)) == ["amx_tile", "avx", "avx2", "avx512f", "f16c", "fma"]  # the first processor's
  assert cpu_features(str(tmp_path / "absent")) == []
  info.write_text("processor\t: 0\nFeatures\t: fp asimd sve2 sme crc32\n")  # an Arm host's
  assert cpu_features(str(info)) == ["asimd", "sme", "sve2"]
  mine = ["avx", "avx2", "fma"]
  assert cpu_note({"cpu_features": mine}, HERE, mine) is None
  assert "digests may differ for the CPU alone" in cpu_note({"cpu_features": ["avx"]}, HERE, mine)
  assert "(not recorded)" in cpu_note({}, HERE, mine)
  assert cpu_note({}, "gpu (H100)", mine) is None  # a GPU's digests do not depend on the host CPU's
