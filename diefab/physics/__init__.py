"""Rigid-body physics: dropping dice in pybullet, physics profiles, and real roll counts to hold simulations against."""
