"""The experiment server: a REST API over the experiment database (and, in time, the dashboard)."""
