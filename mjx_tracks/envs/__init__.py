"""Task environments: config, the Brax env, observations, rewards, wrappers, Gymnasium."""
