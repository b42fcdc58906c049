"""Landing models: the probability that a die comes to rest on each face, without simulating it."""
