"""Screenshots of every dashboard page (docs/screenshots/) served over a copy of a real experiment
database, by default the paper study committed in results/studies/paper, plus one
tiny CPU run launched from the form and run by the server's launcher (a local Dask cluster, the
real train.run and train.evaluate) for the queue: the system Chromium driven by Playwright,
headless. Usage: python scripts/docs/dashboard_screenshots.py [--db PATH] [--out DIR]"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time

from train.server.app import create_app
from train.server.background import serve_in_thread
from train.server.settings import Settings

TINY = ["observation.parts=[v, flippers_paired, arm, pitch]", "episode.max_steps=8"]  # the tests' tiny task


def serve(db: str, runs_root: str = "results", launcher=None) -> tuple[str, object]:
  """The dashboard over `db` on a free local port; returns (base URL, stop())."""
  return serve_in_thread(create_app(Settings(db, runs_root), launcher))


def shoot(base: str, out: str) -> None:
  from playwright.sync_api import sync_playwright  # noqa: PLC0415
  with sync_playwright() as p:
    browser = p.chromium.launch(executable_path=shutil.which("chromium"), headless=True, args=["--no-sandbox"])
    page = browser.new_page(viewport={"width": 1366, "height": 860})
    page.goto(f"{base}/")
    page.wait_for_function("document.querySelectorAll('#rows tr').length > 0")
    page.screenshot(path=f"{out}/runs.png")
    ids = page.evaluate("fetch('/api/runs').then(r => r.json()).then(rs => rs.map(r => r.run_id))")
    page.goto(f"{base}/runs/{ids[0]}")
    page.wait_for_function("document.querySelectorAll('#evals tr').length > 0 && document.querySelector('.chart')")
    page.screenshot(path=f"{out}/run.png", full_page=True)
    page.goto(f"{base}/compare?" + "&".join(f"run={i}" for i in ids))
    page.wait_for_function("document.querySelectorAll('#evals tr').length > 0")
    page.screenshot(path=f"{out}/compare.png", full_page=True)
    page.goto(f"{base}/new")
    page.wait_for_selector("#f-episode--max_steps")
    page.fill("#f-episode--max_steps", "0")
    page.click("#check")
    page.wait_for_function("document.querySelector('.error[data-for=\"episode.max_steps\"]').textContent")
    page.screenshot(path=f"{out}/new-experiment.png")
    page.goto(f"{base}/queue")
    page.wait_for_function("[...document.querySelectorAll('#rows tr')].some(r => r.textContent.includes('done'))")
    page.screenshot(path=f"{out}/queue.png")
    browser.close()


def launch_tiny_run(base: str) -> None:
  """One tiny CPU run through the API, waited for until its launch ends."""
  import json  # noqa: PLC0415
  import urllib.request  # noqa: PLC0415
  body = json.dumps({"task": "asc-inc-cog", "preset": "cpu", "steps": 512, "overrides": TINY, "eval_trials": 4})
  req = urllib.request.Request(f"{base}/api/launches", body.encode(), {"Content-Type": "application/json"})
  t0 = time.time()
  launch_id = json.load(urllib.request.urlopen(req))["id"]
  while True:
    launches = json.load(urllib.request.urlopen(f"{base}/api/launches"))
    status = next(x["status"] for x in launches if x["id"] == launch_id)
    if status not in ("queued", "running"):
      print(f"tiny CPU run (train.run + train.evaluate --suite, 4 trials): launch {launch_id} {status} "
            f"{time.time() - t0:.0f} s after it was queued")
      return
    time.sleep(2)


def main() -> None:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--db", default="results/studies/paper/study.sqlite")
  p.add_argument("--out", default="docs/screenshots")
  args = p.parse_args()
  from distributed import Client, LocalCluster  # noqa: PLC0415

  from train.server.launcher import Launcher  # noqa: PLC0415
  with tempfile.TemporaryDirectory() as tmp, \
       LocalCluster(n_workers=1, threads_per_worker=1, resources={"cpu": 1}, dashboard_address=":0") as cluster, \
       Client(cluster) as client:
    db = os.path.join(tmp, "experiments.sqlite")
    shutil.copy(args.db, db)
    launcher = Launcher(db, tmp, client, ("cpu",)).start()
    base, stop = serve(db, tmp, launcher)
    try:
      launch_tiny_run(base)
      shoot(base, args.out)
    finally:
      stop()
      launcher.stop()
  print(f"screenshots -> {args.out}")


if __name__ == "__main__":
  main()
