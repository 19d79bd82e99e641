"""Constants shared by the scene generators and the simulator: collision filtering, geom groups,
and the name of the per-environment scene boxes. Scenes and robots import these; nothing here
imports either."""

# Collision filtering: robot geoms collide with world geoms only, never with each other.
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 2
ROBOT_CONTYPE, ROBOT_CONAFFINITY = WORLD_CONAFFINITY, WORLD_CONTYPE
WORLD_GROUP = 0  # geom group of the world (what depth beams see)
ROBOT_GROUP = 1  # geom group of robot geoms (depth beams ignore it)
SCENE_BOX = "scenebox"  # name prefix of the world's per-environment boxes (steps, obstacles)
PARKED_HALF = 0.1  # m, half-size of a scene box parked off the area (an unused step, a left-out obstacle)
PARKED_Z = -10.0  # m, the depth of every parking spot: below the floor, where no scene puts a box


def parked_xyz(k):
  """Where scene box k (an int, or an array of them) is parked (m): below the floor, behind every
  scene's area, 3 m from the next one, so that no parked box touches the robot, a beam or another."""
  return -50.0 - 3.0 * k, 0.0, PARKED_Z


def is_parked(box_pos):
  """Whether each scene box (centres (..., 3) m) sits at a parking spot, not in its scene."""
  return box_pos[..., 2] == PARKED_Z


def parked_box_xml(k: int, rgba: str) -> str:
  """A world XML scene box k at its parking spot (a world model's initial box; resets move it)."""
  x, y, z = parked_xyz(k)
  return (f'<geom name="{SCENE_BOX}{k}" type="box" pos="{x} {y} {z}" size="{PARKED_HALF} {PARKED_HALF} {PARKED_HALF}" '
          f'{world_geom_attrs()} rgba="{rgba}"/>')


def world_geom_attrs() -> str:
  """MJCF attributes of every colliding world geom (mjx.ray needs a material)."""
  return (f'contype="{WORLD_CONTYPE}" conaffinity="{WORLD_CONAFFINITY}" group="{WORLD_GROUP}" '
          'condim="3" material="world"')
