"""Procedural scenes: batched randomized staircases and 2D navigation areas, with their samplers."""
