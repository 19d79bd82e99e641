"""The notebooks run headless (nbclient) to the end: the study notebook on a tiny study made here
(a local Dask cluster and the stand-in runner of tests/fake_study_run.py), the results notebook on
the committed results; so neither can rot."""

import pathlib

import nbclient
import nbformat
from distributed import Client, LocalCluster

from train.study.executor import StudyRunner
from train.study.spec import study_from_dict

NOTEBOOKS = pathlib.Path(__file__).parents[1] / "notebooks"
FAKE = str(pathlib.Path(__file__).with_name("fake_study_run.py"))
STUDY = {"name": "nb", "tasks": ["asc-inc-cog", "asc-uni-cog"], "seeds": [0, 1, 2], "eval_trials": 4,
         "groups": [{"name": "g", "algo": "ppo", "preset": "cpu", "steps": [200, 400], "budgets": "milestones",
                     "backend": "cpu"}],
         "compare": [["asc-inc-cog", "asc-uni-cog"]], "baselines": ["full"]}


def _run(name: str) -> nbformat.NotebookNode:
  nb = nbformat.read(NOTEBOOKS / name, as_version=4)
  nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                          resources={"metadata": {"path": str(NOTEBOOKS)}}).execute()
  return nb


def _outputs(nb: nbformat.NotebookNode) -> str:
  data = lambda o: o.get("data", {}).get("text/markdown", o.get("data", {}).get("text/plain", ""))  # noqa: E731
  return "\n".join(str(o.get("text", "")) + str(data(o)) for c in nb.cells if c.cell_type == "code" for o in c.outputs)


def test_the_study_notebook_runs_on_a_study_made_here(tmp_path, monkeypatch):
  folder = tmp_path / "nb"
  with LocalCluster(n_workers=1, threads_per_worker=3, processes=False, resources={"cpu": 3},
                    dashboard_address=":0") as cluster, Client(cluster) as client:
    counts = StudyRunner(study_from_dict(STUDY), str(folder), client, ((FAKE, "train"), (FAKE, "evaluate")),
                         backends=("cpu",)).run()
  assert counts["done"] == 6 + 2  # and the full-throttle baseline on each task
  monkeypatch.setenv("MJX_TRACKS_STUDY", str(folder))
  nb = _run("study.ipynb")
  text = _outputs(nb)
  assert "8 runs: 8 done" in text and "('g', 'asc-inc-cog', 200)" in text
  images = sum("image/png" in o.get("data", {}) for c in nb.cells if c.cell_type == "code" for o in c.outputs)
  assert images == 3  # final metrics, curves, per-trial histogram of the one group


def test_the_results_notebook_runs_on_the_committed_results():
  nb = _run("explore_results.ipynb")
  assert not [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
