"""`python -m train.study report NAME`: STUDY/report.md and its PNG figures from a study's folder:
final metrics per group (IQM over seeds, stratified bootstrap 95 % CIs, rliable), the probability
of improvement of each `compare` pair, the paper's Figure 9 side by side, learning curves, attempts."""

from __future__ import annotations

import datetime
import os

import numpy as np

from mjx_tracks.envs.config import REWARD_SIGNALS, ConfigError, load_config
from train.evaluation import ROBUST
from scenes.kinds import HARDEST, HELD_OUT, NAV, scene_kind
from train.study.executor import folder_parser, no_study, overview
from train.study.figures import write_figures
from train.study.paper import FIGURE9, PAPER_TRIALS, paper_figure
from mjx_tracks.baselines import BASELINES, CONSTANT, SATURATED, saturated
from train.study.results import StudyResults, load_results
from train.study.statistics import LEVEL, REPS, improvement, iqm_intervals

REPORT = "report.md"
FINAL_COLUMNS = (("success", "hardest"), ("progress", "hardest"), ("success", "uniform"))
IMPROVEMENT_METRICS = (("success", "hardest"), ("progress", "hardest"), ("success", "uniform"),
                       ("progress", "uniform"))


def ci_text(est: tuple[float, float, float] | None) -> str:
  """An estimate with its interval, "IQM [low, high]" to 2 decimals ("-" if there is none)."""
  return "-" if est is None else f"{est[0]:.2f} [{est[1]:.2f}, {est[2]:.2f}]"


def _mean_sd(x: np.ndarray, digits: int = 3) -> str:
  return "-" if not len(x) else f"{x.mean():.{digits}f} +- {x.std():.{digits}f}"


def budget_text(budget: int) -> str:
  """A budget for a table: steps, or '-' for a baseline's (0: nothing trained)."""
  return f"{budget:,}" if budget else "-"


def _runs(results: StudyResults, group: str, task: str, budget: int) -> int:
  """Finished runs (seeds) of a row: those with trials on any scene."""
  return max((len(results.final(group, task, budget, s, "success")) for s in results.scenes()), default=0)


def final_table(results: StudyResults) -> list[str]:
  """One row per (group, task, budget): IQM [95 % CI] of success / progress on the hardest
  configuration and uniform scenes, and mean +- sd over seeds of pitch rate and tip-overs on the
  hardest configuration."""
  cols = [f"{m} {s}" for m, s in FINAL_COLUMNS]
  lines = [f"| group | task | budget | runs | {' | '.join(cols)} | pitch rate hardest (rad/s) | tip-overs hardest |",
           "|---" * (len(cols) + 6) + "|"]
  for group, task, budget in results.groups():
    fig = lambda m, s: results.final(group, task, budget, s, m)  # noqa: E731
    est = iqm_intervals({f"{m} {s}": fig(m, s) for m, s in FINAL_COLUMNS})
    lines.append(f"| {group} | {task} | {budget_text(budget)} | {_runs(results, group, task, budget)} | "
                 f"{' | '.join(ci_text(est.get(c)) for c in cols)} | "
                 f"{_mean_sd(fig('pitch_rate', 'hardest'))} | {_mean_sd(fig('tipped_over', 'hardest'), 2)} |")
  return lines


def suite_table(results: StudyResults) -> list[str]:
  """One row per (group, task, budget, scene) of the suite's other scenes (held-out staircases and
  terrains, each terrain kind's hardest, each navigation area): runs, success, progress and the rate
  of trials with a collision (nav scenes), IQM [95 % CI]."""
  lines = ["| group | task | budget | scene | runs | success | progress | collisions |", "|---" * 8 + "|"]
  others = [s for s in results.scenes() if s not in ("hardest", "uniform")]
  for group, task, budget in results.groups():
    for scene in others:
      fig = {m: results.final(group, task, budget, scene, m) for m in ("success", "progress", "collided")}
      if len(fig["success"]):
        est = iqm_intervals(fig)
        lines.append(f"| {group} | {task} | {budget_text(budget)} | {scene} | {len(fig['success'])} | "
                     f"{ci_text(est.get('success'))} | {ci_text(est.get('progress'))} | {ci_text(est.get('collided'))} |")
  return lines if len(lines) > 2 else []


