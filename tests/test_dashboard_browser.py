"""The dashboard in a real browser: Playwright drives the system Chromium (headless, no browser
download) against a server on a free port whose launches run on a local Dask cluster with the
stand-in runner (tests/fake_study_run.py; a real tiny CPU run made from the form: test_training.py). A run is created from the form and reaches `done`; its
page shows a curve with points; two runs are compared; an invalid value shows its field error.
The screenshots in docs/ come from scripts/docs/dashboard_screenshots.py, on real runs."""

import os
import pathlib

import pytest
from distributed import Client, LocalCluster
from helpers import chromium

from train.server.app import create_app
from train.server.background import serve_in_thread
from train.server.launcher import Launcher
from train.server.settings import Settings

FAKE = str(pathlib.Path(__file__).with_name("fake_study_run.py"))
if os.environ.get("MJX_TRACKS_NO_BROWSER") == "1":
  pytest.skip("MJX_TRACKS_NO_BROWSER=1", allow_module_level=True)


@pytest.fixture(scope="module")
def base_url(tmp_path_factory):
  root = tmp_path_factory.mktemp("dash") / "runs"
  settings = Settings(str(root / "experiments.sqlite"), str(root))
  with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, resources={"cpu": 2},
                    dashboard_address=":0") as cluster, Client(cluster) as client:
    launcher = Launcher(settings.db, settings.runs_root, client, ("cpu",), ((FAKE, "train"), (FAKE, "evaluate")),
                        poll_s=0.1).start()
    base, stop = serve_in_thread(create_app(settings, launcher))
    yield base
    stop()
    launcher.stop()


@pytest.fixture(scope="module")
def page():
  from playwright.sync_api import sync_playwright
  with sync_playwright() as p:
    browser = p.chromium.launch(executable_path=chromium(), headless=True, args=["--no-sandbox"])
    yield browser.new_page(viewport={"width": 1366, "height": 900})
    browser.close()


def _launch_from_form(page, base_url: str, seeds: str) -> None:
  page.goto(f"{base_url}/new")
  page.wait_for_selector("#f-episode--max_steps")
  page.fill("#steps", "300")
  page.fill("#seeds", seeds)
  page.fill("#eval_trials", "4")
  page.click("#launch")
  page.wait_for_function("document.getElementById('result').textContent.startsWith('queued')")


def test_a_run_made_from_the_form_reaches_done_and_its_page_draws_its_curves(page, base_url):
  _launch_from_form(page, base_url, "0, 1")
  page.goto(f"{base_url}/queue")
  page.wait_for_function("[...document.querySelectorAll('#rows tr')].filter(r => r.textContent.includes('done')).length == 2",
                         timeout=60_000)
  page.goto(f"{base_url}/")
  page.wait_for_function("document.querySelectorAll('#rows tr').length == 2")
  assert "2 of 2 runs" in page.text_content("#count")
  page.click("#rows tr:first-child a")
  page.wait_for_function("document.querySelector('.chart') && document.querySelector('.chart').data "
                         "&& document.querySelector('.chart').data[0].x.length > 0")
  points = page.evaluate("document.querySelector('.chart').data[0].x.length")
  assert points == 3  # the stand-in logs a training row per 100 steps
  page.wait_for_function("document.querySelectorAll('#evals tr.eval').length == 3")
  page.click("#evals tr.eval")  # every trial of that evaluation
  assert page.locator("#trials-0 tr").count() == 4 and page.is_visible("#trials-0")


def test_two_runs_compare_side_by_side(page, base_url):
  runs = page.evaluate("fetch('/api/runs').then(r => r.json())")
  ids = [r["run_id"] for r in runs][:2]
  page.goto(f"{base_url}/compare?run={ids[0]}&run={ids[1]}")
  page.wait_for_function("document.querySelector('.chart') && document.querySelector('.chart').data "
                         "&& document.querySelector('.chart').data.length == 2")
  page.wait_for_function("document.querySelectorAll('#evals tr').length == 3")
  assert " [" in page.text_content("#evals tr:first-child")  # IQM with its interval


def test_an_invalid_value_shows_the_error_at_its_field(page, base_url):
  page.goto(f"{base_url}/new")
  page.wait_for_selector("#f-episode--max_steps")
  page.fill("#f-episode--max_steps", "0")
  page.click("#check")
  page.wait_for_function("document.querySelector('.error[data-for=\"episode.max_steps\"]').textContent.length > 0")
  assert "must be in [1, 100000]" in page.text_content('.error[data-for="episode.max_steps"]')


def test_a_study_launched_from_the_form_shows_its_groups_with_bands(page, base_url):
  page.goto(f"{base_url}/new")
  page.wait_for_selector("#f-episode--max_steps")
  page.fill("#steps", "200")
  page.fill("#seeds", "0, 1")
  page.fill("#eval_trials", "4")
  page.click("#study")
  page.wait_for_function("document.getElementById('result').textContent.startsWith('study queued')")
  page.goto(f"{base_url}/")
  page.wait_for_function("document.querySelector('#studies a') !== null", timeout=60_000)
  page.click("#studies a")  # its groups
  page.wait_for_function("document.querySelector('.chart') && document.querySelector('.chart').data "
                         "&& document.querySelector('.chart').data.length == 2")  # the band and the mean
  assert "IQM over seeds" in page.text_content("#groups")
