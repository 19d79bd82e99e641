"""Studies: grids of training runs described once in YAML (configs/studies/NAME.yaml).

Needs the [studies] extra (train.extras): importing it without that extra fails in one line."""

from train.extras import require_extra

require_extra("studies", "train.study")
