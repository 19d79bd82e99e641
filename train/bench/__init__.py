"""Benchmarks: `python -m train.bench env|physics|scaling|ablate|time-to-solve|baselines [--out FILE]`.

Each prints a JSON line per row as it measures and writes every row to one result file together
with the device, the command, the date, JAX's version and the host (train.bench.result)."""