def robustness_table(results: StudyResults) -> list[str]:
  """One row per (group, task, budget, robustness case) (train.evaluate --robustness): IQM [95 % CI]
  over seeds of success on the hardest and uniform scenes and mean +- sd of the task's safety figure
  (mjx_tracks.metrics: pitch rate, COG deviation) on the hardest, the nominal robot first."""
  robust = [s for s in results.scenes(robustness=True) if ROBUST in s]
  cases = list(dict.fromkeys(s.partition(ROBUST)[2] for s in robust))
  lines = ["| group | task | budget | case | runs | success hardest | success uniform | safety hardest |",
           "|---" * 8 + "|"]
  for group, task, budget in results.groups():
    signal = REWARD_SIGNALS[load_config(task).reward.kind] or "pitch_rate"
    for case in cases:
      fig = lambda m, base: results.final(group, task, budget, f"{base}{ROBUST}{case}", m)  # noqa: E731
      est = iqm_intervals({base: fig("success", base) for base in ("hardest", "uniform")})
      if est:
        lines.append(f"| {group} | {task} | {budget_text(budget)} | {case} | {len(fig('success', 'uniform'))} | "
                     f"{ci_text(est.get('hardest'))} | {ci_text(est.get('uniform'))} | "
                     f"{signal.replace('_', ' ')} {_mean_sd(fig(signal, 'hardest'))} |")
  return lines if len(lines) > 2 else []


def improvement_table(results: StudyResults) -> list[str]:
  """P(A > B) [95 % CI] for every compare pair, group and budget, per metric and scene."""
  lines = ["| group | budget | A | B | " + " | ".join(f"P(A > B), {m} {s}" for m, s in IMPROVEMENT_METRICS) + " |",
           "|---" * (4 + len(IMPROVEMENT_METRICS)) + "|"]
  for group, budget in dict.fromkeys((g, b) for g, _, b in results.trained_groups()):
    for a, b in results.spec.compare:
      fig = lambda task, m, s: results.final(group, task, budget, s, m)  # noqa: E731
      est = improvement({f"{m} {s}": (fig(a, m, s), fig(b, m, s)) for m, s in IMPROVEMENT_METRICS})
      if est:
        lines.append(f"| {group} | {budget:,} | {a} | {b} | " +
                     " | ".join(ci_text(est.get(f"{m} {s}")) for m, s in IMPROVEMENT_METRICS) + " |")
  return lines


def generalization_table(results: StudyResults) -> list[str]:
  """Each terrain task drawing several kinds (mixed) on each kind's hardest configuration, beside
  the specialist tasks of that kind on theirs: IQM [95 % CI] of success over seeds."""
  kinds = {t: load_config(t).scene for t in results.spec.tasks}
  groups = {t: scene_kind(s.kind).groups(s) if scene_kind(s.kind).has_hardest(s) else () for t, s in kinds.items()}
  mixed = [t for t, g in groups.items() if len(g) > 1]
  lines = []
  for group, task, budget in results.trained_groups():
    if task not in mixed:
      continue
    for kind in groups[task]:
      success = lambda t, scene: iqm_intervals({"x": results.final(group, t, budget, scene, "success")}).get("x")  # noqa: E731
      own = success(task, HARDEST + kind)
      special = [(t, success(t, "hardest")) for t, g in groups.items() if g == (kind,)]
      lines.append(f"| {group} | {budget_text(budget)} | {kind} | {ci_text(own)} | "
                   f"{'; '.join(f'{t}: {ci_text(e)}' for t, e in special) or '-'} |")
  head = ["| group | budget | terrain kind | mixed policy, success on its hardest | specialist policy, success on its hardest |",
          "|---|---|---|---|---|"]
  return head + lines if lines else []


def paper_table(results: StudyResults) -> list[str]:
  """The paper's Figure 9 (PAPER_TRIALS trials on the hardest staircase, one policy each) beside this study's
  hardest-staircase figures: mean +- sd over seeds of each run's mean over its trials."""
  lines = ["| task | source | progress | COG deviation (m) | pitch rate (rad/s) |", "|---|---|---|---|---|"]
  for task in (t for t in results.spec.tasks if t in FIGURE9):
    p = FIGURE9[task]
    lines.append(f"| {task} | paper (Figure 9) | {p.get('progress', '')} | {p.get('cog_deviation', '')} | "
                 f"{p.get('pitch_rate', '')} |")
    for group, t, budget in results.groups():
      if t == task:
        fig = lambda m: results.final(group, task, budget, "hardest", m)  # noqa: E731
        source = f"{group} @ {budget_text(budget)} ({len(fig('progress'))} seeds)"
        lines.append(f"| {task} | {source} | {_mean_sd(fig('progress'))} | {_mean_sd(fig('cog_deviation'))} | "
                     f"{_mean_sd(fig('pitch_rate'))} |")
  return lines


