"""How long the dashboard's Runs page takes to show N runs (default 1,000) in the system Chromium:
from navigation start to the last row in the table, median of 5 loads. Prints the figures.
Usage: python scripts/docs/bench_dashboard.py [--runs 1000]"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import tempfile

from dashboard_screenshots import serve

from train.db import ExperimentDB


def make_db(path: str, n: int) -> None:
  """n finished runs, each with 20 training statistics rows."""
  db = ExperimentDB(path)
  for i in range(n):
    rid = f"asc-inc-cog-ppo-s{i}-bench"
    db.start(rid, "asc-inc-cog", "ppo", "gpu", i, {}, f"runs/{rid}", 2_000_000)
    for k in range(20):
      db.log_stats(rid, {"step": 100_000 * (k + 1), "steps_per_s": 45_000.0, "return_mean": k / 20,
                         "success_rate": k / 20, "eps": k / 20, "source": "train"}, {})
    db.finish(rid, "done", {}, 2_000_000)


def main() -> None:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--runs", type=int, default=1000)
  args = p.parse_args()
  from playwright.sync_api import sync_playwright  # noqa: PLC0415
  with tempfile.TemporaryDirectory() as tmp:
    make_db(f"{tmp}/db.sqlite", args.runs)
    base, stop = serve(f"{tmp}/db.sqlite")
    with sync_playwright() as pw:
      browser = pw.chromium.launch(executable_path=shutil.which("chromium"), headless=True, args=["--no-sandbox"])
      page, times = browser.new_page(), []
      for _ in range(5):
        page.goto(f"{base}/")
        page.wait_for_function(f"document.querySelectorAll('#rows tr').length == {args.runs}")
        times.append(page.evaluate("performance.now()"))
      browser.close()
    stop()
  print(f"runs page, {args.runs:,} runs: {statistics.median(times):.0f} ms median from navigation start to the "
        f"last row (loads: {', '.join(f'{t:.0f}' for t in times)} ms); chromium headless, {sys.platform}")


if __name__ == "__main__":
  main()
