"""mjx_tracks.atomic: a JSON file is replaced whole or not at all."""

import json
import os

import pytest

from mjx_tracks import atomic


def test_a_failed_write_leaves_the_old_file_whole_and_no_temporary_file(tmp_path):
  path = tmp_path / "state.json"
  atomic.write_json(path, {"cells": [1, 2]})
  assert json.loads(path.read_text()) == {"cells": [1, 2]}
  with pytest.raises(TypeError):  # json.dump fails midway: the first key is written, the object is not
    atomic.write_json(path, {"cells": [3], "bad": object()})
  assert json.loads(path.read_text()) == {"cells": [1, 2]}
  assert os.listdir(tmp_path) == ["state.json"]
  atomic.write_json(path, {"cells": [3]})
  assert json.loads(path.read_text()) == {"cells": [3]}
