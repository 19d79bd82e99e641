"""Upper bounds on what a request, a command line or a study may ask for: enough for any real
experiment, small enough that a typo or a hostile request cannot exhaust the machine. One place
for every command line, the study spec and the server."""

MAX_STEPS = 10**10  # environment steps of one run (a day and a half at 64k steps/s)
MAX_TRIALS = 10_000  # trials per evaluation scene (all vmapped at once)
MAX_ENVS = 1 << 20  # parallel environments of one run
MAX_SEED = 2**31 - 1
MAX_RETRIES = 20  # attempts after a failed one, per study run
MAX_NAME_CHARS = 64  # study and group names (folder names)
MAX_OVERRIDES = 64  # KEY=VALUE overrides of one run or study
MAX_OVERRIDE_CHARS = 1_000  # one KEY=VALUE
MAX_YAML_CHARS = 100_000  # a study's or override's YAML text
MAX_YAML_NODES = 100_000  # nodes of one YAML document with its *aliases expanded (alias bombs)
MAX_BODY_BYTES = 1 << 20  # a request body to the server
MAX_COMPARE_RUNS = 64  # runs compared side by side in one request
MAX_STUDY_RUNS = 10_000  # runs of one study
