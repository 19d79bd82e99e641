"""Optional extras: the env and the trainer import none of them; a command whose extra is missing
refuses in one line naming it; pyproject.toml's extras hold the modules train/extras.py lists."""

import os
import pathlib
import re
import subprocess
import sys
import tomllib

from train.extras import EXTRAS

ROOT = pathlib.Path(__file__).resolve().parents[1]
OPTIONAL = sorted({m for mods in EXTRAS.values() for m in mods})


def _run(code: str, block: list[str], tmp_path) -> subprocess.CompletedProcess:
  """Python with the given modules made unimportable (a sitecustomize sets them to None)."""
  (tmp_path / "sitecustomize.py").write_text("import sys\nfor m in %r:\n  sys.modules[m] = None\n" % block)
  env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)]), "JAX_PLATFORMS": "cpu"}
  return subprocess.run([sys.executable, *code], capture_output=True, text=True, env=env, cwd=ROOT, timeout=300)


def test_the_env_and_trainer_import_without_any_extra(tmp_path):
  code = "import train.run, train.evaluate, train.core.build, train.core.loop, mjx_tracks.envs.gym_env; print('ok')"
  r = _run(["-c", code], OPTIONAL, tmp_path)
  assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]


def test_a_command_without_its_extra_says_which_in_one_line(tmp_path):
  for command, extra in (("train.study", "studies"), ("train.server", "server")):
    r = _run(["-m", command, "--help"], OPTIONAL, tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr[-2000:]
    assert f"needs the [{extra}] extra" in r.stderr and f"pip install 'mjx-tracks[{extra}]'" in r.stderr


def test_pyproject_extras_install_the_modules_listed():
  extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]

  def names(extra: str) -> set[str]:
    out = set()
    for req in extras[extra]:
      name = re.match(r"[A-Za-z0-9_.-]+", req).group(0)
      inner = re.match(r"mjx-tracks\[(.+)\]", req)
      out |= set().union(*(names(e) for e in inner.group(1).split(","))) if inner else {name.lower().replace("-", "_")}
    return out

  for extra, modules in EXTRAS.items():
    assert set(modules) <= names(extra), extra
  assert names("all") >= names("studies") | names("server") | names("notebooks")


def test_the_training_core_imports_nothing_of_the_lab_but_evaluation_and_the_database():
  """train/core/ may use the evaluation library (its probe) and the database (its records), not
  studies, benchmarks or the server: found by reading every import of every core module."""
  import ast  # noqa: PLC0415
  core = pathlib.Path(__file__).resolve().parents[1] / "train" / "core"
  allowed = ("train.core", "train.evaluation", "train.db", "train.extras")
  found = {}
  for path in core.rglob("*.py"):
    for node in ast.walk(ast.parse(path.read_text())):
      names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
          [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0 else []
      for name in names:
        if name.startswith("train") and not name.startswith(allowed):
          found.setdefault(path.name, []).append(name)
  assert len(list(core.rglob("*.py"))) >= 17 and not found, found
