"""`python -m train.study STUDY [--set KEY=VALUE] [--plan]`: run a study (a YAML path, or the NAME
of one in configs/studies/) on a Dask cluster: by default one started here (a worker per GPU, CPU
slots), or an existing one (--scheduler). Finished runs of an earlier start are skipped; --plan
lists the runs and stops. `python -m train.study status NAME [--runs]`: where it stands;
`python -m train.study report NAME`: STUDY/report.md with statistics and figures;
`python -m train.study timeline NAME`: when each of its programs started, compiled, trained and ended;
`python -m train.study merge DEST SRC...`: runs finished in other folders of the study into DEST."""

from __future__ import annotations

import argparse
import os
import shlex
import sys

from mjx_tracks.envs.config import ConfigError
from train.study.cluster import add_cluster_args
from train.study.executor import STUDY_DB, cell_folder_of
from train.study.spec import cells, group_tasks, load_study, pack_train_args, packs_of, runs_of


def parser() -> argparse.ArgumentParser:
  p = argparse.ArgumentParser(prog="python -m train.study", description=__doc__.splitlines()[0])
  p.add_argument("study", help="the study's YAML file, e.g. configs/studies/paper.yaml")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                 help="top-level override, e.g. --set seeds=[0,1] or --set retries=2")
  p.add_argument("--plan", action="store_true", help="list the runs and stop")
  p.add_argument("--root", default="studies", help="where study folders go (default ./studies)")
  add_cluster_args(p)
  return p


def _client(args):
  """(Dask client, the worker kinds it has)."""
  from train.study.cluster import make_client  # noqa: PLC0415
  return make_client(args)


def main(argv=None) -> int:
  argv = sys.argv[1:] if argv is None else argv
  if argv[:1] == ["status"]:
    from train.study.status import main as status_main  # noqa: PLC0415
    return status_main(argv[1:])
  if argv[:1] == ["report"]:
    from train.study.report import main as report_main  # noqa: PLC0415
    return report_main(argv[1:])
  if argv[:1] == ["timeline"]:
    from train.study.timeline import main as timeline_main  # noqa: PLC0415
    return timeline_main(argv[1:])
  if argv[:1] == ["merge"]:
    from train.study.merge import main as merge_main  # noqa: PLC0415
    return merge_main(argv[1:])
  args = parser().parse_args(argv)
  try:
    spec = load_study(args.study, tuple(args.set))
  except ConfigError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  folder = os.path.join(args.root, spec.name)
  if not args.plan:
    return _run(spec, folder, args)
  runs = [c for c in cells(spec) if not c.is_baseline]
  base = [c for c in cells(spec) if c.is_baseline]
  per = ", ".join(f"{g.name}: {len(group_tasks(spec, g))} tasks x {len(runs_of(g))}" for g in spec.groups)
  print(f"study {spec.name}: {len(runs)} runs = {len(spec.seeds)} seeds x tasks x runs per task of each group "
        f"({per}), and {len(base)} baseline evaluations; retries per run: {spec.retries} -> {folder}")
  db = os.path.join(folder, STUDY_DB)
  for c in runs:
    print(f"{c.id}: python -m train.run {shlex.join(c.run_args(cell_folder_of(folder, c.id), db))}")
  for pack in packs_of(runs):
    print(f"{pack[0].id} .. {pack[-1].id} start as one program where none has started yet or the study's "
          f"stop cut them off with no checkpoint (a retry resumes each run alone): python -m "
          f"train.run {shlex.join(pack_train_args(pack))} --out SCRATCH --db SCRATCH.sqlite")
  for c in base:
    print(f"{c.id}: python -m train.evaluate {shlex.join([cell_folder_of(folder, c.id), *c.eval_args(spec.eval_trials), '--db', db])}")
  return 0


def _run(spec, folder: str, args) -> int:
  from train.study.executor import StudyRunner, run_until_done_or_stopped  # noqa: PLC0415  (distributed)
  try:
    client, kinds = _client(args)
  except (ValueError, OSError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  if not kinds:
    print("error: the cluster has no worker with a gpu or cpu resource", file=sys.stderr)
    return 2
  return run_until_done_or_stopped(StudyRunner(spec, folder, client, backends=kinds))


if __name__ == "__main__":
  sys.exit(main())
