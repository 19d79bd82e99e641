"""Tools around the simulator: driving by script or keyboard, scripted controller, rendering."""
