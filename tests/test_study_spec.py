"""Study descriptions: validation names the faulty key, the grid has one run per combination, and
each run's arguments plan like a `train.run` command line (no compilation)."""

import pathlib

import pytest

from mjx_tracks.envs.config import ConfigError
from train.core.plan import plan_run
from train.run import parser as run_parser
from train.study.__main__ import main as study_main
from train.study.spec import cells, load_study, study_from_dict

STUDIES = pathlib.Path(__file__).resolve().parents[1] / "configs" / "studies"
GROUP = {"name": "ppo", "algo": "ppo", "preset": "cpu", "steps": [512, 1024]}
STUDY = {"name": "s", "tasks": ["asc-inc-cog", "asc-uni-cog"], "seeds": [0, 1, 2], "groups": [GROUP]}


def test_the_grid_has_one_run_per_group_task_budget_and_seed():
  spec = study_from_dict({**STUDY, "groups": [GROUP, {**GROUP, "name": "sac", "algo": "sac", "steps": [64]}]})
  runs = [c for c in cells(spec) if not c.is_baseline]
  assert len(runs) == 2 * 3 * (2 + 1) and len({c.id for c in cells(spec)}) == len(cells(spec))
  assert len(cells(spec)) - len(runs) == 2 * 4  # every baseline on each task, once
  assert {(c.group, c.steps) for c in runs} == {("ppo", 512), ("ppo", 1024), ("sac", 64)}
  assert spec.retries == 1 and spec.eval_trials == 100  # the defaults
  one = study_from_dict({**STUDY, "groups": [GROUP, {**GROUP, "name": "inc", "tasks": ["asc-inc-cog"]}]})
  assert [c.task for c in cells(one) if c.group == "inc"] == ["asc-inc-cog"] * 2 * 3  # a group's own tasks


def test_a_run_plans_like_its_command_line(tmp_path):
  spec = study_from_dict({**STUDY, "groups": [{**GROUP, "early_stop": "success=0.9x3", "set": ["reward.cog_scale=0.25"]}]})
  c = [c for c in cells(spec) if not c.is_baseline][-1]
  plan = plan_run(run_parser().parse_args(c.run_args(str(tmp_path / "run"), str(tmp_path / "db.sqlite"))))
  assert (plan.task, plan.algo, plan.preset_name, plan.total_steps, plan.seed) == ("asc-uni-cog", "ppo", "cpu", 1024, 2)
  assert plan.cfg.reward.cog_scale == 0.25 and str(plan.early_stop) == "success=0.9x3"


def test_a_group_of_another_library_plans_its_runs_with_it(tmp_path):
  spec = study_from_dict({**STUDY, "groups": [{**GROUP, "library": "brax", "hp": ["discounting=0.99"]}]})
  c = [c for c in cells(spec) if not c.is_baseline][0]
  plan = plan_run(run_parser().parse_args(c.run_args(str(tmp_path / "run"), str(tmp_path / "db.sqlite"))))
  assert (plan.library, plan.early_stop, plan.probe_every, plan.preset.discounting) == ("brax", None, 0, 0.99)
  assert load_study(str(STUDIES / "parity.yaml")).groups[1].library == "brax"


