"""Early-stop criteria and the loop's evaluation cadence, with a fake learner (no compilation)."""

import time
import types

import pytest

from mjx_tracks.envs.config import load_config
from scenes.kinds.stairs import EARLY_STOP_RETURN
from train.core.early_stop import EARLY_STOP_SUCCESS, EARLY_STOP_TIMES, EarlyStop, parse_early_stop
from train.core.loop import Checkpointer, Loop, Schedule


def test_criteria_parse_with_their_defaults_and_name_bad_input():
  up, nav = load_config("asc-inc-cog", ()), load_config("nav", ())
  assert parse_early_stop("return", up) == EarlyStop("return", EARLY_STOP_RETURN["up"])
  assert parse_early_stop("success", up) == EarlyStop("success", EARLY_STOP_SUCCESS, EARLY_STOP_TIMES["success"])
  assert parse_early_stop("success=0.9x3", up) == EarlyStop("success", 0.9, 3)
  assert parse_early_stop("return=x2", up) == EarlyStop("return", EARLY_STOP_RETURN["up"], 2)
  assert parse_early_stop(str(EarlyStop("success", 0.97, 2)), up) == EarlyStop("success", 0.97, 2)
  assert parse_early_stop("success=0.5", up).threshold == 0.5 and str(parse_early_stop("return=0.25", up)) == "return=0.25"
  for text, words in (("speed", "one of return, success"), ("success=abc", "not a number"),
                      ("success=1.5", r"in \[0, 1\]"),
                      ("success=0.9x0", "count of reports in a row"), ("success=0.9xa", "count of reports")):
    with pytest.raises(ValueError, match=words):
      parse_early_stop(text, up)
  assert parse_early_stop("success=0.9", nav) == EarlyStop("success", 0.9, 2)  # on random areas (its probe scene)
  with pytest.raises(ValueError, match="no paper threshold"):
    parse_early_stop("return", nav)


class FakeReporter:
  """Rows as train.core.progress.Reporter makes them: source from the metrics' prefix."""

  def __init__(self):
    self.rows = []

  def __call__(self, step, metrics):
    source = "probe" if "probe/success_rate" in metrics else "train"
    row = {"step": step, "source": source, "success_rate": metrics.get("probe/success_rate"),
           "return_mean": metrics.get("episode/sum_reward"), "steps_per_s": metrics.get("training/steps_per_s")}
    self.rows.append(row)
    return row


def _loop(probe_success, early, probe_every=300):
  """A loop of 100-step updates whose training return is 0.1 and whose probe's success follows a list."""
  successes = iter(probe_success)
  update = lambda s: (s + 1, {"episode/sum_reward": 0.1, "episode/count": 1.0})
  ckpt = Checkpointer(None, {}, None, lambda step: None, every_s=1e9)
  reporter = FakeReporter()
  probe = lambda s: {"probe/success_rate": next(successes)}  # noqa: E731
  loop = Loop(update, 100, ckpt, reporter, types.SimpleNamespace(requested=None),
              Schedule(100, early, ((probe, probe_every),)))
  return loop, reporter


def test_the_loop_stops_at_the_first_probe_reaching_the_success_threshold():
  loop, reporter = _loop([0.5, 0.96, 0.98, 1.0], EarlyStop("success", 0.97))
  result = loop.run(0, 0, 10_000)
  assert result.reason == "early_stop" and result.step == 900 and result.state == 9
  assert [r["step"] for r in reporter.rows if r["source"] == "probe"] == [300, 600, 900]


def test_a_criterion_of_two_in_a_row_waits_for_two_probes_in_a_row():
  loop, reporter = _loop([0.5, 0.98, 0.96, 0.98, 0.99, 1.0], EarlyStop("success", 0.97, 2))
  result = loop.run(0, 0, 10_000)
  assert result.reason == "early_stop" and result.step == 1_500  # the training reports between do not count


def test_a_return_criterion_ignores_the_probe_and_a_run_without_one_goes_to_the_end():
  loop, _ = _loop([1.0] * 10, EarlyStop("return", 0.5))
  assert loop.run(0, 0, 1_000).reason == "done"
  loop, _ = _loop([1.0] * 10, EarlyStop("return", 0.1))
  assert (lambda r: (r.reason, r.step))(loop.run(0, 0, 1_000)) == ("early_stop", 100)
  loop, _ = _loop([1.0] * 10, None)
  assert loop.run(0, 0, 1_000).step == 1_000


class DispatchedState:
  """An update's result still computing: the first wait for it takes 50 ms (asynchronous dispatch)."""

  def __init__(self):
    self.waited = False

  def block_until_ready(self):
    if not self.waited:
      time.sleep(0.05)
      self.waited = True
    return self


def test_time_of_updates_still_running_when_an_evaluation_starts_counts_as_training():
  update = lambda s: (DispatchedState(), {"episode/sum_reward": 0.1, "episode/count": 1.0})
  ckpt = Checkpointer(None, {}, None, lambda step: None, every_s=1e9)
  reporter = FakeReporter()
  probe = lambda s: (s.block_until_ready(), {"probe/success_rate": 0.0})[1]  # waits like an evaluation
  loop = Loop(update, 100, ckpt, reporter, types.SimpleNamespace(requested=None), Schedule(200, None, ((probe, 100),)))
  loop.run(DispatchedState(), 0, 1_000)
  rates = [r["steps_per_s"] for r in reporter.rows if r["source"] == "train"]
  # 100 steps per >= 50 ms wait; the first window holds one wait (its second is the next one's)
  assert len(rates) == 5 and rates[0] < 4_100 and all(r < 2_100 for r in rates[1:]), rates


@pytest.mark.parametrize("argv, expected", [
    (["--task", "asc-inc-cog", "--preset", "gpu"], "success=0.97x2"),  # the GPU main command stops once solved
    (["--task", "asc-inc-cog", "--preset", "gpu", "--early-stop", "none"], None),
    (["--task", "asc-inc-cog", "--preset", "gpu", "--early-stop", "return"], "return=0.5"),
    (["--task", "nav", "--preset", "gpu"], "success=0.97x2"),  # solved on random areas, its probe scene
    (["--task", "asc-inc-cog", "--preset", "laptop"], None),
    (["--task", "des-inc-ang", "--algo", "sac", "--preset", "paper"], None)])
def test_the_preset_says_when_a_run_stops_unless_the_command_line_does(argv, expected, tmp_path):
  from train.core.plan import plan_run
  from train.run import parser
  plan = plan_run(parser().parse_args([*argv, "--out", str(tmp_path / "run")]))
  assert (str(plan.early_stop) if plan.early_stop else None) == expected
  assert plan.probe_every > 0 or expected is None


@pytest.mark.parametrize("task, argv, every", [
    ("asc-inc-cog", [], 81_920),  # 50-step episodes: the preset's interval
    ("step-up", [], 2 * 81_920),  # 80 steps: a probe costs 1.6x, the interval doubles
    ("nav", [], 5 * 81_920),  # 240 steps: 4.8x, five intervals
    ("nav", ["--hp", "probe_steps=100000"], 500_000),  # the preset's field scales alike
    ("nav", ["--probe-every", "1000000"], 1_000_000)])  # asked for: as asked
def test_the_probe_interval_grows_with_the_probe_episodes_length(task, argv, every, tmp_path):
  from train.core.plan import plan_run
  from train.run import parser
  plan = plan_run(parser().parse_args(["--task", task, "--preset", "gpu", *argv, "--out", str(tmp_path / "run")]))
  assert plan.probe_every == every
