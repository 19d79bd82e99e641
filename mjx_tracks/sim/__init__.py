"""The simulator: compiled robot + world, the track-contact model, pose, low-level control."""
