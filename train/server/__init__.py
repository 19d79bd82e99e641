"""The experiment server: the dashboard and a REST API over the experiment database.

Needs the [server] extra (train.extras): importing it without that extra fails in one line."""

from train.extras import require_extra

require_extra("server", "train.server")
