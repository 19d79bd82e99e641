"""Constants shared by the scene generators and the simulator: collision filtering, geom groups,
and the name of the per-environment scene boxes. Scenes and robots import these; nothing here
imports either."""

# Collision filtering: robot geoms collide with world geoms only, never with each other.
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 2
ROBOT_CONTYPE, ROBOT_CONAFFINITY = WORLD_CONAFFINITY, WORLD_CONTYPE
WORLD_GROUP = 0  # geom group of the world (what depth beams see)
ROBOT_GROUP = 1  # geom group of robot geoms (depth beams ignore it)
SCENE_BOX = "scenebox"  # name prefix of the world's per-environment boxes (steps, obstacles)


def world_geom_attrs() -> str:
  """MJCF attributes of every colliding world geom (mjx.ray needs a material)."""
  return (f'contype="{WORLD_CONTYPE}" conaffinity="{WORLD_CONAFFINITY}" group="{WORLD_GROUP}" '
          'condim="3" material="world"')
