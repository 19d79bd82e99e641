"""The learners: PPO and SAC assembled from brax.training's parts, each a pure, jittable
`update(state) -> (state, metrics)` over a typed state that holds everything a checkpoint needs."""