@pytest.mark.parametrize("change, words", [
    ({"seedz": [0]}, "seedz: unknown key"),
    ({"tasks": ["asc-inc-cgo"]}, "unknown task 'asc-inc-cgo'"),
    ({"seeds": [0, 0]}, "seeds: distinct"),
    ({"name": "a/b"}, "not a plain name"),
    ({"groups": []}, "groups: must be a non-empty list"),
    ({"groups": [{**GROUP, "stepz": [1]}]}, r"groups\[0\].stepz: unknown key"),
    ({"groups": [{**GROUP, "preset": "huge"}]}, "unknown preset 'huge'"),
    ({"groups": [{**GROUP, "library": "sb4"}]}, r"groups\[0\].library: one of \('mjx-tracks', 'brax'"),
    ({"groups": [{**GROUP, "library": "brax", "early_stop": "return"}]}, r"groups\[0\].library: brax has no early stop"),
    ({"groups": [{**GROUP, "steps": [0]}]}, "budgets from 1 to"),
    ({"groups": [{**GROUP, "steps": [10**30]}]}, "budgets from 1 to"),
    ({"eval_trials": 10**9}, "eval_trials: from 1 to"),
    ({"seeds": [2**40]}, "seeds: distinct integers from 0 to"),
    ({"name": "x" * 300}, "at most 64 characters"),
    ({"name": "study\n"}, "not a plain name"),  # a trailing newline
    ({"tasks": ["nope"], "compare": [["nope", "asc-inc-cog"]]}, "unknown task 'nope'"),  # not a compare error
    ({"groups": [GROUP, GROUP]}, "group names repeat"),
    ({"groups": [{**GROUP, "tasks": ["nav"]}]}, r"groups\[0\].tasks: distinct tasks of the study's tasks"),
    ({"groups": [{**GROUP, "tasks": ["asc-inc-cog"] * 2}]}, r"groups\[0\].tasks: distinct"),
    ({"groups": [{**GROUP, "set": ["reward.cog_scal=1"]}]}, r"groups\[0\] \(ppo\) on asc-inc-cog: reward.cog_scal: unknown key"),
    ({"groups": [{**GROUP, "budgets": "some"}]}, r"groups\[0\].budgets: one of"),
    ({"groups": [{**GROUP, "budgets": "milestones", "early_stop": "return"}]}, "an early stop would cut them short"),
    ({"compare": [["asc-inc-cog", "nav"]]}, r"compare\[0\]: two different tasks of the study"),
    ({"groups": [{**GROUP, "set": ["robot=2"]}]}, r"on asc-inc-cog: control.mode: '5dof_stairs' drives the arm"),
    ({"tasks": ["step-up"], "groups": [{**GROUP, "set": ["reward.kind=cog"]}]}, r"on step-up: reward.kind: 'cog' penalizes"),
])
def test_bad_studies_fail_naming_the_fault(change, words):
  with pytest.raises(ConfigError, match=words):
    study_from_dict({**STUDY, **change})


def test_the_shipped_studies_validate_and_the_command_lists_their_runs(capsys):
  assert all(cells(load_study(str(path))) for path in STUDIES.glob("*.yaml"))
  trained = lambda name: [c for c in cells(load_study(name)) if not c.is_baseline]  # noqa: E731
  assert len(trained("curricula")) == 3 * (2 + 1 + 1)  # the variant groups train asc-inc-cog only
  paper = trained("paper")  # a shipped study by name
  assert len(paper) == 4 * 5 * 3  # SAC with and without early stop; PPO's 4 budgets: milestones of one run
  ppo = [c for c in paper if c.group == "ppo"]
  assert {c.budgets() for c in ppo} == {(250_000, 500_000, 1_000_000, 2_000_000)}
  assert all(c.train_args()[-4:] == ["--milestones", "250000,500000,1000000", "--early-stop", "none"] for c in ppo)
  assert study_main([str(STUDIES / "tiny.yaml"), "--plan", "--set", "seeds=[7]"]) == 0
  lines = capsys.readouterr().out.splitlines()
  assert len(lines) == 1 + 2 + 2 * 4 and all("--seed 7 " in line for line in lines[1:3])
  assert all("train.evaluate" in line and "--baseline" in line for line in lines[3:])
  assert study_main(["tiny", "--plan", "--set", "retries=-1"]) == 2
  assert study_main([str(STUDIES / "nope.yaml"), "--plan"]) == 2
  assert "no such study file" in capsys.readouterr().err


def test_the_gpu_drivers_take_a_studys_pack_as_the_study_runs_it(capsys):
  """scripts/gpu/pack_args.py: the paper study's SAC pack is its 40 one-robot runs in one program
  (4 tasks x 5 seeds x 2 early stops); a study without a pack of the algorithm says so and exits 2."""
  import importlib.util
  import shlex
  path = pathlib.Path(__file__).parent.parent / "scripts" / "gpu" / "pack_args.py"
  spec = importlib.util.spec_from_file_location("pack_args", path)
  script = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(script)
  assert script.main(["sac"]) == 0
  args = run_parser().parse_args(shlex.split(capsys.readouterr().out))
  assert (args.algo, args.preset, args.steps, args.seeds) == ("sac", "paper", 20000, "0,1,2,3,4")
  assert (args.tasks.count(","), args.early_stops) == (3, "return,none")
  assert script.main(["td3"]) == 2 and "no pack of td3 runs" in capsys.readouterr().err
