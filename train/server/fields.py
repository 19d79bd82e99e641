"""Request fields with their bounds (train.limits): what the API parses at all."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from mjx_tracks.limits import (MAX_NAME_CHARS, MAX_OVERRIDE_CHARS, MAX_OVERRIDES, MAX_SEED, MAX_STEPS, MAX_TRIALS,
                          MAX_YAML_CHARS)

Name = Annotated[str, Field(min_length=1, max_length=MAX_NAME_CHARS)]  # a task, algorithm, preset, backend
Overrides = Annotated[list[Annotated[str, Field(max_length=MAX_OVERRIDE_CHARS)]], Field(max_length=MAX_OVERRIDES)]
Steps = Annotated[int, Field(ge=1, le=MAX_STEPS)]
Seed = Annotated[int, Field(ge=0, le=MAX_SEED)]
Trials = Annotated[int, Field(ge=0, le=MAX_TRIALS)]  # 0: no evaluation
YamlText = Annotated[str, Field(max_length=MAX_YAML_CHARS)]
CriterionText = Annotated[str, Field(max_length=MAX_OVERRIDE_CHARS)]
