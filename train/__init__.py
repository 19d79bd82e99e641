"""Training and the lab around it: train/core/ trains a policy (`python -m train.run`); evaluation,
the experiment database, studies (`train.study`), benchmarks (`train.bench`) and the server
(`train.server`) evaluate, record, compare and show runs."""
