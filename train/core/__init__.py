"""The training core: a run planned (plan, presets, run_record), built (build, networks, mesh, algos),
trained (session, loop, early_stop, probe, progress, interrupts) and saved (checkpoints, policy);
brax_reference trains a plan with Brax's own train() instead (`--library brax`; brax_compat adapts
Brax to this JAX).
`python -m train.run` is its command line. The lab around it lives beside it in train/: evaluation
(a library, with `train.evaluate` its command line), the experiment database (db), studies,
benchmarks and the server. The core probes with the evaluation library and records into the
database; nothing in the core imports studies, benchmarks or the server."""
