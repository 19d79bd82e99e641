"""`python -m train.study merge DEST SRC [SRC ...]`: the finished runs of other folders of the same
study (its runs made on other machines, or the study continued elsewhere) into DEST: each run done
in SRC and not in DEST (or marked done there without its run folder: a folder that came back without
its ignored files) brings its run folder, its database rows, its attempts (after DEST's own, each once when SRC
continued from a copy of DEST). A study that grew in SRC (its study.yaml lists every run of DEST's and
more: tasks or seeds added) gives DEST its study.yaml, and its new runs come too. A SRC that ran new
groups of the study alone (`python -m train.study NAME --set 'groups=[...]'`, with the same tasks, seeds
and evaluation) adds those groups (and any baselines it adds) to DEST's study.yaml, and their runs come
too; a group of one name must be the same in both."""

from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
import sys

from mjx_tracks.envs.config import show
from train.db import ExperimentDB
from train.core.run_record import run_id_in
from train.study.executor import STATE, STUDY_DB, StudyState, cell_folder_of, read_cells
from train.study.results import SPEC_FILE, spec_data, write_spec
from train.study.spec import StudySpec, cells, load_study, study_from_dict


def _study_name(folder: str) -> str:
  """The name in STUDY/study.yaml; FileNotFoundError if the folder holds no study."""
  return load_study(os.path.join(folder, SPEC_FILE)).name


def _merge_cell(dest: str, src: str, name: str, cid: str, dest_cells: dict, src_cells: dict,
                src_attempts: list[dict]) -> None:
  """One cell: run folder, database rows and attempts (SRC's attempts table rows) from SRC; DEST's
  state marks it done."""
  src_run, dest_run = cell_folder_of(src, cid), cell_folder_of(dest, cid)
  if os.path.isdir(src_run):
    shutil.rmtree(dest_run, ignore_errors=True)
    shutil.copytree(src_run, dest_run)
  run_id, db = run_id_in(src_run), ExperimentDB(os.path.join(dest, STUDY_DB))
  if run_id is not None:
    db.import_runs(os.path.join(src, STUDY_DB), dest_run, only=[run_id])
  in_src = {a.get("started") for a in src_cells[cid]["attempts"]}  # SRC continued from DEST: holds DEST's too
  base = [] if dest_cells[cid]["status"] == "done" else [a for a in dest_cells[cid]["attempts"]
                                                         if a.get("started") not in in_src]
  before = len(base)
  for row in src_attempts:
    if row["cell"] == cid:
      db.log_attempt(name, cid, before + row["attempt"], row, row["run_id"])
  dest_cells[cid] = {"status": "done", "attempts": base + src_cells[cid]["attempts"]}


SHARED = ("tasks", "seeds", "eval_trials", "robustness")  # what runs of new groups must share with DEST's


def with_new_groups(dest: StudySpec, src: StudySpec) -> StudySpec:
  """DEST's spec with SRC's groups and baselines that DEST lacks; ValueError, naming the field, where
  they do not share SHARED or a group of one name differs."""
  for field in SHARED:
    if getattr(src, field) != getattr(dest, field):
      raise ValueError(f"{field} is {show(getattr(src, field))} in SRC but {show(getattr(dest, field))} in DEST: "
                       "new groups merge only from a run of the same tasks, seeds and evaluation")
  ours = {g.name: g for g in dest.groups}
  for g in src.groups:
    if g.name in ours and ours[g.name] != g:
      raise ValueError(f"group {g.name!r} differs between the two study.yaml files")
  merged = dataclasses.replace(dest, groups=dest.groups + tuple(g for g in src.groups if g.name not in ours),
                               baselines=dest.baselines + tuple(b for b in src.baselines if b not in dest.baselines))
  return study_from_dict(spec_data(merged))  # validated: e.g. the runs' limit


def _adopt_a_grown_spec(dest: str, src: str) -> None:
  """DEST takes SRC's study.yaml when that lists every run of DEST's and more; else SRC's new groups
  and baselines, where it has runs DEST's does not list (with_new_groups)."""
  specs = [load_study(os.path.join(folder, SPEC_FILE)) for folder in (dest, src)]
  ids_dest, ids_src = ({c.id for c in cells(spec)} for spec in specs)
  if ids_src > ids_dest:
    shutil.copyfile(os.path.join(src, SPEC_FILE), os.path.join(dest, SPEC_FILE))
  elif ids_src - ids_dest:
    write_spec(dest, with_new_groups(*specs))


def merge(dest: str, src: str) -> list[str]:
  """Merges SRC's done runs that DEST lists and has not done (or has no run folder of); returns
  their cell ids."""
  name = _study_name(dest)
  if _study_name(src) != name:
    raise ValueError(f"{src} holds study {_study_name(src)!r}, {dest} holds {name!r}")
  _adopt_a_grown_spec(dest, src)
  dest_cells, src_cells = read_cells(dest), read_cells(src)
  for cell in cells(load_study(os.path.join(dest, SPEC_FILE))):
    dest_cells.setdefault(cell.id, {"status": "queued", "attempts": []})
  ids = [cid for cid, c in src_cells.items()
         if c["status"] == "done" and cid in dest_cells
         and (dest_cells[cid]["status"] != "done" or run_id_in(cell_folder_of(dest, cid)) is None)]
  src_attempts = ExperimentDB(os.path.join(src, STUDY_DB)).attempts(name)
  for cid in ids:
    _merge_cell(dest, src, name, cid, dest_cells, src_cells, src_attempts)
  StudyState(os.path.join(dest, STATE), dest_cells).save()
  return ids


def main(argv: list[str]) -> int:
  p = argparse.ArgumentParser(prog="python -m train.study merge", description=__doc__.splitlines()[0])
  p.add_argument("dest", help="the study folder that receives the runs")
  p.add_argument("src", nargs="+", help="folders of the same study")
  args = p.parse_args(argv)
  for src in args.src:
    try:
      ids = merge(args.dest, src)
    except (FileNotFoundError, ValueError) as e:
      print(f"error: {e}", file=sys.stderr)
      return 2
    print(f"{src}: {len(ids)} runs merged into {args.dest}" + "".join(f"\n  {i}" for i in ids))
  return 0
