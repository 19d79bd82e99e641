"""A study's results as data: every finished run with its cell (group, task, seed, budgets), its
training statistics and its evaluation trials, read from STUDY/state.json and STUDY/study.sqlite;
the report and the study notebook both read them through here."""

from __future__ import annotations

import dataclasses
import json
import os

import numpy as np

from mjx_tracks.metrics import EPISODE_NAMES, REPORT_NAMES
from train.db import ExperimentDB
from train.core.run_record import run_id_in
from train.evaluation import ROBUST
from train.study.executor import STUDY_DB, cell_folder_of, read_cells
from train.study.spec import BASELINE_GROUP, Cell, StudySpec, cells, load_study

SPEC_FILE = "study.yaml"  # the study's spec as it ran, written into its folder
EVAL_METRICS = tuple(n for n in EPISODE_NAMES if n != "length")  # per trial (mjx_tracks.metrics.EPISODE)
CURVE_METRICS = tuple(n for n in REPORT_NAMES if n != "tipped_rate")  # per report (mjx_tracks.metrics.REPORT)


@dataclasses.dataclass(frozen=True)
class RunResult:
  cell: Cell
  run_id: str
  stats: list[dict]  # training statistics rows (source 'train'), by step
  evals: list[dict]  # evaluation trials; budget None = the run's own budget (cell.steps)


@dataclasses.dataclass(frozen=True)
class StudyResults:
  spec: StudySpec
  folder: str
  runs: list[RunResult]
  state: dict  # state.json's cells: status and attempts of every run

  def groups(self) -> list[tuple[str, str, int]]:
    """(group, task, budget) of every finished run's evaluations, in the spec's order."""
    seen = {(r.cell.group, r.cell.task, b) for r in self.runs for b in r.cell.budgets()}
    order = [(g.name, t, b) for g in self.spec.groups for t in self.spec.tasks for b in sorted(set(g.steps))]
    order += [(BASELINE_GROUP + n, t, 0) for t in self.spec.tasks for n in self.spec.baselines]  # budget 0
    return [k for k in order if k in seen]

  def trained_groups(self) -> list[tuple[str, str, int]]:
    """groups() less the baselines'."""
    return [k for k in self.groups() if not k[0].startswith(BASELINE_GROUP)]

  def baseline_figure(self, task: str, scene: str, metric: str) -> dict[str, float]:
    """{baseline name: its mean of `metric` over its trials on the scene} for one task."""
    out = {}
    for n in self.spec.baselines:
      fig = self.final(BASELINE_GROUP + n, task, 0, scene, metric)
      if len(fig):
        out[n] = float(fig[0])
    return out

  def scenes(self, robustness: bool = False) -> list[str]:
    """Evaluation scenes of the finished runs: hardest, uniform, then the others by name; those of
    the robustness suite (BASE+CASE, train.evaluation.ROBUST) only with robustness=True."""
    found = {e["scene"] for r in self.runs for e in r.evals if robustness or ROBUST not in e["scene"]}
    first = [s for s in ("hardest", "uniform") if s in found]
    return first + sorted(found - set(first))

  def _trials(self, group: str, task: str, budget: int, scene: str, metric: str):
    """(run, its trials' rows on the scene at the budget that hold `metric`) per finished run of the
    group (a row without the figure: one added after the trials ran)."""
    for r in self.runs:
      if (r.cell.group, r.cell.task) == (group, task) and budget in r.cell.budgets():
        yield r, [e for e in r.evals if e["scene"] == scene and (e["budget"] or r.cell.steps) == budget
                  and e.get(metric) is not None]

  def final(self, group: str, task: str, budget: int, scene: str, metric: str) -> np.ndarray:
    """One figure per finished run (seed) of the group: the mean of `metric` over its trials."""
    return np.asarray([float(np.mean([e[metric] for e in rows]))
                       for _, rows in self._trials(group, task, budget, scene, metric) if rows])

  def first_trials(self, group: str, task: str, budget: int, scene: str, metric: str,
                   n: int) -> list[tuple[int, np.ndarray]]:
    """(seed, `metric` of its first n trials by trial index) per finished run of the group with at
    least n trials on the scene: an evaluation of n trials of each seed's policy."""
    out = []
    for r, rows in self._trials(group, task, budget, scene, metric):
      trials = sorted((e["trial"], e[metric]) for e in rows)
      if len({i for i, _ in trials}) != len(trials):
        raise ValueError(f"run {r.run_id}: a trial index twice on {scene} at {budget} steps")
      if len(trials) >= n:
        out.append((r.cell.seed, np.asarray([v for _, v in trials[:n]], float)))
    return sorted(out, key=lambda x: x[0])

  def curves(self, group: str, task: str, x: str, metric: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """(x, y) of each run of the group on a task: x 'step' or 'wall_s'; rows without y left out."""
    out = []
    for r in self.runs:
      if (r.cell.group, r.cell.task) == (group, task):
        rows = [s for s in r.stats if s.get(metric) is not None and s.get(x) is not None]
        if rows:
          out.append((np.array([s[x] for s in rows], float), np.array([s[metric] for s in rows], float)))
    return out


def spec_data(spec: StudySpec) -> dict:
  """The spec as plain data (tuples -> lists), as study.yaml holds it and study_from_dict reads it."""
  return json.loads(json.dumps(dataclasses.asdict(spec)))


def write_spec(folder: str, spec: StudySpec) -> None:
  """STUDY/study.yaml: the spec the study runs, so that `report` and `status` need only the folder."""
  import yaml  # noqa: PLC0415
  with open(os.path.join(folder, SPEC_FILE), "w") as f:
    yaml.safe_dump(spec_data(spec), f, sort_keys=False)


def load_results(folder: str) -> StudyResults:
  """Every finished run of the study in `folder`; FileNotFoundError if there is no study."""
  spec = load_study(os.path.join(folder, SPEC_FILE))
  state = read_cells(folder)
  db = ExperimentDB(os.path.join(folder, STUDY_DB))
  runs = []
  for cell in cells(spec):
    run_id = run_id_in(cell_folder_of(folder, cell.id))  # None: no run.json came back
    if state.get(cell.id, {}).get("status") != "done" or run_id is None:
      continue
    try:
      db.run(run_id)
    except KeyError:
      continue
    stats = [s for s in db.stats(run_id) if s["source"] == "train"]
    runs.append(RunResult(cell, run_id, stats, db.evals(run_id)))
  return StudyResults(spec, folder, runs, state)
