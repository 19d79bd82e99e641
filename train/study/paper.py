"""The paper's Figure 9: PAPER_TRIALS trials of one trained policy per task on the hardest staircase,
as printed (mean +- sd; a task lists only the figures the paper gives for it), and the figure the
paper judged each task by."""

FIGURE9 = {
    "asc-inc-cog": {"progress": "0.965 +- 0.05", "cog_deviation": "0.115 +- 0.008"},
    "asc-uni-cog": {"progress": "0.82 +- 0.24", "cog_deviation": "0.125 +- 0.005"},
    "des-inc-ang": {"pitch_rate": "0.215 +- 0.15"},
    "des-uni-ang": {"pitch_rate": "0.235 +- 0.14"},
}
PAPER_TRIALS = 10  # trials of one policy behind each figure of FIGURE9
# the figure the paper judged a task by: progress in ascent, the pitch rate in descent (it refrains
# from progress there, "since the goal is reached more easily")
JUDGED_BY = {"asc-inc-cog": "progress", "asc-uni-cog": "progress", "des-inc-ang": "pitch_rate", "des-uni-ang": "pitch_rate"}


def paper_figure(task: str) -> str:
  """The metric the paper judged a task of FIGURE9 by."""
  return JUDGED_BY[task]
