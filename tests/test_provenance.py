"""scripts/analysis/provenance.py: what a result file says of its making."""

import datetime
import os
import platform
import sys

import jax

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from provenance import provenance  # noqa: E402


def test_a_result_file_names_its_device_time_command_and_jax():
  p = provenance()
  assert jax.devices()[0].platform == "cpu"  # the suite runs with JAX_PLATFORMS=cpu
  assert p["device"] == f"CPU ({platform.processor() or platform.machine()})"  # as the committed files say
  age = datetime.datetime.now(datetime.timezone.utc) - datetime.datetime.fromisoformat(p["date"])
  assert datetime.timedelta(0) <= age < datetime.timedelta(minutes=1)
  assert p["command"] == "python " + " ".join(sys.argv) and p["jax"] == jax.__version__
