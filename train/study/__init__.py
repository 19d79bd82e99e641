"""Studies: grids of training runs described once in YAML (configs/studies/NAME.yaml)."""
