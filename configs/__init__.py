"""Task configurations: defaults.yaml and one YAML per task (installed as mjx_tracks.configs)."""