def paper_trials_table(results: StudyResults) -> list[str]:
  """The paper's own evaluation for each trained group: each seed's policy on its first
  PAPER_TRIALS trials of the hardest staircase, mean +- sd over those trials of the task's figure
  (paper.paper_figure), the paper's own figure first; no table where no seed has that many."""
  lines = []
  for task in (t for t in results.spec.tasks if t in FIGURE9):
    metric = paper_figure(task)
    name = metric.replace("_", " ")
    rows = []
    for group, t, budget in results.trained_groups():
      seeds = results.first_trials(group, task, budget, "hardest", metric, PAPER_TRIALS) if t == task else []
      if seeds:
        cells = ", ".join(f"s{s} {_mean_sd(x, 2)}" for s, x in seeds)
        rows.append(f"| {task} | {name} | {group} @ {budget_text(budget)} | {cells} |")
    if rows:  # the paper's own figure first
      lines += [f"| {task} | {name} | paper (Figure 9, one policy) | {FIGURE9[task][metric]} |", *rows]
  head = [f"| task | figure | source | each seed: mean +- sd over its first {PAPER_TRIALS} trials |", "|---|---|---|---|"]
  return head + lines if lines else []


SAFETY_FIGURES = ("pitch_rate", "cog_deviation")  # the tasks' own safety figures (mjx_tracks.metrics), lower better


def baseline_table(results: StudyResults) -> list[str]:
  """Per task: each baseline's success and safety figures on the hardest scene, every trained
  group's beside them (mean over seeds), and whether the task is saturated (a constant baseline
  reaches SATURATED)."""
  head = ["| task | policy | success hardest | progress hardest | " +
          " | ".join(f"{m.replace('_', ' ')} hardest" for m in SAFETY_FIGURES) + " |", "|---" * (4 + len(SAFETY_FIGURES)) + "|"]
  lines = []
  for task in results.spec.tasks:
    success = results.baseline_figure(task, "hardest", "success")
    if not success:
      continue
    for name in success:
      fig = {m: results.baseline_figure(task, "hardest", m)[name] for m in ("success", "progress", *SAFETY_FIGURES)}
      lines.append(f"| {task} | baseline {name} | " + " | ".join(f"{fig[m]:.3f}" for m in fig) + " |")
    for group, t, budget in results.trained_groups():
      if t == task:
        fig = {m: results.final(group, task, budget, "hardest", m) for m in ("success", "progress", *SAFETY_FIGURES)}
        lines.append(f"| {task} | {group} @ {budget_text(budget)} (mean of {len(fig['success'])} seeds) | " +
                     " | ".join(f"{v.mean():.3f}" if len(v) else "-" for v in fig.values()) + " |")
    lines.append(f"| {task} | **{'saturated' if saturated(success) else 'not saturated'}** |" + " |" * (2 + len(SAFETY_FIGURES)))
  return head + lines if lines else []


def attempts_lines(results: StudyResults) -> list[str]:
  """Runs done / failed / unfinished, retried runs and every failed attempt's reason; attempts cut
  off by the study stopping (a machine given back) are counted in one line, not failures."""
  state = results.state
  lines, cut_off = [f"- {overview(state)}."], 0
  for cid, c in state.items():
    for i, a in enumerate(c["attempts"], 1):
      if a.get("stopped"):
        cut_off += 1
      elif a.get("rc") not in (0, None) or a.get("error"):
        reason = ((a.get("error") or "").strip().splitlines()[-1:] or [""])[0][:160]
        lines.append(f"- `{cid}` attempt {i} on {a.get('worker') or '?'}: rc {a.get('rc')}, {a.get('phase')}: {reason}")
  if cut_off:
    lines.insert(1, f"- {cut_off} attempts were cut off by the study stopping (its process ended, e.g. the machine "
                    "went back) and started again when it resumed; they are not failures.")
  return lines


def report_text(results: StudyResults, figures: list[str], command: str) -> str:
  """The whole report.md."""
  date = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
  spec = results.spec
  out = [f"# Study `{spec.name}`", "",
         f"Written by `{command}` on {date}, from `{os.path.basename(os.path.abspath(results.folder))}/study.sqlite` "
         f"and `state.json`. "
         f"Tasks {', '.join(spec.tasks)}; seeds {', '.join(map(str, spec.seeds))}; "
         f"{spec.eval_trials} trials per evaluation scene.", "",
         "## Runs", "", *attempts_lines(results), "",
         "## Final metrics", "",
         f"Interquartile mean over seeds of each run's mean over its trials, with a stratified bootstrap "
         f"{LEVEL:.0%} confidence interval ({REPS:,} resamples, rliable). Pitch rate and tip-overs: "
         "mean +- sd over seeds.",
         "", *final_table(results), ""]
  suite = suite_table(results)
  if suite:
    out += ["## The rest of the evaluation suite", "",
            f"Held-out configurations (`{HELD_OUT}NAME`), each terrain kind's hardest (`{HARDEST}KIND`) and "
            f"each navigation area (`{NAV}KIND`): IQM over seeds [{LEVEL:.0%} CI].", "", *suite, ""]
  robust = robustness_table(results)
  if robust:
    out += ["## Robustness", "",
            "Each policy on the nominal robot (no randomization) and under each perturbation of the "
            "robustness suite alone (`evaluation.robustness`, `python -m train.evaluate RUN --robustness`): "
            f"success IQM over seeds [{LEVEL:.0%} CI]; the task's safety figure, mean +- sd over seeds.", "",
            *robust, ""]
  base = baseline_table(results)
  if base:
    out += ["## Baselines", "",
            "Policies that ignore learning, on each task's hardest scene (mean over their trials): "
            + "; ".join(f"`{b.name}`: {b.meaning}" for b in BASELINES.values() if b.name in spec.baselines)
            + f". A task is **saturated** when a constant baseline ({', '.join(CONSTANT)}) succeeds in at least "
            f"{SATURATED:.0%} of those trials: success there does not tell a trained policy from a trivial one.",
            "", *base, ""]
  if spec.compare:
    rows = improvement_table(results)
    out += ["## Probability of improvement", "",
            "P(A > B): the probability that a run of A scores above a run of B (ties count half), "
            f"with its {LEVEL:.0%} bootstrap interval (rliable). 0.5: no difference.", "",
            *(rows if len(rows) > 2 else ["No pair has finished runs on both sides yet."]), ""]
  general = generalization_table(results)
  if general:
    out += ["## Generalization: the mixed-terrain policy on each terrain", "",
            "Success on each terrain kind's hardest configuration (`hardest/KIND`), IQM over seeds "
            f"[{LEVEL:.0%} CI], of the policy trained on every kind and of the specialists trained on that kind.",
            "", *general, ""]
  if any(t in FIGURE9 for t in spec.tasks):
    out += ["## The paper's Figure 9 side by side", "",
            f"The paper evaluated one policy per task with {PAPER_TRIALS} trials on the hardest staircase; here each "
            "seed's policy has its own trials, and the figure is mean +- sd over seeds.", "",
            *paper_table(results), ""]
    own = paper_trials_table(results)
    if own:
      out += [f"The paper's evaluation itself, {PAPER_TRIALS} trials of one policy: each seed's first "
              f"{PAPER_TRIALS} trials on the hardest staircase (by trial index, of its evaluation above), "
              "mean +- sd over those trials.", "", *own, ""]
  out += ["## Figures", ""]
  out += [f"![{name}]({name})" for name in figures]
  return "\n".join(out) + "\n"


def write_report(folder: str, command: str) -> str:
  """Writes STUDY/report.md and its figures; returns the report's path."""
  results = load_results(folder)
  figures = write_figures(results, folder)
  path = os.path.join(folder, REPORT)
  with open(path, "w") as f:
    f.write(report_text(results, figures, command))
  return path


def main(argv: list[str]) -> int:
  args = folder_parser("report", __doc__).parse_args(argv)
  folder = os.path.join(args.root, args.name)
  try:
    path = write_report(folder, "python -m train.study report " + " ".join(argv))
  except FileNotFoundError as e:
    return no_study(folder, args.name, e.filename)
  except ConfigError as e:  # e.g. no study.yaml in the folder
    import sys  # noqa: PLC0415
    print(f"error: {e}", file=sys.stderr)
    return 2
  print(f"report -> {path}")
  return 0
